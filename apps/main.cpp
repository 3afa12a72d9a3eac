// The depthfem command line:
//   depthfem run SCENE.json --out RESULT.h5 [--threads N] [--set PATH=VALUE]...
//                [--restart EARLIER.h5 [--step N]]
//   depthfem info RESULT.h5
// Exit code 0 only when the whole run succeeded; otherwise one line "depthfem: error: ..." on
// stderr (2 for usage errors, 1 for input or solver errors). See apps/command_line.hpp.
#include <csignal>
#include <iostream>
#include <string>
#include <vector>

#include "apps/command_line.hpp"

int main(int argc, char** argv) {
  // Past a file-size limit (ulimit -f) a write fails with EFBIG, which the results file reports
  // as its one-line error with the run marked failed, instead of the signal ending the process
  // without a word.
  std::signal(SIGXFSZ, SIG_IGN);
  return depthfem::command_line(std::vector<std::string>(argv + 1, argv + argc), std::cout,
                                std::cerr);
}

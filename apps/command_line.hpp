#pragma once
/// The `depthfem` command line (`run`, `info`): what `main` calls, and what the command-line fuzz
/// target calls.

#include <ostream>
#include <string>
#include <vector>

namespace depthfem {

/// The usage text, printed after every usage error and at the head of `--help`.
extern const char* const kCommandLineUsage;

/// `text` on one line: control characters (a newline in a key or a file name) written as \xNN.
std::string one_line(const std::string& text);

/// How far `command_line` goes.
enum class CommandStage {
  kCheck,    ///< read and check the arguments and the scene with its overrides; run nothing,
             ///< read or write no results file
  kExecute,  ///< also run the scene or summarise the results file
};

/// Runs `depthfem ARGS...` (`args` without the program name), writing what it prints to `out`
/// and errors to `err`, and returns the exit status: 0 success or help (`--help`, `-h`: the help
/// on `out`), 1 input or solver error (one line "depthfem: error: ..."), 2 usage error (that line,
/// then kCommandLineUsage).
int command_line(const std::vector<std::string>& args, std::ostream& out, std::ostream& err,
                 CommandStage stage = CommandStage::kExecute);

}  // namespace depthfem

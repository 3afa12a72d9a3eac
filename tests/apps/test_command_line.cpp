// The command line's entry point in its checking stage: exit statuses and the one error line.
// Runs, results files and restarts end to end are checked by tests/apps/test_cli.sh.
#include <gtest/gtest.h>

#include <sstream>
#include <string>
#include <vector>

#include "apps/command_line.hpp"
#include "scene_runner.hpp"

namespace depthfem {
namespace {

struct Outcome {
  int status;
  std::string out, err;
};

Outcome check(const std::vector<std::string>& args) {
  std::ostringstream out, err;
  const int status = command_line(args, out, err, CommandStage::kCheck);
  return {status, out.str(), err.str()};
}

const std::string kScene = testing::scene_path("uniaxial_block");

TEST(CommandLine, CheckingAValidRunPrintsNothing) {
  const Outcome o =
      check({"run", kScene, "--out", "x.h5", "--threads", "2", "--set", "solver.tolerance=1e-8"});
  EXPECT_EQ(o.status, 0);
  EXPECT_EQ(o.out, "");
  EXPECT_EQ(o.err, "");
}

TEST(CommandLine, UsageErrorsGiveOneLineThenTheUsage) {
  const Outcome o = check({"run", kScene, "--out", "x.h5", "--threads", "0"});
  EXPECT_EQ(o.status, 2);
  EXPECT_EQ(o.err, std::string("depthfem: error: --threads expects a positive integer, got '0'\n") +
                       kCommandLineUsage);
  EXPECT_EQ(check({"frobnicate"}).status, 2);
  EXPECT_EQ(check({"info"}).status, 2);
}

// `--set` without '=' is a mistake on the command line like `--threads 0` (it gave status 1 and
// no usage, as if the scene were wrong).
TEST(CommandLine, SetWithoutEqualsIsAUsageError) {
  const Outcome o = check({"run", kScene, "--out", "x.h5", "--set", "solver.tolerance"});
  EXPECT_EQ(o.status, 2);
  EXPECT_EQ(o.err,
            std::string("depthfem: error: --set expects PATH=VALUE, got 'solver.tolerance'\n") +
                kCommandLineUsage);
}

TEST(CommandLine, InputErrorsGiveOneLineNamingTheScene) {
  const Outcome o = check({"run", kScene, "--out", "x.h5", "--set", "solver.tolerence=1"});
  EXPECT_EQ(o.status, 1);
  EXPECT_EQ(o.err, "depthfem: error: " + kScene + ": solver.tolerence: unknown key\n");
}

}  // namespace
}  // namespace depthfem

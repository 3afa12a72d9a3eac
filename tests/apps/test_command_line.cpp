// The command line's entry point in its checking stage: exit statuses and the one error line.
// Runs, results files and restarts end to end are checked by tests/apps/test_cli.sh.
#include <gtest/gtest.h>

#include <sstream>
#include <string>
#include <string_view>
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

// `--help` (and `-h`) prints the help on stdout and exits 0; `depthfem --help` lists every command
// with all its options, `depthfem COMMAND --help` that command's. Each option and positional is
// on a line of its own with a description after it.
TEST(CommandLine, HelpNamesEveryOptionWithADescription) {
  const std::vector<std::string> run = {"SCENE.json", "--out",     "--threads",
                                        "--set",      "--restart", "--step"};
  const std::vector<std::string> info = {"RESULT.h5"};
  struct Case {
    std::vector<std::string> args, names;
  };
  std::vector<std::string> all = run;
  all.insert(all.end(), info.begin(), info.end());
  for (const Case& c : {Case{{"--help"}, all}, Case{{"-h"}, all}, Case{{"run", "--help"}, run},
                        Case{{"info", "-h"}, info},
                        // help wins over the mistakes beside it
                        Case{{"run", "--threads", "0", "--help"}, run}}) {
    const Outcome o = check(c.args);
    SCOPED_TRACE(c.args.back());
    EXPECT_EQ(o.status, 0);
    EXPECT_EQ(o.err, "");
    EXPECT_NE(o.out.find("\nusage: depthfem "), std::string::npos) << o.out;
    for (const std::string& name : c.names) {
      // The option's line: the name after the indent, then at least two spaces and a description.
      std::istringstream lines(o.out);
      bool described = false;
      for (std::string line; std::getline(lines, line);) {
        const size_t at = line.find_first_not_of(' ');
        if (at == std::string::npos || line.compare(at, name.size() + 1, name + " ") != 0) continue;
        const size_t gap = line.find("  ", at);
        described =
            gap != std::string::npos && line.find_first_not_of(' ', gap) != std::string::npos;
      }
      EXPECT_TRUE(described) << name << " has no line with a description in\n" << o.out;
    }
  }
  // Every option of the usage text is in the help, and the help starts with the usage lines.
  const Outcome o = check({"--help"});
  const std::string_view usage = kCommandLineUsage;
  EXPECT_NE(o.out.find(usage), std::string::npos) << o.out;
  for (size_t at = usage.find("--"); at != std::string_view::npos; at = usage.find("--", at + 2)) {
    const std::string option(usage.substr(at, usage.find_first_of(" ]\n", at) - at));
    EXPECT_NE(o.out.find("  " + option + " "), std::string::npos) << option;
  }
}

// Usage errors found by the parser: one line naming the option or argument, then the usage, and
// nothing of CLI11's own error or help text.
TEST(CommandLine, ParserErrorsGiveOneLineThenTheUsage) {
  const std::vector<std::string> run = {"run", kScene, "--out", "x.h5"};
  const auto with = [&](std::vector<std::string> more) {
    std::vector<std::string> args = run;
    args.insert(args.end(), more.begin(), more.end());
    return args;
  };
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {with({"--fast"}), "unknown option --fast"},
      {with({"--fast=1"}), "unknown option --fast=1"},
      {with({"-x"}), "unknown option -x"},
      {with({"extra.json"}), "unexpected argument extra.json"},
      {with({"--threads"}), "--threads needs a value"},
      {{"run", kScene, "--out"}, "--out needs a value"},
      {with({"--out", ""}), "--out needs a value"},
      {with({"--step", "3"}), "--step needs --restart EARLIER.h5"},
      {with({"--restart", "a.h5", "--step", "-1"}),
       "--step expects a non-negative integer, got '-1'"},
      {with({"--threads", "3x"}), "--threads expects a positive integer, got '3x'"},
      {with({"--threads=0"}), "--threads expects a positive integer, got '0'"},
      {with({"--set", "solver.tolerance=1e-8", "b=2"}), "unexpected argument b=2"},
      {{"run", kScene}, "run needs --out RESULT.h5"},
      {{"run", "--out", "x.h5"}, "run needs SCENE.json"},
      {{"info"}, "info needs RESULT.h5"},
      {{"info", "a.h5", "b.h5"}, "unexpected argument b.h5"},
      {{"info", "--all", "a.h5"}, "unknown option --all"},
      {{"frobnicate", "run", kScene, "--out", "x.h5"}, "unknown command 'frobnicate'"},
      {{"--fast", "run", kScene}, "unknown option --fast"},
      {{}, "a command is needed: run or info"},
  };
  for (const auto& [args, message] : cases) {
    const Outcome o = check(args);
    EXPECT_EQ(o.status, 2) << message;
    EXPECT_EQ(o.err, "depthfem: error: " + message + "\n" + kCommandLineUsage);
    EXPECT_EQ(o.out, "");
  }
}

// A word that names a command is an argument after the command: here the scene file "info".
TEST(CommandLine, ACommandNameAfterTheCommandIsAnArgument) {
  const Outcome o = check({"run", "info", "--out", "x.h5"});
  EXPECT_EQ(o.status, 1);
  EXPECT_EQ(o.err.rfind("depthfem: error: info: ", 0), 0u) << o.err;
}

TEST(CommandLine, InputErrorsGiveOneLineNamingTheScene) {
  const Outcome o = check({"run", kScene, "--out", "x.h5", "--set", "solver.tolerence=1"});
  EXPECT_EQ(o.status, 1);
  EXPECT_EQ(o.err, "depthfem: error: " + kScene + ": solver.tolerence: unknown key\n");
}

}  // namespace
}  // namespace depthfem

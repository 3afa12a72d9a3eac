#include "apps/command_line.hpp"

#include <tbb/info.h>
#include <CLI/CLI.hpp>

#include <algorithm>
#include <charconv>
#include <cstdio>
#include <exception>
#include <new>
#include <sstream>
#include <stdexcept>

#include "apps/run_scene.hpp"
#include "core/error.hpp"
#include "core/results_file.hpp"
#include "integrators/solvers/ranks.hpp"
#include "integrators/solvers/thread_budget.hpp"

namespace depthfem {

const char* const kCommandLineUsage =
    "usage: depthfem run SCENE.json --out RESULT.h5 [--threads N] [--set PATH=VALUE]...\n"
    "                    [--restart EARLIER.h5 [--step N]]\n"
    "       depthfem info RESULT.h5\n";

namespace {

struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// The arguments as given, all text: CLI11 sorts them into commands, options and positionals;
// numbers and overrides are checked after parsing, in depthfem's words.
struct Arguments {
  std::string scene, out, threads, restart, step, results;
  std::vector<std::string> sets;
};

// The lines of kCommandLineUsage for `command` (from the line naming "depthfem COMMAND" to the
// next command), the first one after "usage: "; all of them for "".
std::string usage_of(const std::string& command) {
  std::istringstream lines(kCommandLineUsage);
  std::string usage;
  bool inside = command.empty();
  for (std::string line; std::getline(lines, line);) {
    const size_t at = line.find("depthfem ");
    if (at != std::string::npos && !command.empty())
      inside = line.substr(at + 9, line.find(' ', at + 9) - at - 9) == command;
    if (inside) usage += (usage.empty() ? "usage: " + line.substr(7) : line) + "\n";
  }
  return usage;
}

// CLI11's help with depthfem's usage lines in place of its generated "Usage:" line.
class HelpFormatter : public CLI::Formatter {
 public:
  std::string make_usage(const CLI::App* app, std::string) const override {
    return usage_of(app->get_parent() == nullptr ? "" : app->get_name());
  }
};

// The grammar of the command line: the commands `run` and `info`, their options and positionals
// with a one-line description each (what `--help` lists), writing into `a`.
void declare(CLI::App& app, Arguments& a) {
  app.set_help_flag("-h,--help", "print this help and exit");  // the commands copy it
  app.formatter(std::make_shared<HelpFormatter>());
  app.get_formatter()->column_width(32);
  // An option given twice takes its last value (as the hand-written parser did); --set collects.
  app.option_defaults()->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
  app.require_subcommand(0, 1);  // one command at most: "info" after "run" is an argument of run

  CLI::App* run = app.add_subcommand("run", "run a scene and write its results file");
  run->add_option("SCENE.json", a.scene, "the scene file (JSON; its keys: apps/README.md)")
      ->type_name("")
      ->required();
  run->add_option("--out", a.out, "results file to write (HDF5; .xmf, .xdmf2 beside it)")
      ->type_name("RESULT.h5")
      ->required();
  run->add_option("--threads", a.threads, "threads of all pools together (default: one per core)")
      ->type_name("N");
  run->add_option("--set", a.sets, "override a scene key before checking; VALUE is JSON")
      ->type_name("PATH=VALUE")
      ->allow_extra_args(false)  // one value each: in `--set a=1 b=2`, b=2 is an argument of run
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  CLI::Option* restart = run->add_option("--restart", a.restart,
                                         "start from a written step of an earlier run of the scene")
                             ->type_name("EARLIER.h5");
  run->add_option("--step", a.step, "the step of EARLIER.h5 to start from (default: last)")
      ->type_name("N")
      ->needs(restart);
  run->allow_extras();  // unknown options and surplus arguments: reported below, one line

  CLI::App* info = app.add_subcommand("info", "summarise a results file, also of a live run");
  info->add_option("RESULT.h5", a.results, "the results file")->type_name("")->required();
  info->allow_extras();
  for (CLI::App* command : {run, info}) command->group("Commands");

  // Everything from the first word that is not a command on is left to the check below (after
  // the commands are declared: they would inherit it).
  app.prefix_command();
}

// "--out RESULT.h5", "SCENE.json": `option` as the usage writes it.
std::string usage_name(const CLI::Option& option) {
  return option.get_positional() ? option.get_name()
                                 : option.get_name() + " " + option.get_type_name();
}

// The one line for CLI11's `error` while parsing `command` (the app or its command being parsed):
// a missing value, argument or option in depthfem's words ("--threads needs a value",
// "run needs --out RESULT.h5", "--step needs --restart EARLIER.h5"), CLI11's own line otherwise.
std::string usage_message(const CLI::App& command, const CLI::ParseError& error) {
  const std::string what = error.what();
  const bool required = dynamic_cast<const CLI::RequiredError*>(&error) != nullptr;
  const bool needed = dynamic_cast<const CLI::RequiresError*>(&error) != nullptr;
  for (const CLI::Option* o : command.get_options()) {
    if (what == CLI::ArgumentMismatch::TypedAtLeast(o->get_name(), 1, o->get_type_name()).what())
      return o->get_name() + " needs a value";
    if (required && o->get_required() && o->count() == 0)
      return command.get_name() + " needs " + usage_name(*o);
    if (needed && o->count() > 0) {
      for (const CLI::Option* need : o->get_needs())
        if (need->count() == 0) return o->get_name() + " needs " + usage_name(*need);
    }
  }
  return what;
}

// Throws the usage error for the first of `extras`, the arguments a command did not take.
void refuse_extras(const std::vector<std::string>& extras) {
  if (extras.empty()) return;
  const std::string& e = extras.front();
  if (e.size() > 1 && e[0] == '-') throw UsageError("unknown option " + e);
  throw UsageError("unexpected argument " + e);
}

// Throws the usage error for what `app` left before or instead of a command: an unknown command
// or option.
void refuse_words(const CLI::App& app) {
  const std::vector<std::string> words = app.remaining();
  if (!words.empty() && (words.front().size() <= 1 || words.front()[0] != '-'))
    throw UsageError("unknown command '" + words.front() + "'");
  refuse_extras(words);
}

// Throws the usage error for the first argument of `command` it does not take, or an empty value
// (`--out ""`, which CLI11 takes as given): a file name or number missing.
void refuse_extras_and_empty_values(const CLI::App& command) {
  refuse_extras(command.remaining());
  for (const CLI::Option* o : command.get_options()) {
    for (const std::string& value : o->results()) {
      if (value.empty())
        throw UsageError(o->get_positional() ? command.get_name() + " needs " + o->get_name()
                                             : o->get_name() + " needs a value");
    }
  }
}

// An int of at least `least`, all of `text` ("3x" and "1e2" are refused), the value of `option`.
int int_at_least(const std::string& option, const std::string& text, int least) {
  int value = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (ec != std::errc() || end != text.data() + text.size() || value < least) {
    throw UsageError(option + " expects " + (least == 1 ? "a positive" : "a non-negative") +
                     " integer, got '" + text + "'");
  }
  return value;
}

// Under mpirun every rank reads the same input and meets the same errors before the ranks start
// working together: rank 0 alone reports them. An error once they have started is this rank's
// alone (the others would wait for it forever): it is reported with the rank, and the whole run
// ends (Ranks::abort_run); rank 0's results file keeps the steps completed before.
int report_error(std::ostream& err, const std::string& message, int code) {
  if (Ranks::running()) {
    err << "depthfem: error: rank " << Ranks::launched_rank() << ": " << one_line(message)
        << std::endl;
    Ranks::abort_run(code);
  }
  if (Ranks::launched_rank() == 0) err << "depthfem: error: " << one_line(message) << "\n";
  return code;
}

int run(const CLI::App& command, const Arguments& a, std::ostream& all_out, std::ostream& all_err,
        CommandStage stage) {
  refuse_extras_and_empty_values(command);
  // A distributed run prints from rank 0 only.
  std::ostream silent(nullptr);
  std::ostream& out = Ranks::launched_rank() == 0 ? all_out : silent;
  std::ostream& err = Ranks::launched_rank() == 0 ? all_err : silent;
  RunOptions options;
  options.out = a.out;
  options.restart = a.restart;
  if (command.count("--threads") > 0) {
    options.threads = int_at_least("--threads", a.threads, 1);
  } else if (Ranks::launched() > 1) {  // the cores shared among the ranks of this machine
    options.threads = std::max(1, tbb::info::default_concurrency() / Ranks::launched());
  }
  if (command.count("--step") > 0) options.restart_step = int_at_least("--step", a.step, 0);
  std::vector<Override> overrides;
  for (const std::string& set : a.sets) {
    try {
      overrides.push_back(parse_override(set));
    } catch (const InputError& e) {
      throw UsageError(e.what());
    }
  }
  const ThreadBudget budget(options.threads);  // before anything runs (run_scene sets it too)
  const Scene scene = load_scene(a.scene, overrides);
  if (stage == CommandStage::kCheck) return 0;
  const RunResult r = run_scene(scene, options, out);
  print_timing(r.timers, r.seconds, out);
  if (!r.success) {
    err << "depthfem: error: "
        << one_line(a.scene + ": " + r.message + " (" + std::to_string(r.steps.size()) +
                    " completed steps kept in " + options.out + ")")
        << "\n";
    return 1;
  }
  out << "completed " << r.steps.size() << " steps in " << r.seconds << " s; results in "
      << options.out << "\n";
  return 0;
}

int info(const CLI::App& command, const std::string& path, std::ostream& out, CommandStage stage) {
  refuse_extras_and_empty_values(command);
  if (stage == CommandStage::kCheck) return 0;
  const ResultsSummary s = read_results_summary(path);
  out << path << ": depthfem " << s.version << ", " << s.analysis << " analysis, " << s.threads
      << " threads\n"
      << "  mesh: " << s.num_nodes << " nodes, " << s.num_tets << " tets, " << s.num_tris
      << " boundary triangles, " << s.body_names.size() << " bodies:";
  for (const std::string& b : s.body_names) out << " " << b;
  out << "\n  steps: " << s.num_steps << ", last load/time " << s.last_load
      << ", Newton iterations " << s.total_newton_iterations << ", linear iterations "
      << s.total_linear_iterations << "\n"
      << "  status: " << s.status << (s.message.empty() ? "" : " (" + s.message + ")") << "\n";
  if (!s.timing.empty()) {
    out << "  timing:\n";
    for (const auto& [phase, sec] : s.timing) {
      char seconds[32];
      std::snprintf(seconds, sizeof seconds, "%10.3f", sec);
      out << "    " << phase << std::string(phase.size() < 36 ? 36 - phase.size() : 0, ' ') << " "
          << seconds << " s\n";
    }
  }
  return 0;
}

}  // namespace

std::string one_line(const std::string& text) {
  std::string out;
  for (const char c : text) {
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) {
      char escaped[8];
      std::snprintf(escaped, sizeof escaped, "\\x%02x", static_cast<unsigned char>(c));
      out += escaped;
    } else {
      out += c;
    }
  }
  return out;
}

int command_line(const std::vector<std::string>& args, std::ostream& out, std::ostream& err,
                 CommandStage stage) {
  try {
    CLI::App app("depthfem: implicit FEM for elastic solids in contact", "depthfem");
    Arguments a;
    declare(app, a);
    std::vector<std::string> reversed(args.rbegin(), args.rend());  // CLI11 pops from the back
    try {
      app.parse(reversed);
    } catch (const CLI::CallForHelp&) {
      // `depthfem --help` lists the commands with all their options; `depthfem run --help` one.
      out << (app.get_subcommands().empty() ? app.help("", CLI::AppFormatMode::All) : app.help());
      return 0;
    } catch (const CLI::ParseError& e) {
      refuse_words(app);  // an unknown command or option before the one CLI11 stopped at
      const std::vector<CLI::App*> parsed = app.get_subcommands();
      throw UsageError(usage_message(parsed.empty() ? app : *parsed.front(), e));
    }
    refuse_words(app);
    if (app.got_subcommand("run")) return run(*app.get_subcommand("run"), a, out, err, stage);
    if (app.got_subcommand("info")) return info(*app.get_subcommand("info"), a.results, out, stage);
    throw UsageError("a command is needed: run or info");
  } catch (const UsageError& e) {
    const int code = report_error(err, e.what(), 2);
    if (Ranks::launched_rank() == 0) err << kCommandLineUsage;
    return code;
  } catch (const std::bad_alloc&) {
    return report_error(err, "out of memory", 1);
  } catch (const std::exception& e) {
    return report_error(err, e.what(), 1);
  }
}

}  // namespace depthfem

#include "apps/command_line.hpp"

#include <charconv>
#include <cstdio>
#include <exception>
#include <new>
#include <stdexcept>

#include "apps/run_scene.hpp"
#include "core/error.hpp"
#include "core/results_file.hpp"
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

int run(const std::vector<std::string>& args, std::ostream& out, std::ostream& err,
        CommandStage stage) {
  if (args.empty()) throw UsageError("run needs a scene file");
  RunOptions options;
  std::vector<Override> overrides;
  std::string scene_path;
  for (size_t i = 0; i < args.size(); ++i) {
    const auto value = [&]() -> const std::string& {
      if (i + 1 >= args.size()) throw UsageError(args[i] + " needs a value");
      return args[++i];
    };
    if (args[i] == "--out") {
      options.out = value();
    } else if (args[i] == "--threads") {
      options.threads = int_at_least("--threads", value(), 1);
    } else if (args[i] == "--restart") {
      options.restart = value();
    } else if (args[i] == "--step") {
      options.restart_step = int_at_least("--step", value(), 0);
    } else if (args[i] == "--set") {
      try {
        overrides.push_back(parse_override(value()));
      } catch (const InputError& e) {
        throw UsageError(e.what());
      }
    } else if (args[i].rfind("--", 0) == 0) {
      throw UsageError("unknown option " + args[i]);
    } else if (scene_path.empty()) {
      scene_path = args[i];
    } else {
      throw UsageError("unexpected argument " + args[i]);
    }
  }
  if (scene_path.empty()) throw UsageError("run needs a scene file");
  if (options.out.empty()) throw UsageError("run needs --out RESULT.h5");
  if (options.restart_step >= 0 && options.restart.empty())
    throw UsageError("--step needs --restart EARLIER.h5");
  const ThreadBudget budget(options.threads);  // before anything runs (run_scene sets it too)
  const Scene scene = load_scene(scene_path, overrides);
  if (stage == CommandStage::kCheck) return 0;
  const RunResult r = run_scene(scene, options, out);
  print_timing(r.timers, r.seconds, out);
  if (!r.success) {
    err << "depthfem: error: "
        << one_line(scene_path + ": " + r.message + " (" + std::to_string(r.steps.size()) +
                    " completed steps kept in " + options.out + ")")
        << "\n";
    return 1;
  }
  out << "completed " << r.steps.size() << " steps in " << r.seconds << " s; results in "
      << options.out << "\n";
  return 0;
}

int info(const std::vector<std::string>& args, std::ostream& out, CommandStage stage) {
  if (args.size() != 1) throw UsageError("info needs exactly one results file");
  if (stage == CommandStage::kCheck) return 0;
  const ResultsSummary s = read_results_summary(args[0]);
  out << args[0] << ": depthfem " << s.version << ", " << s.analysis << " analysis, " << s.threads
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
    if (args.empty() || args[0] == "--help" || args[0] == "-h") {
      out << kCommandLineUsage;
      return args.empty() ? 2 : 0;
    }
    const std::vector<std::string> rest(args.begin() + 1, args.end());
    if (args[0] == "run") return run(rest, out, err, stage);
    if (args[0] == "info") return info(rest, out, stage);
    throw UsageError("unknown command '" + args[0] + "'");
  } catch (const UsageError& e) {
    err << "depthfem: error: " << one_line(e.what()) << "\n" << kCommandLineUsage;
    return 2;
  } catch (const std::bad_alloc&) {
    err << "depthfem: error: out of memory\n";
    return 1;
  } catch (const std::exception& e) {
    err << "depthfem: error: " << one_line(e.what()) << "\n";
    return 1;
  }
}

}  // namespace depthfem

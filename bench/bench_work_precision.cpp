// Work-precision study on falling_bars (or another scene): every time integrator at a ladder of
// step sizes (or tolerances for ARKODE's explicit and diagonally implicit methods and CVODE's BDF);
// error = largest distance, over the output times (every 10 ms) and the tip nodes of the three
// bars (with --all-nodes: every node), from a reference run of ARKODE's 8th-order method at a
// relative tolerance of 1e-11 (--reference-rtol; with --bdf-reference: CVODE's BDF up to order 5 at
// 1e-7, for scenes with contact, where an explicit stage can invert an element and ERKStep cannot
// retry); work = wall time of the run.
//
//   build/bench/bench_work_precision [--out bench/results/work_precision.csv] [--duration 2.0]
//                                    [--scene apps/scenes/falling_bars.json] [--all-nodes]
//                                    [--only NAME,...] [--settings [M-]N] [--bdf-reference]
//                                    [--reference-rtol R] [--set PATH=VALUE ...]
//
// --set overrides scene keys as in `depthfem run` (e.g. stiffer bars for a second study); --only
// runs the integrators whose row names start with one of the given names (the references
// always); --settings N runs only the first N rungs of each integrator's ladder (its largest
// steps or loosest tolerances, the cheap end) for large meshes and long runs, --settings M-N
// rungs M to N (counted from 1).
// Plot with bench/plot_work_precision.py. A second, independent reference (ARKODE order 5 at
// ten times the reference's tolerance, 1e-10; with --bdf-reference ARKStep's DIRK order 4 at
// 1e-6) is run too: its distance from the
// first is printed and written as the row "reference_check", a bound on the reference error.
#include <cmath>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "apps/run_scene.hpp"
#include "core/error.hpp"
#include "integrators/solvers/symplectic_euler.hpp"

using namespace depthfem;

namespace {

constexpr double kSampleInterval = 0.01;  // [s]

struct Trajectory {
  std::vector<Points> tips;  // tip positions at t = k * kSampleInterval, k = 1, 2, ...
  double seconds = 0;
  long steps = 0;   // time steps (ARKODE, CVODE: internal steps)
  long newton = 0;  // Newton iterations (implicit schemes; DIRK: over all stages)
  long linear_solves = 0, factorizations = 0;
  std::string failure;
};

bool all_nodes = false;  // the error over every node, not the bars' tips

Trajectory run_case(const std::string& scene_path, std::vector<Override> o,
                    const std::vector<std::string>& overrides) {
  for (const std::string& s : overrides) o.push_back(parse_override(s));
  const Scene scene = load_scene(scene_path, o);
  std::vector<Index> tip;
  for (Index i = 0; i < scene.mesh.num_nodes(); ++i)
    if (all_nodes || std::abs(scene.mesh.X(i, 0) - 1.0) < 1e-9) tip.push_back(i);
  Trajectory t;
  const Integrator integrator = scene.dynamic_options.integrator;
  const bool explicit_rk = integrator == Integrator::kArkode;
  RunOptions options;
  options.threads = 1;
  options.observer = [&](const StepRecord& s, const Points& x) {
    t.steps += s.time_steps;
    if (!explicit_rk) t.newton += s.newton_iterations;
    t.linear_solves += s.linear_solves;
    t.factorizations += s.factorizations;
    const double k = s.load / kSampleInterval;
    if (std::abs(k - std::round(k)) > 1e-6) return;
    Points p(static_cast<Index>(tip.size()), 3);
    for (size_t j = 0; j < tip.size(); ++j) p.row(static_cast<Index>(j)) = x.row(tip[j]);
    t.tips.push_back(std::move(p));
  };
  std::ostringstream log;
  try {
    const RunResult r = run_scene(scene, options, log);
    t.seconds = r.seconds;
    if (!r.success) t.failure = r.message;
  } catch (const InputError& e) {  // e.g. an explicit step above the stable limit
    t.failure = e.what();
  }
  return t;
}

double max_distance(const Trajectory& a, const Trajectory& ref) {
  if (a.tips.size() != ref.tips.size()) return std::numeric_limits<double>::infinity();
  double e = 0;
  for (size_t k = 0; k < a.tips.size(); ++k)
    e = std::max(e, (a.tips[k] - ref.tips[k]).rowwise().norm().maxCoeff());
  return e;
}

// Round-trip exact, so that steps which divide the sample interval still do once parsed back.
std::string number(double v) {
  std::ostringstream s;
  s << std::setprecision(17) << v;
  return s.str();
}

}  // namespace

int main(int argc, char** argv) {
  std::string out = "bench/results/work_precision.csv";
  double duration = 2.0;
  std::string scene = std::string(DEPTHFEM_SOURCE_DIR) + "/apps/scenes/falling_bars.json";
  std::vector<std::string> only;
  bool bdf_reference = false;
  long first_rung = 1, last_rung = 0;  // rungs run per integrator (from 1; last 0: all)
  double reference_rtol = 1e-11;       // of ARKODE's order 8 (the check: order 5 at ten times it)
  std::vector<Override> scene_overrides;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--out" && i + 1 < argc) {
      out = argv[++i];
    } else if (a == "--scene" && i + 1 < argc) {
      scene = argv[++i];
    } else if (a == "--all-nodes") {
      all_nodes = true;
    } else if (a == "--bdf-reference") {
      bdf_reference = true;
    } else if (a == "--only" && i + 1 < argc) {
      std::stringstream list(argv[++i]);
      for (std::string name; std::getline(list, name, ',');) only.push_back(name);
    } else if (a == "--settings" && i + 1 < argc) {
      const std::string range = argv[++i];
      const size_t dash = range.find('-');
      if (dash != std::string::npos) first_rung = std::stol(range.substr(0, dash));
      last_rung = std::stol(dash == std::string::npos ? range : range.substr(dash + 1));
      if (first_rung < 1 || last_rung < first_rung) {
        std::cerr << "bench_work_precision: --settings wants N or M-N with 1 <= M <= N, not "
                  << range << "\n";
        return 2;
      }
    } else if (a == "--reference-rtol" && i + 1 < argc) {
      reference_rtol = std::stod(argv[++i]);
    } else if (a == "--duration" && i + 1 < argc) {
      duration = std::stod(argv[++i]);
    } else if (a == "--set" && i + 1 < argc) {
      scene_overrides.push_back(parse_override(argv[++i]));
    } else {
      std::cerr << "usage: bench_work_precision [--out FILE.csv] [--duration SECONDS] [--scene "
                   "SCENE.json] [--all-nodes] [--only NAME,...] [--settings [M-]N] "
                   "[--bdf-reference] [--reference-rtol R] [--set PATH=VALUE ...]\n";
      return 2;
    }
  }
  const std::string span = "dynamic.duration=" + number(duration);
  const auto arkode = [&](int order, double rtol) {
    return std::vector<std::string>{span, "dynamic.time_step=0.01", "dynamic.integrator=arkode",
                                    "dynamic.arkode={\"order\": " + std::to_string(order) +
                                        ", \"relative_tolerance\": " + number(rtol) +
                                        ", \"absolute_tolerance\": " + number(rtol * 1e-2) + "}"};
  };
  const auto stepped = [&](const char* integrator, double h) {
    return std::vector<std::string>{span, std::string("dynamic.integrator=") + integrator,
                                    "dynamic.time_step=" + number(h)};
  };
  // ARKStep's diagonally implicit table of `order`, error-controlled at rtol (atol rtol / 100).
  const auto dirk = [&](int order, double rtol) {
    std::vector<std::string> o = arkode(order, rtol);
    o[2] = "dynamic.integrator=arkode_dirk";
    return o;
  };
  // CVODE's BDF up to order `q`, error-controlled at rtol (atol rtol / 100).
  const auto bdf = [&](int q, double rtol) {
    return std::vector<std::string>{span, "dynamic.time_step=0.01", "dynamic.integrator=cvode_bdf",
                                    "dynamic.cvode={\"max_order\": " + std::to_string(q) +
                                        ", \"relative_tolerance\": " + number(rtol) +
                                        ", \"absolute_tolerance\": " + number(rtol * 1e-2) + "}"};
  };
  const auto wanted = [&](const std::string& name) {
    if (only.empty()) return true;
    for (const std::string& o : only)
      if (name.rfind(o, 0) == 0) return true;
    return false;
  };

  if (bdf_reference)
    std::cout << "reference: CVODE BDF up to order 5, relative tolerance 1e-7 ..." << std::endl;
  else
    std::cout << "reference: ARKODE order 8, relative tolerance " << reference_rtol << " ..."
              << std::endl;
  const Trajectory ref =
      run_case(scene, scene_overrides, bdf_reference ? bdf(5, 1e-7) : arkode(8, reference_rtol));
  if (!ref.failure.empty()) {
    std::cerr << "bench_work_precision: the reference run failed: " << ref.failure << "\n";
    return 1;
  }
  std::ofstream csv(out);
  if (!csv) {
    std::cerr << "bench_work_precision: cannot write " << out << "\n";
    return 1;
  }
  csv << "integrator,setting,value,steps,newton_iterations,linear_solves,factorizations,wall_s,"
         "max_tip_error_m,status\n";
  // One row: the integrator `name` run with `overrides` (skipped unless wanted and within rungs
  // first_rung to last_rung of its ladder).
  std::map<std::string, long> rungs;
  const auto row = [&](const std::string& name, const std::string& setting, double value,
                       const std::vector<std::string>& overrides) {
    if (name != "reference_check") {
      if (!wanted(name)) return;
      const long rung = ++rungs[name];
      if (rung < first_rung || (last_rung > 0 && rung > last_rung)) return;
    }
    const Trajectory t = run_case(scene, scene_overrides, overrides);
    const double err = max_distance(t, ref);
    csv << name << "," << setting << "," << value << "," << t.steps << "," << t.newton << ","
        << t.linear_solves << "," << t.factorizations << "," << t.seconds << "," << err << ","
        << (t.failure.empty() ? "ok" : "failed") << "\n";
    csv.flush();
    std::printf("%-18s %-9s %-9g steps %7ld  newton %6ld  %8.3f s  error %.3e m %s\n", name.c_str(),
                setting.c_str(), value, t.steps, t.newton, t.seconds, err, t.failure.c_str());
  };
  if (bdf_reference) {
    row("reference_check", "rtol", 1e-6, dirk(4, 1e-6));
  } else {
    row("reference_check", "rtol", 10 * reference_rtol, arkode(5, 10 * reference_rtol));
  }
  for (double h : {0.01, 0.005, 0.0025, 0.00125, 0.000625}) {
    row("implicit_euler", "h", h, stepped("implicit_euler", h));
    row("newmark", "h", h, stepped("newmark", h));
    std::vector<std::string> alpha = stepped("generalized_alpha", h);
    alpha.push_back(R"(dynamic.generalized_alpha={"rho_inf": 0.8})");
    row("generalized_alpha", "h", h, alpha);
  }
  for (int order : {2, 3, 4})
    for (double rtol : {1e-2, 1e-3, 1e-4, 1e-5, 1e-6})
      if (order > 2 || rtol >= 1e-4)  // second order: its order-1 embedding asks ~10x the steps
        row("arkode_dirk" + std::to_string(order), "rtol", rtol, dirk(order, rtol));
  for (int q : {2, 5})
    for (double rtol : {1e-2, 1e-3, 1e-4, 1e-5, 1e-6})
      row("cvode_bdf" + std::to_string(q), "rtol", rtol, bdf(q, rtol));
  // Symplectic Euler from just below its stable step (rounded to divide the sample interval).
  const Scene base = load_scene(scene, scene_overrides);
  const double limit =
      critical_time_step(base.mesh.X, base.mesh.tets, base.tet_density, base.groups);
  const double h0 = kSampleInterval / std::ceil(kSampleInterval / (0.95 * limit));
  std::printf("symplectic Euler stable limit %.3g s, largest step run %.3g s\n", limit, h0);
  for (double h = h0; h > h0 / 20; h /= 2)
    row("symplectic_euler", "h", h, stepped("symplectic_euler", h));
  for (int order : {2, 4, 8})
    for (double rtol : {1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8})
      if (order > 2 || rtol >= 1e-6)  // second order needs ~3x the steps per decade beyond that
        row("arkode_order" + std::to_string(order), "rtol", rtol, arkode(order, rtol));
  std::cout << "wrote " << out << "\n";
  return 0;
}

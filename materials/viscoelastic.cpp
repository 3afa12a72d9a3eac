#include "materials/viscoelastic.hpp"

#include <numeric>
#include <sstream>
#include <stdexcept>

namespace depthfem {

namespace {
// A number as a short decimal (6 significant digits): -1, 0.05, 1e-09.
std::string text(double v) {
  std::ostringstream out;
  out << v;
  return out.str();
}
}  // namespace

double PronySeries::equilibrium_weight() const {
  return 1.0 - std::accumulate(weights.begin(), weights.end(), 0.0);
}

std::optional<PronySeries::Problem> PronySeries::problem() const {
  if (weights.size() != times.size()) {
    return Problem{"weights", std::to_string(weights.size()) + " weights for " +
                                  std::to_string(times.size()) +
                                  " relaxation times; give one weight per time"};
  }
  for (size_t i = 0; i < weights.size(); ++i) {
    const std::string at = "[" + std::to_string(i) + "]";
    if (!(weights[i] > 0) || !std::isfinite(weights[i]))
      return Problem{"weights" + at, "is " + text(weights[i]) + "; each weight must be > 0"};
    if (!(times[i] > 0) || !std::isfinite(times[i])) {
      return Problem{"relaxation_times" + at,
                     "is " + text(times[i]) + " s; each relaxation time must be > 0 and finite"};
    }
  }
  if (!(equilibrium_weight() > 0)) {
    return Problem{"weights", "they sum to " + text(1 - equilibrium_weight()) +
                                  "; they must sum to less than 1 (the equilibrium modulus must "
                                  "stay positive)"};
  }
  return std::nullopt;
}

void PronySeries::validate() const {
  if (const std::optional<Problem> p = problem())
    throw std::invalid_argument(p->key + ": " + p->why);
}

PronyStep prony_step(const PronySeries& prony, double dt) {
  PronyStep step;
  step.scale = prony.equilibrium_weight();
  for (size_t i = 0; i < prony.weights.size(); ++i) {
    const double x = dt / prony.times[i];
    // (1 - e^-x) / x, with expm1 accurate for small x and the limit 1 at x = 0.
    const double ratio = x > 0 ? -std::expm1(-x) / x : 1.0;
    step.decay.push_back(std::exp(-x));
    step.gamma.push_back(prony.weights[i] * ratio);
    step.scale += step.gamma.back();
  }
  return step;
}

}  // namespace depthfem

#include "materials/viscoelastic.hpp"

#include <numeric>
#include <stdexcept>

namespace depthfem {

double PronySeries::equilibrium_weight() const {
  return 1.0 - std::accumulate(weights.begin(), weights.end(), 0.0);
}

void PronySeries::validate() const {
  const auto fail = [](const std::string& what) { throw std::invalid_argument(what); };
  if (weights.size() != times.size()) {
    fail(std::to_string(weights.size()) + " weights for " + std::to_string(times.size()) +
         " relaxation times; give one weight per time");
  }
  for (size_t i = 0; i < weights.size(); ++i) {
    const std::string at = "[" + std::to_string(i) + "]";
    if (!(weights[i] > 0) || !std::isfinite(weights[i]))
      fail("weights" + at + " is " + std::to_string(weights[i]) + "; each weight must be > 0");
    if (!(times[i] > 0) || !std::isfinite(times[i])) {
      fail("relaxation_times" + at + " is " + std::to_string(times[i]) +
           " s; each relaxation time must be > 0 and finite");
    }
  }
  if (!(equilibrium_weight() > 0)) {
    fail("the weights sum to " + std::to_string(1 - equilibrium_weight()) +
         "; they must sum to less than 1 (the equilibrium modulus must stay positive)");
  }
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

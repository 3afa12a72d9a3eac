#include "integrators/solvers/dynamics.hpp"

#include <algorithm>
#include <cmath>

#include "core/decimal.hpp"

namespace depthfem {

Index time_step_count(const DynamicOptions& options) {
  return static_cast<Index>(std::ceil(options.duration / options.time_step - 1e-9));
}

AlphaParameters chung_hulbert(double rho_inf) {
  const double alpha_m = (2 * rho_inf - 1) / (rho_inf + 1), alpha_f = rho_inf / (rho_inf + 1);
  const double shift = 1 - alpha_m + alpha_f;
  return {alpha_m, alpha_f, shift * shift / 4, 0.5 - alpha_m + alpha_f};
}

double step_end_time(const DynamicOptions& options, Index n) {
  if (n + 1 >= time_step_count(options)) return options.duration;
  return std::min(options.duration, round_to_decimal((n + 1) * options.time_step));
}

Index first_step_after(const DynamicOptions& options, double time) {
  const double after = time + 1e-9 * options.time_step;
  Index n = std::max<Index>(0, static_cast<Index>(std::floor(time / options.time_step)) - 1);
  while (n < time_step_count(options) && step_end_time(options, n) <= after) ++n;
  return n;
}

}  // namespace depthfem

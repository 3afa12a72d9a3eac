#include "integrators/solvers/dynamics.hpp"

#include <algorithm>
#include <cmath>

#include "core/decimal.hpp"

namespace depthfem {

Index time_step_count(const DynamicOptions& options) {
  return static_cast<Index>(std::ceil(options.duration / options.time_step - 1e-9));
}

double step_end_time(const DynamicOptions& options, Index n) {
  if (n + 1 >= time_step_count(options)) return options.duration;
  return std::min(options.duration, round_to_decimal((n + 1) * options.time_step));
}

}  // namespace depthfem

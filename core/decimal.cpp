#include "core/decimal.hpp"

#include <cstdio>
#include <cstdlib>

namespace depthfem {

double round_to_decimal(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.11e", value);  // 12 significant digits
  return std::strtod(text, nullptr);
}

std::string shown(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.4g", value);
  return text;
}

}  // namespace depthfem

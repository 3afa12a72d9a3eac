#include "core/error.hpp"

namespace depthfem {

std::string located(const std::string& file, long line, const std::string& what) {
  if (line > 0) return file + ":" + std::to_string(line) + ": " + what;
  return file + ": " + what;
}

}  // namespace depthfem

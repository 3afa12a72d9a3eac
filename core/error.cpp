#include "core/error.hpp"

namespace depthfem {

std::string located(const std::string& file, long line, const std::string& what) {
  std::string out = file;
  if (line > 0) out.append(":").append(std::to_string(line));
  out.append(": ").append(what);
  return out;
}

}  // namespace depthfem

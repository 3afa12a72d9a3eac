#include "core/element_coloring.hpp"

#include <bitset>
#include <stdexcept>
#include <string>

namespace depthfem {

ElementColoring color_elements(const Eigen::Ref<const Eigen::Matrix<Index, Eigen::Dynamic, Eigen::Dynamic>>& elements,
                               Index num_nodes) {
  constexpr int kMaxColors = 256;
  std::vector<std::bitset<kMaxColors>> used(static_cast<size_t>(num_nodes));
  const Index n = static_cast<Index>(elements.rows());
  std::vector<int> color(static_cast<size_t>(n));
  int num_colors = 0;
  for (Index e = 0; e < n; ++e) {
    std::bitset<kMaxColors> taken;
    for (Eigen::Index k = 0; k < elements.cols(); ++k) taken |= used[elements(e, k)];
    int c = 0;
    while (c < kMaxColors && taken[c]) ++c;
    if (c == kMaxColors) {
      throw std::runtime_error("element coloring: element " + std::to_string(e) + " needs more than " +
                               std::to_string(kMaxColors) + " colors (a node in too many elements)");
    }
    color[e] = c;
    num_colors = std::max(num_colors, c + 1);
    for (Eigen::Index k = 0; k < elements.cols(); ++k) used[elements(e, k)].set(c);
  }
  ElementColoring out;
  out.begin.assign(static_cast<size_t>(num_colors) + 1, 0);
  for (Index e = 0; e < n; ++e) ++out.begin[color[e] + 1];
  for (int c = 0; c < num_colors; ++c) out.begin[c + 1] += out.begin[c];
  out.order.resize(static_cast<size_t>(n));
  std::vector<Index> fill(out.begin.begin(), out.begin.end() - 1);
  for (Index e = 0; e < n; ++e) out.order[fill[color[e]]++] = e;
  return out;
}

}  // namespace depthfem

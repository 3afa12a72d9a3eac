#include "core/element_partition.hpp"

#include <algorithm>
#include <bit>
#include <cstdint>
#include <numeric>

namespace depthfem {

namespace {

// Spreads the low 10 bits of v so that they occupy every third bit.
std::uint32_t spread_bits(std::uint32_t v) {
  v &= 0x3ff;
  v = (v | (v << 16)) & 0x030000ff;
  v = (v | (v << 8)) & 0x0300f00f;
  v = (v | (v << 4)) & 0x030c30c3;
  v = (v | (v << 2)) & 0x09249249;
  return v;
}

// 30-bit Morton code of each point inside the bounding box of all points.
std::vector<std::uint32_t> morton_codes(const Points& p) {
  std::vector<std::uint32_t> code(static_cast<size_t>(p.rows()));
  if (p.rows() == 0) return code;
  const Eigen::RowVector3d lo = p.colwise().minCoeff(), hi = p.colwise().maxCoeff();
  const Eigen::RowVector3d scale = (1023.0 / (hi - lo).array().max(1e-300)).matrix();
  for (Index i = 0; i < p.rows(); ++i) {
    std::uint32_t c = 0;
    for (int k = 0; k < 3; ++k) {
      const auto q =
          static_cast<std::uint32_t>(std::clamp((p(i, k) - lo(k)) * scale(k), 0.0, 1023.0));
      c |= spread_bits(q) << k;
    }
    code[i] = c;
  }
  return code;
}

}  // namespace

ElementPartition partition_elements(
    const Eigen::Ref<const Eigen::Matrix<Index, Eigen::Dynamic, Eigen::Dynamic>>& elements,
    Index num_nodes, const Points& centroids, Index chunk_size) {
  const Index n = static_cast<Index>(elements.rows());
  const std::vector<std::uint32_t> code = morton_codes(centroids);
  std::vector<Index> sorted(static_cast<size_t>(n));
  std::iota(sorted.begin(), sorted.end(), 0);
  std::stable_sort(sorted.begin(), sorted.end(),
                   [&](Index a, Index b) { return code[a] < code[b]; });

  // Greedy chunk coloring: a chunk takes the smallest color not yet used at any of its nodes. The
  // colors used at a node are a bit set of `words` 64-bit words per node, widened when needed.
  const Index num_chunks = (n + chunk_size - 1) / chunk_size;
  size_t words = 1;
  std::vector<std::uint64_t> used(static_cast<size_t>(num_nodes) * words, 0);
  std::vector<std::uint64_t> taken(words);
  std::vector<Index> chunk_color(static_cast<size_t>(num_chunks));
  Index num_colors = 0;
  for (Index k = 0; k < num_chunks; ++k) {
    const Index begin = k * chunk_size, end = std::min(n, begin + chunk_size);
    std::fill(taken.begin(), taken.end(), 0);
    for (Index p = begin; p < end; ++p)
      for (Eigen::Index a = 0; a < elements.cols(); ++a)
        for (size_t w = 0; w < words; ++w) taken[w] |= used[elements(sorted[p], a) * words + w];
    size_t w = 0;
    while (w < words && taken[w] == ~std::uint64_t{0}) ++w;
    if (w == words) {  // every color in use at this chunk's nodes: one more word per node
      std::vector<std::uint64_t> wider(static_cast<size_t>(num_nodes) * (words + 1), 0);
      for (Index v = 0; v < num_nodes; ++v)
        std::copy_n(used.begin() + v * words, words, wider.begin() + v * (words + 1));
      used.swap(wider);
      taken.push_back(0);
      ++words;
    }
    const Index color = static_cast<Index>(64 * w + std::countr_one(taken[w]));
    chunk_color[k] = color;
    num_colors = std::max(num_colors, color + 1);
    const std::uint64_t bit = std::uint64_t{1} << (color % 64);
    for (Index p = begin; p < end; ++p)
      for (Eigen::Index a = 0; a < elements.cols(); ++a)
        used[elements(sorted[p], a) * words + color / 64] |= bit;
  }

  // Lay the chunks out color by color, keeping their order within a color.
  ElementPartition out;
  out.color_begin.assign(static_cast<size_t>(num_colors) + 1, 0);
  for (Index k = 0; k < num_chunks; ++k) ++out.color_begin[chunk_color[k] + 1];
  for (Index c = 0; c < num_colors; ++c) out.color_begin[c + 1] += out.color_begin[c];
  std::vector<Index> slot(out.color_begin.begin(), out.color_begin.end() - 1), chunk_at(num_chunks);
  for (Index k = 0; k < num_chunks; ++k) chunk_at[slot[chunk_color[k]]++] = k;
  out.chunk_begin.push_back(0);
  out.order.reserve(static_cast<size_t>(n));
  for (Index k : chunk_at) {
    const Index begin = k * chunk_size, end = std::min(n, begin + chunk_size);
    out.order.insert(out.order.end(), sorted.begin() + begin, sorted.begin() + end);
    out.chunk_begin.push_back(static_cast<Index>(out.order.size()));
  }
  return out;
}

}  // namespace depthfem

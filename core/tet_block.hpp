#pragma once
/// Structure-of-arrays element data for one group of tets, ordered by color for kernels.

#include <span>
#include <vector>

#include "core/types.hpp"

namespace depthfem {

/// Precomputed per-tet data a kernel streams through. Column-major Eigen storage makes every
/// column one contiguous array: four node-index arrays, nine Dm^-1 arrays, one volume array.
/// Rows follow an ElementPartition: chunk k spans rows [chunk_begin[k], chunk_begin[k+1]) and
/// color c spans chunks [color_begin[c], color_begin[c+1]).
struct TetBlock {
  TetIndices nodes;                                 ///< #e x 4 node indices
  Eigen::Matrix<double, Eigen::Dynamic, 9> Dm_inv;  ///< #e x 9, column-major entries of Dm^-1 [1/m]
  VectorX volume;                                   ///< #e rest volumes [m^3]
  Points fiber;                                     ///< #e x 3 unit fiber directions, or 0 rows
  IndexVector tet;                                  ///< #e global tet id (for messages)
  std::vector<Index> chunk_begin;                   ///< #chunks + 1 row offsets
  std::vector<Index> color_begin;                   ///< #colors + 1 chunk offsets

  Index size() const { return static_cast<Index>(nodes.rows()); }
  Index num_colors() const { return static_cast<Index>(color_begin.size()) - 1; }

  /// Dm^-1 of row e as a 3x3 matrix.
  Mat3 dm_inv(Index e) const {
    Mat3 D;
    for (int k = 0; k < 9; ++k) D(k) = Dm_inv(e, k);
    return D;
  }
};

/// Builds the block of the tets listed in `which` (global ids into `tets`), computing
/// Dm = [X1-X0, X2-X0, X3-X0]^-1 and volumes from the reference positions X and partitioning the
/// elements into colored chunks. `fibers` is empty or has one direction per entry of `which`
/// (normalised here). Throws InputError naming the tet if it is degenerate or inverted in X, or a
/// fiber is zero.
TetBlock make_tet_block(const Points& X, const TetIndices& tets, std::span<const Index> which,
                        const Points& fibers = Points());

}  // namespace depthfem

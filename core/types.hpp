#pragma once
/// Basic value types shared by every depthfem module.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>

namespace depthfem {

/// Node, element and degree-of-freedom index. 32 bits keep index arrays small and fast.
using Index = std::int32_t;

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;

/// #points x 3 coordinates [m], column-major: each component is one contiguous array (SoA).
using Points = Eigen::Matrix<double, Eigen::Dynamic, 3>;
/// #tets x 4 node indices, column-major: one contiguous index array per corner.
using TetIndices = Eigen::Matrix<Index, Eigen::Dynamic, 4>;
/// #triangles x 3 node indices, column-major.
using TriIndices = Eigen::Matrix<Index, Eigen::Dynamic, 3>;
/// Dense vector of doubles (unknowns, gradients, per-node or per-element scalars).
using VectorX = Eigen::VectorXd;
/// Dense vector of indices.
using IndexVector = Eigen::Matrix<Index, Eigen::Dynamic, 1>;

/// Interleaved dof vector (3 * node + component) viewed as #nodes x 3 positions, copied to SoA.
inline Points as_points(const VectorX& v) {
  return Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>>(
      v.data(), v.size() / 3, 3);
}
/// #nodes x 3 positions as an interleaved dof vector (3 * node + component).
inline VectorX as_dofs(const Points& x) {
  VectorX v(3 * x.rows());
  Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>>(v.data(), x.rows(), 3) = x;
  return v;
}

}  // namespace depthfem

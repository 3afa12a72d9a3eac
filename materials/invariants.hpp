#pragma once
/// Strain invariants that every depthfem material is written in, and their F-derivatives.
///
/// With C = F^T F:  I1 = tr C,  I2 = (I1^2 - tr C^2) / 2,  J = det F (so I3 = det C = J^2),
/// I4 = f^T C f = |F f|^2 (squared fiber stretch along the unit reference direction f).
/// Using J instead of I3 keeps ln I3 = 2 ln J exact and the Hessian of J free of F^-1.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cmath>

namespace depthfem {

using Vec9 = Eigen::Matrix<double, 9, 1>;
/// 9x9 matrices act on vec(F), column-major: vec index of F(i, j) is i + 3 j.
using Mat9 = Eigen::Matrix<double, 9, 9>;

/// The four invariants of F (and a fiber direction), as doubles or as Lanes (materials/lanes.hpp)
/// holding those of a batch of elements.
template <class S = double>
struct Invariants {
  S I1 = 3, I2 = 3, J = 1, I4 = 1;
};

/// psi and its derivatives with respect to (I1, I2, J, I4), indexed by InvariantSlot; `d2` is
/// symmetric. Entries a material does not depend on stay zero.
template <class S = double>
struct InvariantDerivatives {
  S psi = 0;
  std::array<S, 4> d{};
  std::array<std::array<S, 4>, 4> d2{};
};

/// Slots of (I1, I2, J, I4) in InvariantDerivatives.
enum InvariantSlot : int { kI1 = 0, kI2 = 1, kJ = 2, kI4 = 3 };

/// Adds the volumetric barrier a (J^2 - 1) - 2 k ln J (= a (I3 - 1) - k ln I3) and its J
/// derivatives to e (up to order kOrder). It tends to +infinity as J -> 0; with k chosen so that
/// psi_1 + 2 psi_2 + psi_3 = 0 at F = I it makes an invariant model stress-free.
template <int kOrder, class S>
void add_volumetric_barrier(InvariantDerivatives<S>& e, const S& J, double a, double k) {
  using std::log;
  e.psi += a * (J * J - 1) - 2.0 * k * log(J);
  if constexpr (kOrder >= 1) e.d[kJ] += 2.0 * a * J - 2.0 * k / J;
  if constexpr (kOrder >= 2) e.d2[kJ][kJ] += 2.0 * a + 2.0 * k / (J * J);
}

/// a b + c with one rounding where the target has fused multiply-add, two elsewhere; the same
/// for doubles and for lanes (lanes.hpp), which the compiler would otherwise fuse differently.
inline double multiply_add(double a, double b, double c) {
#ifdef __FMA__
  return std::fma(a, b, c);
#else
  return a * b + c;
#endif
}

/// det of a 3x3 matrix given as its 9 column-major entries (doubles or lanes), expanded along the
/// first row with explicit multiply-adds. The scalar and the batched stress both take J from
/// here and round it alike: where J is small the expansion cancels strongly, and rounding the
/// same terms in another order would change J far more than the last bit.
template <class S>
S determinant(const S* m) {
  const S c0 = multiply_add(m[4], m[8], -(m[7] * m[5]));
  const S c1 = multiply_add(m[1], m[8], -(m[7] * m[2]));
  const S c2 = multiply_add(m[1], m[5], -(m[4] * m[2]));
  return multiply_add(m[6], c2, multiply_add(-m[3], c1, m[0] * c0));
}

/// Cofactor matrix dJ/dF = J F^-T, computed from cross products of the columns of F.
inline Eigen::Matrix3d cofactor(const Eigen::Matrix3d& F) {
  Eigen::Matrix3d c;
  c.col(0) = F.col(1).cross(F.col(2));
  c.col(1) = F.col(2).cross(F.col(0));
  c.col(2) = F.col(0).cross(F.col(1));
  return c;
}

/// I1, I2, J and (with a unit fiber direction `f`) I4 of F.
inline Invariants<> invariants(const Eigen::Matrix3d& F, const Eigen::Vector3d& f) {
  const Eigen::Matrix3d C = F.transpose() * F;
  Invariants<> inv;
  inv.I1 = C.trace();
  inv.I2 = 0.5 * (inv.I1 * inv.I1 - C.squaredNorm());  // tr C^2 = |C|_F^2 as C is symmetric
  inv.J = determinant(F.data());
  inv.I4 = (F * f).squaredNorm();
  return inv;
}

}  // namespace depthfem

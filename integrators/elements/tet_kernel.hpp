#pragma once
/// The per-tet hyperelastic kernel: energy, gradient and 12x12 Hessian of one linear tet. It is the
/// reference for the batched kernel (batched_tet_kernel.hpp) and runs the rows a batch leaves over.
///
/// With Ds = [x1-x0, x2-x0, x3-x0] and D = Dm^-1, F = Ds D, so dF_ij / dDs_ka = delta_ik D_aj.
/// Energy V psi(F); gradient on nodes 1..3 is V P D^T (column a), node 0 takes minus their sum.
/// Hessian on nodes 1..3: K = V A dP/dF A^T with A = D (x) I3 (Kronecker, on column-major vec);
/// rows and columns of node 0 are minus the sums over the other nodes (translation invariance).

#include "core/types.hpp"
#include "materials/hyperelastic.hpp"

namespace depthfem {

/// 12x12 matrices over the 4 nodes of a tet, node-major: row 3 a + c is node a, component c.
using Mat12 = Eigen::Matrix<double, 12, 12>;

/// What one tet contributes: energy [J], gradient [N] (column a = node a), Hessian [N/m].
struct TetLocal {
  double energy = 0;
  Eigen::Matrix<double, 3, 4> gradient;
  Mat12 hessian;
};

/// F = Ds D for column-major 3x3 matrices given as 9 values (doubles or lanes), with explicit
/// multiply-adds. The scalar and the batched kernel share it so that they round F alike:
/// J = det F is ill-conditioned near inversion, and follows any difference in F's rounding.
template <class S>
void deformation_gradient(const S* Ds, const S* D, S* F) {
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i)
      F[3 * j + i] = multiply_add(Ds[6 + i], D[3 * j + 2],
                                  multiply_add(Ds[3 + i], D[3 * j + 1], Ds[i] * D[3 * j]));
}

/// Evaluates one tet: energy (kOrder 0), + gradient (1), + Hessian (2). `Ds` holds the current
/// edge vectors, `D` = Dm^-1, `volume` the rest volume, `f` the unit fiber direction.
/// For det F <= 0 the energy is +infinity and gradient / Hessian are not meaningful.
template <int kOrder, Material M>
inline void tet_local(const M& m, const Mat3& Ds, const Mat3& D, double volume, const Vec3& f,
                      TetLocal& out) {
  Mat3 F;
  deformation_gradient(Ds.data(), D.data(), F.data());
  const StressState s = evaluate_stress<kOrder>(m, F, f);
  out.energy = volume * s.psi;
  if constexpr (kOrder >= 1) {
    const Mat3 G = volume * s.P * D.transpose();
    out.gradient.template rightCols<3>() = G;
    out.gradient.col(0) = -G.rowwise().sum();
  }
  if constexpr (kOrder >= 2) {
    // U = dP/dF A^T: column (3b + d) = sum_l D(b, l) dPdF.col(3l + d).
    Mat9 U;
    for (int b = 0; b < 3; ++b)
      for (int d = 0; d < 3; ++d)
        U.col(3 * b + d) =
            D(b, 0) * s.dPdF.col(d) + D(b, 1) * s.dPdF.col(3 + d) + D(b, 2) * s.dPdF.col(6 + d);
    // K = A U is symmetric, so K = U^T A^T: column (3b + d) = sum_l D(b, l) U^T.col(3l + d).
    // Written straight into the node 1..3 part of the 12x12 (contiguous column segments).
    const Mat9 Ut = U.transpose();
    Mat12& H = out.hessian;
    for (int b = 0; b < 3; ++b)
      for (int d = 0; d < 3; ++d)
        H.col(3 + 3 * b + d).template segment<9>(3) =
            volume * (D(b, 0) * Ut.col(d) + D(b, 1) * Ut.col(3 + d) + D(b, 2) * Ut.col(6 + d));
    // Node 0 rows/columns: minus the sums of the blocks of nodes 1..3.
    for (int d = 0; d < 3; ++d) {
      H.col(d).template segment<9>(3) =
          -(H.col(3 + d).template segment<9>(3) + H.col(6 + d).template segment<9>(3) +
            H.col(9 + d).template segment<9>(3));
      H.row(d).template segment<9>(3) = H.col(d).template segment<9>(3).transpose();
    }
    H.template topLeftCorner<3, 3>() = -(
        H.template block<3, 3>(3, 0) + H.template block<3, 3>(6, 0) + H.template block<3, 3>(9, 0));
  }
}

}  // namespace depthfem

#pragma once
/// Generic psi(F), P(F) = dpsi/dF and dP/dF for any material written in invariants.
///
/// A material type M provides
///   static constexpr bool kUsesI2, kUsesFiber;   which invariants it depends on
///   template <int kOrder> InvariantDerivatives evaluate(const Invariants&) const;
/// returning psi (kOrder 0), its gradient (kOrder >= 1) and Hessian (kOrder 2) in the invariants.
/// The chain rule below turns them into P and dP/dF:
///   P     = sum_x psi_x dI_x/dF
///   dP/dF = sum_x psi_x d2I_x/dF2 + sum_xy psi_xy vec(dI_x/dF) vec(dI_y/dF)^T.

#include <cmath>
#include <concepts>
#include <limits>

#include "materials/invariants.hpp"

namespace depthfem {

/// The interface every material model satisfies.
template <class M>
concept Material = requires(const M m, const Invariants<>& inv) {
  { M::kUsesI2 } -> std::convertible_to<bool>;
  { M::kUsesFiber } -> std::convertible_to<bool>;
  { m.template evaluate<2>(inv) } -> std::same_as<InvariantDerivatives<>>;
};

/// Energy density [J/m^3], first Piola-Kirchhoff stress [Pa] and its derivative [Pa] at one F.
struct StressState {
  double psi = 0;
  Eigen::Matrix3d P = Eigen::Matrix3d::Zero();
  Mat9 dPdF = Mat9::Zero();
};

namespace detail {

// Writes s * [v]x (the cross-product matrix of v) into the 3x3 block at (r, c) of H.
inline void add_cross_block(Mat9& H, int r, int c, double s, const Eigen::Vector3d& v) {
  H(r + 0, c + 1) -= s * v(2);
  H(r + 0, c + 2) += s * v(1);
  H(r + 1, c + 0) += s * v(2);
  H(r + 1, c + 2) -= s * v(0);
  H(r + 2, c + 0) -= s * v(1);
  H(r + 2, c + 1) += s * v(0);
}

}  // namespace detail

/// Evaluates psi (kOrder 0), P (kOrder >= 1) and dP/dF (kOrder 2) of material `m` at F, with unit
/// fiber direction `f` (ignored by materials without fibers). Requires det F > 0; otherwise psi is
/// +infinity and P, dP/dF are left zero (the configuration is illegal, the energy is infinite).
template <int kOrder, Material M>
StressState evaluate_stress(const M& m, const Eigen::Matrix3d& F, const Eigen::Vector3d& f) {
  StressState s;
  const Invariants<> inv = invariants(F, f);
  if (!(inv.J > 0)) {
    s.psi = std::numeric_limits<double>::infinity();
    return s;
  }
  const InvariantDerivatives<> e = m.template evaluate<kOrder>(inv);
  s.psi = e.psi;
  if constexpr (kOrder == 0) return s;

  // First derivatives of the invariants:
  //   dI1/dF = 2F,  dI2/dF = 2(I1 F - F C),  dJ/dF = cof F,  dI4/dF = 2 (F f) f^T.
  const Eigen::Matrix3d B = F * F.transpose();
  Eigen::Matrix3d g[4];
  g[kI1] = 2.0 * F;
  g[kJ] = cofactor(F);
  if constexpr (M::kUsesI2) g[kI2] = 2.0 * (inv.I1 * F - B * F);
  const Eigen::Vector3d Ff = F * f;
  if constexpr (M::kUsesFiber) g[kI4] = 2.0 * Ff * f.transpose();

  s.P = e.d[kI1] * g[kI1] + e.d[kJ] * g[kJ];
  if constexpr (M::kUsesI2) s.P += e.d[kI2] * g[kI2];
  if constexpr (M::kUsesFiber) s.P += e.d[kI4] * g[kI4];
  if constexpr (kOrder == 1) return s;

  // Second derivatives, written per 3x3 block (j, l) of dP/dF, which couples column j of P with
  // column l of F (entries [i, k] = d P_ij / d F_kl):
  //   d2I1:  2 delta_jl Id
  //   d2I2:  2 [ (I1 delta_jl - C_lj) Id + 2 F_j F_l^T - F_l F_j^T - delta_jl B ]
  //   d2J:   -eps_jln [F_n]x   (zero for j == l)
  //   d2I4:  2 f_j f_l Id
  Mat9& H = s.dPdF;
  const Eigen::Matrix3d C = F.transpose() * F;
  for (int j = 0; j < 3; ++j) {
    for (int l = 0; l < 3; ++l) {
      double diag = (j == l) ? 2.0 * e.d[kI1] : 0.0;
      if constexpr (M::kUsesI2) diag += 2.0 * e.d[kI2] * ((j == l ? inv.I1 : 0.0) - C(l, j));
      if constexpr (M::kUsesFiber) diag += 2.0 * e.d[kI4] * f(j) * f(l);
      auto block = H.block<3, 3>(3 * j, 3 * l);
      block.diagonal().array() += diag;
      if constexpr (M::kUsesI2) {
        block += 2.0 * e.d[kI2] *
                 (2.0 * F.col(j) * F.col(l).transpose() - F.col(l) * F.col(j).transpose());
        if (j == l) block -= 2.0 * e.d[kI2] * B;
      }
    }
  }
  // d2J: for j != l let n be the third index and eps = eps_jln; block = -eps psi_J [F_n]x.
  for (int j = 0; j < 3; ++j) {
    const int l = (j + 1) % 3, n = (j + 2) % 3;  // (j, l, n) is an even permutation: eps = +1
    detail::add_cross_block(H, 3 * j, 3 * l, -e.d[kJ], F.col(n));
    detail::add_cross_block(H, 3 * l, 3 * j, e.d[kJ], F.col(n));
  }
  // Rank-one terms psi_xy vec(g_x) vec(g_y)^T over the invariants the material uses.
  constexpr int kCount = 4;
  for (int x = 0; x < kCount; ++x) {
    if ((x == kI2 && !M::kUsesI2) || (x == kI4 && !M::kUsesFiber)) continue;
    const Eigen::Map<const Vec9> gx(g[x].data());
    for (int y = x; y < kCount; ++y) {
      if ((y == kI2 && !M::kUsesI2) || (y == kI4 && !M::kUsesFiber)) continue;
      const double w = e.d2[x][y];
      if (w == 0.0) continue;
      const Eigen::Map<const Vec9> gy(g[y].data());
      if (x == y) {
        H.noalias() += w * gx * gx.transpose();
      } else {
        H.noalias() += w * (gx * gy.transpose() + gy * gx.transpose());
      }
    }
  }
  return s;
}

/// Energy density psi(F) [J/m^3] (+infinity when det F <= 0).
template <Material M>
double energy_density(const M& m, const Eigen::Matrix3d& F,
                      const Eigen::Vector3d& f = Eigen::Vector3d::UnitX()) {
  return evaluate_stress<0>(m, F, f).psi;
}

/// First Piola-Kirchhoff stress P = dpsi/dF [Pa].
template <Material M>
Eigen::Matrix3d first_piola(const M& m, const Eigen::Matrix3d& F,
                            const Eigen::Vector3d& f = Eigen::Vector3d::UnitX()) {
  return evaluate_stress<1>(m, F, f).P;
}

/// dP/dF as a 9x9 matrix on column-major vec(F) [Pa].
template <Material M>
Mat9 first_piola_derivative(const M& m, const Eigen::Matrix3d& F,
                            const Eigen::Vector3d& f = Eigen::Vector3d::UnitX()) {
  return evaluate_stress<2>(m, F, f).dPdF;
}

/// Small-strain Lame parameters of a material at F = I, read off dP/dF:
/// for isotropic linear elasticity dP_01/dF_01 = mu and dP_00/dF_11 = lambda.
struct LinearizedModuli {
  double mu = 0, lambda = 0;
  double bulk() const { return lambda + 2.0 * mu / 3.0; }
  double youngs() const { return mu * (3.0 * lambda + 2.0 * mu) / (lambda + mu); }
  double poisson() const { return lambda / (2.0 * (lambda + mu)); }
};

/// The Lame parameters of `m` at the reference state; for fiber materials (fiber along e_x) these
/// are the isotropic part, as the fiber only stiffens dP_00/dF_00.
template <Material M>
LinearizedModuli linearized_moduli(const M& m) {
  const Mat9 D = first_piola_derivative(m, Eigen::Matrix3d::Identity());
  return {D(0 + 3 * 1, 0 + 3 * 1), D(0, 1 + 3 * 1)};
}

}  // namespace depthfem

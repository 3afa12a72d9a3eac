#pragma once
/// Finite-strain viscoelasticity after Simo (1987): a Prony series relaxes the isochoric stress
/// of any hyperelastic model; its volumetric part stays elastic.
///
/// Split. The isochoric energy of a model psi(C) is psi at the isochoric part of the deformation,
///   psi_iso(C) = psi(Cbar),  Cbar = J^-2/3 C,
/// i.e. psi at the invariants (J^-2/3 I1, J^-4/3 I2, 1, J^-2/3 I4); the rest psi_vol = psi -
/// psi_iso is elastic. For the decoupled nearly incompressible Mooney-Rivlin psi_vol is exactly its
/// volumetric term; for the compressible models it is purely volumetric at small strain (psi_iso
/// carries the whole shear modulus mu and no bulk modulus), which is what a Prony series on the
/// shear modulus means there. psi_iso is stress-free at F = I because psi is.
///
/// Model. The given hyperelastic model is the instantaneous response. With Prony weights beta_i
/// (> 0, sum < 1), relaxation times tau_i > 0 and beta_inf = 1 - sum beta_i, the second
/// Piola-Kirchhoff stress is
///   S = S_vol + beta_inf S_iso(C) + sum_i Q_i,   dQ_i/dt + Q_i / tau_i = beta_i dS_iso/dt,
/// S_iso = 2 dpsi_iso/dC; the body rests in its reference state before t = 0 (Q_i(0) = beta_i
/// S_iso(C(0))). A static analysis uses the equilibrium modulus (Q_i = 0: psi_vol + beta_inf
/// psi_iso) or the instantaneous one (psi) as the scene says.
///
/// Step. Over a step from t^n to t = t^n + dt, with x_i = dt / tau_i and
/// gamma_i = beta_i (1 - e^-x_i) / x_i (-> beta_i as dt -> 0), Simo's recursion
///   Q_i = h_i + gamma_i S_iso(C),   h_i = e^-x_i Q_i^n - gamma_i S_iso(C^n),
/// holds h_i fixed during the step, so the step has the incremental potential
///   Pi(C) = psi(C) + (s - 1) psi_iso(C) + 1/2 h : (C - I),  s = beta_inf + sum_i gamma_i,
///   h = sum_i h_i,
/// whose derivative 2 dPi/dC is the algorithmic stress S_vol + s S_iso + h. Newton minimises Pi:
/// its exact Hessian (the material part through psi and psi_iso, the geometric part of h : C
/// as dP_ij/dF_kl = delta_ik h_lj with P = F h), the energy line search and the per-element
/// positive semi-definite projection all apply unchanged. At the accepted end of the step
/// Q_i^{n+1} = h_i + gamma_i S_iso(C^{n+1}).

#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "materials/hyperelastic.hpp"
#include "materials/isochoric.hpp"

namespace depthfem {

/// Relaxation of the isochoric stress: weights beta_i and times tau_i (same length; empty: the
/// material is elastic).
struct PronySeries {
  std::vector<double> weights;  ///< beta_i, each > 0, sum < 1 [-]
  std::vector<double> times;    ///< tau_i > 0 [s]
  /// A static analysis uses the fully relaxed (equilibrium) modulus; false: the instantaneous.
  bool static_relaxed = true;

  bool empty() const { return weights.empty(); }
  /// beta_inf = 1 - sum beta_i: the share of the isochoric stiffness left at equilibrium.
  double equilibrium_weight() const;
  /// What is wrong with the series, if anything: a weight not positive and finite, weights
  /// summing to 1 or more, a time not positive and finite, or lists of different lengths.
  struct Problem {
    std::string key;  ///< "weights", "weights[1]", "relaxation_times[0]"
    std::string why;
  };
  std::optional<Problem> problem() const;
  /// Throws std::invalid_argument "KEY: WHY" for the problem() there is.
  void validate() const;
};

/// The coefficients of one step of length dt >= 0 [s]: decay_i = e^-x_i, gamma_i and
/// s = beta_inf + sum gamma_i (dt = 0 gives the instantaneous limit gamma_i = beta_i, s = 1).
struct PronyStep {
  std::vector<double> decay, gamma;
  double scale = 1;
};
PronyStep prony_step(const PronySeries& prony, double dt);

/// The model psi + (scale - 1) psi_iso: the base model with its isochoric part scaled, itself a
/// Material (so the scalar and the batched tet kernels take it as they are). scale = beta_inf is
/// the equilibrium model, 1 the instantaneous one, s = beta_inf + sum gamma_i a step's.
template <Material M>
struct IsochoricScaled {
  M base;
  double scale = 1;

  static constexpr bool kUsesI2 = M::kUsesI2;
  static constexpr bool kUsesFiber = M::kUsesFiber;

  template <int kOrder, class S>
  InvariantDerivatives<S> evaluate(const Invariants<S>& inv) const {
    InvariantDerivatives<S> e = base.template evaluate<kOrder>(inv);
    if (scale == 1) return e;
    const InvariantDerivatives<S> iso = isochoric_derivatives<kOrder>(base, inv);
    const double w = scale - 1;
    e.psi += w * iso.psi;
    for (int x = 0; x < 4; ++x) {
      if constexpr (kOrder >= 1) e.d[x] += w * iso.d[x];
      if constexpr (kOrder >= 2)
        for (int y = 0; y < 4; ++y) e.d2[x][y] += w * iso.d2[x][y];
    }
    return e;
  }
};

/// The isochoric second Piola-Kirchhoff stress S_iso = 2 dpsi_iso/dC [Pa] at F (det F > 0), with
/// unit fiber direction f:  2 [psi_1 I + psi_2 (I1 I - C) + psi_4 f f^T] + psi_J J C^-1, the
/// psi_x being those of psi_iso (isochoric_derivatives).
template <Material M>
Eigen::Matrix3d isochoric_pk2(const M& m, const Eigen::Matrix3d& F, const Eigen::Vector3d& f) {
  const Invariants<> inv = invariants(F, f);
  const InvariantDerivatives<> e = isochoric_derivatives<1>(m, inv);
  const Eigen::Matrix3d C = F.transpose() * F;
  Eigen::Matrix3d S = (2.0 * (e.d[kI1] + e.d[kI2] * inv.I1)) * Eigen::Matrix3d::Identity() -
                      (2.0 * e.d[kI2]) * C + (e.d[kJ] * inv.J) * C.inverse();
  if constexpr (M::kUsesFiber) S += (2.0 * e.d[kI4]) * f * f.transpose();
  return S;
}

}  // namespace depthfem

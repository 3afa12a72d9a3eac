#pragma once
/// The isochoric part of any material written in invariants: its derivatives
/// (isochoric_derivatives, which the viscoelastic split of materials/viscoelastic.hpp scales) and
/// the model Isochoric<M> for formulations that treat the volume change apart
/// (integrators/forces/patch_volume.hpp).

#include <array>
#include <cmath>

#include "materials/hyperelastic.hpp"
#include "materials/invariants.hpp"

namespace depthfem {

namespace detail {

// Invariant slots scaled by the isochoric part, with the power k of a = J^-2/3 that scales each:
// I1 and I4 by a, I2 by a^2.
constexpr InvariantSlot kIsochoricSlots[3] = {kI1, kI2, kI4};
constexpr int kIsochoricPower[3] = {1, 2, 1};

}  // namespace detail

/// psi_iso(I1, I2, J, I4) = psi(a I1, a^2 I2, 1, a I4) with a = J^-2/3, and its derivatives in
/// (I1, I2, J, I4) up to order kOrder, for doubles or lanes. With u_p = a^k_p I_p (k = 1, 2, 1):
///   du_p/dI_p = a^k_p,  du_p/dJ = -2k_p/3 u_p/J,  d2u_p/dI_p dJ = -2k_p/3 a^k_p/J,
///   d2u_p/dJ2 = 2k_p/3 (2k_p/3 + 1) u_p/J^2,
/// and psi_iso,xy = sum_pq psi_pq du_p/dx du_q/dy + sum_p psi_p d2u_p/dx dy.
template <int kOrder, Material M, class S>
InvariantDerivatives<S> isochoric_derivatives(const M& m, const Invariants<S>& inv) {
  using std::exp;
  using std::log;
  const S a = exp((-2.0 / 3.0) * log(inv.J));
  const S ak[3] = {a, a * a, a};
  Invariants<S> bar;
  bar.I1 = a * inv.I1;
  bar.I2 = ak[1] * inv.I2;
  bar.J = S(1.0);
  bar.I4 = a * inv.I4;
  const InvariantDerivatives<S> f = m.template evaluate<kOrder>(bar);
  InvariantDerivatives<S> e;
  e.psi = f.psi;
  if constexpr (kOrder == 0) return e;
  constexpr bool used[3] = {true, M::kUsesI2, M::kUsesFiber};
  const S u[3] = {bar.I1, bar.I2, bar.I4};
  const S inv_J = 1.0 / inv.J;
  std::array<S, 3> du_dJ;  // du_p/dJ
  for (int p = 0; p < 3; ++p) {
    if (!used[p]) continue;
    const int x = detail::kIsochoricSlots[p];
    const double c = -2.0 * detail::kIsochoricPower[p] / 3.0;
    du_dJ[p] = c * u[p] * inv_J;
    e.d[x] = f.d[x] * ak[p];
    e.d[kJ] += f.d[x] * du_dJ[p];
  }
  if constexpr (kOrder == 1) return e;
  for (int p = 0; p < 3; ++p) {
    if (!used[p]) continue;
    const int x = detail::kIsochoricSlots[p];
    const double c = 2.0 * detail::kIsochoricPower[p] / 3.0;
    S xJ = -c * f.d[x] * ak[p] * inv_J;  // psi_p d2u_p/dI_p dJ
    e.d2[kJ][kJ] += c * (c + 1) * f.d[x] * u[p] * inv_J * inv_J;
    for (int q = 0; q < 3; ++q) {
      if (!used[q]) continue;
      const int y = detail::kIsochoricSlots[q];
      e.d2[x][y] = f.d2[x][y] * ak[p] * ak[q];
      xJ += f.d2[x][y] * ak[p] * du_dJ[q];
      e.d2[kJ][kJ] += f.d2[x][y] * du_dJ[p] * du_dJ[q];
    }
    e.d2[x][kJ] = xJ;
    e.d2[kJ][x] = xJ;
  }
  return e;
}

/// psi_iso(F) = psi_base(J^-1/3 F) as a model: the base evaluated at the isochoric invariants
/// (isochoric_derivatives), where every volumetric term of the base (a barrier in J, a bulk
/// penalty) vanishes; a fiber term acts on J^-2/3 I4, so it stays on the isochoric side. The
/// small-strain shear modulus is the base's, the bulk modulus zero.
template <Material Base>
struct Isochoric {
  Base base;

  static constexpr bool kUsesI2 = Base::kUsesI2;
  static constexpr bool kUsesFiber = Base::kUsesFiber;

  template <int kOrder, class S>
  InvariantDerivatives<S> evaluate(const Invariants<S>& inv) const {
    return isochoric_derivatives<kOrder>(base, inv);
  }
};

}  // namespace depthfem

#pragma once
/// The isochoric part of any material written in invariants, for formulations that treat the
/// volume change apart (integrators/forces/nodal_volume.hpp).

#include <array>
#include <cmath>

#include "materials/invariants.hpp"

namespace depthfem {

/// psi_iso(F) = psi_base(J^-1/3 F): the base model evaluated at the isochoric invariants
///   I1~ = J^-2/3 I1,  I2~ = J^-4/3 I2,  I4~ = J^-2/3 I4,  J~ = 1,
/// where every volumetric term of the base (a barrier in J, a bulk penalty) vanishes; a fiber
/// term acts on I4~, so it stays on the isochoric side. The small-strain shear modulus is the
/// base's, the bulk modulus zero. Chain rule, with s_u = J^p_u (p = -2/3, -4/3, -2/3 for I1, I2,
/// I4) and dI_u~/dJ = p_u I_u~ / J:
///   d psi / dI_u      = phi_u s_u
///   d psi / dJ        = sum_u phi_u p_u I_u~ / J
///   d2 psi / dI_u dI_v = phi_uv s_u s_v
///   d2 psi / dI_u dJ   = s_u (phi_u p_u / J + sum_v phi_uv p_v I_v~ / J)
///   d2 psi / dJ2       = sum_u phi_u p_u (p_u - 1) I_u~ / J^2 + sum_uv phi_uv p_u p_v I_u~ I_v~ /
///   J^2
/// with phi the base's derivatives at (I1~, I2~, 1, I4~).
template <class Base>
struct Isochoric {
  Base base;

  static constexpr bool kUsesI2 = Base::kUsesI2;
  static constexpr bool kUsesFiber = Base::kUsesFiber;

  template <int kOrder, class S>
  InvariantDerivatives<S> evaluate(const Invariants<S>& inv) const {
    using std::pow;
    const S s1 = pow(inv.J, -2.0 / 3.0), s2 = s1 * s1;
    const Invariants<S> bar{s1 * inv.I1, s2 * inv.I2, S(1.0), s1 * inv.I4};
    const InvariantDerivatives<S> b = base.template evaluate<kOrder>(bar);
    InvariantDerivatives<S> e;
    e.psi = b.psi;
    if constexpr (kOrder >= 1) {
      constexpr std::array<int, 3> u = {kI1, kI2, kI4};
      constexpr std::array<double, 3> p = {-2.0 / 3.0, -4.0 / 3.0, -2.0 / 3.0};
      const std::array<S, 3> s = {s1, s2, s1};
      const S inv_J = 1.0 / inv.J;
      std::array<S, 3> dbar_dJ;  // dI_u~/dJ
      const std::array<S, 3> Ibar = {bar.I1, bar.I2, bar.I4};
      for (int i = 0; i < 3; ++i) dbar_dJ[i] = p[i] * Ibar[i] * inv_J;
      e.d[kJ] = S(0.0);
      for (int i = 0; i < 3; ++i) {
        e.d[u[i]] = b.d[u[i]] * s[i];
        e.d[kJ] += b.d[u[i]] * dbar_dJ[i];
      }
      if constexpr (kOrder >= 2) {
        S jj = S(0.0);
        for (int i = 0; i < 3; ++i) {
          S cross = b.d[u[i]] * p[i] * inv_J;
          for (int k = 0; k < 3; ++k) {
            e.d2[u[i]][u[k]] = b.d2[u[i]][u[k]] * s[i] * s[k];
            cross += b.d2[u[i]][u[k]] * dbar_dJ[k];
            jj += b.d2[u[i]][u[k]] * dbar_dJ[i] * dbar_dJ[k];
          }
          e.d2[u[i]][kJ] = e.d2[kJ][u[i]] = s[i] * cross;
          jj += b.d[u[i]] * (p[i] * (p[i] - 1)) * Ibar[i] * inv_J * inv_J;
        }
        e.d2[kJ][kJ] = jj;
      }
    }
    return e;
  }
};

}  // namespace depthfem

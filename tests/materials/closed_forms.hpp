#pragma once
// Hand-derived uniaxial responses of every material model, shared by the material tests and the
// uniaxial_block scene test. Independent of the library's chain rule: each P11, P22 is written
// out from the model's psi by hand.

#include <cmath>

#include "materials/material.hpp"

namespace depthfem::closed_form {

// Uniaxial stretch F = diag(l, t, t) (fiber along x). Each material's P11, P22 written out by hand.
struct Uniaxial {
  double P11, P22;
};

inline Uniaxial closed_uniaxial(const NeoHookean& m, double l, double t) {
  // P = mu (F - F^-T) + lambda ln J F^-T.
  const double lnJ = std::log(l * t * t);
  return {m.mu * (l - 1 / l) + m.lambda * lnJ / l, m.mu * (t - 1 / t) + m.lambda * lnJ / t};
}
inline Uniaxial closed_uniaxial(const MooneyRivlin& m, double l, double t) {
  // psi = C1 (l^2 + 2t^2 - 3) + C2 (2 l^2 t^2 + t^4 - 3) + a (l^2 t^4 - 1) - k ln(l^2 t^4);
  // P11 = dpsi/dl; P22 = dpsi/dF22 (one lateral stretch varied, the other held).
  const double k = m.C1 + 2 * m.C2 + m.a, J = l * t * t;
  return {2 * m.C1 * l + 4 * m.C2 * l * t * t + 2 * m.a * J * t * t - 2 * k / l,
          2 * m.C1 * t + 2 * m.C2 * t * (l * l + t * t) + 2 * m.a * J * l * t - 2 * k / t};
}
inline Uniaxial closed_uniaxial(const Veronda& m, double l, double t) {
  const double k = m.a + 2 * m.alpha + 2 * m.alpha * m.beta, J = l * t * t;
  const double ex = std::exp(l * l + 2 * t * t - 3);
  return {4 * m.alpha * ex * l + 4 * m.alpha * m.beta * l * t * t + 2 * m.a * J * t * t - 2 * k / l,
          4 * m.alpha * ex * t + 2 * m.alpha * m.beta * t * (l * l + t * t) + 2 * m.a * J * l * t -
              2 * k / t};
}
inline Uniaxial closed_uniaxial(const NearlyIncompressibleMooneyRivlin& m, double l, double t) {
  // With F = diag(l, t2, t3): I1b = J^-2/3 (l^2 + t2^2 + t3^2), J = l t2 t3.
  // d(I1b)/dl = J^-2/3 (2 l - 2/3 I1 / l); d(I2b)/dl = J^-4/3 (2 l (t2^2 + t3^2) - 4/3 I2 / l);
  // d/dl of kappa/2 ((J^2-1)/2 - ln J) = kappa/2 (J - 1/J) J / l.
  const double J = l * t * t, I1 = l * l + 2 * t * t, I2 = 2 * l * l * t * t + t * t * t * t;
  const double j23 = std::pow(J, -2.0 / 3), j43 = j23 * j23, vol = 0.5 * m.kappa * (J - 1 / J) * J;
  const double P11 = m.C1 * j23 * (2 * l - 2.0 / 3 * I1 / l) +
                     m.C2 * j43 * (4 * l * t * t - 4.0 / 3 * I2 / l) + vol / l;
  const double P22 = m.C1 * j23 * (2 * t - 2.0 / 3 * I1 / t) +
                     m.C2 * j43 * (2 * t * (l * l + t * t) - 4.0 / 3 * I2 / t) + vol / t;
  return {P11, P22};
}
template <class Base>
Uniaxial closed_uniaxial(const FiberReinforced<Base>& m, double l, double t) {
  // Fiber along x: I4 = l^2, extra P11 = 2 l alpha beta (exp(beta (l^2 - 1)) - 1).
  Uniaxial u = closed_uniaxial(m.base, l, t);
  u.P11 += 2 * l * m.alpha * m.beta * (std::exp(m.beta * (l * l - 1)) - 1);
  return u;
}

// Lateral stretch t with P22(l, t) = 0, by bisection on the closed form (P22 rises with t).
template <class M>
double lateral_stretch(const M& m, double l) {
  double lo = 0.2, hi = 2.0;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (closed_uniaxial(m, l, mid).P22 > 0 ? hi : lo) = mid;
  }
  return 0.5 * (lo + hi);
}

}  // namespace depthfem::closed_form

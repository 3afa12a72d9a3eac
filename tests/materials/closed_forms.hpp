#pragma once
// Hand-derived uniaxial and simple-shear responses of every material model, shared by the
// material tests and the scene and results-file tests. Independent of the library's chain rule:
// each stress is written out from the model's psi by hand.

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

// Simple shear F = I + g e_x e_y^T (J = 1, I1 = I2 = 3 + g^2; fiber along y: I4 = 1 + g^2).
// Isotropic part: P = 2 psi1 F + 2 psi2 (I1 F - F C) + psiJ cof F gives
//   P01 = 2 g (psi1 + psi2), P10 = -g (2 psi2 + psiJ), P00 = 2 psi1 + 2 psi2 (2) + psiJ,
//   P11 = 2 psi1 + 2 psi2 (2) + psiJ, P22 = 2 psi1 + 2 psi2 (2 + g^2) + psiJ, with
// psi_x evaluated at J = 1 by hand per material below. The fiber adds 2 psi4 (F f) f^T =
// 2 psi4 [g, 1, 0]^T e_y^T: P01 += 2 psi4 g, P11 += 2 psi4.
struct ShearCoefficients {
  double psi1, psi2, psiJ, psi4 = 0;
};
inline ShearCoefficients shear_coefficients(const NeoHookean& m, double) {
  return {m.mu / 2, 0, -m.mu};
}
inline ShearCoefficients shear_coefficients(const MooneyRivlin& m, double) {
  return {m.C1, m.C2, 2 * m.a - 2 * (m.C1 + 2 * m.C2 + m.a)};
}
inline ShearCoefficients shear_coefficients(const Veronda& m, double g) {
  return {2 * m.alpha * std::exp(g * g), m.alpha * m.beta,
          2 * m.a - 2 * (m.a + 2 * m.alpha + 2 * m.alpha * m.beta)};
}
inline ShearCoefficients shear_coefficients(const NearlyIncompressibleMooneyRivlin& m, double g) {
  const double I = 3 + g * g;
  return {m.C1, m.C2, -2.0 / 3 * m.C1 * I - 4.0 / 3 * m.C2 * I};
}
template <class Base>
ShearCoefficients shear_coefficients(const FiberReinforced<Base>& m, double g) {
  ShearCoefficients c = shear_coefficients(m.base, g);
  c.psi4 = m.alpha * m.beta * (std::exp(m.beta * g * g) - 1);
  return c;
}

// P of simple shear F = I + g e_x e_y^T (fiber along y) from the coefficients above.
template <class M>
Eigen::Matrix3d simple_shear_piola(const M& m, double g) {
  const ShearCoefficients c = shear_coefficients(m, g);
  Eigen::Matrix3d P = Eigen::Matrix3d::Zero();
  P(0, 1) = 2 * g * (c.psi1 + c.psi2) + 2 * c.psi4 * g;
  P(1, 0) = -g * (2 * c.psi2 + c.psiJ);
  P(0, 0) = 2 * c.psi1 + 4 * c.psi2 + c.psiJ;
  P(1, 1) = 2 * c.psi1 + 4 * c.psi2 + c.psiJ + 2 * c.psi4;
  P(2, 2) = 2 * c.psi1 + 2 * c.psi2 * (2 + g * g) + c.psiJ;
  return P;
}

}  // namespace depthfem::closed_form

#pragma once
/// Nearly incompressible Mooney-Rivlin: deviatoric invariants plus a volumetric penalty on J.

#include <cmath>

#include "materials/invariants.hpp"

namespace depthfem {

/// psi = C1 (J^-2/3 I1 - 3) + C2 (J^-4/3 I2 - 3) + kappa/2 ((J^2 - 1)/2 - ln J).
/// The isochoric invariants make C1, C2 act on shape only; the volumetric term has
/// U'(1) = 0, U''(1) = kappa (small-strain bulk modulus) and U -> +inf as J -> 0.
/// A large kappa / mu (say 1e3) approximates incompressibility (the paper's future work).
struct NearlyIncompressibleMooneyRivlin {
  double C1 = 0;     ///< [Pa]
  double C2 = 0;     ///< [Pa]
  double kappa = 0;  ///< bulk modulus [Pa]

  static constexpr bool kUsesI2 = true;
  static constexpr bool kUsesFiber = false;
  static constexpr const char* kName = "nearly_incompressible_mooney_rivlin";

  /// Throws std::invalid_argument unless C1, C2 >= 0, C1 + C2 > 0 and kappa > 0.
  void validate() const;

  template <int kOrder, class S>
  InvariantDerivatives<S> evaluate(const Invariants<S>& inv) const {
    using std::log, std::pow;
    const S J = inv.J;
    const S j23 = pow(J, -2.0 / 3.0), j43 = j23 * j23;
    InvariantDerivatives<S> e;
    e.psi = C1 * (j23 * inv.I1 - 3) + C2 * (j43 * inv.I2 - 3) +
            0.5 * kappa * (0.5 * (J * J - 1) - log(J));
    if constexpr (kOrder >= 1) {
      e.d[kI1] = C1 * j23;
      e.d[kI2] = C2 * j43;
      e.d[kJ] = (-2.0 / 3.0 * C1 * j23 * inv.I1 - 4.0 / 3.0 * C2 * j43 * inv.I2) / J +
                0.5 * kappa * (J - 1 / J);
    }
    if constexpr (kOrder >= 2) {
      e.d2[kI1][kJ] = e.d2[kJ][kI1] = -2.0 / 3.0 * C1 * j23 / J;
      e.d2[kI2][kJ] = e.d2[kJ][kI2] = -4.0 / 3.0 * C2 * j43 / J;
      e.d2[kJ][kJ] = (10.0 / 9.0 * C1 * j23 * inv.I1 + 28.0 / 9.0 * C2 * j43 * inv.I2) / (J * J) +
                     0.5 * kappa * (1 + 1 / (J * J));
    }
    return e;
  }
};

}  // namespace depthfem

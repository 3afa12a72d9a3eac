#pragma once
/// Compressible Mooney-Rivlin material (paper section 3.3).

#include <cmath>

#include "materials/invariants.hpp"

namespace depthfem {

/// psi = C1 (I1-3) + C2 (I2-3) + a (I3-1) - (C1 + 2 C2 + a) ln I3, with I3 = J^2.
/// The ln I3 coefficient makes the reference state stress-free and psi -> +inf as J -> 0.
/// Small-strain shear modulus mu = 2 (C1 + C2).
struct MooneyRivlin {
  double C1 = 0;  ///< [Pa]
  double C2 = 0;  ///< [Pa]
  double a = 0;   ///< compressibility [Pa]

  static constexpr bool kUsesI2 = true;
  static constexpr bool kUsesFiber = false;
  static constexpr const char* kName = "mooney_rivlin";

  /// The material with small-strain Young's modulus E and Poisson's ratio nu for a given C2:
  /// linearised at F = I, mu = 2 (C1 + C2) and lambda = 4 (a + C2) (the second derivative of psi
  /// along J^(1/3) I is the bulk modulus 4/3 C1 + 16/3 C2 + 4 a), so C1 = mu / 2 - C2 and
  /// a = lambda / 4 - C2. Throws std::invalid_argument for E <= 0, nu outside (-1, 0.5), or C2
  /// outside [0, mu / 2].
  static MooneyRivlin from_youngs(double E, double nu, double C2 = 0);

  /// Throws std::invalid_argument unless C1, C2 >= 0, C1 + C2 > 0 and the rest state is stable.
  void validate() const;

  template <int kOrder, class S>
  InvariantDerivatives<S> evaluate(const Invariants<S>& inv) const {
    InvariantDerivatives<S> e;
    e.psi = C1 * (inv.I1 - 3) + C2 * (inv.I2 - 3);
    if constexpr (kOrder >= 1) {
      e.d[kI1] = C1;
      e.d[kI2] = C2;
    }
    add_volumetric_barrier<kOrder>(e, inv.J, a, C1 + 2.0 * C2 + a);
    return e;
  }
};

}  // namespace depthfem

#pragma once
/// Compressible neo-Hookean material, the baseline shared with other FEM codes.

#include <cmath>

#include "materials/invariants.hpp"

namespace depthfem {

/// psi = mu/2 (I1 - 3) - mu ln J + lambda/2 (ln J)^2 (Lame parameters at small strain).
struct NeoHookean {
  double mu = 0;      ///< shear modulus [Pa]
  double lambda = 0;  ///< first Lame parameter [Pa]

  static constexpr bool kUsesI2 = false;
  static constexpr bool kUsesFiber = false;
  static constexpr const char* kName = "neo_hookean";

  /// Lame parameters from Young's modulus E [Pa] and Poisson's ratio nu (-1 < nu < 0.5).
  static NeoHookean from_youngs(double E, double nu);

  /// Throws std::invalid_argument unless mu > 0 and the bulk modulus lambda + 2 mu / 3 > 0.
  void validate() const;

  template <int kOrder, class S>
  InvariantDerivatives<S> evaluate(const Invariants<S>& inv) const {
    using std::log;
    const S lnJ = log(inv.J);
    InvariantDerivatives<S> e;
    e.psi = 0.5 * mu * (inv.I1 - 3) - mu * lnJ + 0.5 * lambda * lnJ * lnJ;
    if constexpr (kOrder >= 1) {
      e.d[kI1] = 0.5 * mu;
      e.d[kJ] = (lambda * lnJ - mu) / inv.J;
    }
    if constexpr (kOrder >= 2) e.d2[kJ][kJ] = (mu + lambda * (1 - lnJ)) / (inv.J * inv.J);
    return e;
  }
};

}  // namespace depthfem

#pragma once
/// Compressible Veronda-Westmann material (paper section 3.3), corrected to be stress-free.

#include <cmath>

#include "materials/invariants.hpp"

namespace depthfem {

/// psi = 2 alpha (exp(I1-3) - 1) + alpha beta (I2-3) + a (I3-1) - (a + 2 alpha + 2 alpha beta) ln
/// I3.
///
/// Correction of the printed form. The paper prints
///   psi = 2 alpha exp(I1-3) + alpha beta (I2-3) + a I3 - a ln I3.
/// For psi(I1, I2, I3) the first Piola stress is
///   P = 2 psi_1 F + 2 psi_2 (I1 F - F C) + 2 psi_3 I3 F^-T,
/// which at F = I is 2 (psi_1 + 2 psi_2 + psi_3) I. The printed form has psi_1 = 2 alpha,
/// psi_2 = alpha beta, psi_3 = a - a / I3 = 0 at I3 = 1, so P(I) = 4 alpha (1 + beta) I != 0:
/// the undeformed body would be under hydrostatic tension. Replacing the volumetric part by
/// a (I3 - 1) - k ln I3 gives psi_3(I) = a - k; P(I) = 0 requires k = a + 2 alpha + 2 alpha beta,
/// the same construction as the paper's Mooney-Rivlin (whose k is C1 + 2 C2 + a). The constants
/// -2 alpha and -a only shift psi so that psi(I) = 0. Large-strain behaviour (exponential
/// stiffening in I1, barrier as I3 -> 0) is unchanged. Small-strain shear modulus
/// mu = 4 alpha + 2 alpha beta.
struct Veronda {
  double alpha = 0;  ///< overall stiffness [Pa]
  double beta = 0;   ///< rate of stiffening / I2 weight [-]
  double a = 0;      ///< compressibility [Pa]

  static constexpr bool kUsesI2 = true;
  static constexpr bool kUsesFiber = false;
  static constexpr const char* kName = "veronda";

  /// Throws std::invalid_argument unless alpha > 0, beta >= 0 and the rest state is stable.
  void validate() const;

  template <int kOrder, class S>
  InvariantDerivatives<S> evaluate(const Invariants<S>& inv) const {
    using std::exp;
    const S ex = exp(inv.I1 - 3);
    InvariantDerivatives<S> e;
    e.psi = 2.0 * alpha * (ex - 1) + alpha * beta * (inv.I2 - 3);
    if constexpr (kOrder >= 1) {
      e.d[kI1] = 2.0 * alpha * ex;
      e.d[kI2] = alpha * beta;
    }
    if constexpr (kOrder >= 2) e.d2[kI1][kI1] = 2.0 * alpha * ex;
    add_volumetric_barrier<kOrder>(e, inv.J, a, a + 2.0 * alpha + 2.0 * alpha * beta);
    return e;
  }
};

}  // namespace depthfem

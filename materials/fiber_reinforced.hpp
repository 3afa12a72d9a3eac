#pragma once
/// Fiber reinforcement superimposed on an isotropic base material (paper section 3.3).

#include <cmath>
#include <stdexcept>

#include "materials/invariants.hpp"

namespace depthfem {

/// psi = psi_base + alpha (exp(beta (I4 - 1)) - 1) - alpha beta (I4 - 1), I4 = lambda_f^2 = f^T C
/// f. The paper's form alpha exp(beta (lambda_f^2 - 1)) - alpha beta lambda_f^2, shifted by a
/// constant so that psi(I) = 0; dpsi/dI4 = alpha beta (exp(beta (I4-1)) - 1) vanishes at I4 = 1, so
/// the reference state stays stress-free. The fiber direction f is given per element.
template <class Base>
struct FiberReinforced {
  using BaseMaterial = Base;
  Base base;
  double alpha = 0;  ///< fiber stiffness [Pa]
  double beta = 0;   ///< fiber stiffening rate [-]

  static constexpr bool kUsesI2 = Base::kUsesI2;
  static constexpr bool kUsesFiber = true;

  /// Validates the base material, then requires alpha >= 0, beta > 0.
  void validate() const {
    base.validate();
    if (!(alpha >= 0)) throw std::invalid_argument("fiber: alpha must be >= 0");
    if (!(beta > 0)) throw std::invalid_argument("fiber: beta must be > 0");
  }

  template <int kOrder, class S>
  InvariantDerivatives<S> evaluate(const Invariants<S>& inv) const {
    using std::exp;
    InvariantDerivatives<S> e = base.template evaluate<kOrder>(inv);
    const S ex = exp(beta * (inv.I4 - 1));
    e.psi += alpha * (ex - 1) - alpha * beta * (inv.I4 - 1);
    if constexpr (kOrder >= 1) e.d[kI4] = alpha * beta * (ex - 1);
    if constexpr (kOrder >= 2) e.d2[kI4][kI4] = alpha * beta * beta * ex;
    return e;
  }
};

}  // namespace depthfem

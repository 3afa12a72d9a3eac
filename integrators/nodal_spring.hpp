#pragma once
/// Per-node quadratic tether to an anchor configuration: quasi-viscosity and inertia.

#include "core/force_module.hpp"

namespace depthfem {

/// E(x) = sum_i k_i / 2 |x_i - a_i|^2 with per-node stiffness k_i [N/m] and anchor positions a.
/// With a = the previous solution and k_i = viscosity x node size, it is the paper's
/// quasi-viscosity (a viscous force k_i (x_i - a_i) per unit pseudo time); with
/// k_i = m_i / h^2 and a = the predicted position it is the inertia term of implicit Euler.
class NodalSpring final : public ForceModule {
 public:
  NodalSpring(std::string name, VectorX stiffness) : name_(std::move(name)), k_(std::move(stiffness)) {}
  std::string name() const override { return name_; }
  void add_couplings(SparsityBuilder&) const override {}
  void bind(const BlockSparseMatrix& hessian) override;
  double evaluate(const Points& x, VectorX* gradient, BlockSparseMatrix* hessian) const override;

  /// Sets the anchor positions a (#nodes x 3).
  void set_anchor(const Points& anchor) { anchor_ = anchor; }
  /// Scales every stiffness k_i by `factor` (e.g. a new time step).
  void set_scale(double factor) { scale_ = factor; }
  const VectorX& stiffness() const { return k_; }

 private:
  std::string name_;
  VectorX k_;
  double scale_ = 1.0;
  Points anchor_;
  std::vector<Index> diagonal_;  // block index of (i, i)
};

/// Quasi-viscosity stiffness per node [N/m]: viscosity [Pa] x cube root of the volume of the
/// tets around the node [m] (the paper's "viscosity proportional to the surrounding elements").
VectorX quasi_viscosity_stiffness(const Points& X, const TetIndices& tets, double viscosity);

}  // namespace depthfem

#pragma once
/// Quadratic tethers to an anchor configuration: quasi-viscosity, inertia and damping.

#include "core/force_module.hpp"

namespace depthfem {

/// E(x) = s / 2 (x - a)^T K (x - a) for a fixed symmetric K, a scale s and anchor positions a.
/// Time integrators write inertia and damping as tethers whose scale and anchor they set per step.
class Tether : public ForceModule {
 public:
  /// Sets the anchor positions a (#nodes x 3).
  void set_anchor(const Points& anchor) { anchor_ = anchor; }
  /// Sets the scale s (e.g. 1 / h^2 for a new time step).
  void set_scale(double factor) { scale_ = factor; }
  /// 1/2 d^T K d for #nodes x 3 displacements d, without scale or anchor (with K = M and d = v:
  /// the kinetic energy).
  virtual double quadratic_form(const Points& d) const = 0;

 protected:
  double scale_ = 1.0;
  Points anchor_;
};

/// E(x) = s sum_i k_i / 2 |x_i - a_i|^2 with per-node stiffness k_i [N/m] and anchor positions a.
/// With a = the previous solution and k_i = viscosity x node size, it is the paper's
/// quasi-viscosity (a viscous force k_i (x_i - a_i) per unit pseudo time); with k_i = m_i,
/// s = 1 / h^2 and a = the predicted position it is the inertia term of implicit Euler.
class NodalSpring final : public Tether {
 public:
  NodalSpring(std::string name, VectorX stiffness)
      : name_(std::move(name)), k_(std::move(stiffness)) {}
  std::string name() const override { return name_; }
  void add_couplings(SparsityBuilder&) const override {}
  void bind(const BlockSparseMatrix& hessian) override;
  double evaluate(const Points& x, VectorX* gradient, BlockSparseMatrix* hessian) const override;
  double quadratic_form(const Points& d) const override;

  const VectorX& stiffness() const { return k_; }

 private:
  std::string name_;
  VectorX k_;
  std::vector<Index> diagonal_;  // block index of (i, i)
};

/// Quasi-viscosity stiffness per node [N/m]: viscosity [Pa] x cube root of the volume of the
/// tets around the node [m] (the paper's "viscosity proportional to the surrounding elements").
VectorX quasi_viscosity_stiffness(const Points& X, const TetIndices& tets, double viscosity);

}  // namespace depthfem

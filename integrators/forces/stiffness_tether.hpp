#pragma once
/// Stiffness-proportional (Rayleigh) damping as a tether: the damping matrix is beta K with K the
/// Hessian of the elastic energy at the start of the step.

#include "integrators/forces/nodal_spring.hpp"

namespace depthfem {

/// E(x) = s / 2 (x - a)^T K (x - a) with K = beta times the Hessian of `elastic` at the
/// configuration passed to the last begin_step(); the time integrator sets s (1 / h for implicit
/// Euler) and a.
class StiffnessTether final : public Tether {
 public:
  StiffnessTether(std::string name, const ForceModule& elastic, double beta)
      : name_(std::move(name)), elastic_(elastic), beta_(beta) {}
  std::string name() const override { return name_; }
  void begin_step(const Points& x) override;
  void add_couplings(SparsityBuilder&) const override {}  // those of the elastic module
  void bind(const BlockSparseMatrix& hessian) override;
  double evaluate(const Points& x, VectorX* gradient, BlockSparseMatrix* hessian) const override;
  double quadratic_form(const Points& d) const override;

 private:
  /// Assembles K at the start configuration when begin_step() or bind() made it stale.
  void refresh() const;

  std::string name_;
  const ForceModule& elastic_;
  double beta_;   // [s]
  Points start_;  // configuration K is taken at
  mutable BlockSparseMatrix
      K_;                      // elastic Hessian, pattern of the global one; assembled on first use
  mutable bool stale_ = true;  // (timed with the force evaluation, not with begin_step)
  bool bound_ = false;
};

}  // namespace depthfem

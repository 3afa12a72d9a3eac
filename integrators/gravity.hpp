#pragma once
/// Body force of a uniform gravity field on lumped nodal masses.

#include "core/force_module.hpp"

namespace depthfem {

/// E(x) = -sum_i m_i g . x_i: constant forces m_i g, no stiffness.
class Gravity final : public ForceModule {
 public:
  /// `mass` per node [kg], `g` acceleration [m/s^2].
  Gravity(VectorX mass, const Vec3& g) : mass_(std::move(mass)), g_(g) {}
  std::string name() const override { return "gravity"; }
  void add_couplings(SparsityBuilder&) const override {}
  double evaluate(const Points& x, VectorX* gradient, BlockSparseMatrix* hessian) const override;

 private:
  VectorX mass_;
  Vec3 g_;
};

}  // namespace depthfem

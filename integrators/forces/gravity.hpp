#pragma once
/// Body force of a uniform gravity field on lumped nodal masses.

#include "core/force_module.hpp"

namespace depthfem {

/// E(x) = -s sum_i m_i g . x_i: constant forces s m_i g, no stiffness. The scale s is 1, or the
/// load factor when the load ramps (static analysis, like every other load).
class Gravity final : public ForceModule {
 public:
  /// `mass` per node [kg], `g` acceleration [m/s^2]; `ramp`: scale by the load factor.
  Gravity(VectorX mass, const Vec3& g, bool ramp)
      : mass_(std::move(mass)), g_(g), ramp_(ramp), scale_(ramp ? 0.0 : 1.0) {}
  std::string name() const override { return "gravity"; }
  void set_load(double load) override { scale_ = ramp_ ? load : 1.0; }
  void add_couplings(SparsityBuilder&) const override {}
  double evaluate(const Points& x, VectorX* gradient, BlockSparseMatrix* hessian) const override;

 private:
  VectorX mass_;
  Vec3 g_;
  bool ramp_;
  double scale_;
};

}  // namespace depthfem

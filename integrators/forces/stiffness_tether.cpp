#include "integrators/forces/stiffness_tether.hpp"

#include <stdexcept>

namespace depthfem {

void StiffnessTether::begin_step(const Points& x) {
  start_ = x;
  stale_ = true;
}

void StiffnessTether::bind(const BlockSparseMatrix& hessian) {
  K_ = hessian;
  bound_ = true;
  stale_ = true;
}

double StiffnessTether::evaluate(const Points& x, VectorX* gradient,
                                 BlockSparseMatrix* hessian) const {
  refresh();
  const VectorX d = as_dofs(x - anchor_);
  VectorX Kd;
  K_.multiply(d, Kd);
  const double s = scale_ * beta_;
  if (gradient) *gradient += s * Kd;
  if (hessian) hessian->add_scaled(K_, s);
  return 0.5 * s * d.dot(Kd);
}

double StiffnessTether::quadratic_form(const Points& d) const {
  refresh();
  VectorX Kd;
  K_.multiply(as_dofs(d), Kd);
  return 0.5 * beta_ * as_dofs(d).dot(Kd);
}

void StiffnessTether::refresh() const {
  if (!bound_ || start_.rows() == 0)
    throw std::logic_error(name_ + ": call bind() and begin_step() first");
  if (!stale_) return;
  K_.set_zero();
  VectorX g = VectorX::Zero(3 * start_.rows());
  elastic_.evaluate(start_, &g, &K_);
  stale_ = false;
}

}  // namespace depthfem

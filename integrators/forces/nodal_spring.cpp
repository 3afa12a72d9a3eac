#include "integrators/forces/nodal_spring.hpp"

#include <cmath>

#include "core/mass.hpp"

namespace depthfem {

void NodalSpring::bind(const BlockSparseMatrix& hessian) {
  diagonal_.resize(static_cast<size_t>(k_.size()));
  for (Index i = 0; i < k_.size(); ++i) diagonal_[i] = hessian.block_index(i, i);
}

double NodalSpring::evaluate(const Points& x, VectorX* gradient, BlockSparseMatrix* hessian) const {
  const Points d = x - anchor_;
  if (gradient)
    for (Index i = 0; i < x.rows(); ++i)
      gradient->segment<3>(3 * i) += scale_ * k_(i) * d.row(i).transpose();
  if (hessian)
    for (Index i = 0; i < x.rows(); ++i)
      hessian->block(diagonal_[i]).diagonal().array() += scale_ * k_(i);
  return scale_ * quadratic_form(d);
}

double NodalSpring::quadratic_form(const Points& d) const {
  return 0.5 * (k_.array() * d.rowwise().squaredNorm().array()).sum();
}

VectorX quasi_viscosity_stiffness(const Points& X, const TetIndices& tets, double viscosity) {
  return viscosity * node_volume(X, tets).array().pow(1.0 / 3.0).matrix();
}

}  // namespace depthfem

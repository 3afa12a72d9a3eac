#include "integrators/forces/gravity.hpp"

namespace depthfem {

double Gravity::evaluate(const Points& x, VectorX* gradient, BlockSparseMatrix*) const {
  const Vec3 g = scale_ * g_;
  if (gradient)
    for (Index i = 0; i < x.rows(); ++i) gradient->segment<3>(3 * i) -= mass_(i) * g;
  return -(mass_.transpose() * (x * g)).value();
}

}  // namespace depthfem

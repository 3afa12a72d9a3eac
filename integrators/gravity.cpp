#include "integrators/gravity.hpp"

namespace depthfem {

double Gravity::evaluate(const Points& x, VectorX* gradient, BlockSparseMatrix*) const {
  if (gradient)
    for (Index i = 0; i < x.rows(); ++i) gradient->segment<3>(3 * i) -= mass_(i) * g_;
  return -(mass_.transpose() * (x * g_)).value();
}

}  // namespace depthfem

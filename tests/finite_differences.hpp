#pragma once
// Central finite differences, the one helper every derivative test uses.
//
// With step h, the truncation error of a central difference is h^2/6 times the third derivative
// and the round-off about 1e-16 |f| / h; h = 1e-6..1e-7 on variables of order 0.1..1 keeps both
// near 1e-10..1e-12 relative, so tests assert agreement to 1e-6 (gradients) or 1e-5 (Hessians
// from differences of gradients) of the largest entry.

#include <Eigen/Core>

#include "core/types.hpp"

namespace depthfem::testing {

/// d f / d x_i by central differences, one per coefficient of x in its storage order (an Eigen
/// vector or matrix: for a 3x3 F, the column-major entries).
template <class Vector, class F>
Vector central_gradient(const F& f, const Vector& x, double h) {
  Vector g = x;
  for (Eigen::Index i = 0; i < x.size(); ++i) {
    Vector xp = x, xm = x;
    xp(i) += h;
    xm(i) -= h;
    g(i) = (f(xp) - f(xm)) / (2 * h);
  }
  return g;
}

/// (g(x + h v) - g(x - h v)) / 2h: the Hessian of f times v, from a gradient function g.
template <class Vector, class G>
auto central_directional(const G& g, const Vector& x, const Vector& v, double h) {
  return ((g(x + h * v) - g(x - h * v)) / (2 * h)).eval();
}

/// The Jacobian of a vector function g by central differences: column i is dg/dx_i (of a
/// gradient function, the Hessian).
template <class Vector, class G>
Eigen::MatrixXd central_jacobian(const G& g, const Vector& x, double h) {
  Eigen::MatrixXd J;
  for (Eigen::Index i = 0; i < x.size(); ++i) {
    Vector e = Vector::Zero(x.size());
    e(i) = 1;
    const auto column = central_directional(g, x, e, h);
    J.resize(column.size(), x.size());
    J.col(i) = column;
  }
  return J;
}

/// central_gradient of a function of #nodes x 3 positions, as an interleaved dof vector
/// (3 * node + component), the layout of every force module's gradient.
template <class F>
VectorX central_gradient_dofs(const F& f, const Points& x, double h) {
  return central_gradient([&](const VectorX& z) { return f(as_points(z)); }, as_dofs(x), h);
}

}  // namespace depthfem::testing

#pragma once
/// Second-order forward-mode automatic differentiation over N variables: a value with its
/// gradient and Hessian. Used for contact energies, whose chain of dependencies (clip points,
/// barycentric coordinates, areas) is long: the derivatives are exact and checked against
/// finite differences in the tests.

#include <Eigen/Core>
#include <cmath>

namespace depthfem {

template <int N>
struct Dual2 {
  using Grad = Eigen::Matrix<double, N, 1>;
  using Hess = Eigen::Matrix<double, N, N>;
  double v = 0;
  Grad g = Grad::Zero();
  Hess h = Hess::Zero();

  Dual2() = default;
  Dual2(double value) : v(value) {}  // NOLINT: constants convert implicitly
  /// The k-th independent variable with value `value`.
  static Dual2 variable(int k, double value) {
    Dual2 d(value);
    d.g(k) = 1;
    return d;
  }

  Dual2& operator+=(const Dual2& o) {
    v += o.v;
    g += o.g;
    h += o.h;
    return *this;
  }
  Dual2& operator-=(const Dual2& o) {
    v -= o.v;
    g -= o.g;
    h -= o.h;
    return *this;
  }
};

template <int N>
Dual2<N> operator+(Dual2<N> a, const Dual2<N>& b) {
  return a += b;
}
template <int N>
Dual2<N> operator-(Dual2<N> a, const Dual2<N>& b) {
  return a -= b;
}
template <int N>
Dual2<N> operator-(Dual2<N> a) {
  a.v = -a.v;
  a.g = -a.g;
  a.h = -a.h;
  return a;
}
template <int N>
Dual2<N> operator*(const Dual2<N>& a, const Dual2<N>& b) {
  Dual2<N> r;
  r.v = a.v * b.v;
  r.g = a.v * b.g + b.v * a.g;
  r.h = a.v * b.h + b.v * a.h + a.g * b.g.transpose() + b.g * a.g.transpose();
  return r;
}
template <int N>
Dual2<N> operator*(Dual2<N> a, double s) {
  a.v *= s;
  a.g *= s;
  a.h *= s;
  return a;
}
template <int N>
Dual2<N> operator*(double s, Dual2<N> a) {
  return a * s;
}
template <int N>
Dual2<N> operator+(Dual2<N> a, double s) {
  a.v += s;
  return a;
}
/// 1 / b: value 1/v, gradient -g/v^2, Hessian -h/v^2 + 2 g g^T / v^3.
template <int N>
Dual2<N> inverse(const Dual2<N>& b) {
  const double i = 1.0 / b.v;
  Dual2<N> r;
  r.v = i;
  r.g = -i * i * b.g;
  r.h = -i * i * b.h + 2 * i * i * i * b.g * b.g.transpose();
  return r;
}
template <int N>
Dual2<N> operator/(const Dual2<N>& a, const Dual2<N>& b) {
  return a * inverse(b);
}
/// sqrt(a): value s, gradient g / (2 s), Hessian h / (2 s) - g g^T / (4 s^3).
template <int N>
Dual2<N> sqrt(const Dual2<N>& a) {
  const double s = std::sqrt(a.v);
  Dual2<N> r;
  r.v = s;
  r.g = a.g / (2 * s);
  r.h = a.h / (2 * s) - a.g * a.g.transpose() / (4 * s * s * s);
  return r;
}

/// Value of a plain double or of a Dual2.
inline double value_of(double x) {
  return x;
}
/// 1 / x for plain doubles and dual numbers alike.
inline double inverse_of(double x) {
  return 1.0 / x;
}
template <int N>
Dual2<N> inverse_of(const Dual2<N>& x) {
  return inverse(x);
}
template <int N>
double value_of(const Dual2<N>& x) {
  return x.v;
}

}  // namespace depthfem

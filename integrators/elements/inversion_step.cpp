#include "integrators/elements/inversion_step.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace depthfem {

namespace {

// Adjugate (transposed cofactor matrix): adj(A) A = det(A) I.
Mat3 adjugate(const Mat3& A) {
  Mat3 adj;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      const int r0 = (j + 1) % 3, r1 = (j + 2) % 3, c0 = (i + 1) % 3, c1 = (i + 2) % 3;
      adj(i, j) = A(r0, c0) * A(r1, c1) - A(r0, c1) * A(r1, c0);
    }
  return adj;
}

}  // namespace

double inversion_step(const Mat3& Ds, const Mat3& dDs, double limit) {
  const double c0 = Ds.determinant();
  if (!(c0 > 0)) return 0.0;
  const double c1 = (adjugate(Ds) * dDs).trace(), c2 = (adjugate(dDs) * Ds).trace(),
               c3 = dDs.determinant();
  const auto f = [&](double a) { return c0 + a * (c1 + a * (c2 + a * c3)); };
  // Monotone pieces of [0, limit]: split at the roots of f' = c1 + 2 c2 a + 3 c3 a^2 inside it.
  std::vector<double> ends;
  const double qa = 3 * c3, qb = 2 * c2, qc = c1;
  if (qa != 0) {
    const double disc = qb * qb - 4 * qa * qc;
    if (disc >= 0) {
      const double s = std::sqrt(disc), q = -0.5 * (qb + std::copysign(s, qb));
      for (double r : {q / qa, q != 0 ? qc / q : -1.0})
        if (r > 0 && r < limit) ends.push_back(r);
    }
  } else if (qb != 0) {
    const double r = -qc / qb;
    if (r > 0 && r < limit) ends.push_back(r);
  }
  std::sort(ends.begin(), ends.end());
  ends.push_back(limit);
  double lo = 0;
  for (double hi : ends) {
    if (f(hi) <= 0) {  // f(lo) > 0 >= f(hi) on a monotone piece: one root, bisect it
      for (int k = 0; k < 200 && hi - lo > 1e-15 * hi; ++k) {
        const double mid = 0.5 * (lo + hi);
        (f(mid) > 0 ? lo : hi) = mid;
      }
      return lo;
    }
    lo = hi;
  }
  return std::numeric_limits<double>::infinity();
}

}  // namespace depthfem

#pragma once
/// Exact gradient and Hessian of the pair penalty W = tet_polygon_penalty (penalty.hpp) with
/// respect to z = (P0, ..., P3, Q0, Q1, Q2) (21 coordinates), by a staged chain rule (paper
/// figure 7) in place of automatic differentiation over all 21 variables.
///
/// The depth field of the tet is linear, so every polygon vertex with its depth, y_k = (R_k, G_k),
/// interpolates two "extended corners" Y_i = (x_i, gamma_i) (position and depth) with the
/// vertex's crossing parameter t_k (penalty.hpp, vertex_corners):
///   y_k = Y_A + t_k (Y_B - Y_A)          (a triangle corner inside the tet: y_k = Y_A),
/// with corner depths gamma_j = g_j at the tet corners (constants) and gamma = g0 + a . (Q - P0)
/// at the triangle corners. W is therefore F(u), the fan energy of the y_k, each bilinear in
/// u = (x, gamma, t); only s = (gamma_Q0, gamma_Q1, gamma_Q2, t_0, t_1, ...) depend nonlinearly
/// on z, each on at most 15 coordinates. With S = ds/dz (one row per intermediate):
///   dW/dz     = F_x + S^T F_s
///   d2W/dz2   = F_xx + F_xs S + S^T F_sx + S^T F_ss S + sum_r F_{s_r} d2 s_r/dz2.

#include <array>

#include "contact/clip.hpp"

namespace depthfem {

using PairGradient = Eigen::Matrix<double, 21, 1>;
using PairHessian = Eigen::Matrix<double, 21, 21>;

/// W = tet_polygon_penalty(poly, P, Q, g, eps, min_area2) (returned, with the same value as the
/// double evaluation), its gradient into `gradient` and, where `hessian` is not null, its Hessian.
/// Variables: tet corners P at 0..11, triangle corners Q at 12..20. Fan triangles that do not
/// count for the energy (fan_triangle_counts) contribute no derivatives either.
double tet_polygon_penalty_derivatives(const ClipPolygon& poly, const std::array<Vec3, 4>& P,
                                       const std::array<Vec3, 3>& Q, const std::array<double, 4>& g,
                                       double eps, double min_area2, PairGradient& gradient,
                                       PairHessian* hessian);

/// An obstacle's depth at a point (positive inside) with its gradient [-] and Hessian [1/m] there.
struct DepthSample {
  double value = 0;
  Vec3 gradient = Vec3::Zero();
  Mat3 hessian = Mat3::Zero();
};

using TriangleGradient = Eigen::Matrix<double, 9, 1>;
using TriangleHessian = Eigen::Matrix<double, 9, 9>;

/// W = field_polygon_penalty(poly, Q, G, eps, min_area2) (penalty.hpp) for a triangle Q in an
/// obstacle's depth field, G_i = depth[i].value, returned with its gradient over the 9 corner
/// coordinates and, where `hessian` is not null, its Hessian. The corner depths follow the field
/// (depth[i] gives its derivatives at Q_i), and so do the crossings where the depth is zero: the
/// staged chain rule of tet_polygon_penalty_derivatives with the field's depths in place of the
/// tet's.
double field_polygon_penalty_derivatives(const ClipPolygon& poly, const std::array<Vec3, 3>& Q,
                                         const std::array<DepthSample, 3>& depth, double eps,
                                         double min_area2, TriangleGradient& gradient,
                                         TriangleHessian* hessian);

}  // namespace depthfem

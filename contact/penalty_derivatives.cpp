#include "contact/penalty_derivatives.hpp"

#include <cmath>
#include <cstdint>

#include "contact/penalty.hpp"

namespace depthfem {

namespace {

constexpr int kMaxVertices = 8;  // capacity of a ClipPolygon

using Vec4 = Eigen::Vector4d;
using Mat4 = Eigen::Matrix4d;

// The variables of a penalty with C extended corners (position and depth), of which the first
// kFixed have constant depths: u = (x_0, ..., x_C-1, gamma_0, ..., gamma_C-1, t_0, ..., t_7),
// the positions (z, kZ of them), the corner depths from kGamma on, the parameter of the k-th
// crossing vertex at kT + k; s = u[kS, kU) are the intermediates nonlinear in z.
template <int C, int kFixed>
struct Layout {
  static constexpr int kCorners = C;
  static constexpr int kZ = 3 * C;
  static constexpr int kGamma = kZ;
  static constexpr int kT = kGamma + C;
  static constexpr int kU = kT + kMaxVertices;
  static constexpr int kS = kGamma + kFixed;
  static constexpr int kMaxS = kU - kS;
  // Matrices over z get rows up to a whole number of packets where the padding rows (constant
  // depths) lie before the intermediates, so that columns are whole packets.
  static constexpr int kRows = (kZ + 3) / 4 * 4 <= kS ? (kZ + 3) / 4 * 4 : kZ;
  using VecU = Eigen::Matrix<double, kU, 1>;
  using MatU = Eigen::Matrix<double, kU, kU>;
  using VecS = Eigen::Matrix<double, kMaxS, 1>;
  using Tall = Eigen::Matrix<double, kRows, kMaxS>;  // S^T = (ds/dz)^T, a column per intermediate
};
// A tet (corners 0..3, depths given) and a triangle (corners 4..6, depths from the tet's field).
using TetPair = Layout<7, 4>;
// A triangle in an obstacle's depth field (corner depths nonlinear in the positions).
using FieldTriangle = Layout<3, 0>;

Vec3 vec(const V3<double>& v) {
  return {v.x, v.y, v.z};
}

// [v]x, the matrix of w -> v x w.
Mat3 skew(const Vec3& v) {
  Mat3 m;
  m << 0, -v(2), v(1), v(2), 0, -v(0), -v(1), v(0), 0;
  return m;
}

// Polygon vertex k with its depth: y_k = (R_k, G_k) = (1 - t) Y_A + t Y_B.
struct Vertex {
  VertexCorners corners;
  double t = 0;
  int terms = 1;                       // extended corners y_k depends on: Y_A (and Y_B)
  std::array<double, 2> weight{1, 0};  // dy_k/dY_A = (1 - t) I, dy_k/dY_B = t I
  int u_t = -1;                        // u index of t; -1 for a triangle corner
  Vec4 y, dy_dt;                       // y_k and dy_k/dt = Y_B - Y_A
  int corner(int m) const { return m == 0 ? corners.A : corners.B; }
};

// The values of every stage at z: corner positions and depths, and the polygon's vertices.
template <class L>
struct Stages {
  std::array<Vec3, L::kCorners> x;
  std::array<double, L::kCorners> gamma;
  int size = 0, crossings = 0;
  std::array<Vertex, kMaxVertices> vertex;

  // Makes polygon vertex k the crossing of corners A and B at parameter t (position R, depth G).
  void set_crossing(int k, int A, int B, double t, const Vec3& R, double G) {
    Vertex& v = vertex[k];
    v.corners.A = A, v.corners.B = B;
    v.t = t;
    v.terms = 2;
    v.weight = {1 - t, t};
    v.u_t = L::kT + crossings++;
    v.dy_dt << x[B] - x[A], gamma[B] - gamma[A];
    // Entry by entry: `v.y << R, G` from a temporary R drew GCC 12's -Warray-bounds (a 4-wide
    // load from its 24 bytes).
    v.y = Vec4(R(0), R(1), R(2), G);
  }
  // Makes polygon vertex k corner A itself.
  void set_corner(int k, int A) {
    vertex[k].corners.A = vertex[k].corners.B = A;
    vertex[k].y << x[A], gamma[A];
  }
};

// The tet-pair stages, computed as tet_polygon_penalty computes them, and the gradient a of the
// tet's depth field.
Stages<TetPair> tet_pair_stages(const ClipPolygon& poly, const std::array<Vec3, 4>& P,
                                const std::array<Vec3, 3>& Q, const std::array<double, 4>& g,
                                Vec3& a_out) {
  Stages<TetPair> s;
  std::array<V3<double>, TetPair::kCorners> X;  // as tet_polygon_penalty's point type
  std::array<V3<double>, 4> Pv;
  for (int i = 0; i < TetPair::kCorners; ++i) {
    s.x[i] = i < 4 ? P[i] : Q[i - 4];
    X[i] = make_point<double>(s.x[i], 0);
    if (i < 4) Pv[i] = X[i];
  }
  const V3<double> a = depth_gradient(Pv, g);
  a_out = vec(a);
  const auto depth_at = [&](const V3<double>& r) { return a.dot(r - X[0]) + g[0]; };
  for (int i = 0; i < TetPair::kCorners; ++i) s.gamma[i] = i < 4 ? g[i] : depth_at(X[i]);
  s.size = poly.size;
  for (int k = 0; k < poly.size; ++k) {
    const VertexCorners c = vertex_corners(poly.vertex[k]);
    if (!c.crossing()) {
      s.set_corner(k, c.A);
      continue;
    }
    const double t = crossing_parameter(X[c.A], X[c.B], X[c.C[0]], X[c.C[1]], X[c.C[2]]);
    const V3<double> R = segment_point(X[c.A], X[c.B], t);
    s.set_crossing(k, c.A, c.B, t, vec(R), depth_at(R));
    s.vertex[k].corners.C = c.C;
  }
  return s;
}

// The stages of a triangle in an obstacle's depth field, as field_polygon_penalty computes them:
// a crossing of edge (a, b) sits at t = G_a / (G_a - G_b) with depth 0. Its depth is also
// (1 - t) gamma_a + t gamma_b, identically in z, so the derivatives may follow that form.
Stages<FieldTriangle> field_triangle_stages(const ClipPolygon& poly, const std::array<Vec3, 3>& Q,
                                            const std::array<DepthSample, 3>& depth) {
  Stages<FieldTriangle> s;
  for (int i = 0; i < 3; ++i) s.x[i] = Q[i], s.gamma[i] = depth[i].value;
  s.size = poly.size;
  for (int k = 0; k < poly.size; ++k) {
    const ClipVertex& v = poly.vertex[k];
    if (v.kind == ClipVertex::Kind::kTriangleVertex) {
      s.set_corner(k, v.a);
      continue;
    }
    const double t = s.gamma[v.a] / (s.gamma[v.a] - s.gamma[v.b]);
    s.set_crossing(k, v.a, v.b, t, Q[v.a] + (Q[v.b] - Q[v.a]) * t, 0.0);
  }
  return s;
}

// Derivatives of a fan triangle's w = kappa A q (kappa = eps / 12) with respect to its vertices
// y_i = (R_i, G_i), i = 0, 1, 2 (indices mod 3):
//   c = (R1 - R0) x (R2 - R0) = sum_i R_i x R_{i+1},  n = c / |c|,  A = |c| / 2;
//   q = sum_i G_i^2 + sum_{i<j} G_i G_j:  dq/dG_i = G_i + sum_j G_j,  d2q/dG_i dG_j = 1 + delta_ij;
//   dc = sum_i dR_i x e_i with e_i = R_{i+1} - R_{i+2}, so dA/dR_i = (e_i x n) / 2;
//   d2A = dc^T (I - n n^T) dc / (2 |c|) + n . d2c / 2: only out-of-plane motions turn c, which
//   gives (e_i . e_j) n n^T / (2 |c|) for the block (i, j), and the bilinear c adds -[n]x / 2 to
//   the block (i, i + 1) and [n]x / 2 to the block (i + 1, i).
struct FanTriangle {
  std::array<Vec4, 3> gradient;
  std::array<std::array<Mat4, 3>, 3> hessian;
};

void fan_triangle_derivatives(const std::array<const Vec4*, 3>& y, double kappa, bool with_hessian,
                              FanTriangle& d) {
  std::array<Vec3, 3> R, e, dA;
  std::array<double, 3> G;
  for (int i = 0; i < 3; ++i) R[i] = y[i]->head<3>(), G[i] = (*y[i])(3);
  const Vec3 c = (R[1] - R[0]).cross(R[2] - R[0]);
  const double length = c.norm(), area = 0.5 * length;
  const Vec3 n = c / length;
  const double sum = G[0] + G[1] + G[2];
  const double q =
      G[0] * G[0] + G[1] * G[1] + G[2] * G[2] + G[0] * G[1] + G[0] * G[2] + G[1] * G[2];
  for (int i = 0; i < 3; ++i) {
    e[i] = R[(i + 1) % 3] - R[(i + 2) % 3];
    dA[i] = 0.5 * e[i].cross(n);
    d.gradient[i] << kappa * q * dA[i], kappa * area * (G[i] + sum);
  }
  if (!with_hessian) return;
  const Mat3 nn = n * n.transpose() / (2 * length), half_skew = 0.5 * skew(n);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      Mat3 d2A = e[i].dot(e[j]) * nn;
      if (j == (i + 1) % 3) d2A -= half_skew;
      if (i == (j + 1) % 3) d2A += half_skew;
      Mat4& h = d.hessian[i][j];
      h.topLeftCorner<3, 3>() = kappa * q * d2A;
      h.topRightCorner<3, 1>() = kappa * (G[j] + sum) * dA[i];
      h.bottomLeftCorner<1, 3>() = kappa * (G[i] + sum) * dA[j].transpose();
      h(3, 3) = kappa * area * (i == j ? 2 : 1);
    }
}

// v += w at the u entries of extended corner i: x_i (3 i, 3 i + 1, 3 i + 2) and gamma_i.
template <class L, class V>
void add_at_corner(V&& v, int i, const Vec4& w) {
  v.template segment<3>(3 * i) += w.head<3>();
  v(L::kGamma + i) += w(3);
}

// F_u += (dy_k/du)^T F_y.
template <class L>
void add_gradient(const Vertex& v, const Vec4& Fy, typename L::VecU& Fu) {
  for (int m = 0; m < v.terms; ++m) add_at_corner<L>(Fu, v.corner(m), v.weight[m] * Fy);
  if (v.u_t >= 0) Fu(v.u_t) += v.dy_dt.dot(Fy);
}

// F_uu is symmetric, and what is read of it are its rows of positions (F_xx, F_xs) and its block
// of intermediates (F_ss): the rows of depths and crossing parameters are filled in the columns
// of depths and parameters only.

// F_uu += (dy_k/du)^T H (dy_l/du), H = d2F/dy_k dy_l.
template <class L>
void add_hessian(const Vertex& vk, const Vertex& vl, const Mat4& H, typename L::MatU& Hu) {
  constexpr int kGamma = L::kGamma;
  for (int m = 0; m < vk.terms; ++m)
    for (int p = 0; p < vl.terms; ++p) {
      const int i = vk.corner(m), j = vl.corner(p);
      const Mat4 w = (vk.weight[m] * vl.weight[p]) * H;
      Hu.template block<3, 3>(3 * i, 3 * j) += w.topLeftCorner<3, 3>();
      Hu.template block<3, 1>(3 * i, kGamma + j) += w.topRightCorner<3, 1>();
      Hu(kGamma + i, kGamma + j) += w(3, 3);
    }
  if (vk.u_t >= 0) {
    const double row = H.col(3).dot(vk.dy_dt);  // (dy_k/dt)^T H at the depth of y_l
    for (int p = 0; p < vl.terms; ++p) Hu(vk.u_t, kGamma + vl.corner(p)) += vl.weight[p] * row;
  }
  if (vl.u_t >= 0) {
    const Vec4 col = H * vl.dy_dt;
    for (int m = 0; m < vk.terms; ++m)
      add_at_corner<L>(Hu.col(vl.u_t), vk.corner(m), vk.weight[m] * col);
    if (vk.u_t >= 0) Hu(vk.u_t, vl.u_t) += vk.dy_dt.dot(col);
  }
}

// F_uu += F_y . d2y_k/du2: y_k = Y_A + t (Y_B - Y_A) is bilinear in t and Y, with
// d2y_k/dt dY_A = -I and d2y_k/dt dY_B = I.
template <class L>
void add_curvature(const Vertex& v, const Vec4& Fy, typename L::MatU& Hu) {
  if (v.u_t < 0) return;
  for (int m = 0; m < 2; ++m) {
    const double sign = m == 0 ? -1 : 1;
    add_at_corner<L>(Hu.col(v.u_t), v.corner(m), sign * Fy);
    Hu(v.u_t, L::kGamma + v.corner(m)) += sign * Fy(3);
  }
}

// The parameter t of a crossing vertex solves phi(z, t) = V(C0, C1, C2, A + t (B - A)) = 0 with
// V(p0, p1, p2, p3) = det[p1 - p0, p2 - p0, p3 - p0] (= d at p3: six signed volumes). By the
// implicit-function theorem, with D = -phi_t = d_A - d_B = m . (A - B), m = (C1 - C0) x (C2 - C0):
//   dt/dz = phi_z / D,   d2t/dz2 = (phi_zz - dD dt^T - dt dD^T) / D,
// where phi_z, phi_zz are the derivatives of V at p3 = R with t fixed: the p3 parts go to A with
// weight 1 - t and to B with weight t.
struct Crossing {
  std::array<int, 3> C;
  int A = 0, B = 0;
  double t = 0;
  std::array<Vec3, 4> p;   // C0, C1, C2, R
  std::array<Vec3, 4> dV;  // dV/dp_i: e2 x e3, e3 x e1, e1 x e2 = m at p1..p3 (e_i = p_i - p0),
                           // minus their sum at p0
  Vec3 r;                  // A - B
  double D = 0;            // m . r
};

Crossing crossing_geometry(const Vertex& v, const Stages<TetPair>& s) {
  Crossing k;
  k.C = v.corners.C;
  k.A = v.corners.A;
  k.B = v.corners.B;
  k.t = v.t;
  k.p = {s.x[k.C[0]], s.x[k.C[1]], s.x[k.C[2]], v.y.head<3>()};
  const Vec3 e1 = k.p[1] - k.p[0], e2 = k.p[2] - k.p[0], e3 = k.p[3] - k.p[0];
  k.dV = {Vec3::Zero(), e2.cross(e3), e3.cross(e1), e1.cross(e2)};
  k.dV[0] = -(k.dV[1] + k.dV[2] + k.dV[3]);
  k.r = s.x[k.A] - s.x[k.B];
  k.D = k.dV[3].dot(k.r);
  return k;
}

// Column r of S^T: dt/dz.
void crossing_gradient(const Crossing& k, int r, TetPair::Tall& St) {
  for (int i = 0; i < 3; ++i) St.block<3, 1>(3 * k.C[i], r) = k.dV[i] / k.D;
  St.block<3, 1>(3 * k.A, r) = (1 - k.t) / k.D * k.dV[3];
  St.block<3, 1>(3 * k.B, r) = k.t / k.D * k.dV[3];
}

// v += w dD/dz: D = m . r with m = e1 x e2 gives e2 x r at C1, r x e1 at C2, minus both at C0,
// m at A and -m at B.
template <class V>
void add_denominator_gradient(const Crossing& k, double w, V&& v) {
  const Vec3 e1 = k.p[1] - k.p[0], e2 = k.p[2] - k.p[0];
  const Vec3 at_C1 = w * e2.cross(k.r), at_C2 = w * k.r.cross(e1);
  v.template segment<3>(3 * k.C[0]) -= at_C1 + at_C2;
  v.template segment<3>(3 * k.C[1]) += at_C1;
  v.template segment<3>(3 * k.C[2]) += at_C2;
  v.template segment<3>(3 * k.A) += w * k.dV[3];
  v.template segment<3>(3 * k.B) -= w * k.dV[3];
}

// H += [v]x at the block (i, j) and its transpose -[v]x at the block (j, i).
template <class M>
void add_skew_pair(M& H, int i, int j, const Vec3& v) {
  for (const auto& [a, b, c] :
       {std::array<int, 3>{0, 1, 2}, {1, 2, 0}, {2, 0, 1}}) {  // [v]x(a, b) = -v_c
    H(3 * i + a, 3 * j + b) -= v(c);
    H(3 * i + b, 3 * j + a) += v(c);
    H(3 * j + b, 3 * i + a) -= v(c);
    H(3 * j + a, 3 * i + b) += v(c);
  }
}

// d2V/dp_i dp_j = [p_k - p_l]x for each even permutation (i, j, k, l) of (0, 1, 2, 3) (V is
// a sum of triple products u . (v x w), whose block (u, v) is -[w]x); the block (j, i) is its
// transpose, and V is linear in each point, so there are no diagonal blocks.
constexpr int kVolumeHessian[6][4] = {{0, 1, 2, 3}, {0, 2, 3, 1}, {0, 3, 1, 2},
                                      {1, 2, 0, 3}, {1, 3, 2, 0}, {2, 3, 0, 1}};

// The fan level: W (returned), F_u and, where Hu is not null, F_uu, from each fan triangle's
// derivatives with respect to its y through y(u).
template <class L>
double fan_level(const Stages<L>& st, double eps, double min_area2, typename L::VecU& Fu,
                 typename L::MatU* Hu) {
  double W = 0;
  std::array<Vec4, kMaxVertices> Fy;  // dW/dy_k
  for (int k = 0; k < st.size; ++k) Fy[k].setZero();
  if (Hu) Hu->setZero();
  FanTriangle d;
  for (int k = 1; k + 1 < st.size; ++k) {
    const std::array<int, 3> fan = {0, k, k + 1};
    std::array<V3<double>, 3> R;
    std::array<double, 3> G;
    for (int i = 0; i < 3; ++i) {
      const Vec4& y = st.vertex[fan[i]].y;
      R[i] = {y(0), y(1), y(2)};
      G[i] = y(3);
    }
    W += triangle_penalty(R[0], R[1], R[2], G[0], G[1], G[2], eps, min_area2);
    const V3<double> c = area_vector(R[0], R[1], R[2]);
    if (!fan_triangle_counts(c.dot(c), min_area2)) continue;
    fan_triangle_derivatives({&st.vertex[fan[0]].y, &st.vertex[fan[1]].y, &st.vertex[fan[2]].y},
                             eps / 12, Hu != nullptr, d);
    for (int i = 0; i < 3; ++i) Fy[fan[i]] += d.gradient[i];
    if (!Hu) continue;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        add_hessian<L>(st.vertex[fan[i]], st.vertex[fan[j]], d.hessian[i][j], *Hu);
  }
  Fu.setZero();
  for (int k = 0; k < st.size; ++k) {
    add_gradient<L>(st.vertex[k], Fy[k], Fu);
    if (Hu) add_curvature<L>(st.vertex[k], Fy[k], *Hu);
  }
  return W;
}

// The intermediates s of a tet pair at z with S^T, and what their curvature terms need.
struct Intermediates {
  int count = 0;                           // 3 + crossings
  TetPair::Tall St;                        // zero columns past the last
  std::array<Vec3, 4> b;                   // gradients of the barycentric coordinates in the tet
  std::array<std::array<double, 4>, 3> l;  // l_j(Q_q)
  std::array<Crossing, kMaxVertices> crossing;
};

Intermediates intermediates(const Stages<TetPair>& st, const Vec3& a) {
  Intermediates s;
  s.St.setZero();
  // Triangle-corner depths gamma_q = sum_j l_j(Q_q) g_j, l_j the barycentric coordinates in the
  // tet with gradients b_j (rows of D^-1, D = [P1 - P0, P2 - P0, P3 - P0]; b_0 = -b_1 - b_2 - b_3).
  // Moving P_j by d changes the field as moving Q_q by -l_j d: dgamma_q/dQ_q = a,
  // dgamma_q/dP_j = -l_j(Q_q) a.
  Mat3 D;
  for (int j = 0; j < 3; ++j) D.col(j) = st.x[j + 1] - st.x[0];
  const Mat3 D_inv = D.inverse();
  for (int j = 1; j < 4; ++j) s.b[j] = D_inv.row(j - 1).transpose();
  s.b[0] = -(s.b[1] + s.b[2] + s.b[3]);
  for (int q = 0; q < 3; ++q) {
    s.l[q][0] = 1;
    for (int j = 1; j < 4; ++j) {
      s.l[q][j] = s.b[j].dot(st.x[4 + q] - st.x[0]);
      s.l[q][0] -= s.l[q][j];
    }
    for (int j = 0; j < 4; ++j) s.St.block<3, 1>(3 * j, q) = -s.l[q][j] * a;
    s.St.block<3, 1>(12 + 3 * q, q) = a;
  }
  s.count = 3 + st.crossings;
  for (int k = 0; k < st.size; ++k) {
    const Vertex& v = st.vertex[k];
    if (v.u_t < 0) continue;
    const int r = v.u_t - TetPair::kS;
    s.crossing[r - 3] = crossing_geometry(v, st);
    crossing_gradient(s.crossing[r - 3], r, s.St);
  }
  return s;
}

// Hxx += sum_r F_{s_r} d2s_r/dz2, except for the crossings' terms -mu (dD dt^T + dt dD^T),
// which enter as K(:, t) -= mu dD.
template <class Block, class KBlock>
void add_intermediate_curvature(const Vec3& a, const Intermediates& s, const TetPair::VecS& Fs,
                                Block& Hxx, KBlock& K) {
  constexpr int kCorners = TetPair::kCorners;
  // Crossings: F_t d2t/dz2 = mu (phi_zz - dD dt^T - dt dD^T) with mu = F_t / D. The skew blocks
  // of phi_zz are summed per pair of corners (i < j) first: [v]x at (i, j) is [-v]x at (j, i).
  std::array<Vec3, kCorners * kCorners> skew_sum;
  std::uint64_t touched = 0;  // bit i * kCorners + j: pair (i, j) has a sum
  const auto add_skew = [&](int i, int j, const Vec3& v) {
    const int pair = i < j ? i * kCorners + j : j * kCorners + i;
    if (!(touched >> pair & 1)) skew_sum[pair].setZero();
    touched |= std::uint64_t{1} << pair;
    skew_sum[pair] += i < j ? v : Vec3(-v);
  };
  for (int r = 3; r < s.count; ++r) {
    const Crossing& k = s.crossing[r - 3];
    const double mu = Fs(r) / k.D;
    for (const auto& [i, j, m, n] : kVolumeHessian) {
      const Vec3 v = mu * (k.p[m] - k.p[n]);
      if (j < 3) {
        add_skew(k.C[i], k.C[j], v);
      } else {
        add_skew(k.C[i], k.A, (1 - k.t) * v);
        add_skew(k.C[i], k.B, k.t * v);
      }
    }
    add_denominator_gradient(k, -mu, K.col(r));
  }
  for (int i = 0; i < kCorners; ++i)
    for (int j = i + 1; j < kCorners; ++j)
      if (touched >> (i * kCorners + j) & 1) add_skew_pair(Hxx, i, j, skew_sum[i * kCorners + j]);

  // Triangle-corner depths: with dl_j(Q)/dP_i = -l_i(Q) b_j and da/dP_i = -b_i a^T,
  //   d2gamma_q/dP_j dP_i = l_i(Q_q) a b_j^T + l_j(Q_q) b_i a^T,   d2gamma_q/dP_j dQ_q = -a b_j^T.
  std::array<double, 4> lambda{};  // sum_q F_{gamma_q} l_i(Q_q)
  for (int q = 0; q < 3; ++q)
    for (int i = 0; i < 4; ++i) lambda[i] += Fs(q) * s.l[q][i];
  for (int j = 0; j < 4; ++j) {
    for (int i = 0; i < 4; ++i)
      Hxx.template block<3, 3>(3 * j, 3 * i) +=
          lambda[i] * a * s.b[j].transpose() + lambda[j] * s.b[i] * a.transpose();
    for (int q = 0; q < 3; ++q) {
      const Mat3 block = Fs(q) * a * s.b[j].transpose();
      Hxx.template block<3, 3>(3 * j, 12 + 3 * q) -= block;
      Hxx.template block<3, 3>(12 + 3 * q, 3 * j) -= block.transpose();
    }
  }
}

// The intermediates of a triangle in an obstacle's depth field: s = (gamma_0, gamma_1, gamma_2,
// t_0, ...). gamma_i changes with Q_i as the field does (its gradient and Hessian at Q_i); a
// crossing of edge (a, b) has t = gamma_a / d with d = gamma_a - gamma_b, so that
//   dt/dgamma_a = -gamma_b / d^2,   dt/dgamma_b = gamma_a / d^2,
//   d2t/dgamma_a^2 = 2 gamma_b / d^3,   d2t/dgamma_b^2 = 2 gamma_a / d^3,
//   d2t/dgamma_a dgamma_b = -(gamma_a + gamma_b) / d^3.
struct FieldIntermediates {
  int count = 0;  // 3 + crossings
  FieldTriangle::Tall St;
  std::array<std::array<int, 2>, kMaxVertices> edge;    // (a, b) per crossing
  std::array<std::array<double, 2>, kMaxVertices> dt;   // dt/dgamma_a, dt/dgamma_b
  std::array<std::array<double, 3>, kMaxVertices> d2t;  // aa, ab, bb
};

FieldIntermediates field_intermediates(const Stages<FieldTriangle>& st,
                                       const std::array<DepthSample, 3>& depth) {
  FieldIntermediates s;
  s.St.setZero();
  for (int i = 0; i < 3; ++i) s.St.block<3, 1>(3 * i, i) = depth[i].gradient;
  s.count = 3;
  for (int k = 0; k < st.size; ++k) {
    const Vertex& v = st.vertex[k];
    if (v.u_t < 0) continue;
    const int c = s.count++ - 3, a = v.corners.A, b = v.corners.B;
    const double ga = st.gamma[a], gb = st.gamma[b], d = ga - gb;
    s.edge[c] = {a, b};
    s.dt[c] = {-gb / (d * d), ga / (d * d)};
    s.d2t[c] = {2 * gb / (d * d * d), -(ga + gb) / (d * d * d), 2 * ga / (d * d * d)};
    s.St.block<3, 1>(3 * a, 3 + c) = s.dt[c][0] * depth[a].gradient;
    s.St.block<3, 1>(3 * b, 3 + c) = s.dt[c][1] * depth[b].gradient;
  }
  return s;
}

// Hxx += sum_r F_{s_r} d2s_r/dz2 for a triangle in a depth field: F_gamma_i times the field's
// Hessian at Q_i, and for each crossing F_t (dt/dgamma . d2gamma + dgamma^T d2t/dgamma2 dgamma).
template <class Block>
void add_field_curvature(const FieldIntermediates& s, const std::array<DepthSample, 3>& depth,
                         const FieldTriangle::VecS& Fs, Block& Hxx) {
  for (int i = 0; i < 3; ++i) Hxx.template block<3, 3>(3 * i, 3 * i) += Fs(i) * depth[i].hessian;
  for (int c = 0; c + 3 < s.count; ++c) {
    const double w = Fs(3 + c);
    const auto [a, b] = s.edge[c];
    const Vec3 &ga = depth[a].gradient, &gb = depth[b].gradient;
    Hxx.template block<3, 3>(3 * a, 3 * a) +=
        w * (s.dt[c][0] * depth[a].hessian + s.d2t[c][0] * ga * ga.transpose());
    Hxx.template block<3, 3>(3 * b, 3 * b) +=
        w * (s.dt[c][1] * depth[b].hessian + s.d2t[c][2] * gb * gb.transpose());
    const Mat3 ab = (w * s.d2t[c][1]) * ga * gb.transpose();
    Hxx.template block<3, 3>(3 * a, 3 * b) += ab;
    Hxx.template block<3, 3>(3 * b, 3 * a) += ab.transpose();
  }
}

// The chain rule through the intermediates s (S^T = ds/dz, one column per intermediate, `count`
// of them): dW/dz = F_x + S^T F_s and, where `hessian` is not null,
//   d2W/dz2 = F_xx + K S + S^T K^T + sum_r F_{s_r} d2s_r/dz2,   K = F_xs + S^T F_ss / 2,
// accumulated in place of F_xx and F_xs in F_uu (padding rows, constant depths, are dropped).
// `curvature(Fs, Hxx, K)` adds the sum over r; a term -(v dt^T + dt v^T) of it may enter as
// K(:, t) -= v.
template <class L, class Curvature>
void chain_rule(const typename L::VecU& Fu, typename L::MatU* Hu, const typename L::Tall& St,
                int count, Curvature curvature, Eigen::Matrix<double, L::kZ, 1>& gradient,
                Eigen::Matrix<double, L::kZ, L::kZ>* hessian) {
  const typename L::VecS Fs = Fu.template tail<L::kMaxS>();
  gradient = Fu.template head<L::kZ>() + St.lazyProduct(Fs).template head<L::kZ>();
  if (!hessian) return;
  auto Hxx = Hu->template topLeftCorner<L::kRows, L::kZ>();
  auto K = Hu->template block<L::kRows, L::kMaxS>(0, L::kS);
  const auto Fss = Hu->template bottomRightCorner<L::kMaxS, L::kMaxS>();
  for (int r = 0; r < count; ++r)
    for (int r2 = 0; r2 < count; ++r2) K.col(r) += (0.5 * Fss(r2, r)) * St.col(r2);
  curvature(Fs, Hxx, K);
  // + K S + S^T K^T, a column at a time: column c gains sum_r K(:, r) S(r, c) + S^T(:, r) K(c, r).
  for (int c = 0; c < L::kZ; ++c) {
    Eigen::Matrix<double, L::kRows, 1> column = Hxx.col(c);
    for (int r = 0; r < count; ++r) column += St(c, r) * K.col(r) + K(c, r) * St.col(r);
    hessian->col(c) = column.template head<L::kZ>();
  }
}

// W with its derivatives over z: zero for a polygon without area; otherwise the fan level over
// u from the stage values, then the chain rule through the intermediates that `intermediates(st)`
// gives (their S^T and count), with the curvature terms `curvature(s, Fs, Hxx, K)` adds.
template <class L, class StagesFn, class IntermediatesFn, class CurvatureFn>
double staged_penalty(const ClipPolygon& poly, double eps, double min_area2, StagesFn stages,
                      IntermediatesFn intermediates, CurvatureFn curvature,
                      Eigen::Matrix<double, L::kZ, 1>& gradient,
                      Eigen::Matrix<double, L::kZ, L::kZ>* hessian) {
  if (poly.size < 3) {
    gradient.setZero();
    if (hessian) hessian->setZero();
    return 0;
  }
  const Stages<L> st = stages();
  typename L::MatU Hu;
  typename L::VecU Fu;
  const double W = fan_level(st, eps, min_area2, Fu, hessian ? &Hu : nullptr);
  const auto s = intermediates(st);
  chain_rule<L>(
      Fu, &Hu, s.St, s.count,
      [&](const typename L::VecS& Fs, auto& Hxx, auto& K) { curvature(s, Fs, Hxx, K); }, gradient,
      hessian);
  return W;
}

}  // namespace

double tet_polygon_penalty_derivatives(const ClipPolygon& poly, const std::array<Vec3, 4>& P,
                                       const std::array<Vec3, 3>& Q, const std::array<double, 4>& g,
                                       double eps, double min_area2, PairGradient& gradient,
                                       PairHessian* hessian) {
  Vec3 a;  // gradient of the tet's depth field
  return staged_penalty<TetPair>(
      poly, eps, min_area2, [&] { return tet_pair_stages(poly, P, Q, g, a); },
      [&](const Stages<TetPair>& st) { return intermediates(st, a); },
      [&](const Intermediates& s, const TetPair::VecS& Fs, auto& Hxx, auto& K) {
        add_intermediate_curvature(a, s, Fs, Hxx, K);
      },
      gradient, hessian);
}

double field_polygon_penalty_derivatives(const ClipPolygon& poly, const std::array<Vec3, 3>& Q,
                                         const std::array<DepthSample, 3>& depth, double eps,
                                         double min_area2, TriangleGradient& gradient,
                                         TriangleHessian* hessian) {
  return staged_penalty<FieldTriangle>(
      poly, eps, min_area2, [&] { return field_triangle_stages(poly, Q, depth); },
      [&](const Stages<FieldTriangle>& st) { return field_intermediates(st, depth); },
      [&](const FieldIntermediates& s, const FieldTriangle::VecS& Fs, auto& Hxx, auto&) {
        add_field_curvature(s, depth, Fs, Hxx);
      },
      gradient, hessian);
}

}  // namespace depthfem

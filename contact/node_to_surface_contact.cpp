#include "contact/node_to_surface_contact.hpp"

#include "contact/material_depth.hpp"
#include "contact/penalty.hpp"

namespace depthfem {

namespace {

// Penalty of node p against the plane of triangle (q0, q1, q2): eps A / 2 g^2 for g > 0.
template <class S>
S node_energy(const V3<S>& p, const V3<S>& q0, const V3<S>& q1, const V3<S>& q2, double eps_area) {
  using std::sqrt;
  const V3<S> c = (q1 - q0).cross(q2 - q0);
  const S g = c.dot(q0 - p) * inverse_of(sqrt(c.dot(c)));
  if (value_of(g) <= 0) return S(0.0);
  return g * g * (0.5 * eps_area);
}

}  // namespace

NodeToSurfaceContact::NodeToSurfaceContact(const Mesh& mesh, double penalty)
    : tets_(mesh.tets),
      tris_(mesh.tris),
      tet_body_(mesh.tet_body),
      tri_body_(mesh.tri_body),
      penalty_(penalty),
      interfaces_(mesh.bodies, false) {
  node_area_ = VectorX::Zero(mesh.num_nodes());
  node_body_ = IndexVector::Constant(mesh.num_nodes(), -1);
  for (Index f = 0; f < tris_.rows(); ++f) {
    const Vec3 a = mesh.X.row(tris_(f, 0)), b = mesh.X.row(tris_(f, 1)),
               c = mesh.X.row(tris_(f, 2));
    const double third = (b - a).cross(c - a).norm() / 6;
    for (int k = 0; k < 3; ++k) {
      node_area_(tris_(f, k)) += third;
      node_body_(tris_(f, k)) = tri_body_(f);
    }
  }
  for (Index i = 0; i < mesh.num_nodes(); ++i)
    if (node_area_(i) > 0) surface_nodes_.push_back(i);
  begin_step(mesh.X);
}

void NodeToSurfaceContact::begin_step(const Points& x) {
  tet_tree_ = AabbTree(tet_boxes(x, tets_));
  tri_tree_ = AabbTree(triangle_boxes(x, tris_));
}

void NodeToSurfaceContact::prepare(const Points& x) {
  tet_tree_.refit(tet_boxes(x, tets_));
  tri_tree_.refit(triangle_boxes(x, tris_));
  pairs_.clear();
  for (Index i : surface_nodes_) {
    const Vec3 p = x.row(i);
    // Inside another body: in one of its tets (barycentric coordinates all >= 0).
    Index inside = -1;
    tet_tree_.query(Box3(p, p), [&](Index t) {
      if (inside >= 0 || tet_body_(t) == node_body_(i)) return;
      Mat3 D;
      for (int k = 0; k < 3; ++k) D.col(k) = x.row(tets_(t, k + 1)) - x.row(tets_(t, 0));
      const Vec3 l = D.inverse() * (p - Vec3(x.row(tets_(t, 0))));
      if (l.minCoeff() >= 0 && l.sum() <= 1) inside = tet_body_(t);
    });
    if (inside < 0) continue;
    // Projection: the nearest boundary triangle of that body.
    Index nearest = -1;
    double best = std::numeric_limits<double>::infinity();
    tri_tree_.nearest(p, best, [&](Index f, double) {
      if (tri_body_(f) != inside) return best;
      const double d = (closest_point_on_triangle(p, x.row(tris_(f, 0)), x.row(tris_(f, 1)),
                                                  x.row(tris_(f, 2))) -
                        p)
                           .squaredNorm();
      if (d < best) best = d, nearest = f;
      return best;
    });
    if (nearest >= 0) pairs_.emplace_back(i, nearest);
  }
  pattern_changed_ = false;
  if (bound_) {
    for (const auto& [i, f] : pairs_)
      for (int k = 0; k < 3; ++k)
        if (bound_->block_index(i, tris_(f, k)) < 0) pattern_changed_ = true;
  }
}

void NodeToSurfaceContact::add_couplings(SparsityBuilder& builder) const {
  for (const auto& [i, f] : pairs_) {
    const Index v[4] = {i, tris_(f, 0), tris_(f, 1), tris_(f, 2)};
    builder.add_clique(v);
  }
}

void NodeToSurfaceContact::bind(const BlockSparseMatrix& hessian) {
  bound_ = &hessian;
  pattern_changed_ = false;
}

double NodeToSurfaceContact::evaluate(const Points& x, VectorX* gradient,
                                      BlockSparseMatrix* hessian) const {
  using D = Dual2<12>;
  double energy = 0;
  for (const auto& [i, f] : pairs_) {
    const Index v[4] = {i, tris_(f, 0), tris_(f, 1), tris_(f, 2)};
    const double eps_area = penalty_ * node_area_(i);
    if (!gradient) {
      energy += node_energy(make_point<double>(x.row(v[0]), 0), make_point<double>(x.row(v[1]), 0),
                            make_point<double>(x.row(v[2]), 0), make_point<double>(x.row(v[3]), 0),
                            eps_area);
      continue;
    }
    const D W = pair_derivatives(x, i, f);
    energy += W.v;
    for (int a = 0; a < 4; ++a) {
      gradient->segment<3>(3 * v[a]) += W.g.segment<3>(3 * a);
      if (!hessian) continue;
      for (int b = 0; b < 4; ++b)
        hessian->add_block(hessian->block_index(v[a], v[b]), W.h.block<3, 3>(3 * a, 3 * b));
    }
  }
  return energy;
}

Dual2<12> NodeToSurfaceContact::pair_derivatives(const Points& x, Index i, Index f) const {
  using D = Dual2<12>;
  return node_energy(make_point<D>(x.row(i), 0), make_point<D>(x.row(tris_(f, 0)), 3),
                     make_point<D>(x.row(tris_(f, 1)), 6), make_point<D>(x.row(tris_(f, 2)), 9),
                     penalty_ * node_area_(i));
}

void NodeToSurfaceContact::report(const Points& x, StepRecord& step) const {
  ContactInterfaces::Tally tally = interfaces_.tally(step);
  for (const auto& [i, f] : pairs_) {
    const Vec3 on_node = -pair_derivatives(x, i, f).g.head<3>();
    tally.add(node_body_(i), tri_body_(f), on_node, node_area_(i));
  }
  tally.finish();
}

}  // namespace depthfem

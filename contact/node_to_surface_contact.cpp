#include "contact/node_to_surface_contact.hpp"

#include <stdexcept>

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
  std::vector<std::pair<Index, Index>> pairs;
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
    if (nearest >= 0) pairs.emplace_back(i, nearest);
  }
  // Processing order: colored chunks along a Morton curve (PairSchedule).
  const Index n = static_cast<Index>(pairs.size());
  PairSchedule::Nodes nodes(n, 4);
  Points centres(n, 3);
  for (Index k = 0; k < n; ++k) {
    const auto [i, f] = pairs[k];
    nodes.row(k) << i, tris_(f, 0), tris_(f, 1), tris_(f, 2);
    centres.row(k) = x.row(i);
  }
  const std::vector<Index> order =
      schedule_.arrange(nodes, centres, static_cast<Index>(x.rows()), bound_);
  pairs_.resize(pairs.size());
  for (Index k = 0; k < n; ++k) pairs_[k] = pairs[order[k]];
  // Missing couplings in the bound pattern need a new one (bind() follows).
  pattern_changed_ = bound_ && !schedule_.has_blocks();
}

void NodeToSurfaceContact::add_couplings(SparsityBuilder& builder) const {
  schedule_.add_couplings(builder);
}

void NodeToSurfaceContact::bind(const BlockSparseMatrix& hessian) {
  bound_ = &hessian;
  pattern_changed_ = false;
  schedule_.bind(hessian, name());
}

double NodeToSurfaceContact::pair_energy(const Points& x, Index k) const {
  return node_energy(make_point<double>(x.row(schedule_.node(k, 0)), 0),
                     make_point<double>(x.row(schedule_.node(k, 1)), 0),
                     make_point<double>(x.row(schedule_.node(k, 2)), 0),
                     make_point<double>(x.row(schedule_.node(k, 3)), 0),
                     penalty_ * node_area_(schedule_.node(k, 0)));
}

double NodeToSurfaceContact::evaluate(const Points& x, VectorX* gradient,
                                      BlockSparseMatrix* hessian) const {
  if (!gradient) return schedule_.run(0.0, [&](Index k) { return pair_energy(x, k); });
  if (hessian && !schedule_.has_blocks())
    throw std::logic_error("node-to-surface contact: bind() the Hessian after prepare()");
  return schedule_.run(0.0, [&](Index k) {
    const Dual2<12> W = pair_derivatives(x, pairs_[k].first, pairs_[k].second);
    for (int a = 0; a < 4; ++a)
      gradient->segment<3>(3 * schedule_.node(k, a)) += W.g.segment<3>(3 * a);
    if (hessian) hessian->add_blocks<4>(schedule_.blocks(k), W.h);
    return W.v;
  });
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

#include "contact/obstacle_contact.hpp"

#include <stdexcept>

#include "contact/contact_surface.hpp"
#include "contact/penalty.hpp"
#include "core/error.hpp"
#include "core/overloaded.hpp"

namespace depthfem {

namespace {

// Depth of point q into the obstacle at load factor `load` (positive inside), with its gradient
// and Hessian in q: a plane's depth n . (a - q) is linear; a sphere's R - |q - c| has gradient
// -m and Hessian -(I - m m^T) / |q - c|, m = (q - c) / |q - c|.
DepthSample obstacle_depth(const Obstacle& o, double load, const Vec3& q) {
  const Vec3 shift = load * o.motion;
  DepthSample d;
  std::visit(Overloaded{[&](const PlaneObstacle& p) {
                          const Vec3 n = p.normal.normalized();
                          d.value = n.dot(p.point + shift - q);
                          d.gradient = -n;
                        },
                        [&](const SphereObstacle& s) {
                          const Vec3 r = q - (s.center + shift);
                          const double length = r.norm();
                          const Vec3 m = r / length;
                          d.value = s.radius - length;
                          d.gradient = -m;
                          d.hessian = -(Mat3::Identity() - m * m.transpose()) / length;
                        }},
             o.shape);
  return d;
}

}  // namespace

ObstacleContact::ObstacleContact(const Mesh& mesh, const std::vector<Index>& bodies,
                                 std::vector<Obstacle> obstacles)
    : obstacles_(std::move(obstacles)) {
  for (const Obstacle& o : obstacles_) {
    if (!(o.penalty > 0)) throw InputError("obstacle '" + o.name + "': penalty must be > 0");
    std::visit(Overloaded{[&](const PlaneObstacle& p) {
                            if (!(p.normal.norm() > 0))
                              throw InputError("obstacle '" + o.name + "': zero normal");
                          },
                          [&](const SphereObstacle& s) {
                            if (!(s.radius > 0))
                              throw InputError("obstacle '" + o.name + "': radius must be > 0");
                          }},
               o.shape);
  }
  std::vector<Index> rows;
  for (Index b : bodies) {
    const Body& body = mesh.bodies.at(static_cast<size_t>(b));
    for (Index f = body.first_tri; f < body.first_tri + body.num_tris; ++f) rows.push_back(f);
  }
  tris_.resize(static_cast<Index>(rows.size()), 3);
  for (size_t k = 0; k < rows.size(); ++k)
    tris_.row(static_cast<Index>(k)) = mesh.tris.row(rows[k]);
  tri_ids_ = rows;
  num_mesh_tris_ = mesh.num_tris();
}

void ObstacleContact::set_load(double load) {
  load_ = load;
}

void ObstacleContact::prepare(const Points& x) {
  std::vector<std::pair<Index, Index>> active;
  for (Index o = 0; o < static_cast<Index>(obstacles_.size()); ++o)
    for (Index f = 0; f < tris_.rows(); ++f)
      for (int k = 0; k < 3; ++k)
        if (obstacle_depth(obstacles_[o], load_, x.row(tris_(f, k))).value > 0) {
          active.emplace_back(o, f);
          break;
        }
  // Processing order: colored chunks along a Morton curve; all triangles are coupled in the
  // pattern, so a bound pattern has every block.
  const Index n = static_cast<Index>(active.size());
  PairSchedule::Nodes nodes(n, 3);
  Points centres(n, 3);
  for (Index k = 0; k < n; ++k) {
    nodes.row(k) = tris_.row(active[k].second);
    centres.row(k) = (x.row(nodes(k, 0)) + x.row(nodes(k, 1)) + x.row(nodes(k, 2))) / 3;
  }
  const std::vector<Index> order =
      schedule_.arrange(nodes, centres, static_cast<Index>(x.rows()), bound_);
  active_.resize(active.size());
  for (Index k = 0; k < n; ++k) active_[k] = active[order[k]];
}

void ObstacleContact::bind(const BlockSparseMatrix& hessian) {
  bound_ = &hessian;
  schedule_.bind(hessian, name());
}

void ObstacleContact::add_couplings(SparsityBuilder& builder) const {
  // Any boundary triangle may touch an obstacle: couple all of them once, so that the pattern
  // never changes.
  for (Index f = 0; f < tris_.rows(); ++f) {
    const Index v[3] = {tris_(f, 0), tris_(f, 1), tris_(f, 2)};
    builder.add_clique(v);
  }
}

double ObstacleContact::triangle_derivatives(const Points& x, Index o, Index f,
                                             TriangleGradient* gradient,
                                             TriangleHessian* hessian) const {
  std::array<Vec3, 3> Q;
  std::array<DepthSample, 3> depth;
  for (int k = 0; k < 3; ++k) {
    Q[k] = x.row(tris_(f, k));
    depth[k] = obstacle_depth(obstacles_[o], load_, Q[k]);
  }
  const ClipPolygon poly =
      clip_triangle_by_field(Q, {depth[0].value, depth[1].value, depth[2].value});
  if (!gradient) {
    std::array<V3<double>, 3> Qv;
    for (int k = 0; k < 3; ++k) Qv[k] = make_point<double>(Q[k], 0);
    return field_polygon_penalty(poly, Qv, {depth[0].value, depth[1].value, depth[2].value},
                                 obstacles_[o].penalty, 0.0);
  }
  return field_polygon_penalty_derivatives(poly, Q, depth, obstacles_[o].penalty, 0.0, *gradient,
                                           hessian);
}

double ObstacleContact::evaluate(const Points& x, VectorX* gradient,
                                 BlockSparseMatrix* hessian) const {
  if (!gradient) {
    return schedule_.run(0.0, [&](Index k) {
      return triangle_derivatives(x, active_[k].first, active_[k].second, nullptr, nullptr);
    });
  }
  if (hessian && !schedule_.has_blocks())
    throw std::logic_error("obstacles: bind() the Hessian first");
  // Each triangle's derivatives are added as soon as they are computed.
  return schedule_.run(0.0, [&](Index k) {
    TriangleGradient grad;
    TriangleHessian hess;
    const auto [o, f] = active_[k];
    const double energy = triangle_derivatives(x, o, f, &grad, hessian ? &hess : nullptr);
    for (int a = 0; a < 3; ++a) gradient->segment<3>(3 * tris_(f, a)) += grad.segment<3>(3 * a);
    if (hessian) hessian->add_blocks<3>(schedule_.blocks(k), hess);
    return energy;
  });
}

std::vector<std::string> ObstacleContact::interface_names() const {
  std::vector<std::string> out;
  for (const Obstacle& o : obstacles_) out.push_back("obstacle " + o.name);
  return out;
}

void ObstacleContact::report(const Points& x, StepRecord& step) const {
  const size_t first = step.contact.size();
  for (std::string& name : interface_names())
    step.contact.push_back({std::move(name), Vec3::Zero(), 0, 0});
  step.surface.resize(num_mesh_tris_);
  for (const auto& [o, f] : active_) {
    std::array<Vec3, 3> q;
    std::array<double, 3> G;
    for (int k = 0; k < 3; ++k) {
      q[k] = x.row(tris_(f, k));
      G[k] = obstacle_depth(obstacles_[o], load_, q[k]).value;
    }
    InterfaceForce& row = step.contact[first + static_cast<size_t>(o)];
    const ClipPolygon p = clip_triangle_by_field(q, G);
    std::array<double, 8> depth{};  // corners inside keep their depth, crossings have none
    for (int k = 0; k < p.size; ++k)
      if (p.vertex[k].kind == ClipVertex::Kind::kTriangleVertex) depth[k] = G[p.vertex[k].a];
    const PolygonMoments moments = polygon_moments(p, depth);
    TriangleGradient grad;  // the force on the triangle is -grad W
    triangle_derivatives(x, o, f, &grad, nullptr);
    const Vec3 on_triangle = -grad.reshaped(3, 3).rowwise().sum();
    row.area += moments.area;
    row.force += on_triangle;
    row.magnitude += on_triangle.norm();
    add_to_surface(step.surface, tri_ids_[static_cast<size_t>(f)], on_triangle, moments);
  }
}

}  // namespace depthfem

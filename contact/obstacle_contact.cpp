#include "contact/obstacle_contact.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "contact/penalty.hpp"
#include "core/error.hpp"

namespace depthfem {

namespace {

template <class... F>
struct Overloaded : F... {
  using F::operator()...;
};

// Depth of point q into the obstacle at load factor `load` (positive inside).
template <class S>
S obstacle_depth(const Obstacle& o, double load, const V3<S>& q) {
  const Vec3 shift = load * o.motion;
  return std::visit(Overloaded{[&](const PlaneObstacle& p) -> S {
                                 const Vec3 n = p.normal.normalized(), a = p.point + shift;
                                 return (q.x * (-n(0)) + q.y * (-n(1)) + q.z * (-n(2))) + n.dot(a);
                               },
                               [&](const SphereObstacle& s) -> S {
                                 using std::sqrt;
                                 const Vec3 c = s.center + shift;
                                 const V3<S> d{q.x + (-c(0)), q.y + (-c(1)), q.z + (-c(2))};
                                 return -sqrt(d.dot(d)) + s.radius;
                               }},
                    o.shape);
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
}

void ObstacleContact::set_load(double load) {
  load_ = load;
}

void ObstacleContact::prepare(const Points& x) {
  active_.clear();
  for (Index o = 0; o < static_cast<Index>(obstacles_.size()); ++o)
    for (Index f = 0; f < tris_.rows(); ++f)
      for (int k = 0; k < 3; ++k)
        if (obstacle_depth<double>(obstacles_[o], load_,
                                   make_point<double>(x.row(tris_(f, k)), 0)) > 0) {
          active_.emplace_back(o, f);
          break;
        }
}

void ObstacleContact::add_couplings(SparsityBuilder& builder) const {
  // Any boundary triangle may touch an obstacle: couple all of them once, so that the pattern
  // never changes.
  for (Index f = 0; f < tris_.rows(); ++f) {
    const Index v[3] = {tris_(f, 0), tris_(f, 1), tris_(f, 2)};
    builder.add_clique(v);
  }
}

template <class S, class Corner>
S ObstacleContact::triangle_energy(const Obstacle& o, const Corner& Q) const {
  const std::array<S, 3> G = {obstacle_depth<S>(o, load_, Q[0]), obstacle_depth<S>(o, load_, Q[1]),
                              obstacle_depth<S>(o, load_, Q[2])};
  std::array<Vec3, 3> q;
  for (int k = 0; k < 3; ++k) q[k] = Vec3(value_of(Q[k].x), value_of(Q[k].y), value_of(Q[k].z));
  const ClipPolygon poly =
      clip_triangle_by_field(q, {value_of(G[0]), value_of(G[1]), value_of(G[2])});
  return field_polygon_penalty(poly, Q, G, o.penalty, 0.0);
}

Dual2<9> ObstacleContact::triangle_derivatives(const Points& x, Index o, Index f) const {
  std::array<V3<Dual2<9>>, 3> Q;
  for (int k = 0; k < 3; ++k) Q[k] = make_point<Dual2<9>>(x.row(tris_(f, k)), 3 * k);
  return triangle_energy<Dual2<9>>(obstacles_[o], Q);
}

double ObstacleContact::evaluate(const Points& x, VectorX* gradient,
                                 BlockSparseMatrix* hessian) const {
  using D = Dual2<9>;
  double energy = 0;
  for (const auto& [o, f] : active_) {
    if (!gradient) {
      std::array<V3<double>, 3> Q;
      for (int k = 0; k < 3; ++k) Q[k] = make_point<double>(x.row(tris_(f, k)), 0);
      energy += triangle_energy<double>(obstacles_[o], Q);
      continue;
    }
    const D W = triangle_derivatives(x, o, f);
    energy += W.v;
    for (int a = 0; a < 3; ++a) {
      gradient->segment<3>(3 * tris_(f, a)) += W.g.segment<3>(3 * a);
      if (!hessian) continue;
      for (int b = 0; b < 3; ++b)
        hessian->add_block(hessian->block_index(tris_(f, a), tris_(f, b)),
                           W.h.block<3, 3>(3 * a, 3 * b));
    }
  }
  return energy;
}

void ObstacleContact::report(const Points& x, StepRecord& step) const {
  const size_t first = step.contact.size();
  for (const Obstacle& o : obstacles_)
    step.contact.push_back({"obstacle " + o.name, Vec3::Zero(), 0, 0});
  for (const auto& [o, f] : active_) {
    std::array<Vec3, 3> q;
    std::array<V3<double>, 3> Q;
    std::array<double, 3> G;
    for (int k = 0; k < 3; ++k) {
      q[k] = x.row(tris_(f, k));
      Q[k] = make_point<double>(q[k], 0);
      G[k] = obstacle_depth<double>(obstacles_[o], load_, Q[k]);
    }
    InterfaceForce& row = step.contact[first + static_cast<size_t>(o)];
    const ClipPolygon p = clip_triangle_by_field(q, G);
    for (int k = 1; k + 1 < p.size; ++k)
      row.area += 0.5 * (p.x[k] - p.x[0]).cross(p.x[k + 1] - p.x[0]).norm();
    const Dual2<9> W = triangle_derivatives(x, o, f);  // the force on the triangle is -grad W
    const Vec3 on_triangle = -W.g.reshaped(3, 3).rowwise().sum();
    row.force += on_triangle;
    row.magnitude += on_triangle.norm();
  }
}

}  // namespace depthfem

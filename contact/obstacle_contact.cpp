#include "contact/obstacle_contact.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <functional>
#include <stdexcept>

#include "contact/penalty.hpp"
#include "core/element_partition.hpp"
#include "core/error.hpp"

namespace depthfem {

namespace {

constexpr Index kChunk = 256;  // triangles per task; fixed for reproducible results

template <class... F>
struct Overloaded : F... {
  using F::operator()...;
};

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
}

void ObstacleContact::begin_step(const Points&, double load) {
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
  // Processing order: colored chunks along a Morton curve (as in MaterialDepthContact).
  const Index n = static_cast<Index>(active.size());
  TriIndices nodes(n, 3);
  Points centres(n, 3);
  for (Index k = 0; k < n; ++k) {
    nodes.row(k) = tris_.row(active[k].second);
    centres.row(k) = (x.row(nodes(k, 0)) + x.row(nodes(k, 1)) + x.row(nodes(k, 2))) / 3;
  }
  const ElementPartition part =
      partition_elements(nodes, static_cast<Index>(x.rows()), centres, kChunk);
  active_.resize(active.size());
  for (Index k = 0; k < n; ++k) active_[k] = active[part.order[k]];
  chunk_begin_ = part.chunk_begin;
  color_begin_ = part.color_begin;
}

void ObstacleContact::bind(const BlockSparseMatrix& hessian) {
  offsets_ = hessian.clique_block_indices(tris_);
  if (std::find(offsets_.begin(), offsets_.end(), -1) != offsets_.end())
    throw std::logic_error("obstacles: the Hessian pattern lacks a triangle's coupling");
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
  const Index n = static_cast<Index>(active_.size());
  if (!gradient) {
    return tbb::parallel_deterministic_reduce(
        tbb::blocked_range<Index>(0, n, kChunk), 0.0,
        [&](const tbb::blocked_range<Index>& r, double acc) {
          for (Index k = r.begin(); k < r.end(); ++k)
            acc += triangle_derivatives(x, active_[k].first, active_[k].second, nullptr, nullptr);
          return acc;
        },
        std::plus<double>());
  }
  if (hessian && offsets_.size() != 9 * static_cast<size_t>(tris_.rows()))
    throw std::logic_error("obstacles: bind() the Hessian first");
  // Colored chunks: each triangle's derivatives are added as soon as they are computed.
  return run_by_color(color_begin_, 0.0, [&](Index c) {
    double energy = 0;
    TriangleGradient grad;
    TriangleHessian hess;
    for (Index k = chunk_begin_[c]; k < chunk_begin_[c + 1]; ++k) {
      const auto [o, f] = active_[k];
      energy += triangle_derivatives(x, o, f, &grad, hessian ? &hess : nullptr);
      for (int a = 0; a < 3; ++a) gradient->segment<3>(3 * tris_(f, a)) += grad.segment<3>(3 * a);
      if (hessian) hessian->add_blocks<3>(offsets_.data() + 9 * static_cast<size_t>(f), hess);
    }
    return energy;
  });
}

Vec3 ObstacleContact::total_force(const Points& x) const {
  VectorX g = VectorX::Zero(3 * x.rows());
  evaluate(x, &g, nullptr);
  return -Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>>(g.data(),
                                                                                      x.rows(), 3)
              .colwise()
              .sum()
              .transpose();
}

double ObstacleContact::contact_area(const Points& x) const {
  double area = 0;
  for (const auto& [o, f] : active_) {
    std::array<Vec3, 3> q;
    std::array<double, 3> G;
    for (int k = 0; k < 3; ++k) {
      q[k] = x.row(tris_(f, k));
      G[k] = obstacle_depth(obstacles_[o], load_, q[k]).value;
    }
    const ClipPolygon p = clip_triangle_by_field(q, G);
    for (int k = 1; k + 1 < p.size; ++k)
      area += 0.5 * (p.x[k] - p.x[0]).cross(p.x[k + 1] - p.x[0]).norm();
  }
  return area;
}

}  // namespace depthfem

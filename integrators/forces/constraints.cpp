#include "integrators/forces/constraints.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "core/error.hpp"
#include "core/overloaded.hpp"

namespace depthfem {

namespace {

// A unit vector, or InputError naming the condition.
Vec3 unit(const Vec3& v, const std::string& name, const char* what) {
  const double n = v.norm();
  if (!(n > 0) || !v.allFinite())
    throw InputError("boundary condition '" + name + "': " + what + " must be a non-zero vector");
  return v / n;
}

}  // namespace

Constraints::Constraints(const Points& X, std::vector<Constraint> list)
    : X_(X), list_(std::move(list)) {
  const Index n = static_cast<Index>(X.rows());
  slot_.assign(static_cast<size_t>(n), -1);
  // Per node: constrained directions with their offsets per unit load and their condition.
  struct Plane {
    Vec3 normal;
    double offset;
    Index condition;
  };
  std::vector<std::vector<Plane>> planes(static_cast<size_t>(n));
  std::vector<Index> full(static_cast<size_t>(n), -1);
  std::vector<char> touched(static_cast<size_t>(n), 0);
  for (size_t k = 0; k < list_.size(); ++k) {
    const Constraint& c = list_[k];
    if (c.nodes.empty()) throw InputError("boundary condition '" + c.name + "' selects no nodes");
    for (Index i : c.nodes) {
      if (i < 0 || i >= n) {
        throw InputError("boundary condition '" + c.name + "': node " + std::to_string(i) +
                         " outside 0.." + std::to_string(n - 1));
      }
      touched[i] = 1;
      const Index ck = static_cast<Index>(k);
      std::visit(Overloaded{[&](const InPlane& p) {
                              planes[i].push_back({unit(p.normal, c.name, "normal"), p.offset, ck});
                            },
                            [&](const OnLine& l) {
                              const Vec3 a = unit(l.direction, c.name, "direction");
                              const Vec3 b = a.unitOrthogonal(), d = a.cross(b);
                              planes[i].push_back({b, 0.0, ck});
                              planes[i].push_back({d, 0.0, ck});
                            },
                            [&](const Rotated& r) {
                              unit(r.axis, c.name, "axis");
                              full[i] = static_cast<Index>(k);
                            },
                            [&](const auto&) { full[i] = static_cast<Index>(k); }},
                 c.kind);
    }
  }
  for (Index i = 0; i < n; ++i) {
    if (!touched[i]) continue;
    NodeState s{i, Mat3::Identity(), full[i], Vec3::Zero(), {}};
    if (full[i] >= 0) {
      s.owners.emplace_back(full[i], Mat3::Identity());
    } else {
      // Gram-Schmidt over the plane normals: C = sum b b^T over the orthonormal basis b, and
      // shift_per_load solves n_k . shift = offset_k for every condition on the node. Each b
      // belongs to the condition whose normal added it.
      s.C.setZero();
      for (const auto& [n_k, offset, condition] : planes[i]) {
        Vec3 b = n_k;
        for (int r = 0; r < 3; ++r) b -= s.C * b;  // (repeated for round-off)
        const double len = b.norm();
        const double missing = offset - n_k.dot(s.shift_per_load);
        if (len > 1e-9) {
          b /= len;
          s.shift_per_load += (missing / len) * b;
          s.C += b * b.transpose();
          if (s.owners.empty() || s.owners.back().first != condition)
            s.owners.emplace_back(condition, Mat3::Zero());
          s.owners.back().second += b * b.transpose();
        } else if (std::abs(missing) > 1e-12 * (1 + std::abs(offset))) {
          throw InputError("boundary conditions on node " + std::to_string(i) +
                           " contradict each other");
        }
      }
    }
    slot_[i] = static_cast<Index>(states_.size());
    states_.push_back(s);
  }
}

Vec3 Constraints::target(const NodeState& s, double lambda) const {
  const Vec3 X = X_.row(s.node);
  if (s.full < 0) return X + lambda * s.shift_per_load;
  return std::visit(Overloaded{[&](const Displaced& d) -> Vec3 { return X + lambda * d.u; },
                               [&](const Rotated& r) -> Vec3 {
                                 const Eigen::AngleAxisd R(lambda * r.angle, r.axis.normalized());
                                 return r.center + R * (X - r.center) + lambda * r.translation;
                               },
                               [&](const auto&) -> Vec3 { return X; }},
                    list_[s.full].kind);
}

void Constraints::impose(double lambda, Points& x) const {
  for (const NodeState& s : states_) {
    const Vec3 xi = x.row(s.node);
    x.row(s.node) = (xi - s.C * (xi - target(s, lambda))).transpose();
  }
}

void Constraints::project(VectorX& v) const {
  for (const NodeState& s : states_) v.segment<3>(3 * s.node) -= s.C * v.segment<3>(3 * s.node);
}

void Constraints::project(BlockSparseMatrix& H) const {
  if (states_.empty()) return;
  const Mat3 I = Mat3::Identity();
  const auto P = [&](Index node) -> Mat3 {
    return slot_[node] < 0 ? I : Mat3(I - states_[slot_[node]].C);
  };
  tbb::parallel_for(tbb::blocked_range<Index>(0, H.num_nodes(), 256),
                    [&](const tbb::blocked_range<Index>& r) {
                      for (Index i = r.begin(); i < r.end(); ++i) {
                        const bool row_constrained = slot_[i] >= 0;
                        for (Index k = H.row_begin(i); k < H.row_begin(i + 1); ++k) {
                          const Index j = H.block_col(k);
                          if (!row_constrained && slot_[j] < 0) continue;
                          auto B = H.block(k);
                          B = P(i) * Mat3(B) * P(j);
                          if (i == j) B += states_[slot_[i]].C;
                        }
                      }
                    });
}

std::vector<char> Constraints::fully_constrained_nodes() const {
  std::vector<char> out(slot_.size(), 0);
  for (const NodeState& s : states_) out[size_t(s.node)] = s.C.isIdentity(0) ? 1 : 0;
  return out;
}

Eigen::Matrix<double, Eigen::Dynamic, 3> Constraints::reactions(const VectorX& g) const {
  Eigen::Matrix<double, Eigen::Dynamic, 3> R =
      Eigen::Matrix<double, Eigen::Dynamic, 3>::Zero(static_cast<Eigen::Index>(list_.size()), 3);
  for (const NodeState& s : states_)
    for (const auto& [condition, C] : s.owners)
      R.row(condition) += (C * g.segment<3>(3 * s.node)).transpose();
  return R;
}

}  // namespace depthfem

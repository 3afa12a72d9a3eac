#pragma once
// Meshes edited in code for the validation tests: joined, with tets left out, single tets.

#include <array>
#include <map>
#include <vector>

#include "core/mesh_generators.hpp"
#include "core/tet_mesh.hpp"

namespace depthfem::testing {

// The nodes and tets of both meshes; with `merge`, nodes of b at exactly the position of a node
// of a are that node.
inline TetMesh joined(const TetMesh& a, const TetMesh& b, bool merge = false) {
  std::map<std::array<double, 3>, Index> at;
  for (Index i = 0; i < a.X.rows(); ++i) at[{a.X(i, 0), a.X(i, 1), a.X(i, 2)}] = i;
  TetMesh out;
  out.X = a.X;
  std::vector<Index> index(static_cast<size_t>(b.X.rows()));
  for (Index i = 0; i < b.X.rows(); ++i) {
    const auto it = at.find({b.X(i, 0), b.X(i, 1), b.X(i, 2)});
    if (merge && it != at.end()) {
      index[i] = it->second;
    } else {
      index[i] = static_cast<Index>(out.X.rows());
      out.X.conservativeResize(out.X.rows() + 1, Eigen::NoChange);
      out.X.bottomRows(1) = b.X.row(i);
    }
  }
  out.tets.resize(a.tets.rows() + b.tets.rows(), 4);
  out.tets.topRows(a.tets.rows()) = a.tets;
  for (Index t = 0; t < b.tets.rows(); ++t)
    for (int k = 0; k < 4; ++k) out.tets(a.tets.rows() + t, k) = index[b.tets(t, k)];
  return out;
}

// The tets of `mesh` whose centroids lie outside the box [lo, hi], with the nodes they use.
inline TetMesh without_tets_in(const TetMesh& mesh, const Vec3& lo, const Vec3& hi) {
  TetMesh out;
  std::vector<Index> kept;
  for (Index t = 0; t < mesh.tets.rows(); ++t) {
    Vec3 c = Vec3::Zero();
    for (int k = 0; k < 4; ++k) c += mesh.X.row(mesh.tets(t, k)).transpose() / 4;
    if (!((c.array() > lo.array()).all() && (c.array() < hi.array()).all())) kept.push_back(t);
  }
  std::vector<Index> index(static_cast<size_t>(mesh.X.rows()), -1);
  for (const Index t : kept)
    for (int k = 0; k < 4; ++k) index[mesh.tets(t, k)] = 0;
  Index next = 0;
  for (Index& i : index)
    if (i == 0) i = next++;
  out.X.resize(next, 3);
  for (Index i = 0; i < mesh.X.rows(); ++i)
    if (index[i] >= 0) out.X.row(index[i]) = mesh.X.row(i);
  out.tets.resize(static_cast<Index>(kept.size()), 4);
  for (size_t k = 0; k < kept.size(); ++k)
    for (int c = 0; c < 4; ++c) out.tets(k, c) = index[mesh.tets(kept[k], c)];
  return out;
}

inline TetMesh box(const Vec3& lo, const Vec3& hi, int cells) {
  return box_mesh({lo, hi, Eigen::Vector3i::Constant(cells)});
}

// One tet with the given corners.
inline TetMesh tet(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  TetMesh m;
  m.X.resize(4, 3);
  m.X << a.transpose(), b.transpose(), c.transpose(), d.transpose();
  m.tets.resize(1, 4);
  m.tets << 0, 1, 2, 3;
  return m;
}

// A small tet around point p.
inline TetMesh small_tet(const Vec3& p, double size) {
  return tet(p, p + Vec3(size, 0, 0), p + Vec3(0, size, 0), p + Vec3(0, 0, size));
}

}  // namespace depthfem::testing

#include "core/node_sets.hpp"

namespace depthfem {

std::vector<Index> nodes_in_box(const Points& X, const Vec3& lo, const Vec3& hi, double tol) {
  std::vector<Index> out;
  for (Index i = 0; i < X.rows(); ++i) {
    const Vec3 p = X.row(i);
    if ((p.array() >= lo.array() - tol).all() && (p.array() <= hi.array() + tol).all())
      out.push_back(i);
  }
  return out;
}

std::vector<Index> nodes_on_plane(const Points& X, const Vec3& normal, double offset, double tol) {
  const double len = normal.norm();
  std::vector<Index> out;
  for (Index i = 0; i < X.rows(); ++i)
    if (std::abs((X.row(i).dot(normal) - offset) / len) <= tol) out.push_back(i);
  return out;
}

std::vector<Index> nodes_of_body(const Mesh& mesh, Index body) {
  const Body& b = mesh.bodies.at(static_cast<size_t>(body));
  std::vector<Index> out(static_cast<size_t>(b.num_nodes));
  for (Index k = 0; k < b.num_nodes; ++k) out[k] = b.first_node + k;
  return out;
}

}  // namespace depthfem

#include "core/tet_mesh.hpp"

#include <cmath>

#include "core/error.hpp"

namespace depthfem {

double signed_volume(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  return (b - a).dot((c - a).cross(d - a)) / 6.0;
}

namespace {
long line_of(const std::vector<long>& lines, Index i) {
  return i < static_cast<Index>(lines.size()) ? lines[i] : 0;
}
}  // namespace

Index validate_and_orient(TetMesh& mesh, const MeshSource& source) {
  const Index n_nodes = static_cast<Index>(mesh.X.rows());
  for (Index i = 0; i < n_nodes; ++i) {
    if (!mesh.X.row(i).allFinite()) {
      throw InputError(located(source.file, line_of(source.node_line, i),
                               "node " + std::to_string(i) + " has a non-finite coordinate"));
    }
  }
  Index flipped = 0;
  for (Index t = 0; t < mesh.tets.rows(); ++t) {
    const auto where = [&](const std::string& what) {
      return located(source.file, line_of(source.tet_line, t),
                     "element " + std::to_string(t) + " " + what);
    };
    for (int k = 0; k < 4; ++k) {
      const Index v = mesh.tets(t, k);
      if (v < 0 || v >= n_nodes) {
        throw InputError(where("references node " + std::to_string(v) + ", outside 0.." +
                               std::to_string(n_nodes - 1)));
      }
    }
    const Vec3 p0 = mesh.X.row(mesh.tets(t, 0)), p1 = mesh.X.row(mesh.tets(t, 1)),
               p2 = mesh.X.row(mesh.tets(t, 2)), p3 = mesh.X.row(mesh.tets(t, 3));
    double longest = 0.0;
    const Vec3* p[4] = {&p0, &p1, &p2, &p3};
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b) longest = std::max(longest, (*p[a] - *p[b]).norm());
    const double six_v = 6.0 * signed_volume(p0, p1, p2, p3);
    if (!(std::abs(six_v) > 1e-10 * longest * longest * longest)) {
      throw InputError(where("is degenerate (volume " + std::to_string(six_v / 6.0) + ")"));
    }
    if (six_v < 0) {
      std::swap(mesh.tets(t, 2), mesh.tets(t, 3));
      ++flipped;
    }
  }
  return flipped;
}

}  // namespace depthfem

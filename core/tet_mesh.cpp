#include "core/tet_mesh.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "core/boundary.hpp"
#include "core/error.hpp"

namespace depthfem {

double signed_volume(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  return (b - a).dot((c - a).cross(d - a)) / 6.0;
}

namespace {
long line_of(const std::vector<long>& lines, Index i) {
  return i < static_cast<Index>(lines.size()) ? lines[i] : 0;
}

// "FILE:LINE: node I WHAT" in the file that lists the nodes.
InputError node_error(const MeshSource& source, Index i, const std::string& what) {
  return InputError(located(source.node_file.empty() ? source.file : source.node_file,
                            line_of(source.node_line, i),
                            "node " + std::to_string(i) + " " + what));
}

// "element T (line L)", or "element T" when the line is unknown.
std::string element_at(const MeshSource& source, Index t) {
  const long line = line_of(source.tet_line, t);
  return "element " + std::to_string(t) + (line > 0 ? " (line " + std::to_string(line) + ")" : "");
}

// Whether face `local` of tet t, oriented outward, is an odd permutation of its sorted nodes.
// Two tets on opposite sides of a face see it with opposite parity.
bool odd(const TetIndices& tets, Index t, int local) {
  const Index a = tets(t, kTetFace[local][0]), b = tets(t, kTetFace[local][1]),
              c = tets(t, kTetFace[local][2]);
  return ((a > b) + (a > c) + (b > c)) % 2 == 1;
}

// Every face belongs to one tet (boundary) or two on opposite sides of it (interior). A tet listed
// twice, or two tets folded over each other, see a face with the same orientation; a third tet on
// a face overlaps one of the other two.
void check_faces(const TetIndices& tets, const MeshSource& source) {
  const std::vector<TetFace> faces = face_table(tets);
  for (size_t i = 0; i + 1 < faces.size(); ++i) {
    const TetFace &f = faces[i], &g = faces[i + 1];
    if (f.sorted != g.sorted) continue;
    const auto fail = [&](const std::string& what) {
      throw InputError(located(source.file, line_of(source.tet_line, g.tet),
                               element_at(source, g.tet) + " " + what));
    };
    if (i + 2 < faces.size() && faces[i + 2].sorted == f.sorted) {
      throw InputError(
          located(source.file, line_of(source.tet_line, faces[i + 2].tet),
                  "face (" + std::to_string(f.sorted[0]) + " " + std::to_string(f.sorted[1]) + " " +
                      std::to_string(f.sorted[2]) +
                      ") belongs to three or more elements: " + element_at(source, f.tet) + ", " +
                      element_at(source, g.tet) + ", " + element_at(source, faces[i + 2].tet)));
    }
    if (odd(tets, f.tet, f.local) != odd(tets, g.tet, g.local)) continue;
    std::array<Index, 4> x, y;
    for (int k = 0; k < 4; ++k) x[k] = tets(f.tet, k), y[k] = tets(g.tet, k);
    std::sort(x.begin(), x.end());
    std::sort(y.begin(), y.end());
    if (x == y) fail("repeats the nodes of " + element_at(source, f.tet));
    fail("overlaps " + element_at(source, f.tet) +
         ": both lie on the same side of their shared face");
  }
}

// A node outside every tet has no stiffness: the linear systems turn singular.
void check_every_node_used(const TetMesh& mesh, const MeshSource& source) {
  std::vector<bool> used(static_cast<size_t>(mesh.X.rows()), false);
  for (Index t = 0; t < mesh.tets.rows(); ++t)
    for (int k = 0; k < 4; ++k) used[static_cast<size_t>(mesh.tets(t, k))] = true;
  for (Index i = 0; i < static_cast<Index>(used.size()); ++i) {
    if (!used[static_cast<size_t>(i)]) {
      throw node_error(source, i, "belongs to no element");
    }
  }
}
}  // namespace

Index validate_and_orient(TetMesh& mesh, const MeshSource& source) {
  const Index n_nodes = static_cast<Index>(mesh.X.rows());
  for (Index i = 0; i < n_nodes; ++i) {
    if (!mesh.X.row(i).allFinite()) {
      throw node_error(source, i, "has a non-finite coordinate");
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
  check_faces(mesh.tets, source);
  check_every_node_used(mesh, source);
  return flipped;
}

}  // namespace depthfem

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

std::string stored_set_name(std::string name) {
  std::ranges::replace(name, '/', '_');
  return name;
}

namespace {
template <class T>
T entry_or(const std::vector<T>& v, Index i, T otherwise) {
  return i >= 0 && i < static_cast<Index>(v.size()) ? v[static_cast<size_t>(i)] : otherwise;
}
}  // namespace

long MeshSource::line_of_tet(Index t) const {
  return entry_or(tet_line, t, 0L);
}
long MeshSource::line_of_node(Index i) const {
  return entry_or(node_line, i, 0L);
}

long long MeshSource::file_node(Index i) const {
  return entry_or(node_number, i, static_cast<long long>(i));
}
long long MeshSource::file_element(Index t) const {
  return entry_or(tet_number, t, static_cast<long long>(t));
}

std::string MeshSource::node_name(Index i) const {
  return "node " + std::to_string(file_node(i));
}

std::string MeshSource::element_name(Index t) const {
  const long line = line_of_tet(t);
  return "element " + std::to_string(file_element(t)) +
         (line > 0 ? " (line " + std::to_string(line) + ")" : "");
}

MeshSource MeshSource::subset(const std::vector<Index>& tets,
                              const std::vector<Index>& nodes) const {
  MeshSource out;
  out.file = file;
  out.node_file = node_file;
  const auto pick = [](const auto& from, const std::vector<Index>& which, auto& to) {
    if (from.empty()) return;
    to.reserve(which.size());
    for (const Index i : which) to.push_back(from.at(static_cast<size_t>(i)));
  };
  pick(tet_line, tets, out.tet_line);
  pick(tet_number, tets, out.tet_number);
  pick(node_line, nodes, out.node_line);
  pick(node_number, nodes, out.node_number);
  return out;
}

namespace {
// "FILE:LINE: node N WHAT" in the file that lists the nodes.
InputError node_error(const MeshSource& source, Index i, const std::string& what) {
  return InputError(
      located(source.nodes_file(), source.line_of_node(i), source.node_name(i) + " " + what));
}

// Whether face `local` of tet t, oriented outward, is an odd permutation of its sorted nodes.
// Two tets on opposite sides of a face see it with opposite parity.
bool odd(const TetIndices& tets, Index t, int local) {
  const Index a = tets(t, kTetFace[local][0]), b = tets(t, kTetFace[local][1]),
              c = tets(t, kTetFace[local][2]);
  return ((a > b) + (a > c) + (b > c)) % 2 == 1;
}

// The file's numbers of the nodes of a face, "a b c".
std::string node_numbers(const MeshSource& source, const std::array<Index, 3>& nodes) {
  std::string out;
  for (const Index i : nodes) out += (out.empty() ? "" : " ") + std::to_string(source.file_node(i));
  return out;
}

// Every face belongs to one tet (boundary) or two on opposite sides of it (interior). A tet listed
// twice, or two tets folded over each other, see a face with the same orientation; a third tet on
// a face overlaps one of the other two. Fills `neighbours` (see validate_and_orient).
void check_faces(const TetIndices& tets, const MeshSource& source, TetIndices& neighbours) {
  const std::vector<TetFace> faces = face_table(tets);
  neighbours.setConstant(tets.rows(), 4, -1);
  for (size_t i = 0; i + 1 < faces.size(); ++i) {
    const TetFace &f = faces[i], &g = faces[i + 1];
    if (f.sorted != g.sorted) continue;
    neighbours(f.tet, f.local) = g.tet;
    neighbours(g.tet, g.local) = f.tet;
    const auto fail = [&](const std::string& what) {
      throw InputError(
          located(source.file, source.line_of_tet(g.tet), source.element_name(g.tet) + " " + what));
    };
    if (i + 2 < faces.size() && faces[i + 2].sorted == f.sorted) {
      const Index third = faces[i + 2].tet;
      throw InputError(
          located(source.file, source.line_of_tet(third),
                  "face (" + node_numbers(source, f.sorted) +
                      ") belongs to three or more elements: " + source.element_name(f.tet) + ", " +
                      source.element_name(g.tet) + ", " + source.element_name(third)));
    }
    if (odd(tets, f.tet, f.local) != odd(tets, g.tet, g.local)) continue;
    std::array<Index, 4> x, y;
    for (int k = 0; k < 4; ++k) x[k] = tets(f.tet, k), y[k] = tets(g.tet, k);
    std::sort(x.begin(), x.end());
    std::sort(y.begin(), y.end());
    if (x == y) fail("repeats the nodes of " + source.element_name(f.tet));
    fail("overlaps " + source.element_name(f.tet) +
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

Index validate_and_orient(TetMesh& mesh, const MeshSource& source, TetIndices* neighbours) {
  const Index n_nodes = static_cast<Index>(mesh.X.rows());
  for (Index i = 0; i < n_nodes; ++i) {
    if (!mesh.X.row(i).allFinite()) {
      throw node_error(source, i, "has a non-finite coordinate");
    }
  }
  Index flipped = 0;
  for (Index t = 0; t < mesh.tets.rows(); ++t) {
    const auto where = [&](const std::string& what) {
      return located(source.file, source.line_of_tet(t), source.element_name(t) + " " + what);
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
  TetIndices across;
  check_faces(mesh.tets, source, neighbours ? *neighbours : across);
  check_every_node_used(mesh, source);
  return flipped;
}

}  // namespace depthfem

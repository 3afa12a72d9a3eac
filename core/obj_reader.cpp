#include "core/obj_reader.hpp"

#include <algorithm>
#include <string_view>
#include <tuple>
#include <vector>

#include "core/error.hpp"
#include "core/text_parsing.hpp"

namespace depthfem {

namespace {
constexpr std::string_view kIgnored[] = {"vn", "vt", "vp", "o", "g", "s", "usemtl", "mtllib", "l"};

// Where each triangle came from: the face number (polygons are split into several triangles) and
// its line.
struct FaceOrigin {
  Index face;
  long line;
};

// The surface must bound a solid: no degenerate triangle, every edge shared by exactly two
// triangles that cross it in opposite directions (closed, manifold, consistently oriented), and
// the triangles around each vertex forming a single fan.
void check_closed_manifold(const std::string& path, const Points& V, const TriIndices& F,
                           const std::vector<FaceOrigin>& origin) {
  const auto fail = [&](Index t, const std::string& what) {
    throw InputError(
        located(path, origin[t].line, "face " + std::to_string(origin[t].face) + " " + what));
  };
  const auto edge = [](Index a, Index b) {
    return "(" + std::to_string(a + 1) + " " + std::to_string(b + 1) + ")";
  };
  for (Index t = 0; t < F.rows(); ++t) {
    const Vec3 a = V.row(F(t, 0)), b = V.row(F(t, 1)), c = V.row(F(t, 2));
    const double longest = std::max({(b - a).norm(), (c - b).norm(), (a - c).norm()});
    if (!((b - a).cross(c - a).norm() > 1e-10 * longest * longest))
      fail(t, "is degenerate (zero area or a repeated vertex)");
  }
  // Directed edges (from, to, triangle), grouped by their undirected edge.
  struct DirectedEdge {
    Index lo, hi;
    bool forward;  // from lo to hi
    Index tri;
  };
  std::vector<DirectedEdge> edges;
  for (Index t = 0; t < F.rows(); ++t) {
    for (int k = 0; k < 3; ++k) {
      const Index u = F(t, k), v = F(t, (k + 1) % 3);
      edges.push_back({std::min(u, v), std::max(u, v), u < v, t});
    }
  }
  std::sort(edges.begin(), edges.end(), [](const DirectedEdge& x, const DirectedEdge& y) {
    return std::tie(x.lo, x.hi, x.tri) < std::tie(y.lo, y.hi, y.tri);
  });
  for (size_t i = 0; i < edges.size();) {
    size_t j = i + 1;
    while (j < edges.size() && edges[j].lo == edges[i].lo && edges[j].hi == edges[i].hi) ++j;
    const DirectedEdge& e = edges[i];
    if (j - i == 1)
      fail(e.tri,
           "has edge " + edge(e.lo, e.hi) + " that no other face shares: the surface is open");
    if (j - i > 2) {
      fail(edges[i + 2].tri, "is a third face on edge " + edge(e.lo, e.hi) + " (with faces " +
                                 std::to_string(origin[e.tri].face) + " and " +
                                 std::to_string(origin[edges[i + 1].tri].face) +
                                 "): the surface is not manifold");
    }
    if (e.forward == edges[i + 1].forward) {
      fail(edges[i + 1].tri,
           "runs along edge " + edge(e.lo, e.hi) + " in the same direction as face " +
               std::to_string(origin[e.tri].face) + ": the faces are not consistently oriented");
    }
    i = j;
  }
  // Around vertex v each triangle (v, a, b) leads from a to b; on a manifold these steps form one
  // cycle through all of v's triangles.
  struct Corner {
    Index v, a, b, tri;
  };
  std::vector<Corner> corners;
  for (Index t = 0; t < F.rows(); ++t)
    for (int k = 0; k < 3; ++k)
      corners.push_back({F(t, k), F(t, (k + 1) % 3), F(t, (k + 2) % 3), t});
  std::sort(corners.begin(), corners.end(), [](const Corner& x, const Corner& y) {
    return std::tie(x.v, x.a) < std::tie(y.v, y.a);
  });
  for (size_t i = 0; i < corners.size();) {
    size_t j = i + 1;
    while (j < corners.size() && corners[j].v == corners[i].v) ++j;
    size_t steps = 0;
    Index at = corners[i].a;
    do {
      const auto next = std::lower_bound(corners.begin() + i, corners.begin() + j, at,
                                         [](const Corner& c, Index a) { return c.a < a; });
      if (next == corners.begin() + j || next->a != at)
        break;  // cannot happen after the edge check
      at = next->b;
      ++steps;
    } while (at != corners[i].a && steps <= j - i);
    if (steps != j - i) {
      fail(corners[i].tri, "meets vertex " + std::to_string(corners[i].v + 1) +
                               ", whose faces form more than one fan: the surface is not manifold");
    }
    i = j;
  }
}
}  // namespace

TriSurface read_obj(const std::string& path) {
  LineReader in(path, '#');
  std::vector<double> xyz;
  std::vector<Index> tris;
  std::vector<Index> corners;  // of the current face
  std::vector<FaceOrigin> origin;
  Index num_faces = 0;
  static constexpr const char* kAxis[] = {"x", "y", "z", "w"};
  while (in.next()) {
    const auto& t = in.tokens();
    const std::string_view keyword = t[0];
    if (keyword == "v") {
      const Index vertex = static_cast<Index>(xyz.size() / 3) + 1;
      if (t.size() != 4 && t.size() != 5) {
        in.fail("vertex " + std::to_string(vertex) + " needs 3 or 4 numbers (x y z [w]), found " +
                std::to_string(t.size() - 1));
      }
      for (size_t k = 1; k < t.size(); ++k) {
        const double value = in.to_double(t[k], [&] {
          return std::string(kAxis[k - 1]) + " of vertex " + std::to_string(vertex);
        });
        if (k <= 3) xyz.push_back(value);
      }
    } else if (keyword == "f") {
      ++num_faces;
      const auto face = [&] { return "face " + std::to_string(num_faces); };
      if (t.size() < 4) {
        in.fail(face() + " has " + std::to_string(t.size() - 1) + " vertices; at least 3 needed");
      }
      const long long defined = static_cast<long long>(xyz.size() / 3);
      corners.clear();
      for (size_t k = 1; k < t.size(); ++k) {
        // "a", "a/t", "a//n" or "a/t/n": only the vertex index `a` is used.
        const std::string_view token = t[k].substr(0, t[k].find('/'));
        const long long index = in.to_integer(token, [&] { return "a vertex index of " + face(); });
        if (index == 0) in.fail(face() + " uses vertex index 0; OBJ indices start at 1");
        const long long zero_based = index < 0 ? defined + index : index - 1;
        if (zero_based < 0 || zero_based >= defined) {
          in.fail(face() + " references vertex " + std::to_string(index) + ", but " +
                  std::to_string(defined) + " vertices are defined so far (indices 1.." +
                  std::to_string(defined) + " or -1..-" + std::to_string(defined) + ")");
        }
        corners.push_back(static_cast<Index>(zero_based));
      }
      for (size_t k = 1; k + 1 < corners.size(); ++k) {
        tris.insert(tris.end(), {corners[0], corners[k], corners[k + 1]});
        origin.push_back({num_faces, in.line()});
      }
    } else if (std::ranges::find(kIgnored, keyword) == std::end(kIgnored)) {
      in.fail("unsupported OBJ statement '" + std::string(keyword) + "'");
    }
  }
  if (tris.empty()) throw InputError(located(path, 0, "contains no faces"));
  TriSurface surface{from_row_major<Points>(xyz), from_row_major<TriIndices>(tris)};
  check_closed_manifold(path, surface.V, surface.F, origin);
  return surface;
}

}  // namespace depthfem

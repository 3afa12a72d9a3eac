#include "core/boundary.hpp"

#include <algorithm>

namespace depthfem {

std::vector<TetFace> face_table(const TetIndices& tets) {
  const Index n = static_cast<Index>(tets.rows());
  std::vector<TetFace> faces;
  faces.reserve(4 * static_cast<size_t>(n));
  Index max_node = -1;
  for (Index t = 0; t < n; ++t) {
    for (int k = 0; k < 4; ++k) {
      std::array<Index, 3> v = {tets(t, kTetFace[k][0]), tets(t, kTetFace[k][1]),
                                tets(t, kTetFace[k][2])};
      std::sort(v.begin(), v.end());
      faces.push_back({v, t, k});
      max_node = std::max(max_node, v[2]);
    }
  }
  // Counting sort by the smallest node, stable (tets stay in order within a bucket).
  std::vector<size_t> start(static_cast<size_t>(max_node) + 2, 0);
  for (const TetFace& f : faces) ++start[static_cast<size_t>(f.sorted[0]) + 1];
  for (size_t i = 1; i < start.size(); ++i) start[i] += start[i - 1];
  std::vector<TetFace> out(faces.size());
  std::vector<size_t> next(start.begin(), start.end() - 1);
  for (const TetFace& f : faces) out[next[static_cast<size_t>(f.sorted[0])]++] = f;
  for (size_t b = 0; b + 1 < start.size(); ++b) {
    std::sort(out.begin() + static_cast<std::ptrdiff_t>(start[b]),
              out.begin() + static_cast<std::ptrdiff_t>(start[b + 1]),
              [](const TetFace& x, const TetFace& y) {
                return x.sorted[1] != y.sorted[1]   ? x.sorted[1] < y.sorted[1]
                       : x.sorted[2] != y.sorted[2] ? x.sorted[2] < y.sorted[2]
                                                    : x.tet < y.tet;
              });
  }
  return out;
}

BoundaryFaces boundary_faces(const TetIndices& tets) {
  const std::vector<TetFace> faces = face_table(tets);
  std::vector<const TetFace*> single;
  for (size_t i = 0; i < faces.size();) {
    size_t j = i + 1;
    while (j < faces.size() && faces[j].sorted == faces[i].sorted) ++j;
    if (j - i == 1) single.push_back(&faces[i]);
    i = j;
  }
  std::sort(single.begin(), single.end(), [](const TetFace* a, const TetFace* b) {
    return a->tet != b->tet ? a->tet < b->tet : a->local < b->local;
  });
  BoundaryFaces out;
  out.tris.resize(static_cast<Index>(single.size()), 3);
  out.tet.resize(static_cast<Index>(single.size()));
  for (Index f = 0; f < static_cast<Index>(single.size()); ++f) {
    for (int c = 0; c < 3; ++c)
      out.tris(f, c) = tets(single[f]->tet, kTetFace[single[f]->local][c]);
    out.tet(f) = single[f]->tet;
  }
  return out;
}

}  // namespace depthfem

#include "core/boundary.hpp"

#include <algorithm>
#include <array>
#include <vector>

namespace depthfem {

namespace {
// Faces of a positively oriented tet (0,1,2,3), each listed so that its right-hand normal points
// away from the opposite vertex: face k is opposite vertex k.
constexpr int kFace[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};

struct FaceKey {
  std::array<Index, 3> sorted;
  Index tet;
  int local;
};
}  // namespace

BoundaryFaces boundary_faces(const TetIndices& tets) {
  const Index n = static_cast<Index>(tets.rows());
  std::vector<FaceKey> faces;
  faces.reserve(4 * static_cast<size_t>(n));
  for (Index t = 0; t < n; ++t) {
    for (int k = 0; k < 4; ++k) {
      std::array<Index, 3> v = {tets(t, kFace[k][0]), tets(t, kFace[k][1]), tets(t, kFace[k][2])};
      std::sort(v.begin(), v.end());
      faces.push_back({v, t, k});
    }
  }
  std::sort(faces.begin(), faces.end(), [](const FaceKey& a, const FaceKey& b) {
    return a.sorted != b.sorted ? a.sorted < b.sorted : a.tet < b.tet;
  });
  std::vector<const FaceKey*> single;
  for (size_t i = 0; i < faces.size();) {
    size_t j = i + 1;
    while (j < faces.size() && faces[j].sorted == faces[i].sorted) ++j;
    if (j - i == 1) single.push_back(&faces[i]);
    i = j;
  }
  std::sort(single.begin(), single.end(), [](const FaceKey* a, const FaceKey* b) {
    return a->tet != b->tet ? a->tet < b->tet : a->local < b->local;
  });
  BoundaryFaces out;
  out.tris.resize(static_cast<Index>(single.size()), 3);
  out.tet.resize(static_cast<Index>(single.size()));
  for (Index f = 0; f < static_cast<Index>(single.size()); ++f) {
    for (int c = 0; c < 3; ++c) out.tris(f, c) = tets(single[f]->tet, kFace[single[f]->local][c]);
    out.tet(f) = single[f]->tet;
  }
  return out;
}

}  // namespace depthfem

#include "core/mass.hpp"

#include "core/tet_mesh.hpp"

namespace depthfem {

namespace {
double tet_volume(const Points& X, const TetIndices& tets, Index t) {
  return signed_volume(X.row(tets(t, 0)), X.row(tets(t, 1)), X.row(tets(t, 2)), X.row(tets(t, 3)));
}
}  // namespace

VectorX lumped_mass(const Points& X, const TetIndices& tets, const VectorX& density) {
  VectorX m = VectorX::Zero(X.rows());
  for (Index t = 0; t < tets.rows(); ++t) {
    const double quarter = 0.25 * density(t) * tet_volume(X, tets, t);
    for (int a = 0; a < 4; ++a) m(tets(t, a)) += quarter;
  }
  return m;
}

BlockSparseMatrix consistent_mass(const Points& X, const TetIndices& tets, const VectorX& density,
                                  double factor) {
  SparsityBuilder cliques(static_cast<Index>(X.rows()));
  for (Index t = 0; t < tets.rows(); ++t) {
    const Index n[4] = {tets(t, 0), tets(t, 1), tets(t, 2), tets(t, 3)};
    cliques.add_clique(n);
  }
  BlockSparseMatrix M(cliques);
  for (Index t = 0; t < tets.rows(); ++t) {
    const double m = factor * density(t) * tet_volume(X, tets, t) / 20;
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b)
        M.add_block(M.block_index(tets(t, a), tets(t, b)),
                    Mat3((a == b ? 2 * m : m) * Mat3::Identity()));
  }
  return M;
}

VectorX node_volume(const Points& X, const TetIndices& tets) {
  VectorX v = VectorX::Zero(X.rows());
  for (Index t = 0; t < tets.rows(); ++t) {
    const double vol = tet_volume(X, tets, t);
    for (int a = 0; a < 4; ++a) v(tets(t, a)) += vol;
  }
  return v;
}

double mean_edge_length(const Points& X, const TetIndices& tets) {
  if (tets.rows() == 0) return 0.0;
  double sum = 0;
  for (Index t = 0; t < tets.rows(); ++t)
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b) sum += (X.row(tets(t, a)) - X.row(tets(t, b))).norm();
  return sum / (6.0 * static_cast<double>(tets.rows()));
}

}  // namespace depthfem

#include "integrators/consistent_mass.hpp"

#include "core/tet_mesh.hpp"

namespace depthfem {

namespace {
SparsityBuilder tet_cliques(const TetIndices& tets, Index num_nodes) {
  SparsityBuilder builder(num_nodes);
  for (Index t = 0; t < tets.rows(); ++t) {
    const Index n[4] = {tets(t, 0), tets(t, 1), tets(t, 2), tets(t, 3)};
    builder.add_clique(n);
  }
  return builder;
}
}  // namespace

ConsistentMass::ConsistentMass(std::string name, const Points& X, const TetIndices& tets,
                               const VectorX& tet_density, double factor)
    : name_(std::move(name)), tets_(tets), M_(tet_cliques(tets, static_cast<Index>(X.rows()))) {
  for (Index t = 0; t < tets.rows(); ++t) {
    const double volume =
        signed_volume(X.row(tets(t, 0)).transpose(), X.row(tets(t, 1)).transpose(),
                      X.row(tets(t, 2)).transpose(), X.row(tets(t, 3)).transpose());
    const double m = factor * tet_density(t) * volume / 20;
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b)
        M_.add_block(M_.block_index(tets(t, a), tets(t, b)),
                     Mat3((a == b ? 2 * m : m) * Mat3::Identity()));
  }
}

void ConsistentMass::add_couplings(SparsityBuilder& builder) const {
  for (Index t = 0; t < tets_.rows(); ++t) {
    const Index n[4] = {tets_(t, 0), tets_(t, 1), tets_(t, 2), tets_(t, 3)};
    builder.add_clique(n);
  }
}

void ConsistentMass::bind(const BlockSparseMatrix& hessian) {
  global_.resize(static_cast<size_t>(M_.num_blocks()));
  for (Index i = 0; i < M_.num_nodes(); ++i)
    for (Index k = M_.row_begin(i); k < M_.row_begin(i + 1); ++k)
      global_[k] = hessian.block_index(i, M_.block_col(k));
}

double ConsistentMass::evaluate(const Points& x, VectorX* gradient,
                                BlockSparseMatrix* hessian) const {
  const VectorX d = as_dofs(x - anchor_);
  VectorX Md;
  M_.multiply(d, Md);
  if (gradient) *gradient += scale_ * Md;
  if (hessian)
    for (Index k = 0; k < M_.num_blocks(); ++k)
      hessian->add_block(global_[k], scale_ * M_.block(k));
  return 0.5 * scale_ * d.dot(Md);
}

double ConsistentMass::quadratic_form(const Points& d) const {
  const VectorX v = as_dofs(d);
  VectorX Mv;
  M_.multiply(v, Mv);
  return 0.5 * v.dot(Mv);
}

}  // namespace depthfem

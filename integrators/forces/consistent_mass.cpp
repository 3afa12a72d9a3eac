#include "integrators/forces/consistent_mass.hpp"

#include "core/mass.hpp"

namespace depthfem {

ConsistentMass::ConsistentMass(std::string name, const Points& X, const TetIndices& tets,
                               const VectorX& tet_density, double factor)
    : name_(std::move(name)), tets_(tets), M_(consistent_mass(X, tets, tet_density, factor)) {}

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

void ConsistentMass::rebind(const BlockSparseMatrix&, std::span<const Index> moved) {
  move_block_indices(global_, moved, name());
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

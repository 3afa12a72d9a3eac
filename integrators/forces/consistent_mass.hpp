#pragma once
/// The consistent mass matrix of linear tets as a tether, for inertia and mass-proportional
/// damping of the implicit schemes.

#include "integrators/forces/nodal_spring.hpp"

namespace depthfem {

/// E(x) = s / 2 (x - a)^T M (x - a) with the consistent mass matrix of linear tets
/// (core/mass.hpp) times a factor (1 for inertia, alpha for Rayleigh mass damping). Its rows sum
/// to the lumped masses, so a uniform acceleration costs the same force with either matrix.
class ConsistentMass final : public Tether {
 public:
  /// `tet_density` [kg/m^3] per tet; `factor` scales M.
  ConsistentMass(std::string name, const Points& X, const TetIndices& tets,
                 const VectorX& tet_density, double factor = 1.0);

  std::string name() const override { return name_; }
  void add_couplings(SparsityBuilder& builder) const override;
  void bind(const BlockSparseMatrix& hessian) override;
  bool fixed_couplings() const override { return true; }
  void rebind(const BlockSparseMatrix& hessian, std::span<const Index> moved) override;
  double evaluate(const Points& x, VectorX* gradient, BlockSparseMatrix* hessian) const override;
  double quadratic_form(const Points& d) const override;

 private:
  std::string name_;
  TetIndices tets_;
  BlockSparseMatrix M_;        // own pattern (the tets' cliques); blocks m_ab I
  std::vector<Index> global_;  // block k of M_ -> block of the bound global matrix
};

}  // namespace depthfem

#include "integrators/solvers/residual_scale.hpp"

#include "core/mass.hpp"
#include "materials/material.hpp"

namespace depthfem {

VectorX residual_force_scale(const Points& X, const TetIndices& tets,
                             const std::vector<ElasticGroup>& groups) {
  VectorX E = VectorX::Zero(X.rows());
  double E_max = 0;
  for (const ElasticGroup& g : groups) {
    const double youngs = material_moduli(g.material).youngs();
    E_max = std::max(E_max, youngs);
    for (Index t : g.tets)
      for (int c = 0; c < 4; ++c) E(tets(t, c)) = std::max(E(tets(t, c)), youngs);
  }
  if (E_max == 0) E_max = 1;  // no elastic tets: every dof is prescribed
  const double h = mean_edge_length(X, tets);
  VectorX scale(3 * X.rows());
  for (Index i = 0; i < X.rows(); ++i)
    scale.segment<3>(3 * i).setConstant((E(i) > 0 ? E(i) : E_max) * h * h);
  return scale;
}

}  // namespace depthfem

#pragma once
/// The force scale against which Newton judges the residual at each degree of freedom.

#include <vector>

#include "integrators/forces/elasticity.hpp"

namespace depthfem {

/// Per dof (3 * #nodes, interleaved) [N]: E_i h^2, the force that a strain of one exerts on a
/// cell of edge h made of the stiffest material around node i (E_i: the largest small-strain
/// Young's modulus of the elastic tets sharing node i; h: the mean edge length of `tets`).
/// Dividing the residual by it judges every node against its own material, so a stiff region
/// does not loosen the tolerance of a soft one. Nodes of no elastic tet (rigid bodies: all their
/// dofs are prescribed, their residual is projected out) get the largest E of the scene.
VectorX residual_force_scale(const Points& X, const TetIndices& tets,
                             const std::vector<ElasticGroup>& groups);

}  // namespace depthfem

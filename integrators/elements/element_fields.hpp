#pragma once
/// Stress and strain per tet of a deformed configuration, for the results file.

#include <vector>

#include "core/step_record.hpp"
#include "integrators/forces/elasticity.hpp"

namespace depthfem {

/// Which per-tet fields to compute.
struct ElementFieldOptions {
  bool stress = false;  ///< Cauchy stress and von Mises stress
  bool strain = false;  ///< logarithmic strain and volume ratio
};

/// Per-tet fields at positions x (#nodes x 3 [m]) of the mesh with reference positions X and
/// tets `tets`. With F = Ds Dm^-1 (constant over a linear tet) and J = det F:
///   Cauchy stress sigma = P F^T / J, P = dpsi/dF of the tet's material in `groups` (zero for a
///   tet in no group: a rigid body); von Mises sqrt(3/2 s : s), s = sigma - tr(sigma)/3 I;
///   logarithmic (Hencky) strain ln V = 1/2 ln(F F^T), in the current frame like sigma.
/// A tet of a group with VolumeFormulation::kNodalPressure or kPatchVolume takes the stress of
/// that formulation: the isochoric part's P F^T / J plus its pressure times I, read from
/// `tet_pressure` (#tets [Pa], PatchVolume::tet_pressures), which such a group needs.
/// Arrays not asked for stay empty. Requires J > 0 for every tet (a converged state).
ElementFields element_fields(const Points& X, const TetIndices& tets,
                             const std::vector<ElasticGroup>& groups, const Points& x,
                             ElementFieldOptions options, const VectorX* tet_pressure = nullptr);

}  // namespace depthfem

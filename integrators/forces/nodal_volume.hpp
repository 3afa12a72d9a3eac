#pragma once
/// The volumetric energy of nearly incompressible tets, on volume changes averaged over nodes
/// (average nodal pressure: Bonet and Burton 1998; Bonet, Marriott and Hassan 2001).

#include <memory>
#include <span>
#include <vector>

#include "core/force_module.hpp"
#include "integrators/forces/elasticity.hpp"

namespace depthfem {

/// U(J) / kappa = ((J^2 - 1) / 2 - ln J) / 2 and its first two derivatives: U(1) = U'(1) = 0,
/// U''(1) = kappa (the small-strain bulk modulus), U -> +infinity as J -> 0.
struct VolumetricPenalty {
  static double value(double J);
  static double first(double J);
  static double second(double J);
};

/// E = sum over nodes a of K_a U~(J_a), U~ = VolumetricPenalty, with
///   V_a = sum_{e at a} V_e / 4,  v_a = sum_{e at a} v_e / 4,  J_a = v_a / V_a,
///   K_a = sum_{e at a} kappa_e V_e / 4,
/// V_e, v_e the rest and current volumes of tet e and kappa_e its material's bulk modulus. With
/// the isochoric energy of each tet (VolumeFormulation::kNodalPressure in elasticity.hpp) this
/// is the total energy of the formulation: a tet no longer has to keep its own volume, only the
/// patches around the nodes do, which frees linear tets from volumetric locking.
///
/// With pi_a = K_a U~'(J_a) / V_a (the nodal pressure), k_a = K_a U~''(J_a) / V_a^2 and
/// p_e = (1/4) sum_{a in e} pi_a (the tet's average nodal pressure):
///   grad E = sum_e p_e dv_e/dx,
///   hess E = sum_e p_e d2v_e/dx2 + sum_a k_a w_a w_a^T,  w_a = dv_a/dx = (1/4) sum_{e at a}
///   dv_e/dx,
/// so the second term couples every pair of nodes of a node's patch (the tets around it): the
/// Hessian pattern is wider than the tets' own (add_couplings).
///
/// Evaluation runs in passes over SoA arrays, none with a per-element virtual call: tets
/// (current volume and its gradient), nodes (gathering v_a through the node's list of tets,
/// energy, pressure), tets (p_e), nodes (gathering the gradient, w_a and the Hessian rows). Each
/// node gathers in a fixed order and writes only its own entries, so results are bitwise
/// identical for any number of threads.
class NodalVolume final : public ForceModule {
 public:
  /// The tets `which` (global ids into `tets`) with bulk modulus `kappa` [Pa] each, reference
  /// positions X. Throws InputError naming a tet that is flat or inverted in X.
  NodalVolume(const Points& X, const TetIndices& tets, std::span<const Index> which,
              std::span<const double> kappa);

  std::string name() const override { return "nodal volume"; }
  void add_couplings(SparsityBuilder& builder) const override;
  void bind(const BlockSparseMatrix& hessian) override;
  bool fixed_couplings() const override { return true; }
  void rebind(const BlockSparseMatrix& hessian, std::span<const Index> moved) override;
  double evaluate(const Points& x, VectorX* gradient, BlockSparseMatrix* hessian) const override;

  /// J_a = v_a / V_a of every node the tets touch (in increasing global node order) at x.
  VectorX nodal_volume_ratios(const Points& x) const;
  /// The nodal pressure pi_a = K_a U~'(J_a) / V_a [Pa] (the Cauchy pressure of the volumetric
  /// energy, positive in tension) at x, per global node (#nodes of x; zero at nodes of no tet).
  VectorX nodal_pressures(const Points& x) const;
  /// Global ids of the nodes the tets touch, increasing (the order of nodal_volume_ratios).
  const std::vector<Index>& nodes() const { return node_; }

 private:
  /// Current volume of every tet at x; with `gradient`, also dv_e/dx (#tets x 12, node-major).
  void tet_volumes(const Points& x, VectorX& volume,
                   Eigen::Matrix<double, Eigen::Dynamic, 12>* gradient) const;

  TetIndices tet_;                     ///< #tets x 4 local node ids (into node_)
  std::vector<Index> node_;            ///< global id of each local node
  VectorX rest_volume_;                ///< V_a per local node [m^3]
  VectorX bulk_;                       ///< K_a per local node [N m]
  std::vector<Index> incident_begin_;  ///< #nodes + 1 offsets into incident_
  std::vector<Index> incident_;        ///< 4 tet + corner of each tet at the node, increasing
  std::vector<Index> patch_begin_;     ///< #nodes + 1 offsets into patch_
  std::vector<Index> patch_;           ///< local nodes of the node's patch, increasing
  std::vector<Index> corner_slot_;     ///< per incident_ entry k, 4: patch_ slot of each corner
  std::vector<Index> mirror_;          ///< per patch_ slot (a, c): the slot of a in c's patch
  // Set by bind(): block indices of the Hessian rows, in the order the row pass adds them.
  std::vector<Index> corner_block_;  ///< per incident_ entry k, 4: block (a, corner)
  std::vector<Index> pair_begin_;    ///< per patch_ slot (a, c) + 1: offsets into pair_block_
  std::vector<Index> pair_block_;    ///< block (a, b) for every b in c's patch
};

/// The NodalVolume module of the groups whose formulation is VolumeFormulation::kNodalPressure
/// (their tets, each with its material's small-strain bulk modulus), or null when there is none.
std::unique_ptr<NodalVolume> make_nodal_volume(const Points& X, const TetIndices& tets,
                                               const std::vector<ElasticGroup>& groups);

}  // namespace depthfem

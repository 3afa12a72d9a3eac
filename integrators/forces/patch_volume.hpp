#pragma once
/// The volumetric energy of nearly incompressible tets, on volume changes of tet patches: the
/// patch around each node (average nodal pressure: Bonet and Burton 1998; Bonet, Marriott and
/// Hassan 2001) or disjoint patches of face-adjacent tets (F-bar in its energy form: de Souza
/// Neto, Andrade Pires and Owen 2005).

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

/// Groups of tets ("patches"), each of whose summed volume carries one volumetric energy: the
/// member tets of patch P are tets[begin[P] .. begin[P + 1]), as positions in the module's list
/// of tets, each counted with the patch's `share` of its volume.
struct TetPatches {
  std::vector<Index> begin{0};  ///< #patches + 1 offsets into tets
  std::vector<Index> tets;      ///< members, increasing within a patch
  std::vector<double> share;    ///< per patch: the share of each member's volume
  Index size() const { return static_cast<Index>(share.size()); }
  /// Appends the patches of `more`, whose member positions are offset by `first_tet`.
  void append(const TetPatches& more, Index first_tet);
};

/// The patch of every node that `tets` (#tets x 4 node ids, any numbering) touch, in increasing
/// node order: the tets at the node, each with a quarter of its volume (average nodal pressure).
TetPatches node_patches(const TetIndices& tets);

/// Disjoint patches of face-adjacent tets covering `tets`, each with its whole volume: a patch
/// grows from the lowest-numbered free tet by adding the lowest-numbered free tet that shares a
/// face with it, until it has `target` tets or no free neighbour. A patch left with fewer than
/// target / 2 tets then joins the smallest patch it shares a face with (the lowest-numbered of
/// equals), so that no tet but an isolated one keeps its own volume. Deterministic; on the
/// structured meshes of core/mesh_generators.hpp (6 consecutive tets per hexahedron) target 6
/// gives the hexahedra. Throws std::invalid_argument for target < 1.
TetPatches element_patches(const TetIndices& tets, int target);

/// E = sum over patches P of K_P U~(J_P), U~ = VolumetricPenalty, with (s_P the patch's share)
///   V_P = s_P sum_{e in P} V_e,  v_P = s_P sum_{e in P} v_e,  J_P = v_P / V_P,
///   K_P = s_P sum_{e in P} kappa_e V_e,
/// V_e, v_e the rest and current volumes of tet e and kappa_e its material's bulk modulus. With
/// the isochoric energy of each tet (VolumeFormulation::kNodalPressure or kPatchVolume in
/// elasticity.hpp) this is the total energy of the formulation: a tet no longer has to keep its
/// own volume, only the patches do, which frees linear tets from volumetric locking when there
/// are few enough patches. With node patches (s = 1/4) it is the average nodal pressure tet;
/// with disjoint patches (s = 1) it is F-bar with F~ = (J_P / J_e)^(1/3) F_e for a decoupled
/// energy psi_iso(F) + kappa U~(J).
///
/// With pi_P = K_P U~'(J_P) / V_P (the patch pressure), k_P = K_P U~''(J_P) / V_P^2 and
/// p_e = sum_{P containing e} s_P pi_P (the tet's pressure):
///   grad E = sum_e p_e dv_e/dx,
///   hess E = sum_e p_e d2v_e/dx2 + sum_P k_P w_P w_P^T,  w_P = dv_P/dx = s_P sum_{e in P} dv_e/dx,
/// so the second term couples every pair of nodes of a patch: the Hessian pattern is wider than
/// the tets' own (add_couplings).
///
/// Evaluation runs in passes over SoA arrays, none with a per-element virtual call: tets
/// (current volume and its gradient), patches (v_P, energy, pressure), tets (p_e), nodes
/// (gathering the gradient), patches (w_P) and nodes (the Hessian rows). Each pass writes only
/// its own entries and gathers in a fixed order, so results are bitwise identical for any number
/// of threads.
class PatchVolume final : public ForceModule {
 public:
  /// The tets `which` (global ids into `tets`) with bulk modulus `kappa` [Pa] each, reference
  /// positions X, grouped into `patches` (members are positions in `which`). Throws InputError
  /// naming a tet that is flat or inverted in X.
  PatchVolume(const Points& X, const TetIndices& tets, std::span<const Index> which,
              std::span<const double> kappa, const TetPatches& patches);

  std::string name() const override { return "patch volume"; }
  void add_couplings(SparsityBuilder& builder) const override;
  void bind(const BlockSparseMatrix& hessian) override;
  bool fixed_couplings() const override { return true; }
  void rebind(const BlockSparseMatrix& hessian, std::span<const Index> moved) override;
  double evaluate(const Points& x, VectorX* gradient, BlockSparseMatrix* hessian) const override;

  /// J_P = v_P / V_P of every patch at x, in the patches' order.
  VectorX volume_ratios(const Points& x) const;
  /// The pressure p_e [Pa] (positive in tension) of the volumetric energy in every tet at x, per
  /// global tet (#rows of the constructor's `tets`; zero for the tets not in the module): the
  /// Cauchy pressure of the formulation, constant over a tet.
  VectorX tet_pressures(const Points& x) const;

 private:
  /// Current volume of every tet at x; with `gradient`, also dv_e/dx (#tets x 12, node-major).
  void tet_volumes(const Points& x, VectorX& volume,
                   Eigen::Matrix<double, Eigen::Dynamic, 12>* gradient) const;
  /// v_P of patch P from the tets' current volumes.
  double patch_volume(Index P, const VectorX& v) const;
  /// p_e of every tet from the patch pressures pi_P.
  VectorX pressures(const VectorX& pi) const;

  Index num_tets_ = 0;                 ///< rows of the constructor's `tets`
  std::vector<Index> which_;           ///< global id of each tet
  TetIndices tet_;                     ///< #tets x 4 local node ids (into node_)
  std::vector<Index> node_;            ///< global id of each local node
  TetPatches patches_;                 ///< the patches, members as local tet ids
  VectorX rest_volume_;                ///< V_P per patch [m^3]
  VectorX bulk_;                       ///< K_P per patch [N m]
  std::vector<Index> incident_begin_;  ///< #nodes + 1 offsets into incident_
  std::vector<Index> incident_;        ///< 4 tet + corner of each tet at the node, increasing
  std::vector<Index> in_patch_begin_;  ///< #tets + 1 offsets into in_patch_
  std::vector<Index> in_patch_;        ///< the patches containing each tet, increasing
  std::vector<Index> node_begin_;      ///< #patches + 1 offsets into patch_node_
  std::vector<Index> patch_node_;      ///< local nodes of each patch, increasing ("slots")
  std::vector<Index> corner_slot_;     ///< per patch member m, 4: slot of each corner
  std::vector<Index> member_begin_;    ///< #nodes + 1 offsets into member_patch_, member_slot_
  std::vector<Index> member_patch_;    ///< the patches whose nodes include the node, increasing
  std::vector<Index> member_slot_;     ///< the node's slot in each of those patches
  // Set by bind(): block indices of the Hessian rows, in the order the row pass adds them.
  std::vector<Index> corner_block_;  ///< per incident_ entry k, 4: block (a, corner)
  std::vector<Index> pair_begin_;    ///< per member_ entry + 1: offsets into pair_block_
  std::vector<Index> pair_block_;    ///< block (a, b) for every b of the patch
};

/// The PatchVolume module of the groups whose formulation is VolumeFormulation::kNodalPressure
/// (one patch per node of their tets) or kPatchVolume (each group's tets in element_patches of
/// its patch_size), each tet with its material's small-strain bulk modulus; null when there is
/// none.
std::unique_ptr<PatchVolume> make_patch_volume(const Points& X, const TetIndices& tets,
                                               const std::vector<ElasticGroup>& groups);

}  // namespace depthfem

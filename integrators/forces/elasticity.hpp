#pragma once
/// Hyperelastic force module: TBB-parallel tet kernels over material groups.

#include <optional>
#include <vector>

#include "core/force_module.hpp"
#include "core/tet_block.hpp"
#include "integrators/forces/viscoelastic_history.hpp"
#include "materials/material.hpp"

namespace depthfem {

/// How a group's tets take the volume change.
enum class VolumeFormulation {
  kStandard,  ///< psi(F) of each tet, the material as given (locks as nu -> 0.5)
  /// psi(J^-1/3 F) of each tet (materials/isochoric.hpp); the volume change is averaged over the
  /// nodes by a PatchVolume module (patch_volume.hpp: node_patches), which the owner adds for
  /// these tets
  kNodalPressure,
  /// psi(J^-1/3 F) of each tet; the volume change is taken on disjoint patches of about
  /// ElasticGroup::patch_size face-adjacent tets (F-bar in its energy form) by a PatchVolume
  /// module (patch_volume.hpp: element_patches), which the owner adds for these tets
  kPatchVolume,
};

/// Tets sharing one material model; `fibers` has a direction per tet when the model needs one.
struct ElasticGroup {
  MaterialModel material;
  std::vector<Index> tets;  ///< global tet ids
  Points fibers;            ///< #tets x 3 or empty
  VolumeFormulation formulation = VolumeFormulation::kStandard;
  /// With kPatchVolume: the target number of tets per patch (element_patches in patch_volume.hpp)
  int patch_size = 6;
  /// Relaxation of the isochoric stress (materials/viscoelastic.hpp); empty: elastic. Only with
  /// the standard formulation.
  PronySeries viscoelastic = {};
};

/// Options of the elastic force module.
struct ElasticityOptions {
  /// Project each tet's 12x12 Hessian onto the positive semi-definite matrices before it is
  /// added (psd_projection.hpp): the assembled Hessian is then positive semi-definite however the
  /// elements are compressed, at the price of one 12x12 eigen-decomposition per tet.
  bool project_hessian = false;
  /// Seconds per unit of load (the duration of a time-dependent analysis: load = t / duration);
  /// 0 for a static analysis, where viscoelastic groups use their static modulus.
  double duration = 0;
};

/// Sum over groups of V psi(F) per tet. Each group's data is a color-ordered TetBlock, and the
/// kernel is instantiated per material type: one std::visit per group, none per element. A chunk
/// goes through the batched kernel (batched_tet_kernel.hpp) kLanes rows at a time, the rows left
/// over through the scalar one; the Hessian blocks are added through indices found in bind().
/// Results are bitwise identical for any number of threads: elements of one color share no
/// node, colors run in a fixed order, and energies are summed with a fixed chunking.
class Elasticity final : public ForceModule {
 public:
  /// Validates each group's material and builds its block from the reference positions X.
  Elasticity(const Points& X, const TetIndices& tets, std::vector<ElasticGroup> groups,
             const ElasticityOptions& options = {});

  std::string name() const override { return "elasticity"; }
  void add_couplings(SparsityBuilder& builder) const override;
  void bind(const BlockSparseMatrix& hessian) override;
  bool fixed_couplings() const override { return true; }
  void rebind(const BlockSparseMatrix& hessian, std::span<const Index> moved) override;
  double evaluate(const Points& x, VectorX* gradient, BlockSparseMatrix* hessian) const override;

  /// Viscoelastic groups: the history starts at the first step's x, each step ends at time
  /// load * duration, and an accepted step moves the history to its x.
  void begin_step(const Points& x) override;
  void set_load(double load) override;
  void complete_step(const Points& x) override;
  /// Energy [J] the viscoelastic groups dissipated since the last begin_step: over the step, in
  /// as many accepted parts as it was completed in (ARKODE's internal steps; 0 without).
  double dissipated_energy() const { return dissipated_; }
  /// Whether some group is viscoelastic in time (a time-dependent analysis).
  bool has_history() const;
  /// With a history: the dissipated energy of the step (StepRecord::dissipated_energy).
  void report(const Points& x, StepRecord& step) const override;
  /// Columns of history_state(): 6 (K + 2) for the most Prony terms K of a viscoelastic group
  /// in time; 0 without one.
  Index history_columns() const;
  /// #tets x history_columns() (global tet order): each viscoelastic tet's internal variables
  /// at the last accepted step, S_iso, E, Q_1 ... Q_K (ViscoelasticHistory::state; a group of
  /// fewer terms leaves the columns after its own zero), elastic tets zero. What a restarted run
  /// needs to go on exactly (restore_history).
  Eigen::MatrixXd history_state() const;
  /// Goes on from a history_state() of a step accepted at `load` (its time / the duration), as
  /// if that step had been accepted here. Throws std::logic_error for another shape.
  void restore_history(const Eigen::MatrixXd& state, double load);
  /// #tets x 6 (global tet order; xx, yy, zz, xy, yz, xz) Cauchy viscous stress of the last
  /// accepted step at its positions x [Pa]; zero in elastic groups.
  SymmetricColumns viscous_stress(const Points& x) const;

  /// Largest a such that every tet keeps det F > 0 along x + a dx, looked for up to a = 2 (a
  /// Newton step is at most 1); +infinity beyond.
  double max_step(const Points& x, const Points& dx) const override;

  /// Global id of the first tet (in group order) with det F <= 0 at x, or -1 if none.
  Index first_inverted(const Points& x) const;

 private:
  struct Group {
    MaterialModel material;
    VolumeFormulation formulation;
    TetBlock block;
    std::vector<Index> scatter = {};  ///< 16 block indices per row: (a, b) at 16 e + 4 a + b
    std::optional<ViscoelasticHistory> history = {};  ///< viscoelastic groups only
  };
  std::vector<Group> groups_;
  ElasticityOptions options_;
  Index num_tets_ = 0;
  double dissipated_ = 0;
};

}  // namespace depthfem

#pragma once
/// The internal variables of a viscoelastic element group (materials/viscoelastic.hpp) and what
/// they add to the step's incremental potential: 1/2 V h : (C - I) per tet.
///
/// Per tet and Prony term the viscous stress Q_i of the last accepted step, and per tet the
/// isochoric stress S_iso and Green strain E = (C - I)/2 there: symmetric 3x3 tensors stored as
/// SoA columns in the TetBlock's row order (components xx, yy, zz, xy, yz, xz). A step only reads
/// them: set_time() forms h = sum_i (e^-x_i Q_i - gamma_i S_iso) for the step's length, the
/// kernels evaluate with it, and accept() writes the new state once the step is accepted. A
/// rejected attempt or a failed Newton iterate therefore leaves the history untouched: the next
/// attempt starts again from the accepted state.
///
/// The h term per tet, with P = F h and D = Dm^-1:
///   energy V/2 h : (C - I);  gradient on nodes 1..3: V F h D^T (column b), node 0 minus the sum;
///   Hessian: (D h D^T)(b, c) V I3 between nodes b + 1 and c + 1, node 0 balancing them.

#include <Eigen/Core>
#include <vector>

#include "core/block_sparse_matrix.hpp"
#include "core/tet_block.hpp"
#include "materials/material.hpp"
#include "materials/viscoelastic.hpp"

namespace depthfem {

/// #rows x 6 symmetric tensors (xx, yy, zz, xy, yz, xz), one contiguous column per component.
using SymmetricColumns = Eigen::Matrix<double, Eigen::Dynamic, 6>;

class ViscoelasticHistory {
 public:
  /// For a group of `rows` tets. Untimed (a static analysis): no history, the isochoric scale
  /// stays beta_inf (prony.static_relaxed) or 1.
  ViscoelasticHistory(PronySeries prony, Index rows, bool timed);

  bool timed() const { return timed_; }
  /// The number of Prony terms K.
  Index terms() const { return Index(prony_.weights.size()); }
  /// s of the current step: psi + (s - 1) psi_iso is the group's elastic part.
  double isochoric_scale() const { return step_.scale; }

  /// Starts the history at time 0 at x: the body rested in its reference state before and
  /// reached x at once, so Q_i = beta_i S_iso(C(x)). Done once, at the first step.
  void start(const MaterialModel& m, const TetBlock& b, const Points& x);
  bool started() const { return started_; }

  /// Moves the end of the current step to time t [s] (t >= the accepted time): the coefficients
  /// of prony_step and h per tet. Cheap when t is unchanged.
  void set_time(double t);

  /// Energy of the h term over rows [begin, end) at x; adds its gradient and (through the 16
  /// scatter offsets per row) Hessian when the pointers are non-null, each tet's Hessian
  /// projected to positive semi-definite with `project`.
  double evaluate_rows(const TetBlock& b, const Index* scatter, const Points& x, Index begin,
                       Index end, VectorX* g, BlockSparseMatrix* H, bool project) const;

  /// Accepts the current step at x: Q_i = h_i + gamma_i S_iso(C(x)), S_iso and E move to x.
  /// Returns the energy [J] the group dissipated over the step:
  ///   sum_tets V sum_i [ 1/2 (Q_i^n + Q_i^{n+1}) : (E^{n+1} - E^n)
  ///                      - (Q_i^{n+1} : Q_i^{n+1} - Q_i^n : Q_i^n) / (4 beta_i mu) ],
  /// the work done on each Maxwell branch (trapezoidal rule) less the change of its stored
  /// energy Q : Q / (4 beta_i mu) (mu: the small-strain shear modulus); exact for the linear
  /// model at small strain, where each branch is a spring of modulus beta_i mu and a dashpot.
  double accept(const MaterialModel& m, const TetBlock& b, const Points& x);

  /// The internal variables of the last accepted step per row, what restore() takes back: S_iso,
  /// E, Q_1 ... Q_K (K = the Prony terms), 6 columns each; empty untimed.
  Eigen::MatrixXd state() const;
  /// Goes on from a state() whose step was accepted at time t [s] (a restarted run): exactly as
  /// if that step had been accepted here. `state` must have #rows x 6 (K + 2) values.
  void restore(const Eigen::MatrixXd& state, double t);

  /// The viscous stress sum_i Q_i of the last accepted step per row as a Cauchy stress at x
  /// (that step's positions): F (sum_i Q_i) F^T / J [Pa].
  SymmetricColumns viscous_stress(const TetBlock& b, const Points& x) const;

 private:
  PronySeries prony_;
  bool timed_;
  bool started_ = false;
  double accepted_time_ = 0, time_ = 0;
  PronyStep step_;
  std::vector<SymmetricColumns> Q_;  ///< per Prony term
  SymmetricColumns S_iso_, E_;       ///< at the last accepted step
  SymmetricColumns h_;               ///< of the current step
};

}  // namespace depthfem

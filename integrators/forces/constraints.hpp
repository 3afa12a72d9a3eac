#pragma once
/// Dirichlet conditions: fixed, displaced and rotated node sets, and nodes held to a plane or line.

#include <string>
#include <variant>
#include <vector>

#include "core/block_sparse_matrix.hpp"
#include "core/types.hpp"

namespace depthfem {

/// x = X (held in place).
struct Fixed {};
/// x = X + lambda u.
struct Displaced {
  Vec3 u = Vec3::Zero();  ///< [m]
};
/// x = c + R(lambda angle, axis) (X - c) + lambda t.
struct Rotated {
  Vec3 axis = Vec3::UnitZ();
  Vec3 center = Vec3::Zero();       ///< [m]
  double angle = 0;                 ///< [rad]
  Vec3 translation = Vec3::Zero();  ///< [m]
};
/// n . x = n . X + lambda offset: the node moves only within a plane (which may shift along n).
struct InPlane {
  Vec3 normal = Vec3::UnitZ();
  double offset = 0;  ///< [m]
};
/// x - X parallel to `direction`: the node moves only along a line.
struct OnLine {
  Vec3 direction = Vec3::UnitZ();
};

/// One boundary condition of a scene: a kind applied to a node set.
struct Constraint {
  std::string name;
  std::vector<Index> nodes;
  std::variant<Fixed, Displaced, Rotated, InPlane, OnLine> kind;
};

/// All Dirichlet conditions of a scene as per-node projections.
/// Each constrained node i has a projector C_i onto its constrained directions (I for fixed,
/// displaced and rotated nodes, n n^T for a plane, I - a a^T for a line; several conditions on
/// one node combine into the span of their directions) and a target point x_i(lambda) that
/// satisfies them. The solver keeps C_i x_i = C_i x_i(lambda) and moves only along P_i = I - C_i.
/// Where a node is both fully prescribed and in a plane or on a line, the full prescription wins.
class Constraints {
 public:
  Constraints() = default;
  /// Throws InputError naming the condition for out-of-range nodes or zero directions.
  Constraints(const Points& X, std::vector<Constraint> list);

  /// Moves the constrained components of x to their values at load factor lambda.
  void impose(double lambda, Points& x) const;
  /// Zeroes the constrained components of an interleaved vector (3 per node).
  void project(VectorX& v) const;
  /// Replaces every block B_ij by P_i B_ij P_j, and adds C_i to diagonal blocks: the matrix of
  /// the Newton system restricted to the free directions, identity on the constrained ones.
  void project(BlockSparseMatrix& H) const;
  /// Force each condition exerts on the body [N], #conditions x 3: at equilibrium the supports
  /// balance the energy gradient g on the constrained directions, so it is sum_i C_i g_i. Every
  /// constrained direction belongs to exactly one condition (a full prescription owns its
  /// nodes; a plane or line the directions it added), so the rows sum to sum_i C_i g_i, which
  /// at equilibrium is minus the applied loads.
  Eigen::Matrix<double, Eigen::Dynamic, 3> reactions(const VectorX& g) const;

  const std::vector<Constraint>& list() const { return list_; }
  /// 1 for every node constrained in all three directions (C_i = I), 0 for the others: after
  /// project(H) their rows and columns are zero off the diagonal.
  std::vector<char> fully_constrained_nodes() const;

 private:
  struct NodeState {
    Index node;
    Mat3 C;               // projector onto the constrained directions
    Index full = -1;      // index of the fully prescribing condition, or -1
    Vec3 shift_per_load;  // plane offsets: target = X + lambda shift_per_load
    std::vector<std::pair<Index, Mat3>> owners;  // (condition, its part of C); parts sum to C
  };
  Vec3 target(const NodeState& s, double lambda) const;

  Points X_;
  std::vector<Constraint> list_;
  std::vector<NodeState> states_;
  std::vector<Index> slot_;  // node -> index into states_, or -1
};

}  // namespace depthfem

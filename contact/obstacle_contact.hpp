#pragma once
/// Analytic obstacles (a half-space below a plane, a sphere) pressing on boundary triangles with
/// the same clipping and penalty integration as the material-depth contact: the obstacle's depth
/// g(x) (distance into the obstacle) is evaluated at triangle corners, interpolated linearly, and
/// eps/2 g^2 integrated over the part of the triangle where it is positive.

#include <variant>
#include <vector>

#include "contact/pair_schedule.hpp"
#include "contact/penalty_derivatives.hpp"
#include "core/force_module.hpp"
#include "core/mesh.hpp"

namespace depthfem {

/// Everything below the plane through `point` with outward normal `normal` is solid.
struct PlaneObstacle {
  Vec3 point = Vec3::Zero();
  Vec3 normal = Vec3::UnitZ();
};
/// A solid ball.
struct SphereObstacle {
  Vec3 center = Vec3::Zero();
  double radius = 1;
};

/// An obstacle that moves rigidly by load x `motion` (displacement at full load [m]).
struct Obstacle {
  std::string name;
  std::variant<PlaneObstacle, SphereObstacle> shape;
  Vec3 motion = Vec3::Zero();
  double penalty = 1e6;  ///< eps [Pa/m]
};

/// Contact of the boundary triangles of the listed bodies with analytic obstacles. Derivatives
/// come from the staged chain rule (field_polygon_penalty_derivatives); the triangles touching an
/// obstacle are walked and scattered as the material-depth pairs are (PairSchedule).
class ObstacleContact final : public ForceModule {
 public:
  /// `bodies`: the bodies that touch the obstacles (their boundary triangles).
  ObstacleContact(const Mesh& mesh, const std::vector<Index>& bodies,
                  std::vector<Obstacle> obstacles);

  std::string name() const override { return "obstacles"; }
  void set_load(double load) override;
  void prepare(const Points& x) override;
  void add_couplings(SparsityBuilder& builder) const override;
  void bind(const BlockSparseMatrix& hessian) override;
  bool pattern_changed() const override { return false; }
  double evaluate(const Points& x, VectorX* gradient, BlockSparseMatrix* hessian) const override;

  /// One row per obstacle, "obstacle NAME": the force it exerts on the bodies [N] (and its
  /// magnitudes summed over triangles) and the boundary area inside it [m^2] at x; and each
  /// triangle's share in step.surface.
  void report(const Points& x, StepRecord& step) const override;
  /// "obstacle NAME" per obstacle.
  std::vector<std::string> interface_names() const override;

 private:
  // Energy of triangle f in obstacle o, with its gradient and Hessian where asked for.
  double triangle_derivatives(const Points& x, Index o, Index f, TriangleGradient* gradient,
                              TriangleHessian* hessian) const;

  TriIndices tris_;
  std::vector<Index> tri_ids_;  // mesh triangle of each row of tris_
  Index num_mesh_tris_ = 0;
  std::vector<Obstacle> obstacles_;
  double load_ = 0;
  // (obstacle, triangle) with some corner inside, in processing order; schedule_ has their
  // triangles' corners.
  std::vector<std::pair<Index, Index>> active_;
  PairSchedule schedule_;
  const BlockSparseMatrix* bound_ = nullptr;
};

}  // namespace depthfem

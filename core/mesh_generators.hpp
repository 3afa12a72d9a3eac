#pragma once
/// Structured tetrahedral meshes: box, tube (cylindrical shell) and ball.
/// Each hexahedral cell is split into 6 tets along its main diagonal (Kuhn split); neighbouring
/// cells then split their shared faces the same way, so the meshes are conforming.

#include <cstdint>

#include "core/tet_mesh.hpp"

namespace depthfem {

/// Axis-aligned box [lo, hi] with n cells along each axis. Along an axis with ratio r, each cell
/// is r times as long as the one before it (node k of n at lo + (hi - lo) (r^k - 1) / (r^n - 1)):
/// r > 1 refines towards lo with constant relative resolution; r = 1 is uniform.
struct BoxParams {
  Vec3 lo = Vec3::Zero();  ///< [m]
  Vec3 hi = Vec3::Ones();  ///< [m]
  Eigen::Vector3i cells{1, 1, 1};
  Vec3 ratio = Vec3::Ones();
};

/// Cylindrical shell around the z axis, z in [0, length].
struct TubeParams {
  double inner_radius = 0.5;  ///< [m], > 0
  double outer_radius = 1.0;  ///< [m]
  double length = 1.0;        ///< [m]
  int cells_through_wall = 1;
  int cells_around = 16;  ///< >= 3
  int cells_along = 4;
};

/// Solid ball centred at `center`: a cube grid mapped smoothly onto the ball, so that boundary
/// nodes lie exactly on the sphere.
struct BallParams {
  Vec3 center = Vec3::Zero();  ///< [m]
  double radius = 1.0;         ///< [m]
  int cells_per_axis = 4;      ///< cells along each axis of the underlying cube (>= 1)
};

/// Cube [0, size]^3 graded towards the corner at the origin (a point load or contact at a corner
/// of a symmetric model): a core cube of edge `core` with core_cells^3 uniform cells, then
/// shells between nested cubes whose edges grow geometrically to `size` (by `ratio`, adjusted so
/// that the last is exactly `size`), each face of a shell divided into core_cells^2 cells. Cells
/// keep their shape while growing (aspect ratio about (ratio - 1) core_cells), unlike per-axis
/// grading, whose cells far along one axis and near another are slivers.
struct CornerParams {
  double size = 1.0;   ///< [m]
  double core = 0.1;   ///< [m], < size
  int core_cells = 8;  ///< >= 1
  double ratio = 1.2;  ///< > 1
};

/// How many nodes and tets a generator makes, counted in 64 bits before anything is allocated.
struct MeshCounts {
  std::int64_t nodes = 0, tets = 0;
};

/// Checks the parameters of a generator without generating anything and returns the counts it
/// will make. Throws ParameterError naming the field at fault: sizes out of order or not finite,
/// no cells, grading that overflows, or more nodes or tets than a 32-bit Index can number.
MeshCounts checked_counts(const BoxParams& p);
MeshCounts checked_counts(const TubeParams& p);
MeshCounts checked_counts(const BallParams& p);
MeshCounts checked_counts(const CornerParams& p);

/// Box mesh with (n+1)^3 nodes and 6 n^3 tets; node (i, j, k) has index i + (nx+1)(j + (ny+1) k).
TetMesh box_mesh(const BoxParams& p);
/// Tube mesh. Every generator first runs checked_counts (ParameterError); a generated element that
/// is degenerate throws InputError "GENERATOR: element N is degenerate ...".
TetMesh tube_mesh(const TubeParams& p);
/// Ball mesh.
TetMesh ball_mesh(const BallParams& p);
/// Corner-graded cube.
TetMesh corner_mesh(const CornerParams& p);

}  // namespace depthfem

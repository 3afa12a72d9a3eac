#include "core/mesh_generators.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <map>
#include <numbers>
#include <string>
#include <utility>

#include "core/error.hpp"

namespace depthfem {

namespace {

// The source of a generated mesh, named after its generator (aggregate initialisation of
// MeshSource would leave its other members to -Wmissing-field-initializers).
MeshSource generated(std::string name) {
  MeshSource source;
  source.file = std::move(name);
  return source;
}

// Splits every cell of an nx x ny x nz grid of nodes into 6 tets. `node(i, j, k)` maps grid
// coordinates (i may wrap for periodic directions) to a node index.
TetIndices kuhn_tets(int nx, int ny, int nz, const std::function<Index(int, int, int)>& node) {
  // The 6 monotone lattice paths from corner (0,0,0) to (1,1,1), one per axis permutation.
  static constexpr int kPerm[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2},
                                      {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  TetIndices tets(Index(6) * nx * ny * nz, 4);  // the count was checked to fit an Index
  Index t = 0;
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i)
        for (const auto& perm : kPerm) {
          int c[3] = {i, j, k};
          tets(t, 0) = node(c[0], c[1], c[2]);
          for (int s = 0; s < 3; ++s) {
            ++c[perm[s]];
            tets(t, s + 1) = node(c[0], c[1], c[2]);
          }
          ++t;
        }
  return tets;
}

void require(bool ok, const char* parameter, const std::string& what) {
  if (!ok) throw ParameterError(parameter, what);
}

// Counts of a mesh, refused when they do not fit an Index; products in double are exact far past
// 2^31, so the comparison sees the true count (no overflow).
MeshCounts fitting(double nodes, double tets, const char* parameter) {
  constexpr double kMax = std::numeric_limits<Index>::max();
  const auto shown = [](double n) {
    char text[32];
    std::snprintf(text, sizeof text, "%.4g", n);
    return std::string(text);
  };
  require(nodes <= kMax && tets <= kMax, parameter,
          "gives " + shown(nodes) + " nodes and " + shown(tets) +
              " tets, more than the 2147483647 a 32-bit index can number");
  return {static_cast<std::int64_t>(nodes), static_cast<std::int64_t>(tets)};
}

bool finite(const Vec3& v) {
  return v.allFinite();
}

}  // namespace

MeshCounts checked_counts(const BoxParams& p) {
  const Eigen::Vector3i n = p.cells;
  require(finite(p.lo), "lo", "must be finite");
  require(finite(p.hi) && finite(p.hi - p.lo), "hi", "must be finite, and so must hi - lo");
  require((p.hi - p.lo).minCoeff() > 0, "hi", "must exceed lo along every axis");
  require(n.minCoeff() >= 1, "cells", "must be >= 1 along every axis");
  require(finite(p.ratio) && p.ratio.minCoeff() > 0, "ratio", "cell size ratios must be > 0");
  for (int a = 0; a < 3; ++a) {
    require(std::isfinite(std::pow(p.ratio(a), n(a))) && std::pow(p.ratio(a), n(a)) > 0, "ratio",
            "ratio^cells overflows along axis " + std::to_string(a));
  }
  const Eigen::Array3d c = n.cast<double>().array();
  return fitting((c + 1).prod(), 6 * c.prod(), "cells");
}

TetMesh box_mesh(const BoxParams& p) {
  checked_counts(p);
  const Eigen::Vector3i n = p.cells;
  // Fraction of the length below node k of n along an axis with cell ratio r.
  const auto fraction = [](int k, int n, double r) {
    return std::abs(r - 1) < 1e-12 ? double(k) / n : (std::pow(r, k) - 1) / (std::pow(r, n) - 1);
  };
  TetMesh m;
  m.X.resize((n(0) + 1) * (n(1) + 1) * (n(2) + 1), 3);
  const auto id = [&](int i, int j, int k) { return i + (n(0) + 1) * (j + (n(1) + 1) * k); };
  for (int k = 0; k <= n(2); ++k)
    for (int j = 0; j <= n(1); ++j)
      for (int i = 0; i <= n(0); ++i) {
        const Vec3 s(fraction(i, n(0), p.ratio(0)), fraction(j, n(1), p.ratio(1)),
                     fraction(k, n(2), p.ratio(2)));
        m.X.row(id(i, j, k)) = (p.lo.array() + s.array() * (p.hi - p.lo).array()).transpose();
      }
  m.tets = kuhn_tets(n(0), n(1), n(2), id);
  validate_and_orient(m, generated("box"));
  return m;
}

MeshCounts checked_counts(const TubeParams& p) {
  require(p.inner_radius > 0 && std::isfinite(p.inner_radius), "inner_radius",
          "must be > 0 and finite");
  require(p.outer_radius > p.inner_radius && std::isfinite(p.outer_radius), "outer_radius",
          "must exceed inner_radius and be finite");
  require(p.length > 0 && std::isfinite(p.length), "length", "must be > 0 and finite");
  require(p.cells_through_wall >= 1, "cells_through_wall", "must be >= 1");
  require(p.cells_around >= 3, "cells_around", "must be >= 3");
  require(p.cells_along >= 1, "cells_along", "must be >= 1");
  const double nr = p.cells_through_wall, nt = p.cells_around, nz = p.cells_along;
  return fitting((nr + 1) * nt * (nz + 1), 6 * nr * nt * nz, "cells_around");
}

TetMesh tube_mesh(const TubeParams& p) {
  checked_counts(p);
  const int nr = p.cells_through_wall, nt = p.cells_around, nz = p.cells_along;
  TetMesh m;
  m.X.resize((nr + 1) * nt * (nz + 1), 3);
  // Around the circumference the grid wraps: index it = nt is node it = 0.
  const auto id = [&](int ir, int it, int iz) { return ir + (nr + 1) * ((it % nt) + nt * iz); };
  for (int iz = 0; iz <= nz; ++iz)
    for (int it = 0; it < nt; ++it)
      for (int ir = 0; ir <= nr; ++ir) {
        const double r = p.inner_radius + (p.outer_radius - p.inner_radius) * ir / nr;
        const double th = 2 * std::numbers::pi * it / nt;
        m.X.row(id(ir, it, iz)) =
            Vec3(r * std::cos(th), r * std::sin(th), p.length * iz / nz).transpose();
      }
  m.tets = kuhn_tets(nr, nt, nz, id);
  validate_and_orient(m, generated("tube"));
  return m;
}

MeshCounts checked_counts(const BallParams& p) {
  require(finite(p.center), "center", "must be finite");
  require(p.radius > 0 && std::isfinite(p.radius), "radius", "must be > 0 and finite");
  require(p.cells_per_axis >= 1, "cells_per_axis", "must be >= 1");
  const double n = p.cells_per_axis;
  return fitting((n + 1) * (n + 1) * (n + 1), 6 * n * n * n, "cells_per_axis");
}

TetMesh ball_mesh(const BallParams& p) {
  checked_counts(p);
  const int n = p.cells_per_axis;
  TetMesh m = box_mesh({Vec3::Constant(-1), Vec3::Constant(1), Eigen::Vector3i::Constant(n)});
  // Cube-to-ball map x' = x sqrt(1 - y^2/2 - z^2/2 + y^2 z^2/3) (and cyclic): smooth, one-to-one,
  // and |x'| = 1 exactly on the cube's surface.
  for (Index v = 0; v < m.X.rows(); ++v) {
    const double x = m.X(v, 0), y = m.X(v, 1), z = m.X(v, 2);
    const double x2 = x * x, y2 = y * y, z2 = z * z;
    const Vec3 q(x * std::sqrt(1 - y2 / 2 - z2 / 2 + y2 * z2 / 3),
                 y * std::sqrt(1 - z2 / 2 - x2 / 2 + z2 * x2 / 3),
                 z * std::sqrt(1 - x2 / 2 - y2 / 2 + x2 * y2 / 3));
    m.X.row(v) = (p.center + p.radius * q).transpose();
  }
  validate_and_orient(m, generated("ball"));
  return m;
}

namespace {
// Shells between the core and the outer cube: enough that each grows by at most `ratio` (as a
// double: a ratio just above 1 asks for more shells than an int holds).
double shell_count(const CornerParams& p) {
  return std::max(1.0, std::ceil(std::log(p.size / p.core) / std::log(p.ratio) - 1e-9));
}
}  // namespace

MeshCounts checked_counts(const CornerParams& p) {
  require(p.core > 0 && std::isfinite(p.core), "core", "must be > 0 and finite");
  require(p.size > p.core && std::isfinite(p.size), "size", "must exceed core and be finite");
  require(p.core_cells >= 1, "core_cells", "must be >= 1");
  require(p.ratio > 1 && std::isfinite(p.ratio), "ratio", "must be > 1 and finite");
  const double m = p.core_cells, shells = shell_count(p);
  // Core (m+1)^3 nodes and 6 m^3 tets; each shell adds three faces of m x m cells.
  const double nodes = (m + 1) * (m + 1) * (m + 1) + shells * (3 * m * m + 3 * m + 1);
  return fitting(nodes, 6 * m * m * m + 18 * m * m * shells, "core_cells");
}

TetMesh corner_mesh(const CornerParams& p) {
  checked_counts(p);
  const int m = p.core_cells;
  const int shells = static_cast<int>(shell_count(p));
  const double q = std::pow(p.size / p.core, 1.0 / shells);
  // Nodes shared by the blocks are computed by the same expressions, so they coincide exactly.
  std::map<std::array<double, 3>, Index> index;
  std::vector<Vec3> points;
  const auto node = [&](const Vec3& x) {
    const auto [it, inserted] =
        index.try_emplace({x(0), x(1), x(2)}, static_cast<Index>(points.size()));
    if (inserted) points.push_back(x);
    return it->second;
  };
  const auto frac = [m](int i) { return static_cast<double>(i) / m; };
  std::vector<TetIndices> blocks;
  blocks.push_back(kuhn_tets(m, m, m, [&](int i, int j, int k) {
    return node(p.core * Vec3(frac(i), frac(j), frac(k)));
  }));
  // One block of shells per cube face a = max: in-face axes b < c, both increasing, so that the
  // Kuhn diagonals of the faces two blocks (or a block and the core) share agree.
  for (int a = 0; a < 3; ++a) {
    const int b = a == 0 ? 1 : 0, c = a == 2 ? 1 : 2;
    blocks.push_back(kuhn_tets(m, m, shells, [&](int u, int v, int k) {
      const double r = k == shells ? p.size : p.core * std::pow(q, k);
      Vec3 x;
      x(a) = r;
      x(b) = r * frac(u);
      x(c) = r * frac(v);
      return node(x);
    }));
  }
  TetMesh mesh;
  mesh.X.resize(static_cast<Index>(points.size()), 3);
  for (size_t i = 0; i < points.size(); ++i)
    mesh.X.row(static_cast<Index>(i)) = points[i].transpose();
  Index total = 0;
  for (const TetIndices& t : blocks) total += static_cast<Index>(t.rows());
  mesh.tets.resize(total, 4);
  Index row = 0;
  for (const TetIndices& t : blocks) {
    mesh.tets.middleRows(row, t.rows()) = t;
    row += static_cast<Index>(t.rows());
  }
  validate_and_orient(mesh, generated("corner"));
  return mesh;
}

}  // namespace depthfem

#include "integrators/forces/nodal_volume.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <stdexcept>

#include "core/error.hpp"

namespace depthfem {

namespace {

using TetGradients = Eigen::Matrix<double, Eigen::Dynamic, 12>;

// Nodes per task of the node passes; fixed, so that the energy is summed in one tree.
constexpr Index kNodeGrain = 512;

// [v]x: the matrix of the cross product v x (.).
Mat3 cross_matrix(const Vec3& v) {
  Mat3 m;
  m << 0, -v(2), v(1), v(2), 0, -v(0), -v(1), v(0), 0;
  return m;
}

// d2 v / dx_i dx_j (3x3, row i's components, column j's) of a tet with corners p, i != j.
// 6 v = det[x1 - x0, x2 - x0, x3 - x0] is alternating and linear in each corner, so with k < l
// the other two corners and s the sign of the permutation (i, j, k, l) of (0, 1, 2, 3):
//   d2 (6 v) / dx_i dx_j = s [x_k - x_l]x.
Mat3 volume_hessian_block(const std::array<Vec3, 4>& p, int i, int j) {
  int other[2], n = 0;
  for (int c = 0; c < 4; ++c)
    if (c != i && c != j) other[n++] = c;
  const int order[4] = {i, j, other[0], other[1]};
  int inversions = 0;
  for (int a = 0; a < 4; ++a)
    for (int b = a + 1; b < 4; ++b) inversions += order[a] > order[b];
  const double sign = inversions % 2 ? -1.0 : 1.0;
  return (sign / 6.0) * cross_matrix(p[other[0]] - p[other[1]]);
}

// Position of `node` in the sorted run [first, last) of `v`, as an index into v.
Index slot_of(const std::vector<Index>& v, Index first, Index last, Index node) {
  const auto it = std::lower_bound(v.begin() + first, v.begin() + last, node);
  return static_cast<Index>(it - v.begin());
}

}  // namespace

double VolumetricPenalty::value(double J) {
  return 0.5 * (0.5 * (J * J - 1) - std::log(J));
}
double VolumetricPenalty::first(double J) {
  return 0.5 * (J - 1 / J);
}
double VolumetricPenalty::second(double J) {
  return 0.5 * (1 + 1 / (J * J));
}

NodalVolume::NodalVolume(const Points& X, const TetIndices& tets, std::span<const Index> which,
                         std::span<const double> kappa) {
  if (which.size() != kappa.size())
    throw std::invalid_argument("nodal volume: one bulk modulus per tet");
  // Local ids: the nodes the tets touch, in increasing global order.
  std::vector<Index> local(static_cast<size_t>(X.rows()), -1);
  for (Index t : which)
    for (int c = 0; c < 4; ++c) local[tets(t, c)] = 0;
  for (Index g = 0; g < X.rows(); ++g) {
    if (local[g] < 0) continue;
    local[g] = static_cast<Index>(node_.size());
    node_.push_back(g);
  }
  const Index nn = static_cast<Index>(node_.size()), nt = static_cast<Index>(which.size());
  tet_.resize(nt, 4);
  rest_volume_ = VectorX::Zero(nn);
  bulk_ = VectorX::Zero(nn);
  incident_begin_.assign(static_cast<size_t>(nn) + 1, 0);
  for (Index e = 0; e < nt; ++e) {
    const Index t = which[e];
    Mat3 Dm;
    for (int c = 0; c < 3; ++c) Dm.col(c) = (X.row(tets(t, c + 1)) - X.row(tets(t, 0))).transpose();
    const double V = Dm.determinant() / 6.0;
    if (!(V > 0))
      throw InputError("tet " + std::to_string(t) + " is flat or inverted in the reference mesh");
    for (int c = 0; c < 4; ++c) {
      const Index a = local[tets(t, c)];
      tet_(e, c) = a;
      rest_volume_[a] += 0.25 * V;
      bulk_[a] += 0.25 * kappa[e] * V;
      ++incident_begin_[a + 1];
    }
  }
  for (Index a = 0; a < nn; ++a) incident_begin_[a + 1] += incident_begin_[a];
  incident_.resize(static_cast<size_t>(incident_begin_[nn]));
  std::vector<Index> fill(incident_begin_.begin(), incident_begin_.end() - 1);
  for (Index e = 0; e < nt; ++e)
    for (int c = 0; c < 4; ++c) incident_[fill[tet_(e, c)]++] = 4 * e + c;
  // Patches: the nodes of the tets at each node, sorted; the slots of each tet's corners.
  patch_begin_.push_back(0);
  for (Index a = 0; a < nn; ++a) {
    const auto first = patch_.size();
    for (Index k = incident_begin_[a]; k < incident_begin_[a + 1]; ++k)
      for (int c = 0; c < 4; ++c) patch_.push_back(tet_(incident_[k] / 4, c));
    std::sort(patch_.begin() + first, patch_.end());
    patch_.erase(std::unique(patch_.begin() + first, patch_.end()), patch_.end());
    patch_begin_.push_back(static_cast<Index>(patch_.size()));
    for (Index k = incident_begin_[a]; k < incident_begin_[a + 1]; ++k)
      for (int c = 0; c < 4; ++c)
        corner_slot_.push_back(
            slot_of(patch_, patch_begin_[a], patch_begin_[a + 1], tet_(incident_[k] / 4, c)));
  }
  mirror_.resize(patch_.size());
  for (Index a = 0; a < nn; ++a) {
    for (Index s = patch_begin_[a]; s < patch_begin_[a + 1]; ++s) {
      const Index c = patch_[s];
      mirror_[s] = slot_of(patch_, patch_begin_[c], patch_begin_[c + 1], a);
    }
  }
}

void NodalVolume::add_couplings(SparsityBuilder& builder) const {
  std::vector<Index> clique;
  for (size_t a = 0; a + 1 < patch_begin_.size(); ++a) {
    clique.clear();
    for (Index s = patch_begin_[a]; s < patch_begin_[a + 1]; ++s)
      clique.push_back(node_[patch_[s]]);
    builder.add_clique(clique);
  }
}

void NodalVolume::bind(const BlockSparseMatrix& H) {
  const auto block = [&](Index a, Index b) {
    const Index k = H.block_index(node_[a], node_[b]);
    if (k < 0) throw std::logic_error("nodal volume: Hessian pattern lacks a patch coupling");
    return k;
  };
  const Index nn = static_cast<Index>(node_.size());
  corner_block_.clear();
  pair_begin_.assign(1, 0);
  pair_block_.clear();
  for (Index a = 0; a < nn; ++a) {
    for (Index k = incident_begin_[a]; k < incident_begin_[a + 1]; ++k)
      for (int c = 0; c < 4; ++c) corner_block_.push_back(block(a, tet_(incident_[k] / 4, c)));
    for (Index s = patch_begin_[a]; s < patch_begin_[a + 1]; ++s) {
      const Index c = patch_[s];
      for (Index t = patch_begin_[c]; t < patch_begin_[c + 1]; ++t)
        pair_block_.push_back(block(a, patch_[t]));
      pair_begin_.push_back(static_cast<Index>(pair_block_.size()));
    }
  }
}

void NodalVolume::rebind(const BlockSparseMatrix&, std::span<const Index> moved) {
  move_block_indices(corner_block_, moved, name());
  move_block_indices(pair_block_, moved, name());
}

void NodalVolume::tet_volumes(const Points& x, VectorX& volume, TetGradients* gradient) const {
  const Index nt = static_cast<Index>(tet_.rows());
  volume.resize(nt);
  if (gradient) gradient->resize(nt, 12);
  tbb::parallel_for(tbb::blocked_range<Index>(0, nt, 1024),
                    [&](const tbb::blocked_range<Index>& r) {
                      for (Index e = r.begin(); e < r.end(); ++e) {
                        const Index n0 = node_[tet_(e, 0)];
                        Vec3 d[3];
                        for (int c = 0; c < 3; ++c)
                          d[c] = (x.row(node_[tet_(e, c + 1)]) - x.row(n0)).transpose();
                        // 6 v = d1 . (d2 x d3); dv/dx_1..3 are the cross products of the other two
                        // edges over 6.
                        const Vec3 g1 = d[1].cross(d[2]) / 6.0, g2 = d[2].cross(d[0]) / 6.0,
                                   g3 = d[0].cross(d[1]) / 6.0;
                        volume[e] = d[0].dot(g1);
                        if (!gradient) continue;
                        auto row = gradient->row(e);
                        row.segment<3>(0) = -(g1 + g2 + g3);
                        row.segment<3>(3) = g1;
                        row.segment<3>(6) = g2;
                        row.segment<3>(9) = g3;
                      }
                    });
}

VectorX NodalVolume::nodal_volume_ratios(const Points& x) const {
  VectorX v;
  tet_volumes(x, v, nullptr);
  const Index nn = static_cast<Index>(node_.size());
  VectorX J(nn);
  for (Index a = 0; a < nn; ++a) {
    double va = 0;
    for (Index k = incident_begin_[a]; k < incident_begin_[a + 1]; ++k)
      va += 0.25 * v[incident_[k] / 4];
    J[a] = va / rest_volume_[a];
  }
  return J;
}

VectorX NodalVolume::nodal_pressures(const Points& x) const {
  const VectorX J = nodal_volume_ratios(x);
  VectorX p = VectorX::Zero(x.rows());
  for (size_t a = 0; a < node_.size(); ++a)
    p[node_[a]] = bulk_[a] * VolumetricPenalty::first(J[a]) / rest_volume_[a];
  return p;
}

double NodalVolume::evaluate(const Points& x, VectorX* gradient, BlockSparseMatrix* hessian) const {
  if (hessian && !gradient) throw std::logic_error("nodal volume: a Hessian needs a gradient too");
  const Index nn = static_cast<Index>(node_.size()), nt = static_cast<Index>(tet_.rows());
  VectorX v;
  TetGradients dv;
  tet_volumes(x, v, gradient ? &dv : nullptr);

  // Nodes: J_a, the energy, the nodal pressure pi_a and the stiffness k_a.
  VectorX pi(nn), k(nn);
  const double energy = tbb::parallel_deterministic_reduce(
      tbb::blocked_range<Index>(0, nn, kNodeGrain), 0.0,
      [&](const tbb::blocked_range<Index>& r, double acc) {
        for (Index a = r.begin(); a < r.end(); ++a) {
          double va = 0;
          for (Index q = incident_begin_[a]; q < incident_begin_[a + 1]; ++q)
            va += 0.25 * v[incident_[q] / 4];
          const double V = rest_volume_[a], J = va / V;
          if (!(J > 0)) return std::numeric_limits<double>::infinity();
          acc += bulk_[a] * VolumetricPenalty::value(J);
          pi[a] = bulk_[a] * VolumetricPenalty::first(J) / V;
          k[a] = bulk_[a] * VolumetricPenalty::second(J) / (V * V);
        }
        return acc;
      },
      std::plus<double>());
  if (!gradient || !std::isfinite(energy)) return energy;

  // Tets: the average nodal pressure p_e.
  VectorX p(nt);
  tbb::parallel_for(
      tbb::blocked_range<Index>(0, nt, 4096), [&](const tbb::blocked_range<Index>& r) {
        for (Index e = r.begin(); e < r.end(); ++e)
          p[e] = 0.25 * (pi[tet_(e, 0)] + pi[tet_(e, 1)] + pi[tet_(e, 2)] + pi[tet_(e, 3)]);
      });

  // Nodes: gradient sum_e p_e dv_e/dx_a, and w_a over the patch slots (with a Hessian).
  Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> w;
  if (hessian) w.setZero(static_cast<Index>(patch_.size()), 3);
  tbb::parallel_for(tbb::blocked_range<Index>(0, nn, kNodeGrain),
                    [&](const tbb::blocked_range<Index>& r) {
                      for (Index a = r.begin(); a < r.end(); ++a) {
                        Vec3 ga = Vec3::Zero();
                        for (Index q = incident_begin_[a]; q < incident_begin_[a + 1]; ++q) {
                          const Index e = incident_[q] / 4, corner = incident_[q] % 4;
                          ga += p[e] * dv.row(e).segment<3>(3 * corner).transpose();
                          if (!hessian) continue;
                          for (int c = 0; c < 4; ++c)
                            w.row(corner_slot_[4 * q + c]) += 0.25 * dv.row(e).segment<3>(3 * c);
                        }
                        gradient->segment<3>(3 * node_[a]) += ga;
                      }
                    });
  if (!hessian) return energy;
  if (corner_block_.empty() && nt > 0)
    throw std::logic_error("nodal volume: bind() the Hessian first");

  // Rows: node a adds sum_e p_e d2v_e/dx_a dx_b and sum_c k_c w_c[a] w_c[b]^T to its blocks.
  tbb::parallel_for(tbb::blocked_range<Index>(0, nn, kNodeGrain),
                    [&](const tbb::blocked_range<Index>& r) {
                      for (Index a = r.begin(); a < r.end(); ++a) {
                        for (Index q = incident_begin_[a]; q < incident_begin_[a + 1]; ++q) {
                          const Index e = incident_[q] / 4, i = incident_[q] % 4;
                          std::array<Vec3, 4> corners;
                          for (int c = 0; c < 4; ++c)
                            corners[c] = x.row(node_[tet_(e, c)]).transpose();
                          for (int j = 0; j < 4; ++j)
                            if (j != i)
                              hessian->add_block(corner_block_[4 * q + j],
                                                 p[e] * volume_hessian_block(corners, i, j));
                        }
                        for (Index s = patch_begin_[a]; s < patch_begin_[a + 1]; ++s) {
                          const Index c = patch_[s];
                          const Vec3 wa = k[c] * w.row(mirror_[s]).transpose();
                          const Index* blocks = pair_block_.data() + pair_begin_[s];
                          for (Index t = patch_begin_[c]; t < patch_begin_[c + 1]; ++t)
                            hessian->add_block(blocks[t - patch_begin_[c]], wa * w.row(t));
                        }
                      }
                    });
  return energy;
}

std::unique_ptr<NodalVolume> make_nodal_volume(const Points& X, const TetIndices& tets,
                                               const std::vector<ElasticGroup>& groups) {
  std::vector<Index> which;
  std::vector<double> kappa;
  for (const ElasticGroup& g : groups) {
    if (g.formulation != VolumeFormulation::kNodalPressure) continue;
    const double bulk = material_moduli(g.material).bulk();
    which.insert(which.end(), g.tets.begin(), g.tets.end());
    kappa.insert(kappa.end(), g.tets.size(), bulk);
  }
  if (which.empty()) return nullptr;
  return std::make_unique<NodalVolume>(X, tets, which, kappa);
}

}  // namespace depthfem

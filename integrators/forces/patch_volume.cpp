#include "integrators/forces/patch_volume.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <set>
#include <span>
#include <stdexcept>

#include "core/error.hpp"

namespace depthfem {

namespace {

using TetGradients = Eigen::Matrix<double, Eigen::Dynamic, 12>;

// Nodes or patches per task of their passes; fixed, so that the energy is summed in one tree.
constexpr Index kGrain = 512;

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

void TetPatches::append(const TetPatches& more, Index first_tet) {
  for (Index P = 0; P < more.size(); ++P) {
    for (Index m = more.begin[P]; m < more.begin[P + 1]; ++m)
      tets.push_back(first_tet + more.tets[m]);
    begin.push_back(static_cast<Index>(tets.size()));
    share.push_back(more.share[P]);
  }
}

TetPatches node_patches(const TetIndices& tets) {
  const Index nt = static_cast<Index>(tets.rows()), nodes = nt ? tets.maxCoeff() + 1 : 0;
  // The tets at each node, by a counting sort on the node ids (increasing tets per node).
  std::vector<Index> begin(static_cast<size_t>(nodes) + 1, 0);
  for (Index e = 0; e < nt; ++e)
    for (int c = 0; c < 4; ++c) ++begin[tets(e, c) + 1];
  for (Index a = 0; a < nodes; ++a) begin[a + 1] += begin[a];
  std::vector<Index> at(static_cast<size_t>(begin[nodes])), fill(begin.begin(), begin.end() - 1);
  for (Index e = 0; e < nt; ++e)
    for (int c = 0; c < 4; ++c) at[fill[tets(e, c)]++] = e;
  TetPatches out;
  for (Index a = 0; a < nodes; ++a) {
    if (begin[a] == begin[a + 1]) continue;
    out.tets.insert(out.tets.end(), at.begin() + begin[a], at.begin() + begin[a + 1]);
    out.begin.push_back(static_cast<Index>(out.tets.size()));
    out.share.push_back(0.25);
  }
  return out;
}

TetPatches element_patches(const TetIndices& tets, int target) {
  if (target < 1) throw std::invalid_argument("element patches: the target size must be >= 1");
  const Index nt = static_cast<Index>(tets.rows());
  // Face adjacency: the tets of each face (its sorted node triple), then per tet its neighbours.
  std::vector<std::pair<std::array<Index, 3>, Index>> faces;
  faces.reserve(4 * static_cast<size_t>(nt));
  for (Index e = 0; e < nt; ++e) {
    for (int skip = 0; skip < 4; ++skip) {
      std::array<Index, 3> f;
      for (int c = 0, k = 0; c < 4; ++c)
        if (c != skip) f[k++] = tets(e, c);
      std::sort(f.begin(), f.end());
      faces.emplace_back(f, e);
    }
  }
  std::sort(faces.begin(), faces.end());
  std::vector<std::pair<Index, Index>> adjacent;
  for (size_t i = 0; i < faces.size();) {
    size_t j = i + 1;
    while (j < faces.size() && faces[j].first == faces[i].first) ++j;
    for (size_t a = i; a < j; ++a)
      for (size_t b = i; b < j; ++b)
        if (a != b) adjacent.emplace_back(faces[a].second, faces[b].second);
    i = j;
  }
  std::sort(adjacent.begin(), adjacent.end());
  std::vector<Index> neighbour_begin(static_cast<size_t>(nt) + 1, 0);
  for (const auto& [e, f] : adjacent) ++neighbour_begin[e + 1];
  for (Index e = 0; e < nt; ++e) neighbour_begin[e + 1] += neighbour_begin[e];
  const auto neighbours = [&](Index e) {
    return std::span(adjacent).subspan(
        static_cast<size_t>(neighbour_begin[e]),
        static_cast<size_t>(neighbour_begin[e + 1] - neighbour_begin[e]));
  };
  // Growth: each patch from the lowest-numbered free tet, by the lowest-numbered free neighbour.
  std::vector<Index> patch_of(static_cast<size_t>(nt), -1);
  std::vector<std::vector<Index>> members;
  for (Index seed = 0; seed < nt; ++seed) {
    if (patch_of[seed] >= 0) continue;
    const Index P = static_cast<Index>(members.size());
    members.emplace_back();
    std::set<Index> frontier{seed};
    while (!frontier.empty() && static_cast<int>(members[P].size()) < target) {
      const Index e = *frontier.begin();
      frontier.erase(frontier.begin());
      patch_of[e] = P;
      members[P].push_back(e);
      for (const auto& [self, f] : neighbours(e))
        if (patch_of[f] < 0) frontier.insert(f);
    }
  }
  // Small patches join their smallest face neighbour.
  for (size_t P = 0; P < members.size(); ++P) {
    if (members[P].empty() || 2 * static_cast<int>(members[P].size()) >= target) continue;
    Index best = -1;
    for (Index e : members[P])
      for (const auto& [self, f] : neighbours(e)) {
        const Index Q = patch_of[f];
        if (Q != static_cast<Index>(P) && (best < 0 || members[Q].size() < members[best].size() ||
                                           (members[Q].size() == members[best].size() && Q < best)))
          best = Q;
      }
    if (best < 0) continue;
    for (Index e : members[P]) patch_of[e] = best;
    members[best].insert(members[best].end(), members[P].begin(), members[P].end());
    members[P].clear();
  }
  TetPatches out;
  for (std::vector<Index>& m : members) {
    if (m.empty()) continue;
    std::sort(m.begin(), m.end());
    out.tets.insert(out.tets.end(), m.begin(), m.end());
    out.begin.push_back(static_cast<Index>(out.tets.size()));
    out.share.push_back(1.0);
  }
  return out;
}

PatchVolume::PatchVolume(const Points& X, const TetIndices& tets, std::span<const Index> which,
                         std::span<const double> kappa, const TetPatches& patches)
    : num_tets_(static_cast<Index>(tets.rows())),
      which_(which.begin(), which.end()),
      patches_(patches) {
  if (which.size() != kappa.size())
    throw std::invalid_argument("patch volume: one bulk modulus per tet");
  const Index nt = static_cast<Index>(which.size()), np = patches_.size();
  for (Index e : patches_.tets)
    if (e < 0 || e >= nt) throw std::invalid_argument("patch volume: a patch member is no tet");
  // Local ids: the nodes the tets touch, in increasing global order.
  std::vector<Index> local(static_cast<size_t>(X.rows()), -1);
  for (Index t : which)
    for (int c = 0; c < 4; ++c) local[tets(t, c)] = 0;
  for (Index g = 0; g < X.rows(); ++g) {
    if (local[g] < 0) continue;
    local[g] = static_cast<Index>(node_.size());
    node_.push_back(g);
  }
  const Index nn = static_cast<Index>(node_.size());
  tet_.resize(nt, 4);
  VectorX rest(nt);
  incident_begin_.assign(static_cast<size_t>(nn) + 1, 0);
  for (Index e = 0; e < nt; ++e) {
    const Index t = which[e];
    Mat3 Dm;
    for (int c = 0; c < 3; ++c) Dm.col(c) = (X.row(tets(t, c + 1)) - X.row(tets(t, 0))).transpose();
    rest[e] = Dm.determinant() / 6.0;
    if (!(rest[e] > 0))
      throw InputError("tet " + std::to_string(t) + " is flat or inverted in the reference mesh");
    for (int c = 0; c < 4; ++c) {
      tet_(e, c) = local[tets(t, c)];
      ++incident_begin_[tet_(e, c) + 1];
    }
  }
  for (Index a = 0; a < nn; ++a) incident_begin_[a + 1] += incident_begin_[a];
  incident_.resize(static_cast<size_t>(incident_begin_[nn]));
  std::vector<Index> fill(incident_begin_.begin(), incident_begin_.end() - 1);
  for (Index e = 0; e < nt; ++e)
    for (int c = 0; c < 4; ++c) incident_[fill[tet_(e, c)]++] = 4 * e + c;
  // Per patch: V_P, K_P, its nodes (sorted) and the slots of its members' corners.
  rest_volume_ = VectorX::Zero(np);
  bulk_ = VectorX::Zero(np);
  node_begin_.assign(1, 0);
  in_patch_begin_.assign(static_cast<size_t>(nt) + 1, 0);
  for (Index P = 0; P < np; ++P) {
    const double s = patches_.share[P];
    const auto first = patch_node_.size();
    for (Index m = patches_.begin[P]; m < patches_.begin[P + 1]; ++m) {
      const Index e = patches_.tets[m];
      rest_volume_[P] += s * rest[e];
      bulk_[P] += s * kappa[e] * rest[e];
      ++in_patch_begin_[e + 1];
      for (int c = 0; c < 4; ++c) patch_node_.push_back(tet_(e, c));
    }
    std::sort(patch_node_.begin() + first, patch_node_.end());
    patch_node_.erase(std::unique(patch_node_.begin() + first, patch_node_.end()),
                      patch_node_.end());
    node_begin_.push_back(static_cast<Index>(patch_node_.size()));
    for (Index m = patches_.begin[P]; m < patches_.begin[P + 1]; ++m)
      for (int c = 0; c < 4; ++c)
        corner_slot_.push_back(
            slot_of(patch_node_, node_begin_[P], node_begin_[P + 1], tet_(patches_.tets[m], c)));
  }
  // The patches of each tet, and those of each node with the node's slot, in patch order.
  for (Index e = 0; e < nt; ++e) in_patch_begin_[e + 1] += in_patch_begin_[e];
  in_patch_.resize(static_cast<size_t>(in_patch_begin_[nt]));
  fill.assign(in_patch_begin_.begin(), in_patch_begin_.end() - 1);
  member_begin_.assign(static_cast<size_t>(nn) + 1, 0);
  for (Index P = 0; P < np; ++P) {
    for (Index m = patches_.begin[P]; m < patches_.begin[P + 1]; ++m)
      in_patch_[fill[patches_.tets[m]]++] = P;
    for (Index s = node_begin_[P]; s < node_begin_[P + 1]; ++s) ++member_begin_[patch_node_[s] + 1];
  }
  for (Index a = 0; a < nn; ++a) member_begin_[a + 1] += member_begin_[a];
  member_patch_.resize(static_cast<size_t>(member_begin_[nn]));
  member_slot_.resize(member_patch_.size());
  fill.assign(member_begin_.begin(), member_begin_.end() - 1);
  for (Index P = 0; P < np; ++P)
    for (Index s = node_begin_[P]; s < node_begin_[P + 1]; ++s) {
      const Index k = fill[patch_node_[s]]++;
      member_patch_[k] = P;
      member_slot_[k] = s;
    }
}

void PatchVolume::add_couplings(SparsityBuilder& builder) const {
  std::vector<Index> clique;
  for (Index P = 0; P < patches_.size(); ++P) {
    clique.clear();
    for (Index s = node_begin_[P]; s < node_begin_[P + 1]; ++s)
      clique.push_back(node_[patch_node_[s]]);
    builder.add_clique(clique);
  }
}

void PatchVolume::bind(const BlockSparseMatrix& H) {
  const auto block = [&](Index a, Index b) {
    const Index k = H.block_index(node_[a], node_[b]);
    if (k < 0) throw std::logic_error("patch volume: Hessian pattern lacks a patch coupling");
    return k;
  };
  const Index nn = static_cast<Index>(node_.size());
  corner_block_.clear();
  pair_begin_.assign(1, 0);
  pair_block_.clear();
  for (Index a = 0; a < nn; ++a) {
    for (Index k = incident_begin_[a]; k < incident_begin_[a + 1]; ++k)
      for (int c = 0; c < 4; ++c) corner_block_.push_back(block(a, tet_(incident_[k] / 4, c)));
    for (Index j = member_begin_[a]; j < member_begin_[a + 1]; ++j) {
      const Index P = member_patch_[j];
      for (Index t = node_begin_[P]; t < node_begin_[P + 1]; ++t)
        pair_block_.push_back(block(a, patch_node_[t]));
      pair_begin_.push_back(static_cast<Index>(pair_block_.size()));
    }
  }
}

void PatchVolume::rebind(const BlockSparseMatrix&, std::span<const Index> moved) {
  move_block_indices(corner_block_, moved, name());
  move_block_indices(pair_block_, moved, name());
}

void PatchVolume::tet_volumes(const Points& x, VectorX& volume, TetGradients* gradient) const {
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

double PatchVolume::patch_volume(Index P, const VectorX& v) const {
  double sum = 0;
  for (Index m = patches_.begin[P]; m < patches_.begin[P + 1]; ++m) sum += v[patches_.tets[m]];
  return patches_.share[P] * sum;
}

VectorX PatchVolume::pressures(const VectorX& pi) const {
  const Index nt = static_cast<Index>(tet_.rows());
  VectorX p(nt);
  tbb::parallel_for(tbb::blocked_range<Index>(0, nt, 4096),
                    [&](const tbb::blocked_range<Index>& r) {
                      for (Index e = r.begin(); e < r.end(); ++e) {
                        double pe = 0;
                        for (Index q = in_patch_begin_[e]; q < in_patch_begin_[e + 1]; ++q)
                          pe += patches_.share[in_patch_[q]] * pi[in_patch_[q]];
                        p[e] = pe;
                      }
                    });
  return p;
}

VectorX PatchVolume::volume_ratios(const Points& x) const {
  VectorX v;
  tet_volumes(x, v, nullptr);
  VectorX J(patches_.size());
  for (Index P = 0; P < patches_.size(); ++P) J[P] = patch_volume(P, v) / rest_volume_[P];
  return J;
}

VectorX PatchVolume::tet_pressures(const Points& x) const {
  const VectorX J = volume_ratios(x);
  VectorX pi(J.size());
  for (Index P = 0; P < J.size(); ++P)
    pi[P] = bulk_[P] * VolumetricPenalty::first(J[P]) / rest_volume_[P];
  const VectorX p = pressures(pi);
  VectorX out = VectorX::Zero(num_tets_);
  for (size_t e = 0; e < which_.size(); ++e) out[which_[e]] = p[static_cast<Index>(e)];
  return out;
}

double PatchVolume::evaluate(const Points& x, VectorX* gradient, BlockSparseMatrix* hessian) const {
  if (hessian && !gradient) throw std::logic_error("patch volume: a Hessian needs a gradient too");
  const Index nn = static_cast<Index>(node_.size()), np = patches_.size();
  VectorX v;
  TetGradients dv;
  tet_volumes(x, v, gradient ? &dv : nullptr);

  // Patches: J_P, the energy, the patch pressure pi_P and the stiffness k_P.
  VectorX pi(np), k(np);
  const double energy = tbb::parallel_deterministic_reduce(
      tbb::blocked_range<Index>(0, np, kGrain), 0.0,
      [&](const tbb::blocked_range<Index>& r, double acc) {
        for (Index P = r.begin(); P < r.end(); ++P) {
          const double V = rest_volume_[P], J = patch_volume(P, v) / V;
          if (!(J > 0)) return std::numeric_limits<double>::infinity();
          acc += bulk_[P] * VolumetricPenalty::value(J);
          pi[P] = bulk_[P] * VolumetricPenalty::first(J) / V;
          k[P] = bulk_[P] * VolumetricPenalty::second(J) / (V * V);
        }
        return acc;
      },
      std::plus<double>());
  if (!gradient || !std::isfinite(energy)) return energy;

  // Tets: the pressure p_e; nodes: the gradient sum_e p_e dv_e/dx_a.
  const VectorX p = pressures(pi);
  tbb::parallel_for(tbb::blocked_range<Index>(0, nn, kGrain),
                    [&](const tbb::blocked_range<Index>& r) {
                      for (Index a = r.begin(); a < r.end(); ++a) {
                        Vec3 ga = Vec3::Zero();
                        for (Index q = incident_begin_[a]; q < incident_begin_[a + 1]; ++q) {
                          const Index e = incident_[q] / 4, corner = incident_[q] % 4;
                          ga += p[e] * dv.row(e).segment<3>(3 * corner).transpose();
                        }
                        gradient->segment<3>(3 * node_[a]) += ga;
                      }
                    });
  if (!hessian) return energy;
  if (corner_block_.empty() && tet_.rows() > 0)
    throw std::logic_error("patch volume: bind() the Hessian first");

  // Patches: w_P = dv_P/dx at the patch's node slots.
  Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> w;
  w.setZero(static_cast<Index>(patch_node_.size()), 3);
  tbb::parallel_for(
      tbb::blocked_range<Index>(0, np, kGrain), [&](const tbb::blocked_range<Index>& r) {
        for (Index P = r.begin(); P < r.end(); ++P)
          for (Index m = patches_.begin[P]; m < patches_.begin[P + 1]; ++m) {
            const Index e = patches_.tets[m];
            for (int c = 0; c < 4; ++c)
              w.row(corner_slot_[4 * m + c]) += patches_.share[P] * dv.row(e).segment<3>(3 * c);
          }
      });

  // Rows: node a adds sum_e p_e d2v_e/dx_a dx_b and sum_P k_P w_P[a] w_P[b]^T to its blocks.
  tbb::parallel_for(tbb::blocked_range<Index>(0, nn, kGrain),
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
                        for (Index j = member_begin_[a]; j < member_begin_[a + 1]; ++j) {
                          const Index P = member_patch_[j];
                          const Vec3 wa = k[P] * w.row(member_slot_[j]).transpose();
                          const Index* blocks = pair_block_.data() + pair_begin_[j];
                          for (Index t = node_begin_[P]; t < node_begin_[P + 1]; ++t)
                            hessian->add_block(blocks[t - node_begin_[P]], wa * w.row(t));
                        }
                      }
                    });
  return energy;
}

namespace {
// The rows `which` of `tets`.
TetIndices rows_of(const TetIndices& tets, std::span<const Index> which) {
  TetIndices out(static_cast<Index>(which.size()), 4);
  for (size_t i = 0; i < which.size(); ++i) out.row(static_cast<Index>(i)) = tets.row(which[i]);
  return out;
}
}  // namespace

std::unique_ptr<PatchVolume> make_patch_volume(const Points& X, const TetIndices& tets,
                                               const std::vector<ElasticGroup>& groups) {
  std::vector<Index> which;
  std::vector<double> kappa;
  const auto add = [&](const ElasticGroup& g) {
    which.insert(which.end(), g.tets.begin(), g.tets.end());
    kappa.insert(kappa.end(), g.tets.size(), material_moduli(g.material).bulk());
  };
  // The nodal-pressure groups together: a node between two of them averages both.
  for (const ElasticGroup& g : groups)
    if (g.formulation == VolumeFormulation::kNodalPressure) add(g);
  TetPatches patches = node_patches(rows_of(tets, which));
  for (const ElasticGroup& g : groups) {
    if (g.formulation != VolumeFormulation::kPatchVolume) continue;
    const Index first = static_cast<Index>(which.size());
    add(g);
    patches.append(element_patches(rows_of(tets, g.tets), g.patch_size), first);
  }
  if (which.empty()) return nullptr;
  return std::make_unique<PatchVolume>(X, tets, which, kappa, patches);
}

}  // namespace depthfem

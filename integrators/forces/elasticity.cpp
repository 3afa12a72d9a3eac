#include "integrators/forces/elasticity.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <functional>
#include <limits>
#include <stdexcept>

#include "core/element_partition.hpp"
#include "core/error.hpp"
#include "integrators/elements/inversion_step.hpp"
#include "integrators/elements/psd_projection.hpp"
#include "integrators/elements/tet_inputs.hpp"
#include "integrators/elements/tet_kernel.hpp"
#include "materials/isochoric.hpp"

namespace depthfem {

namespace {

// Adds the lanes of a batch at rows e .. e + W in lane order: energy into `energy`, gradient
// through the node indices.
template <int kOrder, class V>
void add_energy_gradient(const TetBatch<V>& t, const TetBlock& b, Index e, double& energy,
                         VectorX* g) {
  for (int l = 0; l < V::kWidth; ++l) {
    energy += t.energy[l];
    if constexpr (kOrder >= 1) {
      for (int a = 0; a < 4; ++a) {
        double* ga = g->data() + 3 * b.nodes(e + l, a);
        for (int c = 0; c < 3; ++c) ga[c] += t.gradient[a][c][l];
      }
    }
  }
}

// Adds the 16 Hessian blocks of each tet of a batch through its scatter offsets (16 per tet).
// A block's first eight entries are transposed from lanes to rows, so that each tet adds them
// with one vector load, add and store; the ninth is added alone.
template <class V>
void add_hessian(const TetBatch<V>& t, const Index* off, BlockSparseMatrix& H) {
  constexpr int W = V::kWidth;
  for (int blk = 0; blk < 16; ++blk) {
    const int a = blk / 4, c = blk % 4;
    std::array<V, 8> rows;
    for (int k = 0; k < 8; ++k) rows[k] = t.hessian[3 * a + k / 3][3 * c + k % 3];
    for (int q = 0; q < 8; q += W) transpose(rows.data() + q);
    const V& last = t.hessian[3 * a + 2][3 * c + 2];
    for (int l = 0; l < W; ++l) {
      double* v = H.block(off[16 * l + blk]).data();
      for (int q = 0; q < 8; q += W) (V::load(v + q) + rows[q + l]).store(v + q);
      v[8] += last[l];
    }
  }
}

// Asks for the cache lines of the blocks that the next batch (16 W offsets) adds to: the matrix
// is far larger than the caches and its blocks are scattered, so each first touch would wait.
void prefetch_blocks(const Index* off, int count, BlockSparseMatrix& H) {
  for (int k = 0; k < count; ++k) {
    const double* v = H.block(off[k]).data();  // 72 bytes: at most two cache lines
    __builtin_prefetch(v, 1);
    __builtin_prefetch(v + 8, 1);
  }
}

// Projects the Hessian of every lane of a batch onto the positive semi-definite matrices.
template <class V>
void project_batch(TetBatch<V>& t) {
  for (int l = 0; l < V::kWidth; ++l) {
    Mat12 h = t.hessian_of(l);
    if (project_to_psd(h)) t.set_hessian_of(l, h);
  }
}

// Walks rows [begin, end) of a block in order: energy sum, and scatter of gradient / Hessian.
// Whole batches of kLanes rows go through the batched kernel, the rows left over through the
// scalar one. With `project`, each tet's 12x12 Hessian is projected to positive semi-definite
// between kernel and scatter.
template <int kOrder, class M>
double run_rows(const M& m, const TetBlock& b, const Index* scatter, const Points& x, Index begin,
                Index end, VectorX* g, BlockSparseMatrix* H, bool project) {
  using V = Lanes<kLanes>;
  TetBatch<V> batch;
  double energy = 0;
  Index e = begin;
  for (; e + kLanes <= end; e += kLanes) {
    if constexpr (kOrder >= 2) {
      if (e + 2 * kLanes <= end) prefetch_blocks(scatter + 16 * (e + kLanes), 16 * kLanes, *H);
    }
    tet_batch<kOrder>(m, tet_batch_input<V, M::kUsesFiber>(b, x, e), batch);
    add_energy_gradient<kOrder>(batch, b, e, energy, g);
    if constexpr (kOrder >= 2) {
      if (project) project_batch(batch);
      add_hessian(batch, scatter + 16 * e, *H);
    }
  }
  TetLocal local;
  for (; e < end; ++e) {
    const TetInput t = tet_input(b, x, e);
    tet_local<kOrder>(m, t.Ds, t.D, t.volume, t.fiber, local);
    energy += local.energy;
    if constexpr (kOrder >= 1) {
      for (int a = 0; a < 4; ++a) g->segment<3>(3 * b.nodes(e, a)) += local.gradient.col(a);
    }
    if constexpr (kOrder >= 2) {
      if (project) project_to_psd(local.hessian);
      H->add_blocks<4>(scatter + 16 * e, local.hessian);
    }
  }
  return energy;
}

// The chunks of a block color by color (run_by_color: deterministic for any number of threads),
// each chunk with its viscoelastic history term when the group has one.
template <int kOrder, class M>
double run_group(const M& m, const TetBlock& b, const Index* scatter, const Points& x, VectorX* g,
                 BlockSparseMatrix* H, bool project, const ViscoelasticHistory* history) {
  return run_by_color(b.color_begin, 0.0, [&](Index k) {
    const Index begin = b.chunk_begin[k], end = b.chunk_begin[k + 1];
    double energy = run_rows<kOrder>(m, b, scatter, x, begin, end, g, H, project);
    if (history) energy += history->evaluate_rows(b, scatter, x, begin, end, g, H, project);
    return energy;
  });
}

}  // namespace

Elasticity::Elasticity(const Points& X, const TetIndices& tets, std::vector<ElasticGroup> groups,
                       const ElasticityOptions& options)
    : options_(options), num_tets_(static_cast<Index>(tets.rows())) {
  for (size_t i = 0; i < groups.size(); ++i) {
    ElasticGroup& in = groups[i];
    try {
      validate_material(in.material);
    } catch (const std::invalid_argument& e) {
      throw InputError("material group " + std::to_string(i) + ": " + e.what());
    }
    if (material_uses_fiber(in.material) && in.fibers.rows() == 0) {
      throw InputError("material group " + std::to_string(i) + " (" + material_name(in.material) +
                       ") needs a fiber direction per tet");
    }
    for (Index t : in.tets) {
      if (t < 0 || t >= tets.rows()) {
        throw InputError("material group " + std::to_string(i) + " lists tet " + std::to_string(t) +
                         ", outside 0.." + std::to_string(tets.rows() - 1));
      }
    }
    if (!in.viscoelastic.empty()) {
      try {
        in.viscoelastic.validate();
      } catch (const std::invalid_argument& e) {
        throw InputError("material group " + std::to_string(i) + ": viscoelastic: " + e.what());
      }
      if (in.formulation != VolumeFormulation::kStandard) {
        throw InputError("material group " + std::to_string(i) +
                         ": viscoelastic needs the standard formulation");
      }
    }
    Group& grp = groups_.emplace_back(Group{.material = in.material,
                                            .formulation = in.formulation,
                                            .block = make_tet_block(X, tets, in.tets, in.fibers)});
    if (!in.viscoelastic.empty())
      grp.history.emplace(in.viscoelastic, grp.block.size(), options_.duration > 0);
  }
}

bool Elasticity::has_history() const {
  for (const Group& grp : groups_)
    if (grp.history && grp.history->timed()) return true;
  return false;
}

void Elasticity::begin_step(const Points& x) {
  dissipated_ = 0;
  for (Group& grp : groups_)
    if (grp.history && !grp.history->started()) grp.history->start(grp.material, grp.block, x);
}

void Elasticity::set_load(double load) {
  for (Group& grp : groups_)
    if (grp.history) grp.history->set_time(load * options_.duration);
}

void Elasticity::complete_step(const Points& x) {
  for (Group& grp : groups_)
    if (grp.history) dissipated_ += grp.history->accept(grp.material, grp.block, x);
}

void Elasticity::report(const Points& /*x*/, StepRecord& step) const {
  if (has_history()) step.dissipated_energy = dissipated_;
}

Index Elasticity::history_columns() const {
  Index columns = 0;
  for (const Group& grp : groups_)
    if (grp.history && grp.history->timed())
      columns = std::max(columns, Index(6 * (grp.history->terms() + 2)));
  return columns;
}

Eigen::MatrixXd Elasticity::history_state() const {
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(num_tets_, history_columns());
  for (const Group& grp : groups_) {
    if (!grp.history || !grp.history->timed()) continue;
    const Eigen::MatrixXd rows = grp.history->state();
    for (Index e = 0; e < grp.block.size(); ++e)
      out.row(grp.block.tet(e)).head(rows.cols()) = rows.row(e);
  }
  return out;
}

void Elasticity::restore_history(const Eigen::MatrixXd& state, double load) {
  if (state.rows() != num_tets_ || state.cols() != history_columns())
    throw std::logic_error("Elasticity::restore_history: a state of another shape");
  for (Group& grp : groups_) {
    if (!grp.history || !grp.history->timed()) continue;
    Eigen::MatrixXd rows(grp.block.size(), 6 * (grp.history->terms() + 2));
    for (Index e = 0; e < grp.block.size(); ++e)
      rows.row(e) = state.row(grp.block.tet(e)).head(rows.cols());
    // The time set_load(load) gives, the one accept() records.
    grp.history->restore(rows, load * options_.duration);
  }
}

SymmetricColumns Elasticity::viscous_stress(const Points& x) const {
  SymmetricColumns out = SymmetricColumns::Zero(num_tets_, 6);
  for (const Group& grp : groups_) {
    if (!grp.history) continue;
    const SymmetricColumns rows = grp.history->viscous_stress(grp.block, x);
    for (Index e = 0; e < grp.block.size(); ++e) out.row(grp.block.tet(e)) = rows.row(e);
  }
  return out;
}

void Elasticity::add_couplings(SparsityBuilder& builder) const {
  for (const Group& grp : groups_) {
    for (Index e = 0; e < grp.block.size(); ++e) {
      const Index n[4] = {grp.block.nodes(e, 0), grp.block.nodes(e, 1), grp.block.nodes(e, 2),
                          grp.block.nodes(e, 3)};
      builder.add_clique(n);
    }
  }
}

void Elasticity::bind(const BlockSparseMatrix& H) {
  for (Group& grp : groups_) {
    grp.scatter = H.clique_block_indices(grp.block.nodes);
    if (grp.scatter.size() != 16 * static_cast<size_t>(grp.block.size()))
      throw std::logic_error("elasticity: Hessian pattern lacks a tet coupling");
  }
}

void Elasticity::rebind(const BlockSparseMatrix&, std::span<const Index> moved) {
  for (Group& grp : groups_) move_block_indices(grp.scatter, moved, name());
}

double Elasticity::evaluate(const Points& x, VectorX* gradient, BlockSparseMatrix* hessian) const {
  if (hessian && !gradient) throw std::logic_error("elasticity: a Hessian needs a gradient too");
  double total = 0;
  for (const Group& grp : groups_) {
    if (hessian && grp.scatter.size() != static_cast<size_t>(16 * grp.block.size()))
      throw std::logic_error("elasticity: bind() the Hessian first");
    const auto run = [&](const auto& m, const ViscoelasticHistory* history) {
      if (hessian)
        return run_group<2>(m, grp.block, grp.scatter.data(), x, gradient, hessian,
                            options_.project_hessian, history);
      if (gradient)
        return run_group<1>(m, grp.block, nullptr, x, gradient, nullptr, false, history);
      return run_group<0>(m, grp.block, nullptr, x, nullptr, nullptr, false, history);
    };
    // The group's model: the isochoric part alone (nodal pressure or patch volume; never
    // viscoelastic, see the constructor), the material with its isochoric part scaled as the
    // viscoelastic history says (materials/viscoelastic.hpp), or the material as given.
    total += std::visit(
        [&]<class M>(const M& m) {
          if (grp.formulation != VolumeFormulation::kStandard) return run(Isochoric<M>{m}, nullptr);
          if (grp.history)
            return run(IsochoricScaled<M>{m, grp.history->isochoric_scale()}, &*grp.history);
          return run(m, nullptr);
        },
        grp.material);
  }
  return total;
}

double Elasticity::max_step(const Points& x, const Points& dx) const {
  constexpr double kLimit = 2.0;
  double alpha = std::numeric_limits<double>::infinity();
  for (const Group& grp : groups_) {
    const TetBlock& b = grp.block;
    alpha =
        std::min(alpha, tbb::parallel_reduce(
                            tbb::blocked_range<Index>(0, b.size(), 1024), alpha,
                            [&](const tbb::blocked_range<Index>& r, double acc) {
                              for (Index e = r.begin(); e < r.end(); ++e) {
                                acc = std::min(acc, inversion_step(edge_vectors(b, x, e),
                                                                   edge_vectors(b, dx, e), kLimit));
                              }
                              return acc;
                            },
                            [](double a, double c) { return std::min(a, c); }));
  }
  return alpha;
}

Index Elasticity::first_inverted(const Points& x) const {
  for (const Group& grp : groups_) {
    const TetBlock& b = grp.block;
    for (Index e = 0; e < b.size(); ++e)
      if (!(edge_vectors(b, x, e).determinant() > 0)) return b.tet(e);
  }
  return -1;
}

}  // namespace depthfem

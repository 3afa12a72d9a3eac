#include "integrators/elasticity.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <functional>
#include <limits>
#include <stdexcept>

#include "core/error.hpp"
#include "integrators/inversion_step.hpp"
#include "integrators/tet_kernel.hpp"

namespace depthfem {

namespace {

inline Mat3 edge_matrix(const Points& x, const TetIndices& nodes, Index e) {
  const Index n0 = nodes(e, 0);
  Mat3 Ds;
  for (int a = 0; a < 3; ++a) {
    const Index na = nodes(e, a + 1);
    Ds.col(a) = Vec3(x(na, 0) - x(n0, 0), x(na, 1) - x(n0, 1), x(na, 2) - x(n0, 2));
  }
  return Ds;
}

inline Vec3 fiber_of(const TetBlock& b, Index e) {
  return b.fiber.rows() ? Vec3(b.fiber.row(e).transpose()) : Vec3::UnitX();
}

// Walks rows [begin, end) of a block in order: energy sum, and scatter of gradient / Hessian.
template <int kOrder, class M>
double run_rows(const M& m, const TetBlock& b, const Index* scatter, const Points& x, Index begin,
                Index end, VectorX* g, BlockSparseMatrix* H) {
  TetLocal local;
  double energy = 0;
  for (Index e = begin; e < end; ++e) {
    tet_local<kOrder>(m, edge_matrix(x, b.nodes, e), b.dm_inv(e), b.volume(e), fiber_of(b, e),
                      local);
    energy += local.energy;
    if constexpr (kOrder >= 1) {
      for (int a = 0; a < 4; ++a) g->segment<3>(3 * b.nodes(e, a)) += local.gradient.col(a);
    }
    if constexpr (kOrder >= 2) {
      const Index* off = scatter + 16 * e;
      for (int a = 0; a < 4; ++a)
        for (int c = 0; c < 4; ++c)
          H->add_block(off[4 * a + c], local.hessian.block<3, 3>(3 * a, 3 * c));
    }
  }
  return energy;
}

// Colors in order; the chunks of one color share no node and run concurrently, each walked in
// order. Chunk energies are summed in a fixed tree (deterministic reduce, one chunk per leaf).
template <int kOrder, class M>
double run_group(const M& m, const TetBlock& b, const Index* scatter, const Points& x, VectorX* g,
                 BlockSparseMatrix* H) {
  double total = 0;
  for (Index c = 0; c < b.num_colors(); ++c) {
    total += tbb::parallel_deterministic_reduce(
        tbb::blocked_range<Index>(b.color_begin[c], b.color_begin[c + 1], 1), 0.0,
        [&](const tbb::blocked_range<Index>& chunks, double acc) {
          for (Index k = chunks.begin(); k < chunks.end(); ++k)
            acc += run_rows<kOrder>(m, b, scatter, x, b.chunk_begin[k], b.chunk_begin[k + 1], g, H);
          return acc;
        },
        std::plus<double>());
  }
  return total;
}

}  // namespace

Elasticity::Elasticity(const Points& X, const TetIndices& tets, std::vector<ElasticGroup> groups) {
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
    groups_.push_back({in.material, make_tet_block(X, tets, in.tets, in.fibers), {}});
  }
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
    const TetBlock& b = grp.block;
    grp.scatter.resize(16 * static_cast<size_t>(b.size()));
    for (Index e = 0; e < b.size(); ++e)
      for (int a = 0; a < 4; ++a)
        for (int c = 0; c < 4; ++c) {
          const Index off = H.block_index(b.nodes(e, a), b.nodes(e, c));
          if (off < 0) throw std::logic_error("elasticity: Hessian pattern lacks a tet coupling");
          grp.scatter[16 * e + 4 * a + c] = off;
        }
  }
}

double Elasticity::evaluate(const Points& x, VectorX* gradient, BlockSparseMatrix* hessian) const {
  if (hessian && !gradient) throw std::logic_error("elasticity: a Hessian needs a gradient too");
  double total = 0;
  for (const Group& grp : groups_) {
    if (hessian && grp.scatter.empty())
      throw std::logic_error("elasticity: bind() the Hessian first");
    total += std::visit(
        [&](const auto& m) {
          if (hessian) return run_group<2>(m, grp.block, grp.scatter.data(), x, gradient, hessian);
          if (gradient) return run_group<1>(m, grp.block, nullptr, x, gradient, nullptr);
          return run_group<0>(m, grp.block, nullptr, x, nullptr, nullptr);
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
    alpha = std::min(alpha, tbb::parallel_reduce(
                                tbb::blocked_range<Index>(0, b.size(), 1024), alpha,
                                [&](const tbb::blocked_range<Index>& r, double acc) {
                                  for (Index e = r.begin(); e < r.end(); ++e) {
                                    acc = std::min(
                                        acc, inversion_step(edge_matrix(x, b.nodes, e),
                                                            edge_matrix(dx, b.nodes, e), kLimit));
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
      if (!(edge_matrix(x, b.nodes, e).determinant() > 0)) return b.tet(e);
  }
  return -1;
}

}  // namespace depthfem

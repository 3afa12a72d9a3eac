#pragma once
// Force modules for the solver tests, built in code: linear springs between node pairs.

#include <array>
#include <vector>

#include "core/force_module.hpp"

namespace depthfem::testing {

// Linear springs between node pairs: E = sum k/2 |(x_j - x_i) - (X_j - X_i)|^2. The Hessian
// couples i and j: k I on the diagonal blocks, -k I off the diagonal.
class PairSprings final : public ForceModule {
 public:
  struct Pair {
    Index i, j;
    double k;
  };
  PairSprings(Points X, std::vector<Pair> pairs) : X_(std::move(X)), pairs_(std::move(pairs)) {}
  std::string name() const override { return "pair springs"; }
  void add_couplings(SparsityBuilder& builder) const override {
    for (const Pair& p : pairs_) builder.add_clique(std::vector<Index>{p.i, p.j});
  }
  void bind(const BlockSparseMatrix& H) override {
    blocks_.clear();
    for (const Pair& p : pairs_)
      blocks_.push_back({H.block_index(p.i, p.i), H.block_index(p.i, p.j), H.block_index(p.j, p.i),
                         H.block_index(p.j, p.j)});
  }
  double evaluate(const Points& x, VectorX* g, BlockSparseMatrix* H) const override {
    double E = 0;
    for (size_t n = 0; n < pairs_.size(); ++n) {
      const Pair& p = pairs_[n];
      const Vec3 d = (x.row(p.j) - x.row(p.i) - X_.row(p.j) + X_.row(p.i)).transpose();
      E += 0.5 * p.k * d.squaredNorm();
      if (g) {
        g->segment<3>(3 * p.j) += p.k * d;
        g->segment<3>(3 * p.i) -= p.k * d;
      }
      if (H) {
        const Mat3 K = p.k * Mat3::Identity();
        H->add_block(blocks_[n][0], K);
        H->add_block(blocks_[n][1], Mat3(-K));
        H->add_block(blocks_[n][2], Mat3(-K));
        H->add_block(blocks_[n][3], K);
      }
    }
    return E;
  }

 private:
  Points X_;
  std::vector<Pair> pairs_;
  std::vector<std::array<Index, 4>> blocks_;
};

}  // namespace depthfem::testing

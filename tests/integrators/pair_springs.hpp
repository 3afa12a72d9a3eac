#pragma once
// Force modules for the solver tests, built in code: two-node elements, such as linear springs
// between node pairs.

#include <array>
#include <vector>

#include "core/force_module.hpp"

namespace depthfem::testing {

// A force module of two-node elements (i, j, stiffness k), each coupling its two nodes; the
// derived module gives the energy and adds each element's 3x3 stiffness K through add_pair.
class TwoNodeElements : public ForceModule {
 public:
  struct Element {
    Index i, j;
    double k;
  };
  explicit TwoNodeElements(std::vector<Element> elements) : elements_(std::move(elements)) {}
  void add_couplings(SparsityBuilder& builder) const override {
    for (const Element& e : elements_) builder.add_clique(std::vector<Index>{e.i, e.j});
  }
  void bind(const BlockSparseMatrix& H) override {
    blocks_.clear();
    for (const Element& e : elements_)
      blocks_.push_back({H.block_index(e.i, e.i), H.block_index(e.i, e.j), H.block_index(e.j, e.i),
                         H.block_index(e.j, e.j)});
  }

 protected:
  // Element n's Hessian: K on the diagonal blocks, -K off the diagonal.
  void add_pair(BlockSparseMatrix& H, size_t n, const Mat3& K) const {
    H.add_block(blocks_[n][0], K);
    H.add_block(blocks_[n][1], Mat3(-K));
    H.add_block(blocks_[n][2], Mat3(-K));
    H.add_block(blocks_[n][3], K);
  }
  std::vector<Element> elements_;

 private:
  std::vector<std::array<Index, 4>> blocks_;
};

// Linear springs between node pairs: E = sum k/2 |(x_j - x_i) - (X_j - X_i)|^2. The Hessian
// couples i and j: k I on the diagonal blocks, -k I off the diagonal.
class PairSprings final : public TwoNodeElements {
 public:
  using Pair = Element;
  PairSprings(Points X, std::vector<Pair> pairs)
      : TwoNodeElements(std::move(pairs)), X_(std::move(X)) {}
  std::string name() const override { return "pair springs"; }
  double evaluate(const Points& x, VectorX* g, BlockSparseMatrix* H) const override {
    double E = 0;
    for (size_t n = 0; n < elements_.size(); ++n) {
      const Pair& p = elements_[n];
      const Vec3 d = (x.row(p.j) - x.row(p.i) - X_.row(p.j) + X_.row(p.i)).transpose();
      E += 0.5 * p.k * d.squaredNorm();
      if (g) {
        g->segment<3>(3 * p.j) += p.k * d;
        g->segment<3>(3 * p.i) -= p.k * d;
      }
      if (H) add_pair(*H, n, p.k * Mat3::Identity());
    }
    return E;
  }

 private:
  Points X_;
};

}  // namespace depthfem::testing

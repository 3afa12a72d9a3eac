#pragma once
// What the force-module tests share: the energy, gradient and Hessian of modules summed into one
// matrix of their joint pattern, and randomly deformed positions.

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <initializer_list>
#include <random>

#include "core/force_module.hpp"

namespace depthfem::testing {

/// Energy [J], gradient (3 #nodes) and Hessian of a configuration.
struct Assembled {
  double energy;
  VectorX gradient;
  BlockSparseMatrix hessian;
};

/// The sum of `modules` at x: their couplings gathered into one pattern, each bound to it.
inline Assembled assemble(std::initializer_list<ForceModule*> modules, const Points& x) {
  SparsityBuilder builder(static_cast<Index>(x.rows()));
  for (ForceModule* m : modules) m->add_couplings(builder);
  Assembled a{0, VectorX::Zero(3 * x.rows()), BlockSparseMatrix(builder)};
  for (ForceModule* m : modules) {
    m->bind(a.hessian);
    a.energy += m->evaluate(x, &a.gradient, &a.hessian);
  }
  return a;
}

/// One module at x.
inline Assembled assemble(ForceModule& module, const Points& x) {
  return assemble({&module}, x);
}

/// Expects the same bits of energy, gradient and Hessian from assemble() run on one and on two
/// threads (deterministic by construction: colored chunks, fixed chunking, per-node gathers).
template <class Assemble>
void expect_same_bits_on_one_and_two_threads(Assemble assemble) {
  const auto run = [&](int threads) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    return assemble();
  };
  const Assembled one = run(1), two = run(2);
  EXPECT_EQ(one.energy, two.energy);
  EXPECT_EQ((one.gradient - two.gradient).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(
      (one.hessian.to_sparse().coeffs() - two.hessian.to_sparse().coeffs()).cwiseAbs().maxCoeff(),
      0.0);
}

/// Positions X (#nodes x 3) moved by a random affine map (entries of A - I up to 0.2) and random
/// nodal noise of up to `noise` [m].
inline Points perturbed(const Points& X, double noise, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  Mat3 A = Mat3::Identity();
  for (int k = 0; k < 9; ++k) A(k) += 0.2 * u(rng);
  Points x = X * A.transpose();
  for (Index i = 0; i < x.size(); ++i) x(i) += noise * u(rng);
  return x;
}

}  // namespace depthfem::testing

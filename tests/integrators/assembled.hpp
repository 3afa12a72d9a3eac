#pragma once
// What the force-module tests share: a group over a whole mesh, perturbed positions, the energy,
// gradient and Hessian of modules summed into one matrix of their joint pattern, its derivatives
// checked against central differences, and the same bits on one and two threads.

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <initializer_list>
#include <numeric>
#include <random>
#include <string>

#include "core/force_module.hpp"
#include "core/tet_mesh.hpp"
#include "finite_differences.hpp"
#include "integrators/forces/elasticity.hpp"

namespace depthfem::testing {

/// One group of every tet of m, with fiber direction `fiber` where the model has fibers.
inline ElasticGroup whole_mesh(const TetMesh& m, const MaterialModel& model, const Vec3& fiber) {
  ElasticGroup g{model, std::vector<Index>(m.tets.rows()), Points()};
  std::iota(g.tets.begin(), g.tets.end(), 0);
  if (material_uses_fiber(model)) g.fibers = fiber.transpose().replicate(m.tets.rows(), 1);
  return g;
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

/// One module at x, in a pattern of its own couplings.
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

/// The gradient of `r` (assembled at x) against central differences of the energy, and the
/// Hessian times three random directions against central differences of the gradient. The step
/// 1e-7 (positions ~0.1 m) balances truncation and round-off: ~1e-7 relative, asserted at 1e-6
/// of the largest entry.
inline void expect_derivatives_match(const ForceModule& module, const Points& x, const Assembled& r,
                                     std::mt19937& rng, const std::string& what) {
  const double h = 1e-7;
  const VectorX g_fd = central_gradient_dofs(
      [&](const Points& y) { return module.evaluate(y, nullptr, nullptr); }, x, h);
  EXPECT_LE((r.gradient - g_fd).cwiseAbs().maxCoeff(), 1e-6 * r.gradient.cwiseAbs().maxCoeff())
      << what;
  const Eigen::SparseMatrix<double> H = r.hessian.to_sparse();
  std::normal_distribution<double> n;
  for (int trial = 0; trial < 3; ++trial) {
    VectorX v(x.size());
    for (Index i = 0; i < v.size(); ++i) v(i) = n(rng);
    const auto gradient = [&](const VectorX& z) {
      VectorX g = VectorX::Zero(z.size());
      module.evaluate(as_points(z), &g, nullptr);
      return g;
    };
    const VectorX Hv = H * v, Hv_fd = central_directional(gradient, as_dofs(x), v, h);
    EXPECT_LE((Hv - Hv_fd).cwiseAbs().maxCoeff(), 1e-6 * Hv.cwiseAbs().maxCoeff()) << what;
  }
}

}  // namespace depthfem::testing

#include "integrators/solvers/linear_solver.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <stdexcept>
#include <vector>

namespace depthfem {

std::string to_string(LinearSolverKind kind) {
  switch (kind) {
    case LinearSolverKind::kAuto:
      return "auto";
    case LinearSolverKind::kAmg:
      return "amg";
    case LinearSolverKind::kGmres:
      return "gmres";
    case LinearSolverKind::kCg:
      return "cg";
    case LinearSolverKind::kDirect:
      return "direct";
  }
  return "?";
}

namespace {
// Inverse of the Jacobi preconditioner; non-positive or tiny diagonal entries use 1.
VectorX inverse_diagonal(const BlockSparseMatrix& A) {
  VectorX d = A.diagonal();
  const double floor = 1e-14 * d.cwiseAbs().maxCoeff();
  for (Index i = 0; i < d.size(); ++i) d(i) = std::abs(d(i)) > floor ? 1.0 / std::abs(d(i)) : 1.0;
  return d;
}
}  // namespace

LinearSolver::LinearSolver(LinearSolverOptions options) : options_(options) {}

void LinearSolver::set_decoupled_nodes(std::vector<char> nodes) {
  decoupled_ = std::move(nodes);
  if (direct_) direct_->set_decoupled_nodes(decoupled_);
}

void LinearSolver::distribute(Ranks& ranks) {
  ranks_ = &ranks;
  if (options_.kind != LinearSolverKind::kAuto) start_distributed(options_.kind);
}

void LinearSolver::start_distributed(LinearSolverKind kind) {
  DistributedSolverOptions o{.method = DistributedMethod::kDirect,
                             .tolerance = options_.tolerance,
                             .max_iterations = options_.max_iterations,
                             .restart = options_.restart,
                             .reuse_tolerance = options_.direct.reuse_tolerance,
                             .amg = options_.amg};
  if (kind == LinearSolverKind::kAmg) o.method = DistributedMethod::kAmg;
  if (kind == LinearSolverKind::kGmres) o.method = DistributedMethod::kGmres;
  if (kind == LinearSolverKind::kCg) o.method = DistributedMethod::kCg;
  distributed_ = std::make_unique<DistributedSolver>(*ranks_, o);
}

LinearSolver::Choice LinearSolver::choose(const BlockSparseMatrix& A) const {
  return predicted_factor_flops(A, decoupled_) >
                 options_.auto_flops_per_entry * lower_triangle_entries(A)
             ? Choice::kAmg
             : Choice::kDirect;
}

namespace {
// The pattern of the whole matrix, on every rank, from each rank's part: every rank's blocks
// (i, j), j >= i, one after another (as doubles, exact below 2^53).
BlockSparseMatrix whole_pattern(const BlockSparseMatrix& part, const Ranks& ranks) {
  std::vector<double> mine;
  for (Index i = 0; i < part.num_nodes(); ++i)
    for (Index k = part.row_begin(i); k < part.row_begin(i + 1); ++k)
      if (part.block_col(k) >= i) {
        mine.push_back(static_cast<double>(i));
        mine.push_back(static_cast<double>(part.block_col(k)));
      }
  const std::vector<double> all = ranks.concatenate(mine);
  SparsityBuilder builder(part.num_nodes());
  for (size_t k = 0; k + 1 < all.size(); k += 2) {
    const Index pair[2] = {static_cast<Index>(all[k]), static_cast<Index>(all[k + 1])};
    builder.add_clique(pair);
  }
  return BlockSparseMatrix(builder);
}
}  // namespace

LinearSolveStats LinearSolver::solve(const BlockSparseMatrix& A, const VectorX& b, VectorX& x,
                                     const Points* positions, double tolerance) {
  x.setZero(b.size());
  if (b.norm() == 0) return {0, 0.0, true};
  if (ranks_) {
    if (!distributed_) {  // kAuto decides on the first matrix, whole: every rank alike
      choice_ = choose(whole_pattern(A, *ranks_));
      start_distributed(choice_ == Choice::kAmg ? LinearSolverKind::kAmg
                                                : LinearSolverKind::kDirect);
    }
    const DistributedSolveStats s = distributed_->solve(A, b, x, positions, tolerance);
    return {.iterations = s.iterations,
            .relative_residual = 0,  // not computed: A is spread over the ranks
            .reached_tolerance = s.converged,
            .shift = 0,
            .factored = s.factored};
  }
  switch (options_.kind) {
    case LinearSolverKind::kAuto:
      if (choice_ == Choice::kUndecided) choice_ = choose(A);
      return choice_ == Choice::kAmg ? amg(A, b, x, positions) : direct(A, b, x, tolerance);
    case LinearSolverKind::kAmg:
      return amg(A, b, x, positions);
    case LinearSolverKind::kGmres:
      return gmres(A, b, x);
    case LinearSolverKind::kCg:
      return cg(A, b, x);
    case LinearSolverKind::kDirect:
      return direct(A, b, x, tolerance);
  }
  return {};
}

// Restarted GMRES with right preconditioning M^-1 = diag(A)^-1: minimises the true residual
// |b - A x| over x0 + M^-1 K_m(A M^-1, r0); Arnoldi by modified Gram-Schmidt, Givens rotations.
LinearSolveStats LinearSolver::gmres(const BlockSparseMatrix& A, const VectorX& b,
                                     VectorX& x) const {
  const VectorX Minv = inverse_diagonal(A);
  const double bnorm = b.norm(), target = options_.tolerance * bnorm;
  const int m = options_.restart;
  std::vector<VectorX> V(static_cast<size_t>(m) + 1);
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(m + 1, m);
  VectorX cs(m), sn(m), s(m + 1), w, r;
  int total = 0;
  r = b;  // x starts at zero
  double rnorm = bnorm;
  while (rnorm > target && total < options_.max_iterations) {
    V[0] = r / rnorm;
    s.setZero();
    s(0) = rnorm;
    int j = 0;
    for (; j < m && total < options_.max_iterations; ++j) {
      A.multiply(Minv.cwiseProduct(V[j]), w);
      ++total;
      for (int i = 0; i <= j; ++i) {
        H(i, j) = w.dot(V[i]);
        w -= H(i, j) * V[i];
      }
      const double next = w.norm();  // zero: the Krylov space is invariant (exact solution)
      H(j + 1, j) = next;
      if (next > 0) V[j + 1] = w / next;
      for (int i = 0; i < j; ++i) {  // apply earlier rotations to the new column
        const double t = cs(i) * H(i, j) + sn(i) * H(i + 1, j);
        H(i + 1, j) = -sn(i) * H(i, j) + cs(i) * H(i + 1, j);
        H(i, j) = t;
      }
      const double h = std::hypot(H(j, j), H(j + 1, j));
      cs(j) = h > 0 ? H(j, j) / h : 1.0;
      sn(j) = h > 0 ? H(j + 1, j) / h : 0.0;
      H(j, j) = h;
      H(j + 1, j) = 0;
      s(j + 1) = -sn(j) * s(j);
      s(j) = cs(j) * s(j);
      if (std::abs(s(j + 1)) <= target || next == 0) {
        ++j;
        break;
      }
    }
    // y = R^-1 s on the j x j upper triangle; x += M^-1 V y.
    const VectorX y = H.topLeftCorner(j, j).triangularView<Eigen::Upper>().solve(s.head(j));
    VectorX update = VectorX::Zero(b.size());
    for (int i = 0; i < j; ++i) update += y(i) * V[i];
    x += Minv.cwiseProduct(update);
    A.multiply(x, r);
    r = b - r;
    const double new_norm = r.norm();
    if (!(new_norm < rnorm)) {  // stagnation (breakdown or no progress): stop
      rnorm = std::min(rnorm, new_norm);
      break;
    }
    rnorm = new_norm;
  }
  return {total, rnorm / bnorm, rnorm <= target};
}

// Jacobi-preconditioned conjugate gradients. Stops at negative curvature (an indefinite
// matrix near a bifurcation), keeping the iterate reached, or the preconditioned residual if
// it happens at once, so that Newton still gets a usable direction.
LinearSolveStats LinearSolver::cg(const BlockSparseMatrix& A, const VectorX& b, VectorX& x) const {
  const VectorX Minv = inverse_diagonal(A);
  const double bnorm = b.norm(), target = options_.tolerance * bnorm;
  VectorX r = b, z = Minv.cwiseProduct(r), p = z, Ap;
  double rz = r.dot(z);
  int k = 0;
  while (r.norm() > target && k < options_.max_iterations) {
    A.multiply(p, Ap);
    ++k;
    const double pAp = p.dot(Ap);
    if (!(pAp > 0)) {
      if (k == 1) x = z;
      break;
    }
    const double alpha = rz / pAp;
    x += alpha * p;
    r -= alpha * Ap;
    z = Minv.cwiseProduct(r);
    const double rz_new = r.dot(z);
    p = z + (rz_new / rz) * p;
    rz = rz_new;
  }
  A.multiply(x, Ap);
  const double rel = (b - Ap).norm() / bnorm;
  return {k, rel, rel <= options_.tolerance};
}

// Iterations: one per factorisation plus the CG iterations on a kept or single-precision factor.
LinearSolveStats LinearSolver::direct(const BlockSparseMatrix& A, const VectorX& b, VectorX& x,
                                      double tolerance) {
  if (!direct_) {
    direct_ = std::make_unique<DirectSolver>(options_.direct);
    direct_->set_decoupled_nodes(decoupled_);
  }
  const DirectSolveStats d = direct_->solve(A, b, x, tolerance);
  const int iterations = (d.factored ? 1 : 0) + d.cg_iterations;
  if (!d.success) return {iterations, 1.0, false, d.shift, d.factored};
  VectorX Ax;
  A.multiply(x, Ax);
  return {iterations, (b - Ax).norm() / b.norm(), true, d.shift, d.factored};
}

// CG needs a positive definite matrix; one it fails on (indefinite: deep contact, past a
// bifurcation) is solved directly.
LinearSolveStats LinearSolver::amg(const BlockSparseMatrix& A, const VectorX& b, VectorX& x,
                                   const Points* positions) {
  if (!amg_) amg_ = std::make_unique<AmgSolver>(options_.amg);
  const AmgSolveStats s = amg_->solve(A, b, x, positions);
  if (!s.converged || !x.allFinite()) {
    LinearSolveStats d = direct(A, b, x, 0);
    d.iterations += s.iterations;
    return d;
  }
  VectorX Ax;
  A.multiply(x, Ax);
  return {s.iterations, (b - Ax).norm() / b.norm(), true, 0.0};
}

}  // namespace depthfem

#include "integrators/solvers/direct_solver.hpp"

#include <cholmod.h>

#include "integrators/solvers/kept_factor.hpp"
#include "integrators/solvers/supernodal_cholesky.hpp"
#include "integrators/solvers/thread_budget.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <memory>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

namespace depthfem {

namespace {

// The most CG iterations on a new single-precision factor before A is factored in double. The
// factor solves A to about its condition number times 6e-8, so that each iteration gains that
// factor: a few iterations where single precision suits A, many where it does not.
constexpr int kSingleMaxIterations = 30;

// A single-precision LL^T that fails at a pivot below -kIndefinitePivot of A's diagonal entry
// there (SupernodalCholesky::failed_pivot) is taken to have found A indefinite, and A is not
// factored in double before it is shifted. A positive definite A beyond single precision's reach
// fails near zero: at -1.6e-6 of the diagonal with condition 1e9 (test
// DirectSingleFactorFallsBackToDoubleBeyondItsReach). The fine knee's single-precision failures
// lie at -1e-4 to -1e2 of the diagonal, and the double LL^T that followed each of them failed
// as well (38 of 38 over 144-150 degrees).
constexpr double kIndefinitePivot = 1e-3;

// Lowest Ritz value of 30 Lanczos steps on D^-1/2 A D^-1/2, D = diag(weight): it converges to
// the lowest eigenvalue from above, fast at the ends of the spectrum; 30 products cost a few per
// cent of a factorisation. Scaled by the diagonal, the spectrum of a stiffness matrix lies in
// about [-1, 2] whatever the spread of its materials and penalties, so that a negative eigenvalue
// stands clear of the others at the far end, yet may sit close to the many soft modes near zero,
// which 30 steps from a random start do not resolve. `mode` holds the start and returns the
// lowest Ritz vector: the steps start from the last estimate's Ritz vector (a Newton iteration's
// lowest mode is much like the last one's) with a tenth of a fixed pseudo-random unit vector
// added, so that every eigenvector is present in the start; from that vector alone when `mode`
// is not of A's size.
double lowest_eigenvalue_estimate(const BlockSparseMatrix& A, const VectorX& weight,
                                  VectorX& mode) {
  const Index n = 3 * A.num_nodes();
  const VectorX inv_sqrt = weight.cwiseSqrt().cwiseInverse();
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-1, 1);
  VectorX v(n), v_prev = VectorX::Zero(n), w;
  for (Index i = 0; i < n; ++i) v(i) = u(rng);
  v.normalize();
  if (mode.size() == n) {
    v = mode.normalized() + 0.1 * v;
    v.normalize();
  }
  std::vector<VectorX> basis;
  std::vector<double> alpha, beta;
  double b = 0;
  for (int j = 0; j < std::min<Index>(30, n); ++j) {
    basis.push_back(v);
    A.multiply(inv_sqrt.cwiseProduct(v), w);
    w = inv_sqrt.cwiseProduct(w);
    alpha.push_back(w.dot(v));
    w -= alpha.back() * v + b * v_prev;
    b = w.norm();
    if (!(b > 1e-12 * std::abs(alpha.back()))) break;  // invariant subspace: exact
    beta.push_back(b);
    v_prev.swap(v);
    v = w / b;
  }
  const Eigen::Index m = static_cast<Eigen::Index>(alpha.size());
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> T;
  T.computeFromTridiagonal(Eigen::Map<const VectorX>(alpha.data(), m),
                           Eigen::Map<const VectorX>(beta.data(), m - 1),
                           Eigen::ComputeEigenvectors);
  mode = VectorX::Zero(n);
  for (Eigen::Index k = 0; k < m; ++k) mode += T.eigenvectors()(k, 0) * basis[k];
  return T.eigenvalues()(0);
}

// The graph of the 3x3 blocks of M that `kept` keeps (ScalarPattern::keeps) as a CHOLMOD
// pattern matrix with its upper triangle read (stype 1; the full pattern is symmetric), freed
// with the common it was allocated with.
auto block_graph(const BlockSparseMatrix& M, const ScalarPattern& kept, cholmod_common& c) {
  const auto free_sparse = [&c](cholmod_sparse* S) { cholmod_free_sparse(&S, &c); };
  const Index nodes = M.num_nodes();
  std::unique_ptr<cholmod_sparse, decltype(free_sparse)> G(
      cholmod_allocate_sparse(nodes, nodes, M.num_blocks(), 1, 1, 1, CHOLMOD_PATTERN, &c),
      free_sparse);
  if (!G) throw std::runtime_error("CHOLMOD allocation failed");
  int* p = static_cast<int*>(G->p);
  int* rows = static_cast<int*>(G->i);
  p[0] = 0;
  for (Index i = 0; i < nodes; ++i) {
    p[i + 1] = p[i];
    for (Index k = M.row_begin(i); k < M.row_begin(i + 1); ++k)
      if (kept.keeps(i, M.block_col(k))) rows[p[i + 1]++] = M.block_col(k);
  }
  return G;
}

}  // namespace

double predicted_factor_flops(const BlockSparseMatrix& A, std::vector<char> decoupled) {
  cholmod_common c;
  cholmod_start(&c);
  c.print = 0;
  c.nmethods = 1;
  c.method[0].ordering = CHOLMOD_AMD;
  c.supernodal = CHOLMOD_SIMPLICIAL;  // column counts only
  double flops = -1;
  {
    const auto G = block_graph(A, ScalarPattern{.decoupled = std::move(decoupled)}, c);
    cholmod_factor* L = cholmod_analyze(G.get(), &c);
    if (L) flops = 27 * c.fl;
    cholmod_free_factor(&L, &c);
  }
  cholmod_finish(&c);
  if (!(flops >= 0)) throw std::runtime_error("CHOLMOD analysis of the block graph failed");
  return flops;
}

double lower_triangle_entries(const BlockSparseMatrix& A) {
  return (9.0 * A.num_blocks() + 3.0 * A.num_nodes()) / 2;
}

struct DirectSolver::Impl {
  DirectSolverOptions options;
  std::vector<char> decoupled;  // nodes left out of the pattern off the diagonal
  cholmod_common c;
  std::uint64_t version = 0;    // pattern version of the analysis (0: none)
  ScalarPattern pattern;        // upper triangle by rows = lower triangle by columns
  cholmod_sparse* A = nullptr;  // lower triangle (stype -1), values refreshed every solve
  DirectAnalysis analysis;
  std::vector<int> perm;                            // fill-reducing dof ordering
  std::vector<Index> diagonal;                      // position of every diagonal entry in A->x
  cholmod_factor* llt = nullptr;                    // supernodal LL^T
  std::unique_ptr<SupernodalCholesky> llt_numeric;  // fills llt
  cholmod_factor* ldlt = nullptr;                   // simplicial LDL^T, analysed on first need
  double ordered_flops = 0;    // of the pattern the ordering perm was computed for
  KeptFactor kept;             // llt, kept for the matrices of this pattern after the factored one
  bool shifted = false;        // the last factorisation was of a shifted matrix
  std::vector<float> single;   // llt's values in single precision (FactorPrecision::kSingle)
  bool factor_single = false;  // llt's factor is `single` (else llt->x)
  VectorX lowest_mode;         // the last Lanczos estimate's Ritz vector, the next one's start
  cholmod_dense *X = nullptr, *Y = nullptr, *E = nullptr;  // solve workspace

  explicit Impl(DirectSolverOptions o) : options(o) {
    cholmod_start(&c);
    c.print = 0;  // a failed LL^T is expected on indefinite matrices and handled
    c.supernodal = CHOLMOD_SUPERNODAL;
  }
  ~Impl() {
    release_pattern();
    cholmod_free_dense(&X, &c);
    cholmod_free_dense(&Y, &c);
    cholmod_free_dense(&E, &c);
    cholmod_finish(&c);
  }
  void release_pattern() {
    llt_numeric.reset();
    cholmod_free_sparse(&A, &c);
    cholmod_free_factor(&llt, &c);
    cholmod_free_factor(&ldlt, &c);
    version = 0;
    kept.drop();
  }
  void check(const char* what) const {
    if (c.status < CHOLMOD_OK)
      throw std::runtime_error(std::string("CHOLMOD ") + what + " failed (status " +
                               std::to_string(c.status) + ")");
  }

  // Fills `diagonal` for `pattern` and returns a lower triangle with that pattern.
  cholmod_sparse* lower_triangle();
  // Keeps the ordering and symbolic factor when the pattern of `next` (M's lower triangle) fits
  // in the factor's (a contact coupling already present as fill): only where its entries land
  // in L is found anew, and A becomes `next`. False (next untouched) otherwise.
  bool refit(const BlockSparseMatrix& M, cholmod_sparse* next);
  // Analyses A under the ordering perm, kept where the factorisation costs at most 2 % more flops
  // than that of the pattern perm was computed for: only the symbolic analysis is redone.
  bool reanalyse();
  // A new ordering of A (M's pattern) and its analysis into llt.
  void order(const BlockSparseMatrix& M);
  void analyse(const BlockSparseMatrix& M);
  std::vector<int> node_ordering(cholmod_sparse* G, DirectOrdering ordering);
  cholmod_factor* analyse_with(int supernodal);
  bool factorize_llt(bool in_single, DirectSolveStats& stats);
  bool factorize_ldlt();
  void shift_diagonal(const VectorX& d, const VectorX& weight, double s);
  void solve_with(cholmod_factor* L, const VectorX& b, VectorX& x);
  void precondition(const VectorX& r, VectorX& z);
  bool cg(const BlockSparseMatrix& M, const VectorX& shift, const VectorX& b, VectorX& x,
          double tolerance, int cap, int& iterations);
  bool solve_factored(const BlockSparseMatrix& M, const VectorX& shift, const VectorX& b,
                      VectorX& x, double tolerance, DirectSolveStats& stats);
};

// Orders the graph G of the 3x3 blocks (nine times fewer edges than the scalar graph) and
// keeps the three dofs of a node together.
std::vector<int> DirectSolver::Impl::node_ordering(cholmod_sparse* G, DirectOrdering ordering) {
  std::vector<int> node_perm(G->nrow);
  const int ok = ordering == DirectOrdering::kMetis
                     ? cholmod_metis(G, nullptr, 0, 1, node_perm.data(), &c)
                     : cholmod_amd(G, nullptr, 0, node_perm.data(), &c);
  if (!ok) check("ordering");
  std::vector<int> p(3 * node_perm.size());
  for (size_t k = 0; k < node_perm.size(); ++k)
    for (int d = 0; d < 3; ++d) p[3 * k + d] = 3 * node_perm[k] + d;
  return p;
}

cholmod_factor* DirectSolver::Impl::analyse_with(int supernodal) {
  c.nmethods = 1;
  c.method[0].ordering = CHOLMOD_GIVEN;
  c.postorder = 1;
  c.supernodal = supernodal;
  cholmod_factor* L = cholmod_analyze_p(A, perm.data(), nullptr, 0, &c);
  check("analysis");
  return L;
}

cholmod_sparse* DirectSolver::Impl::lower_triangle() {
  const size_t n = pattern.row_begin.size() - 1, nnz = pattern.col.size();
  cholmod_sparse* out = cholmod_allocate_sparse(n, n, nnz, 1, 1, -1, CHOLMOD_REAL, &c);
  check("allocate");
  std::copy(pattern.row_begin.begin(), pattern.row_begin.end(), static_cast<int*>(out->p));
  std::copy(pattern.col.begin(), pattern.col.end(), static_cast<int*>(out->i));
  diagonal.resize(n);  // every diagonal block is in the pattern
  for (size_t j = 0; j < n; ++j) {
    const auto row = pattern.col.begin();
    diagonal[j] =
        std::find(row + pattern.row_begin[j], row + pattern.row_begin[j + 1], Index(j)) - row;
  }
  return out;
}

bool DirectSolver::Impl::refit(const BlockSparseMatrix& M, cholmod_sparse* next) {
  if (!llt || next->nrow != llt->n) return false;
  std::unique_ptr<SupernodalCholesky> numeric = SupernodalCholesky::fitted(*next, *llt, c);
  if (!numeric) return false;
  numeric->keep_probes_of(*llt_numeric);
  cholmod_free_sparse(&A, &c);
  cholmod_free_factor(&ldlt, &c);
  A = next;
  llt_numeric = std::move(numeric);
  kept.drop();
  version = M.pattern_version();
  ++analysis.refitted;
  return true;
}

bool DirectSolver::Impl::reanalyse() {
  llt = analyse_with(CHOLMOD_SUPERNODAL);
  if (!(c.fl <= 1.02 * ordered_flops)) {
    cholmod_free_factor(&llt, &c);
    return false;
  }
  analysis.flops = c.fl;
  analysis.factor_entries = c.lnz;
  ++analysis.reanalysed;
  return true;
}

// A pattern that differs from the analysed one only in couplings of decoupled nodes (a contact
// pair of a prescribed node and a free one) leaves the factor's as it is: nothing is redone but
// the kept factor's end, as after any new pattern. Otherwise the lower triangle of M is built
// once, for whichever of refit, reanalyse and a new ordering takes it.
void DirectSolver::Impl::analyse(const BlockSparseMatrix& M) {
  ScalarPattern next_pattern = M.scalar_pattern(Triangle::kUpper, decoupled);
  if (A && llt && next_pattern.row_begin == pattern.row_begin && next_pattern.col == pattern.col) {
    kept.drop();
    version = M.pattern_version();
    ++analysis.unchanged;
    return;
  }
  pattern = std::move(next_pattern);
  cholmod_sparse* next = lower_triangle();
  if (refit(M, next)) return;
  const bool ordered = llt && next->nrow == llt->n;  // perm orders a matrix of this size
  release_pattern();
  A = next;
  if (!(ordered && reanalyse())) order(M);
  llt_numeric = std::make_unique<SupernodalCholesky>(*A, *llt, c);
  version = M.pattern_version();
}

void DirectSolver::Impl::order(const BlockSparseMatrix& M) {
  const auto G = block_graph(M, pattern, c);
  const auto try_ordering = [&](DirectOrdering o) {
    perm = node_ordering(G.get(), o);
    llt = analyse_with(CHOLMOD_SUPERNODAL);
    analysis = {o, c.fl, c.lnz, 0, 0, 0};
  };
  // A pattern of the size of the last ordering, where METIS beat AMD (the best ordering's
  // analysis is METIS's only then), is a mesh's graph with other contact couplings: METIS wins
  // again (by 2.8 times in flops on the fine knee, 1.8 on the coarse one) and is computed alone.
  const bool best = options.ordering == DirectOrdering::kBest;
  const bool metis_won = analysis.ordering == DirectOrdering::kMetis &&
                         perm.size() == 3 * static_cast<size_t>(M.num_nodes());
  const DirectOrdering first = options.ordering == DirectOrdering::kMetis || (best && metis_won)
                                   ? DirectOrdering::kMetis
                                   : DirectOrdering::kAmd;
  try_ordering(first);
  // CHOLMOD's own rule for trying nested dissection after AMD: large fronts (flops >= 500 per
  // entry of L) mean large separators, where nested dissection cuts the fill.
  if (best && first == DirectOrdering::kAmd && analysis.flops >= 500 * analysis.factor_entries) {
    const DirectAnalysis amd = analysis;
    std::vector<int> amd_perm = perm;
    cholmod_factor* amd_llt = llt;
    try_ordering(DirectOrdering::kMetis);
    if (analysis.flops < amd.flops) {
      cholmod_free_factor(&amd_llt, &c);
    } else {
      cholmod_free_factor(&llt, &c);
      llt = amd_llt;
      perm = std::move(amd_perm);
      analysis = amd;
    }
    analysis.compared = true;
  }
  ordered_flops = analysis.flops;
}

// Factors A into llt, in single precision into `single` or in double into llt->x; false (counted
// in stats) when it is not positive definite. Not cholmod_factorize: that hands the large dense
// blocks to OpenBLAS's threads, which make the factor depend on the thread count
// (SupernodalCholesky shares them by TBB, each on one BLAS thread).
bool DirectSolver::Impl::factorize_llt(bool in_single, DirectSolveStats& stats) {
  const SerialBlas serial;
  factor_single = in_single;
  const bool positive =
      in_single ? llt_numeric->factorize(*A, *llt, single) : llt_numeric->factorize(*A, *llt);
  if (!positive) ++stats.failed_factorizations;
  return positive;
}

// Factors A into ldlt (simplicial: no BLAS); false when it has a zero pivot.
bool DirectSolver::Impl::factorize_ldlt() {
  if (!ldlt) ldlt = analyse_with(CHOLMOD_SIMPLICIAL);
  cholmod_factorize(A, ldlt, &c);
  check("factorization");
  return ldlt->minor == ldlt->n;
}

// A's diagonal becomes that of A + s diag(weight), where d holds the diagonal of A.
void DirectSolver::Impl::shift_diagonal(const VectorX& d, const VectorX& weight, double s) {
  double* values = static_cast<double*>(A->x);
  for (size_t j = 0; j < diagonal.size(); ++j) values[diagonal[j]] = d(j) + s * weight(j);
}

void DirectSolver::Impl::solve_with(cholmod_factor* L, const VectorX& b, VectorX& x) {
  cholmod_dense B{};
  B.nrow = B.d = static_cast<size_t>(b.size());
  B.ncol = 1;
  B.nzmax = B.nrow;
  B.x = const_cast<double*>(b.data());
  B.xtype = CHOLMOD_REAL;
  B.dtype = CHOLMOD_DOUBLE;
  const SerialBlas serial;
  cholmod_solve2(CHOLMOD_A, L, &B, nullptr, &X, nullptr, &Y, &E, &c);
  check("solve");
  x = Eigen::Map<const VectorX>(static_cast<const double*>(X->x), b.size());
}

// z = L^-T L^-1 r with llt's factor, in whichever precision it was computed.
void DirectSolver::Impl::precondition(const VectorX& r, VectorX& z) {
  if (!factor_single) return solve_with(llt, r, z);
  z.resize(r.size());
  llt_numeric->solve(*llt, single, r.data(), z.data());
}

DirectSolver::DirectSolver(DirectSolverOptions options) : impl_(std::make_unique<Impl>(options)) {}
DirectSolver::~DirectSolver() = default;

void DirectSolver::set_decoupled_nodes(std::vector<char> nodes) {
  if (nodes == impl_->decoupled) return;
  impl_->release_pattern();
  impl_->decoupled = std::move(nodes);
}

const DirectAnalysis& DirectSolver::analyse(const BlockSparseMatrix& M) {
  if (impl_->version != M.pattern_version()) impl_->analyse(M);
  return impl_->analysis;
}

// Conjugate gradients on M + diag(shift) (shift empty: M) preconditioned by llt's factor, to
// |b - A x| <= tolerance |b| in at most `cap` iterations; false when they fall short (A not
// positive definite, or too slow: as soon as the reduction so far, extrapolated at its mean rate,
// misses the cap).
bool DirectSolver::Impl::cg(const BlockSparseMatrix& M, const VectorX& shift, const VectorX& b,
                            VectorX& x, double tolerance, int cap, int& iterations) {
  x.setZero(b.size());
  VectorX r = b, z, p, Ap;
  precondition(r, z);
  p = z;
  double rz = r.dot(z);
  for (iterations = 1; iterations <= cap; ++iterations) {
    M.multiply(p, Ap);
    if (shift.size()) Ap += shift.cwiseProduct(p);
    const double pAp = p.dot(Ap);
    if (!(pAp > 0)) return false;  // A is not positive definite
    const double alpha = rz / pAp;
    x += alpha * p;
    r -= alpha * Ap;
    const double reduction = r.norm() / b.norm();
    if (reduction <= tolerance) return true;
    if (iterations >= 2 && iterations * std::log(tolerance) / std::log(reduction) > cap)
      return false;
    precondition(r, z);
    const double rz_next = r.dot(z);
    p = z + (rz_next / rz) * p;
    rz = rz_next;
  }
  --iterations;
  return false;
}

// Solves with the factor just computed of the matrix A holds (M + diag(shift), its diagonal
// shifted already): a double factor directly, a single-precision one by CG (to `tolerance`, 0:
// kSingleExactTolerance), and where that falls short A is factored in double after all. False
// when that factorisation fails.
bool DirectSolver::Impl::solve_factored(const BlockSparseMatrix& M, const VectorX& shift,
                                        const VectorX& b, VectorX& x, double tolerance,
                                        DirectSolveStats& stats) {
  if (factor_single) {
    const double goal = tolerance > 0 ? tolerance : kSingleExactTolerance;
    int iterations = 0;
    const bool solved = cg(M, shift, b, x, goal, kSingleMaxIterations, iterations);
    stats.cg_iterations += iterations;
    if (solved) {
      stats.single = true;
      return true;
    }
    if (!factorize_llt(false, stats)) return false;
  }
  solve_with(llt, b, x);
  return true;
}

DirectSolveStats DirectSolver::solve(const BlockSparseMatrix& M, const VectorX& b, VectorX& x,
                                     double tolerance) {
  Impl& s = *impl_;
  analyse(M);
  DirectSolveStats stats;
  if (b.squaredNorm() == 0) {
    x.setZero(b.size());
    stats.success = true;
    return stats;
  }
  if (s.options.reuse_tolerance > 0 && s.kept.try_cg() &&
      s.cg(M, {}, b, x, tolerance > 0 ? tolerance : s.options.reuse_tolerance,
           s.kept.max_iterations(), stats.cg_iterations)) {
    s.kept.record(stats.cg_iterations);
    stats.single = s.factor_single;
    stats.success = x.allFinite();
    return stats;
  }
  M.scalar_values(s.pattern, static_cast<double*>(s.A->x));
  stats.factored = true;
  s.kept.drop();
  // A + s D, D the diagonal of |A| (floored at 1e-12 of its largest entry), with s just past the
  // lowest eigenvalue of D^-1/2 A D^-1/2: a Lanczos estimate of it (from above, so 1.5 times
  // its size, and at least 1e-3), raised fourfold until the factorisation succeeds. Each dof is
  // stiffened in proportion to its own stiffness: a soft tissue beside a stiff bone or a strong
  // penalty keeps nearly its Newton step, where a shift s I large enough for the stiff dofs
  // would freeze it. The shifted solve is invariant under a rescaling of the dofs.
  const bool shifts = s.options.indefinite == IndefiniteFallback::kShift;
  VectorX d, weight;
  double lowest = 0;
  const auto estimate = [&] {
    d = M.diagonal();
    weight = d.cwiseAbs().cwiseMax(1e-12 * d.cwiseAbs().maxCoeff());
    lowest = lowest_eigenvalue_estimate(M, weight, s.lowest_mode);
    ++stats.estimates;
  };
  // After a shifted factorisation the next matrix is likely indefinite too. The estimate comes
  // first then: a Ritz value below zero proves an eigenvalue below zero (it bounds the lowest
  // from above), so LL^T would fail, and is not tried.
  if (shifts && s.shifted) estimate();
  const bool single = s.options.precision == FactorPrecision::kSingle;
  bool positive = lowest >= 0 && s.factorize_llt(single, stats);
  // A single-precision LL^T also fails on a positive definite A beyond its reach (condition
  // above about 1e7): LL^T in double decides, unless the failed pivot or the estimate proves A
  // indefinite.
  if (!positive && single && lowest >= 0 && s.llt_numeric->failed_pivot() >= -kIndefinitePivot) {
    if (shifts && d.size() == 0) estimate();
    positive = lowest >= 0 && s.factorize_llt(false, stats);
  }
  if (positive && s.solve_factored(M, {}, b, x, tolerance, stats)) {
    s.shifted = false;
    s.kept.start(s.analysis.flops, s.analysis.factor_entries);
  } else if (!shifts) {
    if (!s.factorize_ldlt()) return stats;
    s.solve_with(s.ldlt, b, x);
    stats.ldlt = true;
  } else {
    if (d.size() == 0) estimate();
    double shift = std::max(1e-3, -1.5 * lowest);
    for (;;) {
      s.shift_diagonal(d, weight, shift);
      if (s.factorize_llt(single, stats) &&
          s.solve_factored(M, shift * weight, b, x, tolerance, stats))
        break;
      shift *= 4;
      if (!(shift < 1e3)) return stats;
    }
    s.shifted = true;
    s.kept.start(s.analysis.flops, s.analysis.factor_entries);
    stats.shift = shift;
  }
  stats.success = x.allFinite();
  return stats;
}

}  // namespace depthfem

#include "integrators/solvers/supernodal_cholesky.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <stdexcept>
#include <string>
#include <type_traits>

#include "integrators/solvers/tiled_blas.hpp"

namespace depthfem {

namespace {

// The arrays of a supernodal CHOLMOD factor (integer version) that place its values.
struct Layout {
  int n, nsuper;
  const int *super, *pi, *px, *rows, *perm;
  explicit Layout(const cholmod_factor& L)
      : n(static_cast<int>(L.n)),
        nsuper(static_cast<int>(L.nsuper)),
        super(static_cast<const int*>(L.super)),
        pi(static_cast<const int*>(L.pi)),
        px(static_cast<const int*>(L.px)),
        rows(static_cast<const int*>(L.s)),
        perm(static_cast<const int*>(L.Perm)) {}
};

}  // namespace

// CHOLMOD's supernodal layout (integer version): supernode s holds the columns
// super[s] .. super[s+1]-1 of L; its row indices are s[pi[s]] .. s[pi[s+1]-1], ascending, the
// first ones its own columns; its values are a dense column-major block of those rows by its
// columns at x[px[s]].
SupernodalCholesky::SupernodalCholesky(const cholmod_sparse& A, cholmod_factor& L,
                                       cholmod_common& common) {
  bool fits = false;
  *this = SupernodalCholesky(A, L, common, fits);
  if (!fits) throw std::invalid_argument("SupernodalCholesky: an entry of A is not in L's pattern");
}

std::unique_ptr<SupernodalCholesky> SupernodalCholesky::fitted(const cholmod_sparse& A,
                                                               cholmod_factor& L,
                                                               cholmod_common& common) {
  bool fits = false;
  std::unique_ptr<SupernodalCholesky> out(new SupernodalCholesky(A, L, common, fits));
  if (!fits) out.reset();
  return out;
}

SupernodalCholesky::SupernodalCholesky(const cholmod_sparse& A, cholmod_factor& L,
                                       cholmod_common& common, bool& fits) {
  fits = false;
  if (!L.is_super || L.itype != CHOLMOD_INT || A.stype >= 0 || A.xtype != CHOLMOD_REAL ||
      !A.packed || A.nrow != L.n || A.ncol != L.n)
    throw std::invalid_argument(
        "SupernodalCholesky: needs the lower triangle of a real matrix and its supernodal "
        "analysis (int indices)");
  if (L.xtype == CHOLMOD_PATTERN &&
      !cholmod_change_factor(CHOLMOD_REAL, true, true, true, true, &L, &common))
    throw std::runtime_error("CHOLMOD: allocating the supernodal factor failed (status " +
                             std::to_string(common.status) + ")");
  // Named variables, not a structured binding: the lambdas below capture them (which clang
  // allows structured bindings only from version 16).
  const Layout layout(L);
  const int n = layout.n, nsuper = layout.nsuper;
  const int *super = layout.super, *pi = layout.pi, *px = layout.px, *rows = layout.rows,
            *perm = layout.perm;

  super_of_column_.resize(n);
  for (int s = 0; s < nsuper; ++s)
    std::fill(super_of_column_.begin() + super[s], super_of_column_.begin() + super[s + 1], s);
  std::vector<int> inverse(n);
  for (int k = 0; k < n; ++k) inverse[perm[k]] = k;

  // Entry (i, j), i >= j, of A is entry (max, min) of the permuted indices in L, in the
  // supernode of the smaller. The entries grouped by supernode (a counting sort, in the order of
  // A within each), then each supernode's placed through a map of its rows, in parallel.
  const int* Ap = static_cast<const int*>(A.p);
  const int* Ai = static_cast<const int*>(A.i);
  const auto for_each_entry = [&](auto&& visit) {
    for (int j = 0; j < n; ++j)
      for (int p = Ap[j]; p < Ap[j + 1]; ++p)
        if (Ai[p] >= j) {  // the upper triangle is not read (as CHOLMOD)
          const int a = inverse[Ai[p]], b = inverse[j];
          visit(p, std::max(a, b), std::min(a, b));
        }
  };
  entry_begin_.assign(nsuper + 1, 0);
  for_each_entry([&](int, int, int col) { ++entry_begin_[super_of_column_[col] + 1]; });
  for (int s = 0; s < nsuper; ++s) entry_begin_[s + 1] += entry_begin_[s];
  const size_t entries = entry_begin_[nsuper];
  entry_source_.resize(entries);
  entry_destination_.resize(entries);
  std::vector<int> entry_row(entries), entry_column(entries);
  std::vector<size_t> next = entry_begin_;
  for_each_entry([&](int p, int row, int col) {
    const size_t to = next[super_of_column_[col]]++;
    entry_source_[to] = p;
    entry_row[to] = row;
    entry_column[to] = col;
  });
  struct RowMap {
    std::vector<int> place, supernode;  // of each row of L: in the supernode it was last set for
  };
  tbb::enumerable_thread_specific<RowMap> maps([n] {
    return RowMap{std::vector<int>(n), std::vector<int>(n, -1)};
  });
  std::atomic<bool> all_found{true};
  tbb::parallel_for(tbb::blocked_range<int>(0, nsuper), [&](const tbb::blocked_range<int>& range) {
    RowMap& map = maps.local();
    for (int s = range.begin(); s != range.end() && all_found.load(std::memory_order_relaxed);
         ++s) {
      const int nrow = pi[s + 1] - pi[s];
      for (int k = 0; k < nrow; ++k) {
        map.place[rows[pi[s] + k]] = k;
        map.supernode[rows[pi[s] + k]] = s;
      }
      for (size_t e = entry_begin_[s]; e < entry_begin_[s + 1]; ++e) {
        if (map.supernode[entry_row[e]] != s) {
          all_found.store(false, std::memory_order_relaxed);
          return;
        }
        entry_destination_[e] = size_t(px[s]) + size_t(entry_column[e] - super[s]) * nrow +
                                size_t(map.place[entry_row[e]]);
      }
    }
  });
  if (!all_found.load()) return;
  schedule(L);
  fits = true;
}

// The updates in the order of CHOLMOD's left-looking loop, found by running it on the pattern
// alone: supernodes in order, each takes the descendants queued for it (last queued first), and a
// descendant with rows past the supernode's columns is queued for the supernode of the next row.
// Each supernode's sum of updates is then the one of that loop, whatever order the supernodes
// run in.
void SupernodalCholesky::schedule(const cholmod_factor& L) {
  const Layout layout(L);
  const int nsuper = layout.nsuper;
  const int *super = layout.super, *pi = layout.pi, *rows = layout.rows;
  std::vector<int> head(nsuper, -1), next(nsuper), position(nsuper);
  parent_.assign(nsuper, -1);
  children_.assign(nsuper, 0);
  update_begin_.assign(1, 0);
  updates_.clear();
  for (int s = 0; s < nsuper; ++s) {
    const int k2 = super[s + 1], ncol = k2 - super[s];
    for (int d = head[s], d_next; d != -1; d = d_next) {
      d_next = next[d];
      const int* drows = rows + pi[d];
      const int drow = pi[d + 1] - pi[d];
      int past = position[d];
      while (past < drow && drows[past] < k2) ++past;
      updates_.push_back({d, position[d], past});
      position[d] = past;
      if (past < drow) {
        const int a = super_of_column_[drows[past]];
        next[d] = head[a];
        head[a] = d;
      }
    }
    update_begin_.push_back(updates_.size());
    if (pi[s + 1] - pi[s] > ncol) {
      const int a = super_of_column_[rows[pi[s] + ncol]];
      parent_[s] = a;
      ++children_[a];
      position[s] = ncol;
      next[s] = head[a];
      head[a] = s;
    }
  }
}

template <class T>
bool SupernodalCholesky::factorize_supernode(int s, const cholmod_sparse& A,
                                             const cholmod_factor& L, T* Lx, Workspace& w) const {
  const Layout layout(L);
  const int *super = layout.super, *pi = layout.pi, *px = layout.px, *rows = layout.rows;
  const double* Ax = static_cast<const double*>(A.x);
  const int k1 = super[s], ncol = super[s + 1] - k1;
  const int* srows = rows + pi[s];
  const int nrow = pi[s + 1] - pi[s];
  T* Ls = Lx + px[s];
  std::vector<T>& update = [&]() -> std::vector<T>& {
    if constexpr (std::is_same_v<T, float>) {
      return w.update_single;
    } else {
      return w.update;
    }
  }();

  // The columns of A.
  std::fill(Ls, Ls + size_t(nrow) * ncol, T(0));
  for (size_t e = entry_begin_[s]; e < entry_begin_[s + 1]; ++e)
    Lx[entry_destination_[e]] = static_cast<T>(Ax[entry_source_[e]]);
  for (int k = 0; k < nrow; ++k) w.row_map[srows[k]] = k;

  // Minus L(k1:, d) L(k1:k2, d)^T for every descendant d whose columns have rows in k1:k2.
  for (size_t u = update_begin_[s]; u < update_begin_[s + 1]; ++u) {
    const auto [d, first, past] = updates_[u];
    const int dcol = super[d + 1] - super[d];
    const int* drows = rows + pi[d];
    const int drow = pi[d + 1] - pi[d];
    const int m = drow - first, n = past - first;  // the update is m x n
    if (update.size() < size_t(m) * n) update.resize(size_t(m) * n);
    lower_product<T>(m, n, dcol, 1, Lx + px[d] + first, drow, 0, update.data(), m);
    for (int i = 0; i < m; ++i) w.relative_map[i] = w.row_map[drows[first + i]];
    const auto subtract = [&](int j) {
      T* column = Ls + size_t(w.relative_map[j]) * nrow;
      const T* v = update.data() + size_t(j) * m;
      for (int i = j; i < m; ++i) column[w.relative_map[i]] -= v[i];
    };
    if (double(m) * n < 1 << 16) {  // entries: fewer are not worth a parallel loop
      for (int j = 0; j < n; ++j) subtract(j);
    } else {
      tbb::parallel_for(0, n, subtract);
    }
  }

  const int info = cholesky_lower(ncol, Ls, nrow);
  if (info != 0) {
    w.failed_column = k1 + info - 1;
    return false;
  }
  solve_right_lower_transposed(nrow - ncol, ncol, Ls, nrow, Ls + ncol, nrow);
  return true;
}

bool SupernodalCholesky::factorize(const cholmod_sparse& A, cholmod_factor& L) {
  return factorize_into(A, L, static_cast<double*>(L.x));
}

bool SupernodalCholesky::factorize(const cholmod_sparse& A, cholmod_factor& L,
                                   std::vector<float>& values) {
  values.resize(L.xsize);
  return factorize_into(A, L, values.data());
}

template <class T>
bool SupernodalCholesky::factorize_into(const cholmod_sparse& A, cholmod_factor& L, T* Lx) {
  const Layout layout(L);
  const int nsuper = layout.nsuper, n = layout.n;
  const int* super = layout.super;
  // A supernode runs once its children have (its descendants' updates are then final), on
  // the thread that finished the last of them; the leaves start in parallel. A failed pivot
  // stops the supernodes past its column from starting: those before it still run, so the
  // first failing column is the one of the sequential loop.
  std::vector<std::atomic<int>> waiting(static_cast<size_t>(nsuper));
  for (int s = 0; s < nsuper; ++s) waiting[s].store(children_[s], std::memory_order_relaxed);
  std::atomic<int> failed{n}, factored{0};
  // Runs the supernodes `starts` and, as each finishes the last child of its parent, the
  // parent, as long as it is `within` (null: anywhere).
  const auto run = [&](const std::vector<int>& starts, const std::vector<char>* within) {
    tbb::parallel_for(size_t(0), starts.size(), [&](size_t i) {
      Workspace& w = workspaces_.local();
      w.row_map.resize(size_t(n));
      w.relative_map.resize(size_t(n));
      for (int s = starts[i]; s != -1;) {
        if (super[s] > failed.load()) return;
        // Isolated: a thread waiting for the supernode's own parallel loops takes no other
        // supernode, which would reuse its workspace.
        const bool ok =
            tbb::this_task_arena::isolate([&] { return factorize_supernode(s, A, L, Lx, w); });
        factored.fetch_add(1, std::memory_order_relaxed);
        if (!ok) {
          for (int f = failed.load();
               w.failed_column < f && !failed.compare_exchange_weak(f, w.failed_column);) {
          }
          return;
        }
        const int p = parent_[s];
        if (p == -1 || (within && !(*within)[p]) || waiting[p].fetch_sub(1) != 1) return;
        s = p;
      }
    });
  };
  // The subtrees of the supernodes where recent factorisations failed run first (a supernode's
  // parent comes after it, so that one is in those subtrees when its parent is).
  std::vector<char> probed(static_cast<size_t>(nsuper), 0);
  std::vector<int> starts;
  if (!probes_.empty()) {
    for (const int p : probes_) probed[p] = 1;
    const int highest = *std::ranges::max_element(probes_);  // no probed supernode lies above
    for (int s = highest; s >= 0; --s) {
      if (parent_[s] != -1 && probed[parent_[s]]) probed[s] = 1;
      if (probed[s] && children_[s] == 0) starts.push_back(s);
    }
    run(starts, &probed);
    starts.clear();
    if (failed.load() == n)  // the parents of the subtrees' roots have one child less to wait for
      for (int s = 0; s <= highest; ++s) {
        const int p = parent_[s];
        if (probed[s] && p != -1 && !probed[p] && waiting[p].fetch_sub(1) == 1) starts.push_back(p);
      }
  }
  if (failed.load() == n) {
    for (int s = 0; s < nsuper; ++s)
      if (!probed[s] && children_[s] == 0) starts.push_back(s);
    run(starts, nullptr);
  }
  last_factored_ = factored.load();
  L.minor = size_t(failed.load());
  failed_pivot_ = 0;
  if (failed.load() == n) return true;
  // The supernode that failed becomes the first probe of the next factorisation.
  const int column = failed.load(), s = super_of_column_[column];
  failed_pivot_ = failed_pivot_ratio(A, L, Lx, column);
  std::erase(probes_, s);
  if (probes_.size() == kProbes) probes_.pop_back();
  probes_.insert(probes_.begin(), s);
  return false;
}

// The dense Cholesky kernels (LAPACK's and OpenBLAS's potf2) leave the failed pivot in the
// diagonal entry of its column; the diagonal entry of A is that of column perm[column].
template <class T>
double SupernodalCholesky::failed_pivot_ratio(const cholmod_sparse& A, const cholmod_factor& L,
                                              const T* Lx, int column) const {
  const Layout layout(L);
  const int s = super_of_column_[column], k = column - layout.super[s];
  const double pivot = Lx[layout.px[s] + size_t(k) * (layout.pi[s + 1] - layout.pi[s] + 1)];
  const int a = layout.perm[column];
  const int* Ap = static_cast<const int*>(A.p);
  const int* Ai = static_cast<const int*>(A.i);
  const double* Ax = static_cast<const double*>(A.x);
  for (int e = Ap[a]; e < Ap[a + 1]; ++e)
    if (Ai[e] == a) return Ax[e] > 0 && pivot <= 0 ? pivot / Ax[e] : 0;
  return 0;
}

void SupernodalCholesky::keep_probes_of(const SupernodalCholesky& before) {
  probes_ = before.probes_;
}

namespace {

// sum a[i] b[i] over i < n in double, in eight interleaved partial sums (one running sum is a
// chain of dependent additions the compiler may not reorder).
double dot(const float* a, const double* b, int n) {
  double part[8] = {};
  int i = 0;
  for (; i + 8 <= n; i += 8)
    for (int k = 0; k < 8; ++k) part[k] += double(a[i + k]) * b[i + k];
  double sum = 0;
  for (; i < n; ++i) sum += double(a[i]) * b[i];
  for (const double p : part) sum += p;
  return sum;
}

}  // namespace

// Forward (L y = P b) and backward (L^T z = y, x = P^T z) substitution by supernodes: each
// supernode's rows of y gathered into a dense vector t, its block applied column by column in
// double from the single-precision values (contiguous loops), and t scattered back.
void SupernodalCholesky::solve(const cholmod_factor& L, const std::vector<float>& values,
                               const double* b, double* x) {
  const auto [n, nsuper, super, pi, px, rows, perm] = Layout(L);
  std::vector<double>& y = solve_work_;
  y.resize(size_t(n));
  std::vector<double>& t = solve_rows_;
  for (int k = 0; k < n; ++k) y[k] = b[perm[k]];
  for (int s = 0; s < nsuper; ++s) {
    const int k1 = super[s], ncol = super[s + 1] - k1, nrow = pi[s + 1] - pi[s];
    const int* srows = rows + pi[s];
    const float* Ls = values.data() + px[s];
    t.resize(size_t(nrow));
    for (int i = 0; i < nrow; ++i) t[i] = y[srows[i]];
    for (int j = 0; j < ncol; ++j) {
      const float* column = Ls + size_t(j) * nrow;
      const double tj = t[j] / column[j];
      t[j] = tj;
      for (int i = j + 1; i < nrow; ++i) t[i] -= double(column[i]) * tj;
    }
    for (int i = 0; i < nrow; ++i) y[srows[i]] = t[i];
  }
  for (int s = nsuper - 1; s >= 0; --s) {
    const int k1 = super[s], ncol = super[s + 1] - k1, nrow = pi[s + 1] - pi[s];
    const int* srows = rows + pi[s];
    const float* Ls = values.data() + px[s];
    t.resize(size_t(nrow));
    for (int i = 0; i < nrow; ++i) t[i] = y[srows[i]];
    for (int j = ncol - 1; j >= 0; --j) {
      const float* column = Ls + size_t(j) * nrow;
      t[j] = (t[j] - dot(column + j + 1, t.data() + j + 1, nrow - j - 1)) / column[j];
    }
    for (int k = 0; k < ncol; ++k) y[k1 + k] = t[k];
  }
  for (int k = 0; k < n; ++k) x[perm[k]] = y[k];
}

}  // namespace depthfem

#pragma once
/// psi, P and dP/dF of a batch of deformation gradients at once: the chain rule of
/// hyperelastic.hpp written entry by entry on lane values (V = Lanes<W>, lane l = element l), so
/// that every operation serves W elements. evaluate_stress (hyperelastic.hpp) stays the reference.

#include <array>
#include <limits>

#include "materials/hyperelastic.hpp"
#include "materials/lanes.hpp"

namespace depthfem {

/// A symmetric N x N matrix of lane values, its upper triangle packed: (p, q) and (q, p) are the
/// same entry.
template <class V, int N>
struct SymmetricLanes {
  std::array<V, N*(N + 1) / 2> packed;
  static constexpr int index(int p, int q) {
    return p <= q ? q * (q + 1) / 2 + p : p * (p + 1) / 2 + q;
  }
  V& operator()(int p, int q) { return packed[index(p, q)]; }
  const V& operator()(int p, int q) const { return packed[index(p, q)]; }
};

/// A 3x3 matrix of lane values, column-major: entry (i, j) at 3 j + i (as vec F).
template <class V>
using LaneMatrix3 = std::array<V, 9>;

/// Energy density [J/m^3], first Piola stress [Pa] and dP/dF [Pa] of a batch, on column-major
/// vec F (as Mat9 in hyperelastic.hpp).
template <class V>
struct BatchedStress {
  V psi;
  LaneMatrix3<V> P;
  SymmetricLanes<V, 9> dPdF;
};

namespace detail {

// Levi-Civita symbol of (i, j, k) in {0, 1, 2}.
constexpr int levi_civita(int i, int j, int k) {
  return (i - j) * (j - k) * (k - i) / 2;
}

// H += w a a^T (upper triangle).
template <class V>
void add_rank_one(SymmetricLanes<V, 9>& H, const V& w, const LaneMatrix3<V>& a) {
#pragma GCC unroll 9
  for (int q = 0; q < 9; ++q) {
    const V wa = w * a[q];
#pragma GCC unroll 9
    for (int p = 0; p <= q; ++p) H(p, q) += a[p] * wa;
  }
}

// H += w (a b^T + b a^T) (upper triangle).
template <class V>
void add_rank_two(SymmetricLanes<V, 9>& H, const V& w, const LaneMatrix3<V>& a,
                  const LaneMatrix3<V>& b) {
#pragma GCC unroll 9
  for (int q = 0; q < 9; ++q) {
    const V wa = w * a[q], wb = w * b[q];
#pragma GCC unroll 9
    for (int p = 0; p <= q; ++p) H(p, q) += a[p] * wb + b[p] * wa;
  }
}

}  // namespace detail

/// Evaluates psi (kOrder 0), P (kOrder >= 1) and dP/dF (kOrder 2) of material `m` at the
/// deformation gradients F of a batch with unit fiber directions f (read only by fiber
/// materials). Lanes with det F <= 0 get psi = +infinity and zero P and dP/dF, as
/// evaluate_stress gives them.
template <int kOrder, Material M, class V>
BatchedStress<V> evaluate_batched_stress(const M& m, const LaneMatrix3<V>& F,
                                         const std::array<V, 3>& f) {
  const auto at = [&](int i, int j) -> const V& { return F[3 * j + i]; };
  // C = F^T F and B = F F^T (symmetric), the fiber image F f and the cofactor dJ/dF.
  SymmetricLanes<V, 3> C, B;
#pragma GCC unroll 3
  for (int j = 0; j < 3; ++j)
#pragma GCC unroll 3
    for (int l = j; l < 3; ++l) {
      C(j, l) = at(0, j) * at(0, l) + at(1, j) * at(1, l) + at(2, j) * at(2, l);
      B(j, l) = at(j, 0) * at(l, 0) + at(j, 1) * at(l, 1) + at(j, 2) * at(l, 2);
    }
  LaneMatrix3<V> cof;
#pragma GCC unroll 3
  for (int j = 0; j < 3; ++j) {
    const int j1 = (j + 1) % 3, j2 = (j + 2) % 3;
#pragma GCC unroll 3
    for (int i = 0; i < 3; ++i) {
      const int i1 = (i + 1) % 3, i2 = (i + 2) % 3;
      cof[3 * j + i] = at(i1, j1) * at(i2, j2) - at(i2, j1) * at(i1, j2);
    }
  }
  std::array<V, 3> Ff;
  if constexpr (M::kUsesFiber) {
#pragma GCC unroll 3
    for (int i = 0; i < 3; ++i) Ff[i] = at(i, 0) * f[0] + at(i, 1) * f[1] + at(i, 2) * f[2];
  }

  Invariants<V> inv;
  inv.I1 = C(0, 0) + C(1, 1) + C(2, 2);
  const V trace_C2 = C(0, 0) * C(0, 0) + C(1, 1) * C(1, 1) + C(2, 2) * C(2, 2) +
                     2.0 * (C(0, 1) * C(0, 1) + C(0, 2) * C(0, 2) + C(1, 2) * C(1, 2));
  inv.I2 = 0.5 * (inv.I1 * inv.I1 - trace_C2);
  inv.J = determinant(F.data());
  if constexpr (M::kUsesFiber) inv.I4 = Ff[0] * Ff[0] + Ff[1] * Ff[1] + Ff[2] * Ff[2];

  // Inverted lanes: psi = +infinity, all derivatives zero (so P = 0 and dP/dF = 0 there).
  const auto valid = inv.J > V(0.0);
  InvariantDerivatives<V> e = m.template evaluate<kOrder>(inv);
  BatchedStress<V> s;
  s.psi = select(valid, e.psi, V(std::numeric_limits<double>::infinity()));
  if constexpr (kOrder == 0) return s;
  for (int x = 0; x < 4; ++x) {
    e.d[x] = select(valid, e.d[x], V(0.0));
    for (int y = 0; y < 4; ++y) e.d2[x][y] = select(valid, e.d2[x][y], V(0.0));
  }

  // dI/dF for each invariant used: dI1 = 2F, dI2 = 2 (I1 F - F C), dJ = cof F, dI4 = 2 (F f) f^T.
  std::array<LaneMatrix3<V>, 4> g;
#pragma GCC unroll 9
  for (int p = 0; p < 9; ++p) {
    const int i = p % 3, j = p / 3;
    g[kI1][p] = 2.0 * F[p];
    g[kJ][p] = cof[p];
    if constexpr (M::kUsesI2)
      g[kI2][p] =
          2.0 * (inv.I1 * F[p] - (at(i, 0) * C(0, j) + at(i, 1) * C(1, j) + at(i, 2) * C(2, j)));
    if constexpr (M::kUsesFiber) g[kI4][p] = 2.0 * Ff[i] * f[j];
  }
#pragma GCC unroll 9
  for (int p = 0; p < 9; ++p) {
    s.P[p] = e.d[kI1] * g[kI1][p] + e.d[kJ] * g[kJ][p];
    if constexpr (M::kUsesI2) s.P[p] += e.d[kI2] * g[kI2][p];
    if constexpr (M::kUsesFiber) s.P[p] += e.d[kI4] * g[kI4][p];
  }
  if constexpr (kOrder == 1) return s;

  // Entry (p, q) = dP_ij / dF_kl with p = i + 3 j, q = k + 3 l:
  //   psi_1 d2I1:  2 delta_ik delta_jl
  //   psi_2 d2I2:  2 [(I1 delta_jl - C_lj) delta_ik + 2 F_ij F_kl - F_il F_kj - delta_jl B_ik]
  //   psi_J d2J:   eps_ikm eps_jln F_mn
  //   psi_4 d2I4:  2 f_j f_l delta_ik
  // plus sum_xy psi_xy (dI_x/dF)_p (dI_y/dF)_q.
  const V a1 = 2.0 * e.d[kI1], a2 = 2.0 * e.d[kI2], a4 = 2.0 * e.d[kI4];
#pragma GCC unroll 9
  for (int q = 0; q < 9; ++q) {
#pragma GCC unroll 9
    for (int p = 0; p <= q; ++p) {
      const int i = p % 3, j = p / 3, k = q % 3, l = q / 3;
      V h(0.0);
      if (i == k) {
        if (j == l) h = a1;
        if constexpr (M::kUsesI2) h += a2 * ((j == l ? inv.I1 : V(0.0)) - C(l, j));
        if constexpr (M::kUsesFiber) h += a4 * f[j] * f[l];
      }
      if constexpr (M::kUsesI2) {
        h += a2 * (2.0 * at(i, j) * at(k, l) - at(i, l) * at(k, j));
        if (j == l) h -= a2 * B(i, k);
      }
      if (i != k && j != l) {
        const int mm = 3 - i - k, n = 3 - j - l;
        const double sign = detail::levi_civita(i, k, mm) * detail::levi_civita(j, l, n);
        h += sign * e.d[kJ] * at(mm, n);
      }
      s.dPdF(p, q) = h;
    }
  }
  // Rank-one terms over the invariants used, skipped where psi_xy is zero in every lane (most
  // models couple only a few invariants).
  constexpr std::array<bool, 4> used = {true, M::kUsesI2, true, M::kUsesFiber};
  for (int x = 0; x < 4; ++x) {
    if (!used[x]) continue;
    for (int y = x; y < 4; ++y) {
      if (!used[y] || !(e.d2[x][y] != V(0.0)).any()) continue;
      if (x == y) {
        detail::add_rank_one(s.dPdF, e.d2[x][x], g[x]);
      } else {
        detail::add_rank_two(s.dPdF, e.d2[x][y], g[x], g[y]);
      }
    }
  }
  return s;
}

}  // namespace depthfem

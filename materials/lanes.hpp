#pragma once
/// Lanes<W>: W doubles that go through every operation together, lane l belonging to element l of
/// a batch. The batched kernels are written once on this type; each operation is one vector
/// instruction when W doubles fill a register (kLanes: 8 with AVX-512, 4 with AVX, 2 otherwise).
///
/// Lanes wrap GCC vector extensions, so +, -, *, / and comparisons are the compiler's own vector
/// operations and a double on either side is broadcast. exp and log come from Eigen's packet math
/// (accurate to about one unit in the last place), applied to as many packets as W needs.

#include <Eigen/Core>
#include <cstdint>
#include <cstring>
#include <utility>

namespace depthfem {

/// Lanes per batch at the instruction set this file is compiled for: one register of doubles.
#if defined(__AVX512F__)
inline constexpr int kLanes = 8;
#elif defined(__AVX__)
inline constexpr int kLanes = 4;
#else
inline constexpr int kLanes = 2;
#endif

namespace detail {
// The GCC vector types of W doubles and of W 64-bit masks (spelled out per width: the attribute
// must not depend on a template parameter).
template <int W>
struct NativeLanes;
template <>
struct NativeLanes<2> {
  typedef double Value __attribute__((vector_size(16)));
  typedef std::int64_t Mask __attribute__((vector_size(16)));
};
template <>
struct NativeLanes<4> {
  typedef double Value __attribute__((vector_size(32)));
  typedef std::int64_t Mask __attribute__((vector_size(32)));
};
template <>
struct NativeLanes<8> {
  typedef double Value __attribute__((vector_size(64)));
  typedef std::int64_t Mask __attribute__((vector_size(64)));
};
}  // namespace detail

/// Per-lane truth values of a comparison of Lanes<W> (all bits set where true).
template <int W>
struct LaneMask {
  using Native = typename detail::NativeLanes<W>::Mask;
  Native m;
  friend LaneMask operator&&(const LaneMask& a, const LaneMask& b) { return {a.m & b.m}; }
  /// Whether any lane is true.
  bool any() const {
    for (int l = 0; l < W; ++l)
      if (m[l]) return true;
    return false;
  }
};

/// W doubles (W = 2, 4 or 8), one per element of a batch; arithmetic acts lane by lane.
template <int W>
struct Lanes {
  using Native = typename detail::NativeLanes<W>::Value;
  static constexpr int kWidth = W;
  Native v;

  Lanes() = default;                    // uninitialised, like a double; Lanes{} is zero
  Lanes(double s) : v(Native{} + s) {}  // NOLINT: constants broadcast implicitly
  explicit Lanes(const Native& n) : v(n) {}

  /// W consecutive doubles from p (no alignment needed).
  static Lanes load(const double* p) {
    Lanes r;
    std::memcpy(&r.v, p, sizeof r.v);
    return r;
  }
  /// Lane l = base[index[l]] (a gather; loads lane by lane, which measured no slower than the
  /// gather instruction).
  static Lanes gather(const double* base, const std::int32_t* index) {
    Lanes r;
    for (int l = 0; l < W; ++l) r.v[l] = base[index[l]];
    return r;
  }
  /// Writes the W lanes to p[0 .. W).
  void store(double* p) const { std::memcpy(p, &v, sizeof v); }
  double operator[](int l) const { return v[l]; }
  void set(int l, double s) { v[l] = s; }

  friend Lanes operator+(const Lanes& a, const Lanes& b) { return Lanes(a.v + b.v); }
  friend Lanes operator-(const Lanes& a, const Lanes& b) { return Lanes(a.v - b.v); }
  friend Lanes operator*(const Lanes& a, const Lanes& b) { return Lanes(a.v * b.v); }
  friend Lanes operator/(const Lanes& a, const Lanes& b) { return Lanes(a.v / b.v); }
  friend Lanes operator-(const Lanes& a) { return Lanes(-a.v); }
  Lanes& operator+=(const Lanes& b) { return v += b.v, *this; }
  Lanes& operator-=(const Lanes& b) { return v -= b.v, *this; }
  Lanes& operator*=(const Lanes& b) { return v *= b.v, *this; }
  friend LaneMask<W> operator>(const Lanes& a, const Lanes& b) { return {a.v > b.v}; }
  friend LaneMask<W> operator!=(const Lanes& a, const Lanes& b) { return {a.v != b.v}; }
};

/// Lane by lane: a where `m` is true, b elsewhere.
template <int W>
Lanes<W> select(const LaneMask<W>& m, const Lanes<W>& a, const Lanes<W>& b) {
  return Lanes<W>(m.m ? a.v : b.v);
}

namespace detail {
// One butterfly stage of a W x W transpose: rows i and i + h (i & h == 0) swap their
// off-diagonal h x h sub-blocks; the low result takes row i's entries k with k & h == 0 and row
// i + h's entries k - h elsewhere, the high result the rest (indices >= W pick from row i + h).
// __builtin_shufflevector is understood by GCC (12 and later) and clang alike.
template <int W, int h, bool kHigh, std::size_t... k>
typename NativeLanes<W>::Value butterfly(const typename NativeLanes<W>::Value& a,
                                         const typename NativeLanes<W>::Value& b,
                                         std::index_sequence<k...>) {
  return __builtin_shufflevector(
      a, b, (kHigh ? ((k & h) ? W + k : k + h) : ((k & h) ? W + k - h : k))...);
}

template <int W, int h>
void butterfly_stage(Lanes<W>* rows) {
  for (int i = 0; i < W; ++i) {
    if (i & h) continue;
    const Lanes<W> a = rows[i], b = rows[i + h];
    rows[i].v = butterfly<W, h, false>(a.v, b.v, std::make_index_sequence<W>{});
    rows[i + h].v = butterfly<W, h, true>(a.v, b.v, std::make_index_sequence<W>{});
  }
}
}  // namespace detail

/// Transposes W rows of W lanes in place: afterwards rows[l][k] is what rows[k][l] was (lane l of
/// W values becomes a row of its own, ready for a contiguous store).
template <int W>
void transpose(Lanes<W>* rows) {
  detail::butterfly_stage<W, 1>(rows);
  if constexpr (W > 2) detail::butterfly_stage<W, 2>(rows);
  if constexpr (W > 4) detail::butterfly_stage<W, 4>(rows);
}

namespace detail {
// Applies an Eigen packet function to the W lanes, as many of the widest packets of at most four
// doubles as fit (GCC 12 warns falsely about uninitialised values inside Eigen's eight-lane exp
// and log).
template <int W, class F>
Lanes<W> per_packet(const Lanes<W>& x, F f) {
  using Packet = typename Eigen::internal::find_best_packet<double, (W < 4 ? W : 4)>::type;
  constexpr int kSize = Eigen::internal::unpacket_traits<Packet>::size;
  double in[W], out[W];
  x.store(in);
  for (int k = 0; k < W; k += kSize)
    Eigen::internal::pstoreu(out + k, f(Eigen::internal::ploadu<Packet>(in + k)));
  return Lanes<W>::load(out);
}
}  // namespace detail

/// a b + c lane by lane, fused where the target has FMA (as multiply_add on doubles).
template <int W>
Lanes<W> multiply_add(const Lanes<W>& a, const Lanes<W>& b, const Lanes<W>& c) {
#ifdef __FMA__
  using Packet = typename Eigen::internal::find_best_packet<double, W>::type;
  constexpr int kSize = Eigen::internal::unpacket_traits<Packet>::size;
  double x[W], y[W], z[W], out[W];
  a.store(x), b.store(y), c.store(z);
  for (int k = 0; k < W; k += kSize)
    Eigen::internal::pstoreu(out + k,
                             Eigen::internal::pmadd(Eigen::internal::ploadu<Packet>(x + k),
                                                    Eigen::internal::ploadu<Packet>(y + k),
                                                    Eigen::internal::ploadu<Packet>(z + k)));
  return Lanes<W>::load(out);
#else
  return a * b + c;
#endif
}

/// e^x lane by lane.
template <int W>
Lanes<W> exp(const Lanes<W>& x) {
  return detail::per_packet(x, [](const auto& p) { return Eigen::internal::pexp(p); });
}
/// Natural logarithm lane by lane (NaN for x < 0, -infinity at 0).
template <int W>
Lanes<W> log(const Lanes<W>& x) {
  return detail::per_packet(x, [](const auto& p) { return Eigen::internal::plog(p); });
}
/// x^p = e^(p ln x) lane by lane, for x > 0.
template <int W>
Lanes<W> pow(const Lanes<W>& x, double p) {
  return exp(p * log(x));
}

}  // namespace depthfem

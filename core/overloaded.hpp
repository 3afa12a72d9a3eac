#pragma once
/// `Overloaded{lambdas...}`: one callable with the overloads of several lambdas, for std::visit.

namespace depthfem {

/// Inherits the call operators of every F.
template <class... F>
struct Overloaded : F... {
  using F::operator()...;
};
/// Deduces F... from the lambdas (GCC does without it in C++20; clang 14 needs it).
template <class... F>
Overloaded(F...) -> Overloaded<F...>;

}  // namespace depthfem

#pragma once
// Random deformation gradients and fiber directions for the material tests.

#include <random>

#include "core/types.hpp"

namespace depthfem::testing {

/// F = I + 0.35 noise with det F >= 0.3, and random unit fiber directions, from a fixed seed.
struct RandomState {
  std::mt19937 rng{12345};
  Mat3 F() {
    std::uniform_real_distribution<double> u(-1, 1);
    for (;;) {
      Mat3 F = Mat3::Identity();
      for (int i = 0; i < 9; ++i) F(i) += 0.35 * u(rng);
      if (F.determinant() >= 0.3) return F;
    }
  }
  Vec3 fiber() {
    std::normal_distribution<double> n;
    return Vec3(n(rng), n(rng), n(rng)).normalized();
  }
};

}  // namespace depthfem::testing

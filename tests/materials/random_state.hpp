#pragma once
// Random deformation gradients and fiber directions for the material tests.

#include <Eigen/Core>
#include <random>

namespace depthfem::testing {

/// Random F = I + 0.35 * noise with det F >= 0.3, and random unit fiber directions.
struct RandomState {
  std::mt19937 rng;
  explicit RandomState(unsigned seed = 12345) : rng(seed) {}
  Eigen::Matrix3d F() {
    std::uniform_real_distribution<double> u(-1, 1);
    for (;;) {
      Eigen::Matrix3d F = Eigen::Matrix3d::Identity();
      for (int i = 0; i < 9; ++i) F(i) += 0.35 * u(rng);
      if (F.determinant() >= 0.3) return F;
    }
  }
  Eigen::Vector3d fiber() {
    std::normal_distribution<double> n;
    return Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized();
  }
};

}  // namespace depthfem::testing

#include "integrators/elements/psd_projection.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

namespace depthfem {

bool project_to_psd(Mat12& h) {
  if (!h.allFinite()) return false;
  if (Eigen::LLT<Mat9>(h.bottomRightCorner<9, 9>()).info() == Eigen::Success) return false;
  const Eigen::SelfAdjointEigenSolver<Mat12> eig(h);
  const auto& lambda = eig.eigenvalues();  // ascending
  if (lambda(0) >= 0) return false;
  const auto& v = eig.eigenvectors();
  const Mat12 p = v * lambda.cwiseMax(0.0).asDiagonal() * v.transpose();
  h = 0.5 * (p + p.transpose());  // exactly symmetric: the two triangles are scattered apart
  return true;
}

}  // namespace depthfem

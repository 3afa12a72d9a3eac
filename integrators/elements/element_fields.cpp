#include "integrators/elements/element_fields.hpp"

#include <tbb/parallel_for.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <stdexcept>
#include <variant>

#include "materials/isochoric.hpp"

namespace depthfem {

namespace {

/// [x1 - x0, x2 - x0, x3 - x0] of tet t.
Mat3 edges(const Points& x, const TetIndices& tets, Index t) {
  Mat3 D;
  for (int a = 0; a < 3; ++a) D.col(a) = (x.row(tets(t, a + 1)) - x.row(tets(t, 0))).transpose();
  return D;
}

/// Deformation gradient F = Ds Dm^-1 of tet t.
Mat3 deformation_gradient(const Points& X, const Points& x, const TetIndices& tets, Index t) {
  return edges(x, tets, t) * edges(X, tets, t).inverse();
}

/// The symmetric matrix S as (xx, yy, zz, xy, yz, xz).
Eigen::Matrix<double, 1, 6> voigt(const Mat3& S) {
  return {S(0, 0), S(1, 1), S(2, 2), S(0, 1), S(1, 2), S(0, 2)};
}

}  // namespace

ElementFields element_fields(const Points& X, const TetIndices& tets,
                             const std::vector<ElasticGroup>& groups, const Points& x,
                             ElementFieldOptions options, const VectorX* tet_pressure) {
  const Index n = static_cast<Index>(tets.rows());
  ElementFields out;
  if (options.strain) {
    out.strain.resize(n, 6);
    out.volume_ratio.resize(n);
    tbb::parallel_for(Index(0), n, [&](Index t) {
      const Mat3 F = deformation_gradient(X, x, tets, t);
      // ln V = Q diag(ln sqrt(lambda_i)) Q^T with F F^T = Q diag(lambda) Q^T.
      const Eigen::SelfAdjointEigenSolver<Mat3> B(F * F.transpose());
      const Vec3 log_stretch = 0.5 * B.eigenvalues().array().log();
      out.strain.row(t) =
          voigt(B.eigenvectors() * log_stretch.asDiagonal() * B.eigenvectors().transpose());
      out.volume_ratio(t) = F.determinant();
    });
  }
  if (options.stress) {
    out.stress = Eigen::Matrix<double, Eigen::Dynamic, 6>::Zero(n, 6);
    out.von_mises = VectorX::Zero(n);
    for (const ElasticGroup& group : groups) {
      const Index size = static_cast<Index>(group.tets.size());
      const bool split = group.formulation != VolumeFormulation::kStandard;
      if (split && !tet_pressure)
        throw std::logic_error(
            "element fields: a nodal-pressure or patch-volume group needs the "
            "pressures of its tets");
      const auto stresses = [&](const auto& material) {
        tbb::parallel_for(Index(0), size, [&](Index k) {
          const Index t = group.tets[static_cast<size_t>(k)];
          const Mat3 F = deformation_gradient(X, x, tets, t);
          const Vec3 f = group.fibers.rows() ? Vec3(group.fibers.row(k)) : Vec3::UnitX();
          Mat3 sigma = first_piola(material, F, f) * F.transpose() / F.determinant();
          if (split) sigma.diagonal().array() += (*tet_pressure)[t];
          const Mat3 s = sigma - sigma.trace() / 3 * Mat3::Identity();
          out.stress.row(t) = voigt(sigma);
          out.von_mises(t) = std::sqrt(1.5 * s.cwiseAbs2().sum());
        });
      };
      std::visit(
          [&]<class M>(const M& material) {
            if (split) return stresses(Isochoric<M>{material});
            stresses(material);
          },
          group.material);
    }
  }
  return out;
}

}  // namespace depthfem

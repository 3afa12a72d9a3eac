#include "integrators/forces/viscoelastic_history.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <functional>
#include <stdexcept>

#include "integrators/elements/psd_projection.hpp"
#include "integrators/elements/tet_inputs.hpp"

namespace depthfem {

namespace {

using Sym = Eigen::Matrix<double, 1, 6>;

// Component (i, j) of the order xx, yy, zz, xy, yz, xz.
constexpr int kSymRow[6] = {0, 1, 2, 0, 1, 0};
constexpr int kSymCol[6] = {0, 1, 2, 1, 2, 2};

Sym to_sym(const Mat3& A) {
  Sym s;
  for (int k = 0; k < 6; ++k) s(k) = A(kSymRow[k], kSymCol[k]);
  return s;
}

Mat3 from_sym(const Sym& s) {
  Mat3 A;
  for (int k = 0; k < 6; ++k) A(kSymRow[k], kSymCol[k]) = A(kSymCol[k], kSymRow[k]) = s(k);
  return A;
}

// A : B of two symmetric tensors.
double contract(const Sym& a, const Sym& b) {
  return a.head<3>().dot(b.head<3>()) + 2 * a.tail<3>().dot(b.tail<3>());
}

// F of row e at x.
Mat3 deformation(const TetBlock& b, const Points& x, Index e) {
  return edge_vectors(b, x, e) * b.dm_inv(e);
}

// Runs row(e) -> double over all rows of b, summed in a fixed tree (independent of threads).
template <class RowFn>
double sum_rows(Index rows, RowFn row) {
  return tbb::parallel_deterministic_reduce(
      tbb::blocked_range<Index>(0, rows, 1024), 0.0,
      [&](const tbb::blocked_range<Index>& r, double acc) {
        for (Index e = r.begin(); e < r.end(); ++e) acc += row(e);
        return acc;
      },
      std::plus<double>());
}

}  // namespace

ViscoelasticHistory::ViscoelasticHistory(PronySeries prony, Index rows, bool timed)
    : prony_(std::move(prony)), timed_(timed) {
  step_ = prony_step(prony_, 0.0);
  if (!timed_) {
    step_.scale = prony_.static_relaxed ? prony_.equilibrium_weight() : 1.0;
    return;
  }
  Q_.assign(prony_.weights.size(), SymmetricColumns::Zero(rows, 6));
  S_iso_ = E_ = h_ = SymmetricColumns::Zero(rows, 6);
}

void ViscoelasticHistory::start(const MaterialModel& m, const TetBlock& b, const Points& x) {
  if (!timed_) return;
  std::visit(
      [&](const auto& model) {
        tbb::parallel_for(tbb::blocked_range<Index>(0, b.size(), 1024),
                          [&](const tbb::blocked_range<Index>& r) {
                            for (Index e = r.begin(); e < r.end(); ++e) {
                              const Mat3 F = deformation(b, x, e);
                              const Vec3 f = b.fiber.rows() ? Vec3(b.fiber.row(e)) : Vec3::UnitX();
                              S_iso_.row(e) = to_sym(isochoric_pk2(model, F, f));
                              E_.row(e) = to_sym(0.5 * (F.transpose() * F - Mat3::Identity()));
                              for (size_t i = 0; i < Q_.size(); ++i)
                                Q_[i].row(e) = prony_.weights[i] * S_iso_.row(e);
                            }
                          });
      },
      m);
  started_ = true;
  accepted_time_ = 0;
  time_ = -1;  // forces set_time to form h
  set_time(0);
}

void ViscoelasticHistory::set_time(double t) {
  if (!timed_ || t == time_) return;
  time_ = t;
  step_ = prony_step(prony_, std::max(0.0, t - accepted_time_));
  h_.setZero();
  for (size_t i = 0; i < Q_.size(); ++i) h_ += step_.decay[i] * Q_[i] - step_.gamma[i] * S_iso_;
}

double ViscoelasticHistory::evaluate_rows(const TetBlock& b, const Index* scatter, const Points& x,
                                          Index begin, Index end, VectorX* g, BlockSparseMatrix* H,
                                          bool project) const {
  if (!timed_) return 0;
  double energy = 0;
  for (Index e = begin; e < end; ++e) {
    const Mat3 h = from_sym(h_.row(e));
    const Mat3 D = b.dm_inv(e);
    const Mat3 F = edge_vectors(b, x, e) * D;
    const double V = b.volume(e);
    energy += 0.5 * V * ((F.transpose() * F - Mat3::Identity()).cwiseProduct(h)).sum();
    if (!g) continue;
    const Mat3 G = V * F * h * D.transpose();
    for (int a = 0; a < 3; ++a) g->segment<3>(3 * b.nodes(e, a + 1)) += G.col(a);
    g->segment<3>(3 * b.nodes(e, 0)) -= G.rowwise().sum();
    if (!H) continue;
    // The 4x4 node coupling k (times I3): D h D^T on nodes 1..3, node 0 balancing them.
    Eigen::Matrix4d k;
    k.bottomRightCorner<3, 3>() = V * D * h * D.transpose();
    k.block<3, 1>(1, 0) = -k.bottomRightCorner<3, 3>().rowwise().sum();
    k.block<1, 3>(0, 1) = k.block<3, 1>(1, 0).transpose();
    k(0, 0) = -k.block<3, 1>(1, 0).sum();
    Mat12 K = Mat12::Zero();
    for (int p = 0; p < 4; ++p)
      for (int q = 0; q < 4; ++q) K.block<3, 3>(3 * p, 3 * q).diagonal().setConstant(k(p, q));
    if (project) project_to_psd(K);
    H->add_blocks<4>(scatter + 16 * e, K);
  }
  return energy;
}

double ViscoelasticHistory::accept(const MaterialModel& m, const TetBlock& b, const Points& x) {
  if (!timed_) return 0;
  const double mu = material_moduli(m).mu;
  const double dissipated = std::visit(
      [&](const auto& model) {
        return sum_rows(b.size(), [&](Index e) {
          const Mat3 F = deformation(b, x, e);
          const Vec3 f = b.fiber.rows() ? Vec3(b.fiber.row(e)) : Vec3::UnitX();
          const Sym S = to_sym(isochoric_pk2(model, F, f));
          const Sym E = to_sym(0.5 * (F.transpose() * F - Mat3::Identity()));
          double d = 0;
          for (size_t i = 0; i < Q_.size(); ++i) {
            const Sym before = Q_[i].row(e);
            const Sym after = step_.decay[i] * before + step_.gamma[i] * (S - S_iso_.row(e));
            d += 0.5 * contract(before + after, E - E_.row(e)) -
                 (contract(after, after) - contract(before, before)) / (4 * prony_.weights[i] * mu);
            Q_[i].row(e) = after;
          }
          S_iso_.row(e) = S;
          E_.row(e) = E;
          return b.volume(e) * d;
        });
      },
      m);
  accepted_time_ = time_;
  time_ = -1;                // forces set_time to form h
  set_time(accepted_time_);  // a step of length 0 until the next set_time
  return dissipated;
}

Eigen::MatrixXd ViscoelasticHistory::state() const {
  if (!timed_) return {};
  Eigen::MatrixXd out(S_iso_.rows(), 6 * (Q_.size() + 2));
  out.leftCols<6>() = S_iso_;
  out.middleCols<6>(6) = E_;
  for (size_t i = 0; i < Q_.size(); ++i) out.middleCols<6>(6 * Eigen::Index(i + 2)) = Q_[i];
  return out;
}

void ViscoelasticHistory::restore(const Eigen::MatrixXd& state, double t) {
  if (!timed_) return;
  if (state.rows() != S_iso_.rows() || state.cols() != Eigen::Index(6 * (Q_.size() + 2)))
    throw std::logic_error("ViscoelasticHistory::restore: a state of another shape");
  S_iso_ = state.leftCols<6>();
  E_ = state.middleCols<6>(6);
  for (size_t i = 0; i < Q_.size(); ++i) Q_[i] = state.middleCols<6>(6 * Eigen::Index(i + 2));
  started_ = true;
  accepted_time_ = t;  // as accept() leaves it
  time_ = -1;
  set_time(accepted_time_);
}

SymmetricColumns ViscoelasticHistory::viscous_stress(const TetBlock& b, const Points& x) const {
  SymmetricColumns out = SymmetricColumns::Zero(b.size(), 6);
  if (!timed_) return out;
  tbb::parallel_for(tbb::blocked_range<Index>(0, b.size(), 1024),
                    [&](const tbb::blocked_range<Index>& r) {
                      for (Index e = r.begin(); e < r.end(); ++e) {
                        Sym Q = Sym::Zero();
                        for (const SymmetricColumns& q : Q_) Q += q.row(e);
                        const Mat3 F = deformation(b, x, e);
                        out.row(e) = to_sym(F * from_sym(Q) * F.transpose() / F.determinant());
                      }
                    });
  return out;
}

}  // namespace depthfem

#include "integrators/solvers/symplectic_euler.hpp"

#include <chrono>
#include <cmath>

#include "core/error.hpp"
#include "core/tet_mesh.hpp"

namespace depthfem {

double critical_time_step(const Points& X, const TetIndices& tets, const VectorX& tet_density,
                          const std::vector<ElasticGroup>& groups) {
  double h = std::numeric_limits<double>::infinity();
  for (const ElasticGroup& group : groups) {
    const LinearizedModuli mod = material_moduli(group.material);
    for (Index t : group.tets) {
      const Vec3 p[4] = {X.row(tets(t, 0)), X.row(tets(t, 1)), X.row(tets(t, 2)),
                         X.row(tets(t, 3))};
      double largest_face = 0;
      for (int f = 0; f < 4; ++f) {
        const Vec3& a = p[(f + 1) % 4];
        largest_face =
            std::max(largest_face, 0.5 * (p[(f + 2) % 4] - a).cross(p[(f + 3) % 4] - a).norm());
      }
      const double length = 3 * signed_volume(p[0], p[1], p[2], p[3]) / largest_face;
      const double speed = std::sqrt((mod.lambda + 2 * mod.mu) / tet_density(t));
      h = std::min(h, length / speed);
    }
  }
  return h;
}

SymplecticEuler::SymplecticEuler(StepLifecycle& lifecycle, VectorX mass, DynamicOptions options,
                                 double critical_step)
    : lifecycle_(lifecycle), mass_(std::move(mass)), options_(options) {
  if (options_.time_step > critical_step) {
    throw InputError("symplectic_euler: time step " + std::to_string(options_.time_step) +
                     " s exceeds the stable limit " + std::to_string(critical_step) +
                     " s of this mesh (smallest element altitude / wave speed)");
  }
  if (options_.damping.stiffness != 0) {
    throw InputError(
        "symplectic_euler: stiffness-proportional damping needs an implicit integrator");
  }
  if (options_.mass != MassMatrix::kLumped)
    throw InputError("symplectic_euler: a consistent mass matrix needs an implicit integrator");
}

void SymplecticEuler::run(Points& x, Points& v, const DynamicStart& start) {
  const Constraints& constraints = lifecycle_.constraints();
  const Index steps = time_step_count(options_);
  VectorX g;
  double t = start.time;
  lifecycle_.begin(x, t / options_.duration);
  double energy = lifecycle_.gradient(x, g);
  // A restart's force: the one the uninterrupted run evaluated when it completed the step (a
  // viscoelastic history forms it before that step is accepted; after, it agrees to round-off).
  if (start.force.size() > 0) g = as_dofs(start.force);
  for (Index n = first_step_after(options_, t); n < steps; ++n) {
    const double t_next = step_end_time(options_, n), h = t_next - t;
    if (!std::isfinite(energy)) {
      throw SolveError("time step " + std::to_string(n) + " (t = " + std::to_string(t) +
                       " s): an element inverted (the explicit step is too large for this motion)");
    }
    v *= 1.0 - h * options_.damping.mass;
    for (Index i = 0; i < x.rows(); ++i)
      v.row(i) -= (h / mass_(i)) * g.segment<3>(3 * i).transpose();
    const Points before = x;
    x += h * v;
    constraints.impose(t_next / options_.duration, x);
    v = (x - before) / h;  // constrained nodes move as prescribed
    t = t_next;
    lifecycle_.set_load(t / options_.duration);
    NewtonResult explicit_step;  // no solve
    explicit_step.converged = true;
    explicit_step.residuals.push_back(0.0);
    lifecycle_.complete(t, explicit_step, x, &v);
    if (n + 1 == steps) break;
    lifecycle_.begin(x, t / options_.duration);
    g = lifecycle_.last_gradient();
    energy = lifecycle_.last_energy();
  }
}

}  // namespace depthfem

#include "integrators/forces/system.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace depthfem {

void System::begin_step(const Points& x) {
  for (const auto& m : modules_) {
    PhaseTimers::Scope t(timers_, "collision detection: " + m->name());
    m->begin_step(x);
  }
}

void System::set_load(double load) {
  for (const auto& m : modules_) m->set_load(load);
}

double System::max_step(const Points& x, const Points& dx) const {
  double alpha = std::numeric_limits<double>::infinity();
  for (const auto& m : modules_) {
    PhaseTimers::Scope t(timers_, "force/stiffness: " + m->name());
    alpha = std::min(alpha, m->max_step(x, dx));
  }
  return alpha;
}

void System::complete_step(const Points& x) {
  for (const auto& m : modules_) {
    PhaseTimers::Scope t(timers_, "force/stiffness: " + m->name());
    m->complete_step(x);
  }
}

void System::report(const Points& x, StepRecord& step) const {
  for (const auto& m : modules_) m->report(x, step);
}

std::vector<std::string> System::interface_names() const {
  std::vector<std::string> out;
  for (const auto& m : modules_)
    for (std::string& name : m->interface_names()) out.push_back(std::move(name));
  return out;
}

void System::prepare(const Points& x) {
  for (const auto& m : modules_) {
    PhaseTimers::Scope t(timers_, "collision detection: " + m->name());
    m->prepare(x);
    if (m->pattern_changed()) pattern_valid_ = false;
  }
}

double System::evaluate(const Points& x, VectorX* g, BlockSparseMatrix* H) {
  double total = 0;
  for (const auto& m : modules_) {
    PhaseTimers::Scope t(timers_, "force/stiffness: " + m->name());
    total += m->evaluate(x, g, H);
    if (!std::isfinite(total)) return total;
  }
  return total;
}

double System::energy(const Points& x) {
  return evaluate(x, nullptr, nullptr);
}

double System::gradient(const Points& x, VectorX& g) {
  g.setZero(3 * num_nodes_);
  return evaluate(x, &g, nullptr);
}

double System::hessian(const Points& x, VectorX& g) {
  if (!pattern_valid_) {
    PhaseTimers::Scope t(timers_, "force/stiffness: pattern");
    SparsityBuilder builder(num_nodes_);
    for (const auto& m : modules_) m->add_couplings(builder);
    hessian_ = BlockSparseMatrix(builder);
    for (const auto& m : modules_) m->bind(hessian_);
    pattern_valid_ = true;
  }
  hessian_.set_zero();
  g.setZero(3 * num_nodes_);
  return evaluate(x, &g, &hessian_);
}

}  // namespace depthfem

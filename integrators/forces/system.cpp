#include "integrators/forces/system.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "integrators/solvers/ranks.hpp"

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

bool System::evaluates(size_t m) const {
  return !ranks_ || shares_[m] == Share::kOwnPart || ranks_->rank() == 0;
}

void System::sum_over_ranks(VectorX& v) const {
  if (ranks_) ranks_->sum(v);
}

double System::max_step(const Points& x, const Points& dx) const {
  double alpha = std::numeric_limits<double>::infinity();
  for (size_t m = 0; m < modules_.size(); ++m) {
    if (!evaluates(m)) continue;
    PhaseTimers::Scope t(timers_, "force/stiffness: " + modules_[m]->name());
    alpha = std::min(alpha, modules_[m]->max_step(x, dx));
  }
  return ranks_ ? ranks_->min(alpha) : alpha;
}

double System::module_energy(const ForceModule& module, const Points& x) const {
  const auto found =
      std::ranges::find_if(modules_, [&](const auto& m) { return m.get() == &module; });
  if (found == modules_.end()) throw std::logic_error("System::module_energy: not a module of it");
  const size_t m = static_cast<size_t>(found - modules_.begin());
  const double energy = evaluates(m) ? module.evaluate(x, nullptr, nullptr) : 0.0;
  return ranks_ ? ranks_->sum(energy) : energy;
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
  for (size_t m = 0; m < modules_.size(); ++m) {
    if (!evaluates(m)) continue;
    PhaseTimers::Scope t(timers_, "force/stiffness: " + modules_[m]->name());
    total += modules_[m]->evaluate(x, g, H);
    if (!std::isfinite(total)) break;
  }
  if (!ranks_) return total;
  PhaseTimers::Scope t(timers_, "force/stiffness: sum over ranks");
  total = ranks_->sum(total);
  if (g && std::isfinite(total)) ranks_->sum(*g);
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
    rebuild_pattern();
  }
  hessian_.set_zero();
  g.setZero(3 * num_nodes_);
  return evaluate(x, &g, &hessian_);
}

void System::rebuild_pattern() {
  if (!fixed_rows_) {
    SparsityBuilder fixed(num_nodes_);
    for (const auto& m : modules_)
      if (m->fixed_couplings()) m->add_couplings(fixed);
    fixed_rows_ = fixed.rows();
    bound_ = false;
  }
  SparsityBuilder varying(num_nodes_);
  for (const auto& m : modules_)
    if (!m->fixed_couplings()) m->add_couplings(varying);
  BlockSparseMatrix next(SparsityBuilder::merged(*fixed_rows_, varying.rows()));
  const std::vector<Index> moved = bound_ ? hessian_.block_map(next) : std::vector<Index>{};
  hessian_ = std::move(next);
  for (const auto& m : modules_) {
    if (bound_ && m->fixed_couplings())
      m->rebind(hessian_, moved);
    else
      m->bind(hessian_);
  }
  bound_ = true;
  pattern_valid_ = true;
}

}  // namespace depthfem

#include "materials/material.hpp"

#include <stdexcept>

namespace depthfem {

namespace {
void require(bool ok, const char* what) {
  if (!ok) throw std::invalid_argument(what);
}

// A rest state is stable when the small-strain shear and bulk moduli are positive.
void require_stable(const LinearizedModuli& m, const char* model) {
  if (!(m.mu > 0) || !(m.bulk() > 0)) {
    throw std::invalid_argument(std::string(model) + ": parameters give shear modulus " +
                                std::to_string(m.mu) + " and bulk modulus " +
                                std::to_string(m.bulk()) + "; both must be positive");
  }
}

// "fiber_" + the base model's name for fiber-reinforced models, the model's kName otherwise.
template <class M>
std::string name_of() {
  if constexpr (requires { typename M::BaseMaterial; }) {
    return "fiber_" + name_of<typename M::BaseMaterial>();
  } else {
    return M::kName;
  }
}
}  // namespace

void NeoHookean::validate() const {
  require(mu > 0, "neo_hookean: mu must be > 0");
  require_stable(linearized_moduli(*this), "neo_hookean");
}

NeoHookean NeoHookean::from_youngs(double E, double nu) {
  require(E > 0, "neo_hookean: Young's modulus must be > 0");
  require(nu > -1 && nu < 0.5, "neo_hookean: Poisson's ratio must be in (-1, 0.5)");
  return {E / (2 * (1 + nu)), E * nu / ((1 + nu) * (1 - 2 * nu))};
}

MooneyRivlin MooneyRivlin::from_youngs(double E, double nu, double C2) {
  require(E > 0, "mooney_rivlin: Young's modulus must be > 0");
  require(nu > -1 && nu < 0.5, "mooney_rivlin: Poisson's ratio must be in (-1, 0.5)");
  const double mu = E / (2 * (1 + nu)), lambda = E * nu / ((1 + nu) * (1 - 2 * nu));
  require(C2 >= 0 && C2 <= mu / 2,
          "mooney_rivlin: C2 must be in [0, mu / 2] = [0, E / (4 (1 + nu))]");
  return {mu / 2 - C2, C2, lambda / 4 - C2};
}

void MooneyRivlin::validate() const {
  require(C1 >= 0 && C2 >= 0, "mooney_rivlin: C1 and C2 must be >= 0");
  require(C1 + C2 > 0, "mooney_rivlin: C1 + C2 must be > 0");
  require_stable(linearized_moduli(*this), "mooney_rivlin");
}

void Veronda::validate() const {
  require(alpha > 0, "veronda: alpha must be > 0");
  require(beta >= 0, "veronda: beta must be >= 0");
  require_stable(linearized_moduli(*this), "veronda");
}

void NearlyIncompressibleMooneyRivlin::validate() const {
  require(C1 >= 0 && C2 >= 0, "nearly_incompressible_mooney_rivlin: C1 and C2 must be >= 0");
  require(C1 + C2 > 0, "nearly_incompressible_mooney_rivlin: C1 + C2 must be > 0");
  require(kappa > 0, "nearly_incompressible_mooney_rivlin: kappa must be > 0");
}

std::string material_name(const MaterialModel& m) {
  return std::visit([](const auto& x) { return name_of<std::decay_t<decltype(x)>>(); }, m);
}

bool material_uses_fiber(const MaterialModel& m) {
  return std::visit([](const auto& x) { return std::decay_t<decltype(x)>::kUsesFiber; }, m);
}

void validate_material(const MaterialModel& m) {
  std::visit([](const auto& x) { x.validate(); }, m);
}

LinearizedModuli material_moduli(const MaterialModel& m) {
  return std::visit([](const auto& x) { return linearized_moduli(x); }, m);
}

}  // namespace depthfem

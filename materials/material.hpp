#pragma once
/// The closed set of material models an element group can use.

#include <string>
#include <variant>

#include "materials/fiber_reinforced.hpp"
#include "materials/hyperelastic.hpp"
#include "materials/mooney_rivlin.hpp"
#include "materials/nearly_incompressible_mooney_rivlin.hpp"
#include "materials/neo_hookean.hpp"
#include "materials/veronda.hpp"

namespace depthfem {

/// One of the supported models. Kernels dispatch on it once per element group (std::visit), so
/// each model gets its own fully inlined kernel and no per-element branch.
using MaterialModel =
    std::variant<NeoHookean, MooneyRivlin, Veronda, NearlyIncompressibleMooneyRivlin,
                 FiberReinforced<MooneyRivlin>, FiberReinforced<Veronda>>;

/// Short name of the model held ("neo_hookean", "mooney_rivlin", "fiber_mooney_rivlin", ...).
std::string material_name(const MaterialModel& m);

/// Whether the model needs a per-element fiber direction.
bool material_uses_fiber(const MaterialModel& m);

/// Validates the parameters of the model held (std::invalid_argument naming the parameter).
void validate_material(const MaterialModel& m);

/// Small-strain Lame parameters of the model held.
LinearizedModuli material_moduli(const MaterialModel& m);

}  // namespace depthfem

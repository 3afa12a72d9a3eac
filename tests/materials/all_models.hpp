#pragma once
/// One of every material model, with the parameters the integrator tests share.

#include <vector>

#include "materials/material.hpp"

namespace depthfem {

inline std::vector<MaterialModel> all_models() {
  return {NeoHookean::from_youngs(3e4, 0.4),
          MooneyRivlin{4e3, 1e3, 2e4},
          Veronda{1.5e3, 0.8, 2e4},
          NearlyIncompressibleMooneyRivlin{4e3, 1e3, 2e5},
          FiberReinforced<MooneyRivlin>{{4e3, 1e3, 2e4}, 2e3, 3.0},
          FiberReinforced<Veronda>{{1.5e3, 0.8, 2e4}, 2e3, 3.0}};
}

}  // namespace depthfem

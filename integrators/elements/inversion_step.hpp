#pragma once
/// The step length at which a tet turns flat: the smallest root of det(Ds + a dDs), a cubic in a.

#include "core/types.hpp"

namespace depthfem {

/// Smallest a in (0, limit] with det(Ds + a dDs) = 0, for edge matrices Ds (det Ds > 0) and
/// their change dDs along a step; +infinity when the tet stays positive up to `limit`. The
/// cubic det(Ds + a dDs) = det Ds + a tr(adj(Ds) dDs) + a^2 tr(adj(dDs) Ds) + a^3 det dDs is
/// split at its turning points into monotone pieces, and the first piece that reaches zero is
/// bisected to full precision. Returns 0 when det Ds <= 0.
double inversion_step(const Mat3& Ds, const Mat3& dDs, double limit);

}  // namespace depthfem

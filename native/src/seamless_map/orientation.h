// Exact orientation of triangles with double coordinates (parametric flips are combinatorial
// decisions: no epsilon).
#pragma once
#include "core/mesh.h"

namespace qgp {

// Sign of (b - a) x (c - a) evaluated exactly: +1 counter-clockwise, -1 clockwise, 0 collinear.
// A floating-point filter decides almost always; ties fall back to GMP rationals.
int orient2d_sign(const Vec2& a, const Vec2& b, const Vec2& c);

}  // namespace qgp

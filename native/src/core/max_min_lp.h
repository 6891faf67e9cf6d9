// Small exact linear programs of the untangle steps: maximize the smallest of a few linear
// functions over a bounded region of the plane or of a line.
#pragma once
#include <vector>

#include "core/mesh.h"

namespace qgp {

// argmax over d in the regular octagon of apothem `radius` around `centre` of min_i (c[i] + g[i]·d).
// The optimum lies at an octagon vertex, at a point of an octagon side where two terms are equal,
// or where three terms are equal: every such point is tried (O(m^3) for m terms). d = 0 when
// nothing beats it.
Vec2 maximize_worst_term(const std::vector<double>& c, const std::vector<Vec2>& g, const Vec2& centre, double radius);

// argmax over d in [-1, 1] of min_i (c[i] + g[i] d): an end or where two terms are equal.
double maximize_worst_term_1d(const std::vector<double>& c, const std::vector<double>& g);

}  // namespace qgp

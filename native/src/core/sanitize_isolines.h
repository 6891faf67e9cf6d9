// Exact sanitization that also keeps feature and boundary edges exact parameter isolines.
//
// sanitize_parametrization (core/parametrization.h) makes transitions exact but rounds every
// free value on its own, so an edge that is an isoline in the continuous map (both corners share
// u or v) can end up one grid unit off, e.g. next to a singular vertex whose position is implied by
// the rounded translations. Traced T-meshes need features as exact isolines (else their cell
// equations hold only up to that unit). This variant solves the transition equations and the
// isoline equations together, exactly, in integer coordinates (one real unknown per coordinate of
// each wedge and of each cut translation, unit pivots), then rounds the free unknowns to the grid.
#pragma once
#include <array>
#include <vector>

#include "core/parametrization.h"

namespace qgp {

struct IsolineConstraint {
  int halfedge = -1;  // the edge of this halfedge...
  int axis = 0;       // ...has constant u (0) or v (1) in the chart of face(halfedge)
};

// Constraints for the flagged edges (#E flags; boundary edges are added when include_boundary),
// each on the axis along which its two corners differ least in the continuous map.
std::vector<IsolineConstraint> isoline_constraints(const TriMesh& mesh, const Parametrization& param,
                                                   const std::vector<char>& edges, bool include_boundary);

// As sanitize_parametrization (the same options: fraction bits, snapping), and every isoline
// constraint holds exactly. unresolved_equations counts equations (transition or isoline) that
// could not be satisfied exactly on the grid (0 expected). Faces positive in the continuous map
// stay positively oriented (exact test): where rounding flips or collapses one (a triangle only a
// few grid units high), free unknowns move by a few grid units (reoriented_faces; faces where no
// such move exists are counted in non_positive_faces).
SanitizeResult sanitize_with_isolines(const TriMesh& mesh, const Parametrization& param,
                                      const std::vector<IsolineConstraint>& isolines, const SanitizeOptions& options);

}  // namespace qgp

// Unfolding an exact integer-grid map where the global solve left flipped or degenerate triangles:
// only free vertices move (inside the surface, off the cut graph and off feature edges, so they have
// one uv and no integer constraint), which keeps every transition, singularity, feature isoline and
// the total parametric area exactly as they were.
#pragma once
#include <vector>

#include "core/mesh.h"
#include "core/parametrization.h"
#include "core/progress.h"

namespace qgp {

struct MapUntangleStats {
  int flipped_before = 0, degenerate_before = 0;  // exact counts
  int flipped_after = 0, degenerate_after = 0;
  int moved_vertices = 0;
  double seconds = 0;
};

// Each free vertex of a flipped or degenerate triangle (and up to max_rings rings around them) moves,
// one at a time, to the fixed-point uv that maximizes the smallest area of its triangles (exact
// linear program within its mean uv edge length, then exact re-check); a move is kept only if its
// triangles have fewer non-positive areas, or as many and a larger smallest one, and every vertex of
// its triangles keeps its angle sum or gets one that its transitions allow (4 quarter turns where
// they add up to none, 3 or 5 where odd): no new cone appears (a ring wound twice has positive
// triangles but an angle sum of 4 pi).
// mesh: the component (connectivity built); feature_edges: #E (may be empty); param: 3#F corners.
MapUntangleStats untangle_map(const TriMesh& mesh, const std::vector<char>& feature_edges, ExactParametrization& param,
                              Progress& progress, int max_rings = 3);

}  // namespace qgp

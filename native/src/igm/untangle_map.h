// Unfolding an exact integer-grid map where the global solve left flipped or degenerate triangles.
// A vertex moves by the same fixed-point step in every chart it appears in (rotated by the
// transitions between them), so every transition stays exact; feature and boundary vertices slide
// along their integer isoline; singular, corner and other pinned vertices stay. Transitions,
// singularities, feature isolines and the total parametric area are kept exactly.
#pragma once
#include <vector>

#include "core/mesh.h"
#include "core/parametrization.h"
#include "core/progress.h"
#include "core/sanitize_isolines.h"

namespace qgp {

struct MapUntangleStats {
  int flipped_before = 0, degenerate_before = 0;  // exact counts
  int flipped_after = 0, degenerate_after = 0;
  int moved_vertices = 0;
  double seconds = 0;
};

// Each movable vertex of a flipped or degenerate triangle (and up to max_rings rings around them)
// moves, one at a time, to the fixed-point uv that maximizes the smallest area of its triangles
// (exact linear program within its mean uv edge length, in the plane or along its isoline, then an
// exact re-check); a move is kept only if its triangles have fewer non-positive areas, or as many and
// a larger smallest one, and every vertex of its triangles keeps its angle sum or gets one that its
// transitions allow (4 quarter turns where they add up to none, 3 or 5 where odd): no new cone
// appears (a ring wound twice has positive triangles but an angle sum of 4 pi).
// mesh: the component (connectivity built); pinned: #V flags of vertices that keep their uv (may be
// empty; interior vertices whose transitions add up to a rotation are always pinned); isolines:
// edges whose corners keep sharing the coordinate `axis` (a vertex on two isolines of different
// direction stays); param: 3#F corners.
struct MapUntangleOptions {
  int max_rings = 3;
  // For opening degenerate triangles of a flip-free map: a move may not flip more of the vertex's
  // triangles than before...
  bool never_flip = false;
  // ...nor, where given (#V quarter turns), leave an interior vertex whose triangles are all
  // positive with an angle sum other than its cone's (a ring wound twice).
  std::vector<int> cone_turns;
};
MapUntangleStats untangle_map(const TriMesh& mesh, const std::vector<char>& pinned,
                              const std::vector<IsolineConstraint>& isolines, ExactParametrization& param,
                              Progress& progress, const MapUntangleOptions& options = {});

}  // namespace qgp

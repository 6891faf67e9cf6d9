// Geometric clean-up of extracted quads: quads folded against the surface (where the layout's or
// the map's points crowd on a curved, thin part) are unfolded by moving free vertices only. The
// connectivity never changes.
#pragma once
#include <vector>

#include "core/mesh.h"
#include "core/progress.h"
#include "core/quad_mesh.h"

namespace qgp {

struct UntangleStats {
  int flipped_before = 0, flipped_after = 0;  // quads flipped against the surface normals
  int moved_vertices = 0;                     // vertices at a new position
  int accepted_rounds = 0, rounds = 0;
  double seconds = 0;
};

// Free vertices (not on the quad mesh's boundary, not on a feature or boundary edge or feature
// vertex of `surface`) around flipped quads move to the average of their edge neighbours,
// projected onto `surface`, a few times; the move is kept only where it lowers the number of
// flipped quads it touches, and the region widens (up to max_rings rings) while it does not.
// quads.vertex_face (#V, triangles of `surface`) is required and kept up to date.
// feature_edges: #E of `surface` (may be empty).
UntangleStats untangle_flipped_quads(QuadMesh& quads, const TriMesh& surface, const std::vector<char>& feature_edges,
                                     Progress& progress, int max_rings = 3);

}  // namespace qgp

// Geometric clean-up of extracted quads: quads folded against the surface (where the layout's or
// the map's points crowd on a curved, thin part) are unfolded by moving free vertices only. The
// connectivity never changes.
#pragma once
#include <vector>

#include "core/json.h"
#include "core/mesh.h"
#include "core/progress.h"
#include "core/quad_mesh.h"

namespace qgp {

struct UntangleStats {
  int flipped_before = 0, flipped_after = 0;      // quads flipped against the surface normals
  int collapsed_before = 0, collapsed_after = 0;  // quads with a collapsed edge (metrics/quad_metrics.h;
                                                  // reported by the collapse, collapse_quads.h)
  int moved_vertices = 0;                         // vertices at a new position
  int accepted_rounds = 0, rounds = 0;
  int collapsed_quads = 0;  // folded quads removed by collapse_folded_quads (collapse_quads.h)
  double seconds = 0;
};
QGP_JSON_FIELDS(UntangleStats, flipped_before, flipped_after, moved_vertices, seconds)

// Free vertices (not on the quad mesh's boundary, not on a feature or boundary edge or feature
// vertex of `surface`) of flipped quads and up to max_rings rings around them move one at a time:
// each goes, in its tangent plane and back onto `surface`, to where the worst of its quads' corner
// areas and diagonal cross products (along the surface normal, scaled) is largest, staying within
// 0.5 of its mean edge length of where it started (then 1 and 2 where quads stay flipped). A round
// is kept only if fewer quads are flipped.
// quads.vertex_face (#V, triangles of `surface`) is required and kept up to date.
// feature_edges: #E of `surface` (may be empty).
UntangleStats untangle_flipped_quads(QuadMesh& quads, const TriMesh& surface, const std::vector<char>& feature_edges,
                                     Progress& progress, int max_rings = 3);

class FeatureCurves;
class TriangleBvh;

// Throws Error(Internal) when the quads have no surface triangle per vertex or the feature edges
// do not match the surface.
void check_untangle_inputs(const QuadMesh& quads, const TriMesh& surface, const std::vector<char>& feature_edges);

// untangle_flipped_quads on a surface whose closest-point tree and curves are built (the collapse
// runs it many times), starting only from flipped quads with a vertex in `near` (#V; every flipped
// quad when empty). flipped: per quad, whether it is flipped, when known (else empty); on return,
// after.
// collapsed_edges: quads with a collapsed edge (two corners on one point: metrics/quad_metrics.h)
// are untangled the same way, after the flipped ones: a round is also kept when as many quads are
// flipped and fewer have such an edge, and no move makes one unless it unflips a quad (the final
// clean-up, collapse_quads.h; the untangles that choose between layouts leave them to it).
UntangleStats untangle_flipped_quads_near(QuadMesh& quads, const TriMesh& surface, const TriangleBvh& bvh,
                                          const FeatureCurves& curves, const std::vector<char>& near,
                                          std::vector<char>& flipped, Progress& progress, int max_rings,
                                          bool collapsed_edges);

}  // namespace qgp

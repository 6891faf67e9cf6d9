// Topological clean-up of extracted quads where the untangle (quad_extraction/untangle_quads.h)
// cannot unfold them: folded quads are collapsed, which changes the connectivity.
#pragma once
#include <vector>

#include "core/mesh.h"
#include "core/progress.h"
#include "core/quad_mesh.h"
#include "quad_extraction/untangle_quads.h"

namespace qgp {

// Topological clean-up where the untangle leaves quads folded: flipped against the surface (it
// folds within them: a dart-shaped quad on a thin part, a quad across a crease) or slivers (the
// shorter diagonal under 1/10 of the longer; along a crease, whether such a quad faces with the
// surface is round-off; or a quad with a collapsed edge, metrics/quad_metrics.h). First the
// untangle runs over every flipped quad and every quad with a collapsed edge, moving the corners of
// those apart (untangle_flipped_quads_near with collapsed_edges). Then each bad quad left, in turn,
// is collapsed along one of its diagonals: its two opposite corners merge into one vertex and it
// disappears; a corner left between two quads is dissolved, the two made one. Every other face
// stays a quad and the mesh stays a consistently oriented manifold of the same Euler
// characteristic. The untangle then runs again around the merged vertex. Of the two diagonals, the
// one leaving fewer flipped quads (then slivers) is kept, and only if it leaves fewer than before.
// A collapse adds up to three irregular vertices. Corners on feature or boundary curves stay where
// they are; two of them are never merged. Parts with more than 32 flipped quads (not a local fold)
// are not collapsed.
// Returns flipped_before / flipped_after and collapsed_before / collapsed_after (over the whole
// mesh), collapsed_quads and the moved_vertices of the first untangle.
// Some quad is a sliver (as collapse_folded_quads says).
bool has_slivers(const QuadMesh& quads);
UntangleStats collapse_folded_quads(QuadMesh& quads, const TriMesh& surface, const std::vector<char>& feature_edges,
                                    Progress& progress);

}  // namespace qgp

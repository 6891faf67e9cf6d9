// Quadric edge-collapse decimation in sorted passes (the working mesh's engine).
//
// Garland–Heckbert quadrics (area-weighted face planes) with subset placement: a collapse moves
// no vertex, it removes one endpoint of an edge and keeps the other where it was. Each pass sorts
// the collapsible edges by error and collapses them in that order; a vertex takes part in at most
// one collapse per pass (the survivor's quadric and faces changed, so its other errors are stale),
// and a pass tries no more edges than collapses are still needed, so the order stays close to a
// global greedy one. A pass is O(n log n) and touches flat arrays only; the passes shrink
// geometrically. The same input gives the same faces on every run (sorted with index tie-breaks,
// sequential).
//
// A collapse is made only when it keeps the surface a manifold of the same topology (the link
// condition: the edge's endpoints share exactly its two opposite vertices), turns no face normal by
// more than max_normal_deviation_deg, leaves no face degenerate, and either keeps every new face's
// aspect ratio (longest edge / its height) under max_aspect_ratio or makes the worst one better.
#pragma once
#include <Eigen/Core>
#include <vector>

#include "core/mesh.h"
#include "core/progress.h"

namespace qgp {

struct EdgeCollapseOptions {
  int max_faces = 0;                       // stop when at most this many faces are left
  double max_normal_deviation_deg = 60.0;  // per face, per collapse
  double max_aspect_ratio = 5.0;           // unless the collapse improves the worst face
};

using FaceMatrix = Eigen::Matrix<int, Eigen::Dynamic, 3, Eigen::RowMajor>;

// mesh: manifold and oriented (connectivity built); locked: #V, vertices that are never removed
// (every boundary vertex must be locked). Returns the remaining faces in input vertex indices, with
// their input orientation, in input face order; the budget may stay out of reach where the checks
// refuse every collapse left.
FaceMatrix collapse_edges(const TriMesh& mesh, const std::vector<char>& locked, const EdgeCollapseOptions& options,
                          Progress& progress);

}  // namespace qgp

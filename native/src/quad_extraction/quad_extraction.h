// Quad extraction from an integer-grid map (as QEx, Ebke, Bommes, Campen, Kobbelt 2013).
//
// The integer grid points of the map (on mesh vertices, inside edges, inside faces) become the
// quad vertices; every integer isoline segment between two of them, traced through triangles and
// across transitions, becomes a quad edge; faces are assembled by walking the edges (at each
// vertex turn to the next edge clockwise from the one we arrived on, which yields quads that are
// counter-clockwise in every chart and so on the surface). All combinatorial decisions use exact
// integer predicates on the fixed-point coordinates; nothing depends on a tolerance.
//
// Requirements on the map: exact transitions (90 deg * k rotation plus a translation that is a
// multiple of one()), mesh vertices that are singular (cone angle != 2 pi inside, != pi on the
// boundary) on integer points, boundary edges on integer isolines, no flipped or degenerate
// triangle. Violations are detected and reported (see QuadExtractionStats); with
// allow_defects = false (default) any defect throws Error(StageFailed) naming it.
#pragma once
#include <cstdint>
#include <string>

#include "core/json.h"
#include "core/mesh.h"
#include "core/parametrization.h"
#include "core/progress.h"
#include "core/quad_mesh.h"

namespace qgp {

struct QuadExtractionOptions {
  // false: throw Error(StageFailed) on the first kind of defect found (flipped triangles, isolines
  // leaving the surface, faces that are not quads, ...). true: skip what cannot be extracted and
  // report the counts in the stats (the quad mesh may then have holes).
  bool allow_defects = false;
  // Refuse maps whose parametric area (the quad count) exceeds this, and bound the work spent on
  // scanning grid lines accordingly, so that a wild map cannot exhaust time or memory.
  int64_t max_quads = 50000000;
};

struct QuadExtractionStats {
  int grid_points_on_vertices = 0;
  int grid_points_on_edges = 0;
  int grid_points_in_faces = 0;
  int64_t traced_segments = 0;   // isoline segments traced (each quad edge twice, once per
                                 // direction; boundary edges twice too)
  int64_t triangle_steps = 0;    // triangles visited while tracing
  int64_t expected_quads = 0;    // parametric area of the map (integer for an IGM)
  bool area_is_integral = true;  // false if the parametric area is not a whole number
  int singular_vertices = 0;     // quad vertices flagged singular
  int boundary_edges = 0;        // quad edges with a face on one side only
  // Defects (all 0 for a valid integer-grid map):
  int flipped_triangles = 0;      // negative parametric area
  int degenerate_triangles = 0;   // zero parametric area
  int failed_traces = 0;          // isolines that left the surface or did not meet a grid point
  int inconsistent_segments = 0;  // traced A->B but B's reverse trace does not return to A
  int non_quad_faces = 0;         // walked faces with a number of sides other than 4
  double seconds = 0;
};

struct QuadExtraction {
  QuadMesh quads;  // vertex_face and vertex_singular are filled
  QuadExtractionStats stats;
};

// mesh: working triangle mesh with connectivity; igm: exact integer-grid map of it (one chart per
// face, see core/parametrization.h). Throws Error(InvalidArgument) on mismatched sizes,
// Error(StageFailed) on defects unless options.allow_defects, Error(Cancelled) on cancel.
QuadExtraction extract_quads(const TriMesh& mesh, const ExactParametrization& igm, const QuadExtractionOptions& options,
                             Progress& progress);

// Appends `part` (e.g. one intake component's quads) to `into`, offsetting vertex indices and
// tagging its quads with `component` (per-vertex/per-quad source data is kept only if both have it).
void append_quad_mesh(QuadMesh& into, const QuadMesh& part, int component);

// Stats as JSON (for the `quad` / diagnostics part of the report).
void to_json(Json& j, const QuadExtractionStats& stats);

}  // namespace qgp

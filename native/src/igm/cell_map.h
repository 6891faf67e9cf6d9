// The paper's fallback integer-grid map (§7.1.1): the T-mesh's traces are inserted into the
// triangle mesh, and every cell is mapped onto its integer rectangle (w x h, the quantized lengths
// of its sides) by a Tutte embedding with mean-value weights. The boundary of each rectangle is
// convex and the weights are positive, so no triangle flips (Floater 2003); cells of zero width or
// height collapse to segments (their triangles are degenerate, never flipped). Cells are glued
// along a spanning tree of the cell graph: every seam carries a quarter-turn rotation plus an
// integer translation, and every T-mesh node (singularities included) sits on an integer point.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "core/json.h"
#include "core/mesh.h"
#include "core/parametrization.h"
#include "core/progress.h"
#include "tmesh/tmesh.h"

namespace qgp {

struct CellMapStats {
  int vertices = 0, faces = 0;        // of the refined mesh
  int inner_vertices = 0;             // placed by the Tutte embedding
  int degenerate_before_opening = 0;  // degenerate triangles of the Tutte embedding (made exact)
  int flipped_before_opening = 0;     // flipped by rounding onto the exact grid
  int opened_vertices = 0;            // moved by the opening step
  int wound_vertices = 0;             // all triangles positive, angle sum not the cone's (0 expected)
  int flipped_triangles = 0;          // signed uv area < 0 (floating point)
  int degenerate_triangles = 0;       // signed uv area == 0 (collapsed cells, chords along a side)
  int collapsed_cell_triangles = 0;   // of them, in cells of zero width or height
  double seconds = 0;
};

struct CellMap {
  TriMesh mesh;                  // the working mesh with the traces inserted (connectivity built)
  ExactParametrization param;    // the map, exact (fraction_bits of CellMapOptions)
  std::vector<int> source_face;  // #F: the working-mesh face each triangle lies in
  std::vector<int> face_cell;    // #F: the T-mesh cell each triangle lies in
  std::vector<Vec2> corner_uv;   // 3#F: integer-grid coordinates of the corners (param as doubles)
  CellMapStats stats;
};

struct CellMapOptions {
  int fraction_bits = 30;  // finer than the IGM's 20: fewer slivers flipped by rounding
  // Degenerate triangles (collapsed cells, chords) are opened where moving a vertex can do it
  // without flipping anything: igm/untangle_map, with singular and feature-corner nodes pinned and
  // feature and boundary traces kept on their integer isolines. The same step always runs where
  // rounding onto the exact grid flipped a sliver.
  bool open_degenerate = true;
  // #V of the working mesh: each vertex's cone angle in quarter turns (the cross field's
  // cone_quarter_turns), or empty. Inserted points are regular (4 inside, 2 on the boundary). With
  // them, the opening winds no ring twice and wound_vertices is counted.
  std::vector<int> cone_turns;
};

// mesh: the working mesh the T-mesh was traced on; tmesh: its T-mesh (four-sided cells, traces);
// x: #edges integer lengths with the cell equations holding (a valid quantization).
// Throws Error(StageFailed) naming the reason when the traces cannot be inserted as a partition of
// the surface into the T-mesh's cells (inconsistent traces, a cell bordering itself),
// Error(InvalidArgument) on mismatched sizes, Error(Cancelled) on cancel.
CellMap map_cells_to_rectangles(const TriMesh& mesh, const TMesh& tmesh, const std::vector<int64_t>& x,
                                Progress& progress, const CellMapOptions& options = {});

QGP_JSON_FIELDS(CellMapStats, vertices, faces, inner_vertices, flipped_triangles, degenerate_triangles,
                collapsed_cell_triangles, degenerate_before_opening, flipped_before_opening, opened_vertices,
                wound_vertices, seconds)

}  // namespace qgp

// Quads straight from the quantized T-mesh (the guaranteed path when no valid integer-grid map
// exists; cf. the paper's §7.1.1, which maps every cell onto its integer rectangle).
//
// Every cell with integer width w and height h (sums of x over opposite sides, equal when Ax = 0)
// becomes a w x h grid of quads. T-edges carry x(e) + 1 grid points, shared by the cells on both
// sides; zero-length edges merge their end points and zero-width cells glue their opposite sides,
// so the connectivity is a closed-up quad layout whenever the quantization is valid (no
// singularities collapse). Geometry: points on T-edges lie on the traced isolines at their
// parametric fraction; points inside a cell are found in the map: the cell is a rectangle there, and
// a monotone blend of its four sides' point spacings places the inner points, each reached by a
// straight walk from its bottom side point (a homeomorphism of the rectangle, so the grid lines do
// not cross). Points merged by a collapse are averaged and projected onto the surface, unless one
// of them is a node on a pinned vertex (a sharp tip): they then lie there.
#pragma once
#include <cstdint>
#include <vector>

#include "core/json.h"
#include "core/mesh.h"
#include "core/parametrization.h"
#include "core/progress.h"
#include "core/quad_mesh.h"
#include "tmesh/tmesh.h"

namespace qgp {

struct LayoutQuadsStats {
  int64_t quads = 0;        // == sum over cells of w * h
  int collapsed_cells = 0;  // cells of zero width or height
  int zero_edges = 0;       // T-edges of length 0
  int merged_points = 0;    // grid points identified with others by the collapses
  int walk_failures = 0;    // inner points placed by the Coons patch (no walk in the map)
  double seconds = 0;
};

struct LayoutQuads {
  QuadMesh quads;              // vertex_face (working-mesh triangle) and vertex_singular are filled
  std::vector<int> quad_cell;  // #Q: the T-mesh cell each quad belongs to
  LayoutQuadsStats stats;
};

// mesh: working triangle mesh (the T-mesh's traces refer to its faces); seamless: the exact map the
// T-mesh was traced in (its traces' uv are in its charts); tmesh: the T-mesh with
// four-sided cells; x: #edges integer lengths with Ax = 0 and x >= 0 (a valid quantization).
// with_positions false: the connectivity only (every position zero, vertex_face -1; much faster).
// pinned_vertices: #V flags of `mesh` (may be empty); points merged with a node on one lie on it.
// Throws Error(InvalidArgument) on mismatched sizes or a cell whose opposite sides differ,
// Error(Cancelled) on cancel.
LayoutQuads extract_layout_quads(const TriMesh& mesh, const ExactParametrization& seamless, const TMesh& tmesh,
                                 const std::vector<int64_t>& x, Progress& progress, bool with_positions = true,
                                 const std::vector<char>& pinned_vertices = {});

QGP_JSON_FIELDS(LayoutQuadsStats, quads, collapsed_cells, zero_edges, merged_points, walk_failures, seconds)

}  // namespace qgp

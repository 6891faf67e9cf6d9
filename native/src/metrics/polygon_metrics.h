// Validity and quality of any polygon mesh (our quads or another remesher's output) against the
// triangle surface it approximates; the side-by-side benchmark measures both tools with this.
#pragma once
#include "core/json.h"
#include "core/mesh.h"
#include "core/progress.h"
#include "intake/polygon_soup.h"
#include "metrics/quad_metrics.h"

namespace qgp {

struct PolygonMeshMetrics {
  int vertices = 0, faces = 0, quads = 0, non_quads = 0;
  int euler_characteristic = 0;            // V - E + F of the polygon mesh (used vertices only)
  int reference_euler_characteristic = 0;  // of the reference surface
  int non_manifold_edges = 0;              // edges with more than two faces
  QuadMetrics quad;                        // quality of the quads (hausdorff: over all faces)
  int sharp_edges = 0;                     // reference edges with dihedral angle > sharp_angle_deg
  double sharp_edge_coverage = 1;          // share of their length within `tolerance` of a mesh edge
  double sharp_edge_tolerance = 0;         // model units (1e-3 x bbox diagonal)
};

// mesh: the polygon mesh; reference: the input surface (connectivity built). sharp_angle_deg < 0
// skips the sharp-edge coverage.
PolygonMeshMetrics measure_polygon_mesh(const PolygonSoup& mesh, const TriMesh& reference, double sharp_angle_deg,
                                        Progress& progress);

void to_json(Json& j, const PolygonMeshMetrics& m);

}  // namespace qgp

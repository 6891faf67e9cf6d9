// Working resolution of a dense component (DESIGN: "very dense inputs are decimated to a working
// resolution derived from the target quad count"), and working triangles for a component whose own
// are needles (CAD tessellations): those are remeshed isotropically (intake/isotropic_remesh.h).
//
// Quadric edge collapses (intake/edge_collapse.h: quadric error, normal deviation <= 60deg, aspect
// ratio) down to a face budget. Vertices of feature and boundary edges are locked, so every
// feature and boundary edge stays an edge of the working mesh and every kept vertex keeps its
// input position. The result has the input's topology (checked: Euler characteristic, boundary
// loops, manifold and oriented); if not, the input is kept.
#pragma once
#include <vector>

#include "core/mesh.h"
#include "core/progress.h"

namespace qgp {

struct WorkingMesh {
  TriMesh mesh;                      // connectivity built
  std::vector<int> vertex_of_input;  // #V of mesh: its vertex index in the input mesh (remeshed: the
                                     // nearest input vertex, whose attributes it takes)
  std::vector<char> feature_edges;   // #E of mesh: the input's feature edges, carried over
  bool decimated = false;
  bool remeshed = false;
  bool replaces_input() const { return decimated || remeshed; }  // false: mesh is a copy of the input
};

// Face budget of the working mesh for about `target_quads` quads on this component: a fixed
// number of triangles per quad, never below kMinWorkingFaces.
int working_face_budget(double target_quads);
constexpr int kWorkingFacesPerQuad = 5;
constexpr int kMinWorkingFaces = 20000;
// Face count of an isotropic working mesh for about `target_quads` quads on a component with this
// share of the mesh's area: faces_per_quad triangles per quad, never below its share of
// kMinWorkingFaces (so that a many-part CAD model is not remeshed to kMinWorkingFaces per part).
int remesh_face_budget(double target_quads, double area_share, double faces_per_quad);
// Only components with more than this many times their budget are decimated (below, the gain in
// time is small and the input's own triangles are the better surface).
constexpr double kDecimateAboveBudget = 2;
// A component with feature edges whose needle triangles (smallest angle under kNeedleAngleDeg)
// cover more than this share of its area can be remeshed isotropically (pipeline/policy.h says
// when): the seamless map keeps every feature edge on an isoline, and through needles it may fold
// (featuretype with edges over 40 degrees: 15 flipped triangles, so no quads).
constexpr double kRemeshAboveNeedleShare = 0.1;
bool has_needles_across_features(const TriMesh& mesh, const std::vector<char>& feature_edges);
// Likewise a component with feature edges whose triangles with an edge longer than
// kCoarseEdgeInQuads quad edges (edge_length) cover more than that share of its area: the map is
// linear on each triangle, so where a few large triangles fan around one inner vertex the field
// can turn only there (block with edges over 40 degrees at 8 000 quads laid 29 of the 32 rim edges
// around its fan on one straight isoline, 1.21 % of the diagonal off, before the fan's quarter turns
// were spread around it in stop 65).
// Such a part is remeshed to kCoarseRemeshFacesPerQuad triangles per quad (floored as below):
// triangles about a quad's size are enough there, and cost less than the needles' count.
constexpr double kCoarseEdgeInQuads = 2;
constexpr double kCoarseRemeshFacesPerQuad = 2;
bool has_coarse_triangles_across_features(const TriMesh& mesh, const std::vector<char>& feature_edges,
                                          double edge_length);
// Triangles per quad of a component's isotropic remesh: kWorkingFacesPerQuad on needles across
// features, kCoarseRemeshFacesPerQuad otherwise.
double remesh_faces_per_quad(const TriMesh& mesh, const std::vector<char>& feature_edges);

// mesh: one connected, oriented, manifold component (connectivity built); feature_edges: #E.
// With remesh_faces > 0 (pipeline/policy.h decides when: has_needles_across_features), the component
// is remeshed to about remesh_faces equilateral triangles. Otherwise decimates to max_faces when mesh has more than
// kDecimateAboveBudget * max_faces faces, as far as the locks and the quality checks allow (the
// budget may stay out of reach); otherwise, or when no collapse is possible, returns a copy.
WorkingMesh make_working_mesh(const TriMesh& mesh, const std::vector<char>& feature_edges, int max_faces,
                              int remesh_faces, Progress& progress);

}  // namespace qgp

// Working resolution of a dense component (DESIGN: "very dense inputs are decimated to a working
// resolution derived from the target quad count").
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
  std::vector<int> vertex_of_input;  // #V of mesh: its vertex index in the input mesh
  std::vector<char> feature_edges;   // #E of mesh: the input's feature edges, carried over
  bool decimated = false;            // false: mesh is a copy of the input
};

// Face budget of the working mesh for about `target_quads` quads on this component: a fixed
// number of triangles per quad, never below kMinWorkingFaces.
int working_face_budget(double target_quads);
constexpr int kWorkingFacesPerQuad = 5;
constexpr int kMinWorkingFaces = 20000;
// Only components with more than this many times their budget are decimated (below, the gain in
// time is small and the input's own triangles are the better surface).
constexpr double kDecimateAboveBudget = 2;

// mesh: one connected, oriented, manifold component (connectivity built); feature_edges: #E.
// Decimates to max_faces when mesh has more than kDecimateAboveBudget * max_faces faces, as far
// as the locks and the quality checks allow (the budget may stay out of reach); otherwise, or
// when no collapse is possible, returns a copy.
WorkingMesh make_working_mesh(const TriMesh& mesh, const std::vector<char>& feature_edges, int max_faces,
                              Progress& progress);

}  // namespace qgp

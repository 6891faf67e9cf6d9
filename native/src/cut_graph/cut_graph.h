// Stage 1b: cut graph that opens the surface into one topological disc, and the combed field
// whose matchings are non-zero only on cut edges.
#pragma once
#include <cstdint>
#include <vector>

#include "core/mesh.h"
#include "core/progress.h"
#include "cross_field/cross_field.h"

namespace qgp {

struct CutGraph {
  std::vector<char> is_cut;          // #E: cut edges (boundary edges are never cuts)
  std::vector<int8_t> rotation;      // 3#F: combed transition rotation of every halfedge
                                     // (0 on non-cut edges), as Parametrization::rotation
  std::vector<Vec3> frame_u;         // #F: combed unit tangent, the +u axis of each face's chart
  std::vector<char> singular_vertex; // #V
  int num_cut_edges = 0;
};

CutGraph compute_cut_graph(const TriMesh& mesh, const CrossField& field, Progress& progress);

}  // namespace qgp

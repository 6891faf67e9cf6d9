// Stage 1b: cut graph that opens the surface into one topological disc, and the combed field
// whose matchings are non-zero only on cut edges.
//
// Construction (tree-cotree with every boundary loop contracted to one node): a primal tree T
// that joins the terminals (singularities and boundary loops) by shortest edge paths (multi-source
// Dijkstra regions joined by a minimum spanning tree of region-crossing edges, Mehlhorn's Steiner
// approximation), a dual spanning tree T* of the faces across the remaining interior edges
// (maximum spanning tree, so that the 2g left-over edges close short handle loops), cut
// candidates = interior edges not crossed by T*, then dangling branches are pruned until every
// branch ends at a singularity, at the boundary or on a handle loop. The faces glued along the
// non-cut edges form one topological disc. The field is combed along T* (rotation 0 across T*);
// pruned edges end at index-0 vertices and therefore have rotation 0 as well.
#pragma once
#include <cstdint>
#include <vector>

#include "core/mesh.h"
#include "core/progress.h"
#include "cross_field/cross_field.h"

namespace qgp {

struct CutGraph {
  std::vector<char> is_cut;           // #E: cut edges (boundary edges are never cuts)
  std::vector<int8_t> rotation;       // 3#F: combed transition rotation of every halfedge
                                      // (0 on non-cut edges), as Parametrization::rotation
  std::vector<Vec3> frame_u;          // #F: combed unit tangent, the +u axis of each face's chart
                                      // (+v = unit normal x frame_u); across non-cut edges the
                                      // charts agree up to the field's residual rotation
  std::vector<char> singular_vertex;  // #V: vertex_index != 0 (boundary corners included)
  std::vector<int8_t> frame_turns;    // #F: frame_u[f] = direction[f] turned by frame_turns[f]
                                      // quarter turns counter-clockwise about the face normal
  std::vector<int8_t> edge_sector;    // 3#F: CrossField::edge_sector in the combed charts: the
                                      // feature/boundary halfedge runs along R^q(+u) of frame_u
                                      // (q even: v constant along the edge; q odd: u constant);
                                      // q(opposite) = (q(h) + rotation[h] + 2) % 4; -1 elsewhere
  int num_cut_edges = 0;
};

// mesh: the component the field was computed on. Throws Error(InvalidArgument) if the field does
// not match the mesh, Error(StageFailed) if an internal invariant is violated.
CutGraph compute_cut_graph(const TriMesh& mesh, const CrossField& field, Progress& progress);

}  // namespace qgp

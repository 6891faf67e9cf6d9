// Feature-preserving isotropic remeshing (Botsch & Kobbelt 2004, "A remeshing approach to
// multiresolution modeling"): the working mesh of a part whose own triangles are too poor for the
// seamless map (pipeline/policy.h says when). CAD tessellations cover a flat face with a fan of
// needles that reach across it; the map may fold on them (featuretype with sharp edges: 15 flipped
// triangles after 14 repair rounds) or cut across the part.
//
// Each iteration splits edges longer than 4/3 of the target length at their midpoints, collapses
// edges shorter than 4/5 of it, flips edges toward valence 6 (4 on the boundary) and moves every
// free vertex toward the centroid of its neighbours in its tangent plane, projected back onto
// the input surface. Lines are kept: feature edges, boundary edges and creases (faces meeting at
// more than crease_angle_deg) are split along themselves, collapsed only along themselves where
// the chord stays within a twentieth of the target length of the removed vertex, and never
// flipped; their vertices do not move, and the ends and sharp turns of lines never go. A collapse
// keeps the link condition, so the topology stays; a change that would turn a face by more than
// 30 degrees or leave it degenerate is not made. A pass of Delaunay flips ends the remesh.
// Sequential, in sorted order: the same input gives the same mesh on every run.
#pragma once
#include <optional>
#include <vector>

#include "core/mesh.h"

namespace qgp {

struct IsotropicRemeshOptions {
  double edge_length = 0;        // target edge length (> 0)
  int iterations = 5;            // split / collapse / flip / relax rounds
  double crease_angle_deg = 30;  // edges whose faces meet at more than this are kept as lines
};

struct RemeshedSurface {
  TriMesh mesh;                           // connectivity built
  std::vector<char> feature_edges;        // #E of mesh: the pieces of the input's feature edges
  std::vector<int> nearest_input_vertex;  // #V of mesh: the input vertex closest to each vertex
};

// mesh: manifold and oriented (connectivity built); feature_edges: #E of mesh. nullopt when the
// result would not have the input's Euler characteristic and boundary loops (never expected).
std::optional<RemeshedSurface> remesh_isotropic(const TriMesh& mesh, const std::vector<char>& feature_edges,
                                                const IsotropicRemeshOptions& options);

// The share of the surface's area in needle triangles: those whose smallest angle is below
// kNeedleAngleDeg (0 for a mesh without area).
constexpr double kNeedleAngleDeg = 5;
double needle_area_share(const TriMesh& mesh);
// Share of the mesh's area in triangles with an edge longer than edge_length.
double coarse_area_share(const TriMesh& mesh, double edge_length);

}  // namespace qgp

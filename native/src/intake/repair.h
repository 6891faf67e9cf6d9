// The individual validation and repair steps of intake, in the order run_intake applies them.
// Each works on a triangle soup and returns how many elements it changed.
#pragma once
#include <array>
#include <vector>

#include "intake/polygon_soup.h"

namespace qgp {

struct TriangleSoup {
  std::vector<Vec3> positions;
  std::vector<std::array<int, 3>> triangles;
  std::vector<int> input_vertex;  // per position: input soup index
  std::vector<int> input_face;    // per triangle: input polygon index
};

// Throws Error(InvalidMesh) for: no faces, non-finite coordinates, indices out of range,
// faces with fewer than three or repeated vertices.
void validate_soup(const PolygonSoup& soup);

// Triangulates polygons (ear clipping in their best-fit plane). Returns #polygons split.
int triangulate_polygons(const PolygonSoup& soup, TriangleSoup& out);

// Removes vertices no triangle references. Returns #removed.
int remove_unreferenced_vertices(TriangleSoup& soup);

// Removes triangles with the same vertex set as an earlier one. Returns #removed.
int remove_duplicate_faces(TriangleSoup& soup);

// Edges shared by more than two triangles. Returns their vertex pairs.
std::vector<std::array<int, 2>> find_nonmanifold_edges(const TriangleSoup& soup);

// Face components connected through shared edges (any number of faces per edge).
std::vector<int> edge_connected_components(const TriangleSoup& soup, int* num_components);

// Orients every orientable component consistently (flipping the minority of its faces).
// Returns #faces flipped; components that cannot be oriented are listed in *non_orientable
// (component ids of edge_connected_components).
int orient_consistently(TriangleSoup& soup, std::vector<int>* non_orientable);

// Gives every fan of faces around a non-manifold vertex its own vertex. Returns #vertices split.
int split_nonmanifold_vertices(TriangleSoup& soup);

// Removes zero-area faces by collapsing their shortest edge (needles) or flipping their longest
// edge (caps), keeping the mesh manifold. Returns #zero-area faces found; *remaining gets the
// number that could not be repaired.
int repair_zero_area_faces(TriangleSoup& soup, double zero_area, double flatness, int* remaining);

// Keeps only the triangles whose flag is set (then drops unreferenced vertices silently).
void keep_triangles(TriangleSoup& soup, const std::vector<char>& keep);

}  // namespace qgp

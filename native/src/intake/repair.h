// The individual validation and repair steps of intake, in the order run_intake applies them.
// Each works on a triangle soup and returns how many elements it changed; where given, `where`
// receives the first few input vertices at which it changed something.
#pragma once
#include <algorithm>
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

// Up to kMaxRepairLocations input vertex indices where a repair happened (first ones found).
constexpr int kMaxRepairLocations = 10;
struct RepairLocations {
  std::vector<int> input_vertices;
  void add(int input_vertex) {
    if (static_cast<int>(input_vertices.size()) < kMaxRepairLocations &&
        std::find(input_vertices.begin(), input_vertices.end(), input_vertex) == input_vertices.end())
      input_vertices.push_back(input_vertex);
  }
};

// Throws Error(InvalidMesh) for: no faces, non-finite coordinates, indices out of range,
// faces with fewer than three or repeated vertices.
void validate_soup(const PolygonSoup& soup);

// Triangulates polygons (ear clipping in their best-fit plane). Returns #polygons split.
int triangulate_polygons(const PolygonSoup& soup, TriangleSoup& out, RepairLocations* where = nullptr);

// Puts the triangles in a canonical order: each starts at its lowest vertex (orientation kept) and
// they are sorted by their vertices, then by input face. Every later step depends on the order of
// the triangles, and the same surface comes in other orders (Blender gives a new UV sphere's
// polygons and loops in another order each run; exporters differ): with this, the same vertices
// and triangles give the same quads whatever their order. run_intake applies it after welding
// (the repairs then see one order) and again after the repairs.
void sort_triangles_canonically(TriangleSoup& soup);

// Removes vertices no triangle references. Returns #removed.
int remove_unreferenced_vertices(TriangleSoup& soup, RepairLocations* where = nullptr);

// Removes triangles with the same vertex set as an earlier one. Returns #removed.
int remove_duplicate_faces(TriangleSoup& soup, RepairLocations* where = nullptr);

// Merges boundary vertices (vertices of edges with one triangle) closer than tolerance * the
// bounding-box diagonal (exact duplicates always, when tolerance > 0) where the merge zips
// boundary edges together (a group whose merge joins no two boundary edges, e.g. two boundary
// loops touching at a point, is left alone); other vertices are left alone, so a closed mesh is
// unchanged. Each merged group keeps its lowest-indexed vertex.
// Returns #vertices merged away; *input_weld_target (optional, per input vertex) gets, for each
// merged vertex, the input vertex it was merged into; *where gets the input vertices kept.
int weld_boundary_vertices(TriangleSoup& soup, double tolerance, std::vector<int>* input_weld_target,
                           RepairLocations* where);

// Removes triangles with a repeated vertex (two corners welded together). Returns #removed.
int remove_collapsed_triangles(TriangleSoup& soup, RepairLocations* where);

// Edges shared by more than two triangles. Returns their vertex pairs.
std::vector<std::array<int, 2>> find_nonmanifold_edges(const TriangleSoup& soup);

// Cuts every edge shared by more than two triangles into sheets: the triangles around the edge
// are paired in angular order (preferring pairs oriented consistently around a solid wedge; of
// two triangles at the same angle, the one ending a wedge goes first), and each pair (or left-over
// triangle) gets its own copies of the edge's vertices, so that the cut edges become boundaries.
// Where sheets still share an edge afterwards (they meet again around its vertices), the extra
// triangles get copies of their own. Returns #edges cut; *where gets an input vertex of each.
int cut_nonmanifold_edges(TriangleSoup& soup, RepairLocations* where);

// Face components connected through shared edges (any number of faces per edge).
std::vector<int> edge_connected_components(const TriangleSoup& soup, int* num_components);

// Orients every orientable component consistently (flipping the minority of its faces).
// Returns #faces flipped; components that cannot be oriented are listed in *non_orientable
// (component ids of edge_connected_components).
int orient_consistently(TriangleSoup& soup, std::vector<int>* non_orientable, RepairLocations* where = nullptr);

// Gives every fan of faces around a non-manifold vertex its own vertex. Returns #vertices split.
int split_nonmanifold_vertices(TriangleSoup& soup, RepairLocations* where = nullptr);

// Removes zero-area faces by collapsing their shortest edge (needles) or flipping their longest
// edge (caps), keeping the mesh manifold. Returns #zero-area faces found; *remaining gets the
// number that could not be repaired.
int repair_zero_area_faces(TriangleSoup& soup, double zero_area, double flatness, int* remaining,
                           RepairLocations* where = nullptr);

// Keeps only the triangles whose flag is set (then drops unreferenced vertices silently).
void keep_triangles(TriangleSoup& soup, const std::vector<char>& keep);

}  // namespace qgp

// Triangle mesh with implicit halfedges, the working representation of every stage.
//
// Halfedge h = 3*f + k belongs to face f and runs from F(f,k) to F(f,(k+1)%3).
// Faces are counter-clockwise seen from outside; the mesh is edge-manifold and consistently
// oriented once build_connectivity() has succeeded.
#pragma once
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <utility>
#include <vector>

namespace qgp {

using Vec2 = Eigen::Vector2d;
using Vec3 = Eigen::Vector3d;

struct TriMesh {
  Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> V;  // #V x 3 positions
  Eigen::Matrix<int, Eigen::Dynamic, 3, Eigen::RowMajor> F;     // #F x 3 vertex indices

  // Filled by build_connectivity():
  std::vector<int> opposite;         // 3#F: opposite halfedge, -1 on a boundary
  std::vector<int> edge_of;          // 3#F: undirected edge index of each halfedge
  std::vector<int> edge_halfedge;    // #E: one halfedge of each edge (the lower index)
  std::vector<int> vertex_halfedge;  // #V: an outgoing halfedge; on the boundary the one with
                                     //     no opposite, so that CCW rotation visits every face

  int num_vertices() const { return static_cast<int>(V.rows()); }
  int num_faces() const { return static_cast<int>(F.rows()); }
  int num_edges() const { return static_cast<int>(edge_halfedge.size()); }
  int num_halfedges() const { return 3 * num_faces(); }

  static int face(int h) { return h / 3; }
  static int corner(int h) { return h % 3; }
  static int next(int h) { return h - h % 3 + (h % 3 + 1) % 3; }
  static int prev(int h) { return h - h % 3 + (h % 3 + 2) % 3; }
  int from(int h) const { return F(h / 3, h % 3); }
  int to(int h) const { return F(h / 3, (h % 3 + 1) % 3); }
  bool is_boundary_edge(int e) const { return opposite[edge_halfedge[e]] < 0; }
  // Next outgoing halfedge counter-clockwise around from(h); -1 past a boundary.
  int rotate_ccw(int h) const { return opposite[prev(h)]; }
  // Next outgoing halfedge clockwise around from(h); -1 past a boundary.
  int rotate_cw(int h) const {
    int o = opposite[h];
    return o < 0 ? -1 : next(o);
  }

  Vec3 position(int v) const { return V.row(v).transpose(); }
  Vec3 edge_vector(int h) const { return position(to(h)) - position(from(h)); }
  Vec3 face_normal_unnormalized(int f) const;  // cross product of two edges (2 x area)
  double bounding_box_diagonal() const;
};

// Fills opposite/edge_of/edge_halfedge/vertex_halfedge. Throws Error(InvalidMesh) when an edge
// has more than two faces or two faces traverse it in the same direction.
void build_connectivity(TriMesh& mesh);

// Sorts (undirected edge key, id) pairs exactly as std::sort would, in linear time: a counting sort
// on the key's lower vertex (its high 32 bits, < num_vertices), then each vertex's few pairs.
void sort_by_edge_key(std::vector<std::pair<uint64_t, int>>& keyed, int num_vertices);

// Outgoing halfedges of vertex v in counter-clockwise order (starting at vertex_halfedge[v]).
std::vector<int> outgoing_halfedges(const TriMesh& mesh, int v);

bool is_boundary_vertex(const TriMesh& mesh, int v);

// Interior angle of face(h) at from(h) (radians).
double corner_angle(const TriMesh& mesh, int h);

// Sum of the corner angles of its triangles at each vertex (radians; 2 pi where the surface is flat
// inside). #V.
std::vector<double> vertex_angle_sums(const TriMesh& mesh);

// Number of boundary loops (cycles of boundary halfedges).
int count_boundary_loops(const TriMesh& mesh);

}  // namespace qgp

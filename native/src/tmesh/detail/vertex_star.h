// Parametric structure around each mesh vertex (internal to the tracer): the ring of corners
// with their charts, the total parametric angle in quarter turns, the separatrix directions
// (sectors), how feature/boundary edges ("walls") split them, and the local direction frame
// used for T-mesh node incidences.
#pragma once
#include <climits>
#include <string>
#include <vector>

#include "core/mesh.h"
#include "tmesh/detail/exact.h"

namespace qgp::tmesh_detail {

struct StarCorner {
  int face = -1;
  int h_out = -1;       // halfedge from the vertex in `face`
  int acc = 0;          // direction d in ring[0]'s chart is d + acc in this face's chart
  int rot_to_next = 0;  // quarter turns from this face's chart to the next corner's (CCW)
  int orient = 0;       // sign of the face's parametric orientation
  P2 e1{}, e2{};        // edge vectors from the vertex (first / second edge CCW), this chart
};

// A cardinal direction leaving the vertex inside a corner's half-open angle [e1, e2).
struct StarDirection {
  int corner = -1;
  int dir = 0;              // in the corner face's chart
  bool along_edge = false;  // exactly along e1 (the corner's h_out edge)
  int number = 0;           // direction in the vertex frame (see VertexStar::sector_frame)
};

struct VertexStar {
  std::vector<StarCorner> ring;  // counter-clockwise; on the boundary from the boundary halfedge
  bool boundary = false;
  bool on_wall = false;   // incident to a feature or boundary edge
  bool positive = true;   // every corner of the ring has positive parametric orientation
  int holonomy = 0;       // sum of transition rotations around an interior vertex (mod 4)
  int quarter_turns = 0;  // total parametric angle (sectors rounded to walls on features)
  int index = 0;          // 4 - quarter_turns inside, 2 - quarter_turns on the boundary
  // Frame of node incidences: false = chart directions 0..3 of ring[0]'s face (regular vertex);
  // true = sector numbers counter-clockwise (period > 0: modulo period; period 0: linear, on the
  // boundary, from the first boundary edge).
  bool sector_frame = false;
  int period = 4;
  bool corner = false;                    // a T-mesh node from the start (singular, feature/boundary corner)
  bool straight_wall = false;             // on a wall, but the wall passes straight (not a corner)
  bool virtual_corner = false;            // straight wall vertex made a corner (closed wall without corners)
  bool seed = false;                      // regular vertex chosen as start where nothing else emits
  std::vector<StarDirection> directions;  // every cardinal direction in the corners, CCW
  std::vector<int> emissions;             // indices into directions: separatrix starts
  std::vector<int> wall_number;           // per corner: frame number of e1 if it is a wall, else INT_MIN
  std::vector<int> wall_dir;              // per corner: nearest cardinal of e1 (corner chart) if a wall
  int end_wall_number = INT_MIN;          // boundary: frame number of the last corner's e2
  std::string problem;                    // why the star cannot be used for tracing (empty: fine)

  bool regular() const { return !boundary && !on_wall && quarter_turns == 4 && holonomy == 0 && problem.empty(); }
  int corner_of_face(int face) const {
    for (size_t i = 0; i < ring.size(); ++i)
      if (ring[i].face == face) return static_cast<int>(i);
    return -1;
  }
  // Frame number of cardinal direction `dir` (chart of ring[corner]) leaving the vertex, or
  // INT_MIN if it is not a direction of the star.
  int frame_number(int corner, int dir) const;
};

// uv2: doubled fixed-point corner coordinates (3#F); rotation: per halfedge; wall_edge: #E.
VertexStar analyse_vertex(const TriMesh& mesh, const std::vector<P2>& uv2, const std::vector<int8_t>& rotation,
                          const std::vector<char>& wall_edge, int v);

// Turns a straight wall vertex into a virtual corner (a node emitting one separatrix per side).
void make_virtual_corner(VertexStar& star);
// Turns a regular vertex into a seed (a node emitting its four directions).
void make_seed(VertexStar& star);

}  // namespace qgp::tmesh_detail

// The T-mesh (paper §5): the motorcycle graph of a seamless parametrization, a partition of the
// surface into four-sided cells whose edges are parameter isolines. Quantization (§6) works on
// its topology only; the integer-grid map (§7) also uses the traces on the surface.
// Built by trace_tmesh (tmesh/trace_tmesh.h).
#pragma once
#include <array>
#include <cstdint>
#include <vector>

#include "core/surface_point.h"

namespace qgp {

// Directions in a node's local frame. At a regular node (including T-junctions, crossings and
// feature/boundary nodes) they are parameter directions in the node's chart:
// 0 = +u, 1 = +v, 2 = -u, 3 = -v (counter-clockwise). At a singular node of valence k they are
// sector numbers 0..k-1, counter-clockwise; neighbouring sectors are a quarter turn apart.
// The node's chart is the chart of node.point.face. A singular node on the boundary (a boundary
// corner whose interior angle is q quarter turns, q != 2) numbers its directions 0..q linearly,
// from the boundary edge at which the surface starts counter-clockwise; a singular node on an
// interior feature curve (total angle q != 4 quarter turns) numbers them 0..q-1 modulo q.
struct TMeshIncidence {
  int edge = -1;
  int direction = 0;     // in the node's frame
  bool outgoing = true;  // true: the edge's positive direction points away from this node
};

struct TMeshNode {
  // Singularity: interior singular vertex. TJunction: a separatrix ends on an edge (or on a
  // feature/boundary curve: on_feature). Crossing: two isolines pass through (four edges).
  // FeatureCorner: vertex on an interior feature curve where the curve turns, ends, branches or
  // is singular, or a virtual corner on a closed curve without any (paper §9.1).
  // BoundaryNode: the same on the boundary (boundary corners; virtual boundary nodes).
  // Seed: a regular vertex chosen as start because nothing else emits separatrices (torus).
  enum class Kind : uint8_t { Singularity, TJunction, Crossing, FeatureCorner, BoundaryNode, Seed };
  Kind kind = Kind::TJunction;
  int index = 0;            // singularity index in quarter turns (4 - valence: +1 at a cube
                            // corner); on the boundary 2 - q (q = interior angle in quarter
                            // turns: +1 at a convex corner); 0 if regular
  bool on_feature = false;  // lies on a feature curve or on the boundary
  int mesh_vertex = -1;     // the mesh vertex it sits on, or -1
  SurfacePoint point;
  std::vector<TMeshIncidence> incidences;  // counter-clockwise around the node
  bool singular() const { return index != 0; }
};

struct TMeshEdge {
  int from = -1, to = -1;  // the edge runs from -> to in the positive parameter direction
  int axis = 0;            // 0: the parameter varying along the edge is u (a v-isoline), 1: v
  // `axis` refers to the chart of trace[0].face, in which from -> to is the positive direction,
  // except for an edge that crosses a half-turn transition and starts in the negative direction
  // from either end: it keeps from = where it starts negatively in trace[0]'s chart and runs
  // positively in the chart of its last piece. Use the incidences' local directions (and the
  // trace's chart coordinates) for anything local.
  double length = 0;                 // continuous parametric length (ideal length at scale 1), >= 0
  bool on_feature = false;           // part of a feature curve or of the boundary
  std::array<int, 2> cells{-1, -1};  // cell on the left / right of the edge (-1: boundary)
  // Path on the surface from `from` to `to`. Consecutive points either lie in the same face
  // (a straight piece inside that triangle, both given in that face's chart) or are the same
  // surface point given in two adjacent faces (a change of face).
  std::vector<SurfacePoint> trace;
};

struct TMeshCell {
  // sides[s]: T-edges along side s in order; sides 0/2 and 1/3 are opposite, side s runs along
  // axis s % 2. The cell equations (4) are  sum(x over sides[0]) = sum(x over sides[2])  and
  // sum(x over sides[1]) = sum(x over sides[3]).
  // Sides are listed counter-clockwise (the cell lies to their left) starting at a corner; when
  // that corner is a regular node, side 0 runs along u in its chart.
  std::array<std::vector<int>, 4> sides;
  // false: the face of the graph does not have exactly four corners (an invalid T-mesh); then
  // sides[0] holds its whole boundary counter-clockwise and the other sides are empty.
  bool four_sided = true;
};

// Figures of the tracing run (for reports and tests of degenerate configurations).
struct TMeshStats {
  double trace_seconds = 0;
  int motorcycles = 0;         // separatrices traced
  long long steps = 0;         // face-to-face advances
  int head_on = 0;             // separatrix pairs meeting head-on (merged into one edge)
  int crossings = 0;           // simultaneous perpendicular crossings
  int vertex_passes = 0;       // separatrices passing exactly through a mesh vertex
  int edge_runs = 0;           // separatrix pieces running exactly along a mesh edge
  int cut_crossings = 0;       // transitions applied while crossing cut edges
  int cut_vertex_passes = 0;   // passes through a vertex whose one-ring is cut
  int virtual_corners = 0;     // closed feature/boundary curves that got a virtual node
  int seeds = 0;               // regular seed vertices (components without singularities)
  int merged_nodes = 0;        // straight degree-2 nodes removed (head-on meeting points)
  int walls_not_isolines = 0;  // feature/boundary mesh edges that are no exact isolines of the
                               // input map (then cell equations along them hold only roughly;
                               // sanitize_with_isolines avoids this)
};

struct TMesh {
  std::vector<TMeshNode> nodes;
  std::vector<TMeshEdge> edges;
  std::vector<TMeshCell> cells;
  TMeshStats stats;

  int euler_characteristic() const {
    return static_cast<int>(nodes.size()) - static_cast<int>(edges.size()) + static_cast<int>(cells.size());
  }
};

}  // namespace qgp

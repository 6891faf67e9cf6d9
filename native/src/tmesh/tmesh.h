// The T-mesh (paper §5): the motorcycle graph of a seamless parametrization, a partition of the
// surface into four-sided cells whose edges are parameter isolines. Quantization (§6) works on
// its topology only; the integer-grid map (§7) also uses the traces on the surface.
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
struct TMeshIncidence {
  int edge = -1;
  int direction = 0;   // in the node's frame
  bool outgoing = true;  // true: the edge's positive direction points away from this node
};

struct TMeshNode {
  enum class Kind : uint8_t { Singularity, TJunction, Crossing, FeatureCorner, BoundaryNode, Seed };
  Kind kind = Kind::TJunction;
  int index = 0;            // singularity index in quarter turns (4 - valence: +1 at a cube
                            // corner); 0 if regular
  bool on_feature = false;  // lies on a feature curve or on the boundary
  int mesh_vertex = -1;     // the mesh vertex it sits on, or -1
  SurfacePoint point;
  std::vector<TMeshIncidence> incidences;  // counter-clockwise around the node
  bool singular() const { return index != 0; }
};

struct TMeshEdge {
  int from = -1, to = -1;  // the edge runs from -> to in the positive parameter direction
  int axis = 0;            // 0: the parameter varying along the edge is u (a v-isoline), 1: v
  double length = 0;       // continuous parametric length (ideal length at scale 1), >= 0
  bool on_feature = false; // part of a feature curve or of the boundary
  std::array<int, 2> cells{-1, -1};  // cell on the left / right of the edge (-1: boundary)
  std::vector<SurfacePoint> trace;   // polyline on the surface from `from` to `to`; every
                                     // consecutive pair lies in one triangle
};

struct TMeshCell {
  // sides[s]: T-edges along side s in order; sides 0/2 and 1/3 are opposite, side s runs along
  // axis s % 2. The cell equations (4) are  sum(x over sides[0]) = sum(x over sides[2])  and
  // sum(x over sides[1]) = sum(x over sides[3]).
  std::array<std::vector<int>, 4> sides;
};

struct TMesh {
  std::vector<TMeshNode> nodes;
  std::vector<TMeshEdge> edges;
  std::vector<TMeshCell> cells;

  int euler_characteristic() const {
    return static_cast<int>(nodes.size()) - static_cast<int>(edges.size()) + static_cast<int>(cells.size());
  }
};

}  // namespace qgp

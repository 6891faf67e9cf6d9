// Polygons with a 2D coordinate per corner (an atlas or a grid map), and the sides across each other.
#pragma once
#include <array>
#include <vector>

#include "intake/polygon_soup.h"

namespace qgp {

using CornerUv = std::array<double, 2>;

// soup's faces, with per corner c (an entry of soup.face_vertices) its coordinate, its face and the
// next corner of that face.
struct CornerFaces {
  const PolygonSoup& soup;
  std::vector<CornerUv> uv;
  std::vector<int> corner_face;
  CornerFaces(const PolygonSoup& faces, std::vector<CornerUv> corner_uv);
  int next(int c) const {
    const int f = corner_face[c];
    return c + 1 < soup.face_start[f + 1] ? c + 1 : soup.face_start[f];
  }
};

// Per corner c, the corner whose side (from it to the next corner) is c's side the other way round, or -1
// (a boundary side, or an edge with more than two sides or two sides the same way). Edges are matched by
// their vertex indices.
std::vector<int> sides_across(const CornerFaces& faces);

}  // namespace qgp

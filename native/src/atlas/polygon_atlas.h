// A texture atlas for any polygons carrying an integer-grid map (per-corner grid coordinates whose
// transitions across cuts are quarter turns plus whole grid units, as the integer-grid map of
// Integer-Grid UVs): the source's own triangles, or the refined copy where only that has a flip-free map.
//
// Charts grow face by face across sides whose two corners have the same grid coordinates on both sides,
// as long as the new face overlaps no face of the chart in the grid (so every chart is injective; faces
// that are flipped or degenerate in the map stay charts of their own). Each chart's bounding box, from
// the grid point below its lowest corner to the grid point above its highest, is packed as in
// atlas/packing.h with K texels per grid unit. So the texel grid is the integer grid scaled by K in every
// chart, and every seam, wherever it runs, maps texels onto texels: its transition is the map's (a
// quarter turn plus whole grid units) scaled by K, plus the two charts' whole-texel offsets. Seam
// stitching (atlas/stitch_seams.h) applies.
#pragma once
#include <vector>

#include "atlas/corner_faces.h"
#include "atlas/packing.h"
#include "core/json.h"

namespace qgp {

struct PolygonAtlas : AtlasFigures {  // seam edges: between charts, or cuts inside one
  std::vector<CornerUv> corner_uv;    // per corner (entry of face_vertices), in [0,1]^2
  std::vector<int> face_chart;        // #faces
};

// faces: polygons; grid_uv: per corner, its integer-grid coordinate (1 unit = one quad: K texels).
// Throws Error(InvalidArgument) on mismatched sizes, coordinates that are not finite, no faces, or charts
// that do not fit the texture (naming the sizes).
PolygonAtlas build_polygon_atlas(const PolygonSoup& faces, const std::vector<CornerUv>& grid_uv,
                                 const AtlasOptions& options);

}  // namespace qgp

// Seam stitching for an image in a texture atlas whose seams map texels onto texels (atlas/quad_atlas.h),
// after Ray et al., "Invisible Seams" (EGSR 2010): every gutter texel beside a seam takes the texel the
// surface continues into across the seam, so bilinear sampling on either side of the seam reads the same
// texels and gives the same colour.
//
// Only the faces and their per-corner atlas coordinates are needed: the transition across each seam (a
// rotation by k * 90 degrees plus a whole number of texels) is read from the coordinates of the edge's two
// endpoints on its two sides. Texels covered by no face are filled as follows:
//   1. each is given to the nearest covered texel (so gutters between charts are split between them);
//   2. beside a seam of that texel's face (or of a face covering a texel next to it), the texel takes the
//      value across the seam where that is covered by the chart on the other side, or (at chart corners,
//      where the surface turns through a third chart) a gutter texel of that chart stitched in this step;
//   3. every other uncovered texel takes the value of its nearest covered texel.
// A gutter of g texels between charts thus holds g / 2 texels of each side's continuation, which keeps
// mip levels seam-free where the atlas aligns them (AtlasOptions::mip_levels). Covered texels never change.
#pragma once
#include <array>
#include <vector>

#include "core/json.h"
#include "intake/polygon_soup.h"

namespace qgp {

// An image in atlas space: texel (x, y) spans [x/W, (x+1)/W] x [y/H, (y+1)/H], row 0 at v = 0 (Blender's
// order; PNG files store the top row first).
struct AtlasImage {
  int width = 0, height = 0, channels = 0;
  std::vector<float> texels;  // width * height * channels, row-major, channels interleaved
  float* texel(int x, int y) { return &texels[(static_cast<size_t>(y) * width + x) * channels]; }
  const float* texel(int x, int y) const { return &texels[(static_cast<size_t>(y) * width + x) * channels]; }
};

struct StitchReport {
  int faces = 0, charts = 0;
  int seam_edges = 0;            // edges whose two sides lie apart in the atlas, with a texel-grid transition
  int unmatched_seam_edges = 0;  // edges whose sides lie apart without one (not stitched: filled as boundaries)
  long long covered_texels = 0;  // texels whose centre lies in a face
  long long seam_texels = 0;     // uncovered texels filled from across a seam
  long long filled_texels = 0;   // uncovered texels filled from their nearest covered texel
};

// faces: polygons (their positions are not used); corner_uv: per entry of faces.face_vertices, the corner's
// atlas coordinate. Edges are matched by their vertex indices (two sides of opposite directions). Changes
// only uncovered texels of image. Throws Error(InvalidArgument) on an empty image or mismatched sizes.
StitchReport stitch_seams(const PolygonSoup& faces, const std::vector<std::array<double, 2>>& corner_uv,
                          AtlasImage& image);

void to_json(Json& j, const StitchReport& report);

}  // namespace qgp

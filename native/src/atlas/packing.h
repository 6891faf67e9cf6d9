// Packing an atlas's charts into a texture: the options every atlas takes, and a bottom-left skyline
// packing of the charts' bounding boxes (in grid cells, K x K texels each) at whole-texel offsets,
// turned by 0 or 90 degrees, longest first, each in a rectangle `gutter` texels wider and higher than
// the chart (which goes gutter / 2 texels in). K is the largest that packs, or the one asked.
#pragma once
#include <array>
#include <string>
#include <vector>

#include "core/json.h"

namespace qgp {

struct AtlasOptions {
  int texture_width = 1024, texture_height = 1024;
  int texels_per_quad = 0;  // K; 0: the largest K for which every chart fits
  int gutter = 2;           // empty texels between charts (raised for mip_levels)
  int mip_levels = 0;       // L: the mip levels 1 .. L stay seam-free (K a power of two >= 2^L)
};

// What every atlas reports (the report's "atlas" / "uv_atlas" objects).
struct AtlasFigures {
  int num_charts = 0, texels_per_quad = 0, texture_width = 0, texture_height = 0;
  int gutter = 0, mip_levels = 0;  // as used
  int seam_edges = 0;              // edges whose two sides lie apart in the atlas
  double texture_use = 0.0;        // texels covered by faces / all texels
};
void to_json(Json& j, const AtlasFigures& figures);

using TexelPoint = std::array<int, 2>;

// p turned by turns * 90 degrees counter-clockwise about the origin (texel or grid coordinates).
template <class T>
std::array<T, 2> quarter_turns(const std::array<T, 2>& p, int turns) {
  std::array<T, 2> r = p;
  for (int t = 0; t < turns; ++t) r = {-r[1], r[0]};
  return r;
}

// Where a chart goes: the texel its turned bounding box starts at (the chart itself gutter / 2
// texels further), and its quarter turns.
struct ChartPlacement {
  TexelPoint offset{0, 0};
  int turns = 0;
};

struct AtlasPacking {
  int texels_per_quad = 0, gutter = 0;
  std::vector<ChartPlacement> placements;  // per chart
};

// Throws Error(InvalidArgument) naming the sizes when a size is not positive or too large (65 536
// texels), or when mip levels cannot be kept (K not a power of two >= 2^L, sides not multiples of 2^L).
void check_atlas_options(const AtlasOptions& options);

// chart_size: per chart, its unturned bounding box in cells; cells: the charts' area in cells (sets the
// largest K tried). Throws Error(InvalidArgument) "atlas: <what> do not fit a W x H texture at K
// texel(s) per quad ..." when they do not fit at the K asked or at the smallest.
AtlasPacking pack_atlas(const std::vector<TexelPoint>& chart_size, double cells, const AtlasOptions& options,
                        const std::string& what);

}  // namespace qgp

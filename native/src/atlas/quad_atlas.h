// A texture atlas for a quad mesh: every quad becomes one square of K x K texels, charts of quads
// are laid out on the texel grid without overlap, and every seam maps the texel grid of one side
// onto that of the other (a rotation by a multiple of 90 degrees plus a whole number of texels).
//
// Charts grow quad by quad over shared edges, each quad a unit cell of the chart's integer grid
// placed beside the quad it was reached from; a quad joins only where its cell is free and each of
// its vertices has one place in the chart (so a chart stops at the irregular vertices it would wind
// around), and never across a separatrix of the quad mesh's irregular vertices (traced as a
// motorcycle graph), so charts are the layout's grid rectangles. Then neighbouring charts are merged
// while their union is still injective and a rectangle of cells (pairs sharing the most edges first):
// fewer seams, and rectangles still pack tightly (spot at 1 000 quads: 110 charts and 669 seam edges
// become 45 and 426, texture use 82 % either way). A chart is injective and its cells are whole
// quads. Charts are packed bottom-left into the texture at whole-texel offsets, turned by
// 0 or 90 degrees, longest first, with `gutter` empty texels between charts and half of it at the
// texture's sides: each chart has gutter / 2 texels of its own around it, which seam stitching
// (atlas/stitch_seams.h) fills from the chart across each seam.
//
// With mip_levels = L > 0, K is a power of two of at least 2^L, the gutter a multiple of 2^(L+1)
// and every chart starts at a multiple of 2^L texels: at mip levels 1 .. L (each texel the mean of
// 2 x 2 texels of the level below) quads are still whole texels, seams still map texels onto texels,
// and every chart keeps at least one texel of its own gutter.
#pragma once
#include <vector>

#include "atlas/packing.h"
#include "core/json.h"
#include "core/quad_mesh.h"

namespace qgp {

struct QuadAtlas : AtlasFigures {  // seam edges: quad edges whose two quads lie in different charts
  // Per quad corner (row 4q + k: corner k of quad q), the atlas coordinate in [0,1]^2: texel
  // (x, y) of the texture spans [x/W, (x+1)/W] x [y/H, (y+1)/H].
  Eigen::Matrix<double, Eigen::Dynamic, 2, Eigen::RowMajor> corner_uv;
  std::vector<int> quad_chart;  // #Q: the chart of each quad
};

// quads: a quad mesh, counter-clockwise (edges with more than two quads are treated as seams).
// Throws Error(InvalidArgument) when the texture size or K is not positive (for mip levels: when K
// is not a power of two of at least 2^L or the texture's sides not multiples of 2^L), or when the
// charts do not fit the texture at the K asked (or at the smallest K), naming the sizes.
QuadAtlas build_quad_atlas(const QuadMesh& quads, const AtlasOptions& options);

}  // namespace qgp

// The quad atlas (atlas/quad_atlas.h) over real and generated quad meshes: every UV in [0,1]; every
// quad a counter-clockwise square of K x K whole texels; no texel covered twice (rasterized at
// texel resolution) and `gutter` texels between charts; across every edge inside a chart the same
// UVs, across every seam a turn by a multiple of 90 degrees plus a whole number of texels; the same
// atlas every run.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <iostream>
#include <map>
#include <memory>
#include <string>
#include <utility>

#include "atlas/quad_atlas.h"
#include "core/error.h"
#include "intake/read_mesh_file.h"
#include "pipeline/session.h"
#include "quad_extraction/split_triangles.h"
#include "test_support.h"

namespace qgp {
namespace {

using Texel = std::array<long, 2>;

// Corner c of the atlas in texels (exact: UVs are whole texels over the texture size).
Texel texel_of(const QuadAtlas& a, int c) {
  const double x = a.corner_uv(c, 0) * a.texture_width, y = a.corner_uv(c, 1) * a.texture_height;
  EXPECT_NEAR(x, std::round(x), 1e-6);
  EXPECT_NEAR(y, std::round(y), 1e-6);
  return {std::lround(x), std::lround(y)};
}

// Every quad a counter-clockwise K x K square of whole texels inside the texture.
void expect_texel_squares(const QuadMesh& quads, const QuadAtlas& a) {
  const long k = a.texels_per_quad;
  for (int q = 0; q < quads.num_quads(); ++q)
    for (int c = 0; c < 4; ++c) {
      const Texel p = texel_of(a, 4 * q + c), n = texel_of(a, 4 * q + (c + 1) % 4);
      ASSERT_TRUE(p[0] >= 0 && p[1] >= 0 && p[0] <= a.texture_width && p[1] <= a.texture_height) << q;
      const Texel d = {n[0] - p[0], n[1] - p[1]},
                  e = {texel_of(a, 4 * q + (c + 2) % 4)[0] - n[0], texel_of(a, 4 * q + (c + 2) % 4)[1] - n[1]};
      ASSERT_EQ(std::abs(d[0]) + std::abs(d[1]), k) << "quad " << q << " side " << c;
      ASSERT_TRUE(d[0] == 0 || d[1] == 0) << "quad " << q;
      ASSERT_EQ(d[0] * e[1] - d[1] * e[0], k * k) << "quad " << q << " is not counter-clockwise";
    }
}

// The chart covering each texel (-1: none), failing where two quads cover one; then the gutter.
void expect_no_overlap(const QuadMesh& quads, const QuadAtlas& a, int gutter) {
  std::vector<int> owner(static_cast<size_t>(a.texture_width) * a.texture_height, -1);
  for (int q = 0; q < quads.num_quads(); ++q) {
    Texel lo = texel_of(a, 4 * q), hi = lo;
    for (int c = 1; c < 4; ++c)
      for (int d = 0; d < 2; ++d) {
        lo[d] = std::min(lo[d], texel_of(a, 4 * q + c)[d]);
        hi[d] = std::max(hi[d], texel_of(a, 4 * q + c)[d]);
      }
    for (long y = lo[1]; y < hi[1]; ++y)
      for (long x = lo[0]; x < hi[0]; ++x) {
        int& o = owner[y * a.texture_width + x];
        ASSERT_EQ(o, -1) << "texel (" << x << ", " << y << ") covered twice, again by quad " << q;
        o = a.quad_chart[q];
      }
  }
  long covered = 0;
  for (long y = 0; y < a.texture_height; ++y)
    for (long x = 0; x < a.texture_width; ++x) {
      const int o = owner[y * a.texture_width + x];
      if (o < 0) continue;
      ++covered;
      // Texels above, and right on the same row, within the gutter (the rest by symmetry).
      for (long v = y; v <= std::min<long>(a.texture_height - 1, y + gutter); ++v)
        for (long u = std::max(0L, v == y ? x + 1 : x - gutter); u <= std::min<long>(a.texture_width - 1, x + gutter);
             ++u) {
          const int p = owner[v * a.texture_width + u];
          ASSERT_TRUE(p < 0 || p == o) << "charts " << o << " and " << p << " closer than the gutter at (" << x << ", "
                                       << y << ")";
        }
    }
  EXPECT_NEAR(a.texture_use, double(covered) / owner.size(), 1e-12);
}

// Across every edge of two quads: equal texels inside a chart; across a seam, one of the four turns
// and a whole-texel shift carrying one side's corners onto the other's.
int expect_seam_transitions(const QuadMesh& quads, const QuadAtlas& a) {
  std::map<std::pair<int, int>, int> corner_of_edge;  // directed edge (a, b) -> corner of a in its quad
  for (int q = 0; q < quads.num_quads(); ++q)
    for (int c = 0; c < 4; ++c) corner_of_edge[{quads.Q(q, c), quads.Q(q, (c + 1) % 4)}] = 4 * q + c;
  int seams = 0;
  for (const auto& [edge, c1] : corner_of_edge) {
    const auto twin = corner_of_edge.find({edge.second, edge.first});
    if (twin == corner_of_edge.end() || edge.first > edge.second) continue;
    const int c2 = twin->second, n1 = 4 * (c1 / 4) + (c1 % 4 + 1) % 4, n2 = 4 * (c2 / 4) + (c2 % 4 + 1) % 4;
    const Texel a1 = texel_of(a, c1), b1 = texel_of(a, n1), b2 = texel_of(a, c2), a2 = texel_of(a, n2);
    if (a.quad_chart[c1 / 4] == a.quad_chart[c2 / 4]) {
      EXPECT_EQ(a1, a2);
      EXPECT_EQ(b1, b2);
      continue;
    }
    ++seams;
    const Texel d1 = {b1[0] - a1[0], b1[1] - a1[1]};
    Texel d = d1;
    int turns = 0;
    while (turns < 4 && d != Texel{b2[0] - a2[0], b2[1] - a2[1]}) {
      d = {-d[1], d[0]};
      ++turns;
    }
    EXPECT_LT(turns, 4) << "the seam's two sides differ by more than a turn";
    // a2 = R a1 + t with t whole texels: holds by construction of R from whole-texel corners.
  }
  return seams;
}

QuadAtlas checked_atlas(const QuadMesh& quads, const AtlasOptions& options, const std::string& name) {
  const QuadAtlas a = build_quad_atlas(quads, options);
  SCOPED_TRACE(name);
  EXPECT_EQ(a.corner_uv.rows(), 4 * quads.num_quads());
  EXPECT_EQ(static_cast<int>(a.quad_chart.size()), quads.num_quads());
  expect_texel_squares(quads, a);
  expect_no_overlap(quads, a, options.gutter);
  EXPECT_EQ(expect_seam_transitions(quads, a), a.seam_edges);
  const QuadAtlas again = build_quad_atlas(quads, options);
  EXPECT_EQ(again.corner_uv, a.corner_uv) << "not the same atlas twice";
  std::cout << name << ": " << quads.num_quads() << " quads, " << a.num_charts << " charts, " << a.texels_per_quad
            << " texels per quad, " << a.seam_edges << " seam edges, texture use " << a.texture_use << "\n";
  return a;
}

// The pipeline's own quads: rectangles of the layout pack well.
TEST(QuadAtlas, RemeshedMeshes) {
  for (const auto& [name, sharp_angle] :
       {std::pair{"spot.obj", -1.0}, {"fandisk.obj", 40.0}, {"camelhead.off", -1.0}}) {
    const std::unique_ptr<Session> session = test::remeshed_session(name, 1000, sharp_angle);
    const QuadAtlas a = checked_atlas(*session->quad_result(), AtlasOptions{}, name);
    EXPECT_GT(a.texture_use, 0.6) << name;
  }
}

// Quads with irregular vertices everywhere (every triangle split into three), on real meshes and on
// a many-part one with boundaries; the texel size asked is kept, a smaller texture is refused.
TEST(QuadAtlas, SplitTrianglesOfRealMeshes) {
  for (const std::string name : {"joint.obj", "torus.obj", "spot.obj"}) {
    const QuadMesh quads = split_triangles_into_quads(test::load_mesh(name).mesh);
    checked_atlas(quads, AtlasOptions{1024, 1024, 0, 2}, name + " split");
  }
  const QuadMesh truck = split_triangles_into_quads(test::load_mesh("truck.obj").mesh);
  const QuadAtlas a = checked_atlas(truck, AtlasOptions{2048, 2048, 0, 1}, "truck split");
  EXPECT_GE(a.num_charts, test::load_mesh("truck.obj").components.size());
  const QuadAtlas fixed = checked_atlas(truck, AtlasOptions{2048, 2048, 2, 3}, "truck split, 2 texels per quad");
  EXPECT_EQ(fixed.texels_per_quad, 2);
  try {
    build_quad_atlas(truck, AtlasOptions{256, 256, 4, 2});
    FAIL() << "a 256 x 256 texture cannot hold the truck's quads at 4 texels each";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::InvalidArgument);
    EXPECT_NE(std::string(e.what()).find("do not fit a 256 x 256 texture"), std::string::npos) << e.what();
  }
}

// A torus of quads without any irregular vertex: no separatrix cuts it, so charts stop where they
// would wind around; a quad mesh of one quad; bad sizes are refused.
TEST(QuadAtlas, GeneratedCases) {
  const test::SyntheticParametrized torus = test::make_grid_torus(24, 8);
  const QuadMesh torus_quads = split_triangles_into_quads(torus.mesh);
  checked_atlas(torus_quads, AtlasOptions{}, "grid torus split");
  QuadMesh grid;  // a 12 x 12 grid of quads: regular, with a boundary
  grid.V.resize(13 * 13, 3);
  grid.Q.resize(12 * 12, 4);
  for (int i = 0; i <= 12; ++i)
    for (int j = 0; j <= 12; ++j) grid.V.row(13 * i + j) << j, i, 0;
  for (int i = 0; i < 12; ++i)
    for (int j = 0; j < 12; ++j)
      grid.Q.row(12 * i + j) << 13 * i + j, 13 * i + j + 1, 13 * (i + 1) + j + 1, 13 * (i + 1) + j;
  const QuadAtlas g = checked_atlas(grid, AtlasOptions{256, 256, 0, 2}, "grid");
  EXPECT_EQ(g.num_charts, 1);
  EXPECT_EQ(g.seam_edges, 0);
  EXPECT_EQ(g.texels_per_quad, 21);  // 12 * 21 + 2 = 254 <= 256
  QuadMesh one;
  one.V = grid.V.topRows(13 * 2);
  one.Q = grid.Q.topRows(1);
  EXPECT_EQ(checked_atlas(one, AtlasOptions{64, 64, 0, 2}, "one quad").texels_per_quad, 62);
  for (const AtlasOptions& bad : {AtlasOptions{0, 64, 0, 2}, AtlasOptions{64, 64, -1, 2}, AtlasOptions{64, 64, 0, -1}})
    EXPECT_THROW(build_quad_atlas(one, bad), Error);
  EXPECT_THROW(build_quad_atlas(QuadMesh{}, AtlasOptions{}), Error);
}

}  // namespace
}  // namespace qgp

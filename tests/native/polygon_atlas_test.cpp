// The atlas of polygons with an integer-grid map (atlas/polygon_atlas.h), on the integer-grid maps of
// real meshes (the triangles Integer-Grid UVs maps: the repaired input, refined where only the cell map
// is flip-free): every UV in [0,1]; no texel centre in two triangles (rasterized at texel resolution); no
// triangle turned over by the atlas; every seam a quarter turn plus whole texels (seam stitching matches
// every one); the same atlas every run.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <string>
#include <utility>
#include <vector>

#include "atlas/polygon_atlas.h"
#include "atlas/stitch_seams.h"
#include "core/error.h"
#include "core/progress.h"
#include "intake/read_mesh_file.h"
#include "pipeline/uv_mesh.h"
#include "test_support.h"

namespace qgp {
namespace {

// The session's integer-grid map as triangles with per-corner grid coordinates.
std::pair<PolygonSoup, std::vector<CornerUv>> grid_mapped_triangles(const std::string& name, double sharp_angle) {
  Session session(read_mesh_file(test::mesh_path(name)));
  RemeshOptions options;
  options.target_faces = 1000;
  options.sharp_angle_deg = sharp_angle;
  options.fallback_uv_map = true;
  session.set_options(options);
  Progress progress;
  session.run(Job::Remesh, progress);
  const UvMesh map = compose_uv_mesh(session, UvMapKind::IntegerGrid);
  PolygonSoup soup;
  for (int f = 0; f < map.mesh.num_faces(); ++f) soup.add_face(map.mesh.F.row(f).data(), 3);
  soup.positions.resize(map.mesh.num_vertices());
  std::vector<CornerUv> uv(3 * map.mesh.num_faces());
  for (size_t c = 0; c < uv.size(); ++c) uv[c] = {map.uv(c, 0), map.uv(c, 1)};
  return {soup, uv};
}

double area(const CornerUv& a, const CornerUv& b, const CornerUv& c) {
  return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
}

// Texel centres inside each triangle (in atlas texels); fails where one is inside two.
long covered_texels(const PolygonAtlas& atlas) {
  const int W = atlas.texture_width, H = atlas.texture_height;
  std::vector<int> owner(static_cast<size_t>(W) * H, -1);
  long covered = 0;
  for (size_t f = 0; f < atlas.corner_uv.size() / 3; ++f) {
    CornerUv p[3];
    for (int k = 0; k < 3; ++k) p[k] = {atlas.corner_uv[3 * f + k][0] * W, atlas.corner_uv[3 * f + k][1] * H};
    const double total = area(p[0], p[1], p[2]);
    if (total <= 0) continue;
    const int x0 = static_cast<int>(std::floor(std::min({p[0][0], p[1][0], p[2][0]})));
    const int x1 = static_cast<int>(std::ceil(std::max({p[0][0], p[1][0], p[2][0]})));
    const int y0 = static_cast<int>(std::floor(std::min({p[0][1], p[1][1], p[2][1]})));
    const int y1 = static_cast<int>(std::ceil(std::max({p[0][1], p[1][1], p[2][1]})));
    for (int y = std::max(0, y0); y < std::min(H, y1); ++y)
      for (int x = std::max(0, x0); x < std::min(W, x1); ++x) {
        const CornerUv q = {x + 0.5, y + 0.5};
        if (area(p[0], p[1], q) < 0 || area(p[1], p[2], q) < 0 || area(p[2], p[0], q) < 0) continue;
        int& o = owner[static_cast<size_t>(y) * W + x];
        EXPECT_TRUE(o < 0 || o == atlas.face_chart[f])
            << "texel (" << x << ", " << y << ") in charts " << o << " and " << atlas.face_chart[f];
        if (o < 0) ++covered;
        o = atlas.face_chart[f];
      }
  }
  return covered;
}

TEST(PolygonAtlas, IntegerGridMapsOfRealMeshes) {
  for (const auto& [name, sharp_angle] :
       {std::pair{"spot.obj", -1.0}, {"fandisk.obj", 40.0}, {"camelhead.off", -1.0}, {"joint.obj", 40.0}}) {
    SCOPED_TRACE(name);
    const auto [faces, grid_uv] = grid_mapped_triangles(name, sharp_angle);
    const PolygonAtlas atlas = build_polygon_atlas(faces, grid_uv, AtlasOptions{});
    for (const CornerUv& uv : atlas.corner_uv) ASSERT_TRUE(uv[0] >= 0 && uv[0] <= 1 && uv[1] >= 0 && uv[1] <= 1);
    int turned = 0;
    for (size_t f = 0; f < grid_uv.size() / 3; ++f)
      turned += (area(grid_uv[3 * f], grid_uv[3 * f + 1], grid_uv[3 * f + 2]) > 0) !=
                (area(atlas.corner_uv[3 * f], atlas.corner_uv[3 * f + 1], atlas.corner_uv[3 * f + 2]) > 0);
    EXPECT_EQ(turned, 0) << "triangles turned over by the atlas";
    const long covered = covered_texels(atlas);
    AtlasImage image{atlas.texture_width, atlas.texture_height, 1,
                     std::vector<float>(static_cast<size_t>(atlas.texture_width) * atlas.texture_height, 0.0f)};
    const StitchReport stitched = stitch_seams(faces, atlas.corner_uv, image);
    EXPECT_EQ(stitched.unmatched_seam_edges, 0) << "seams that do not map texels onto texels";
    EXPECT_EQ(stitched.seam_edges, atlas.seam_edges);
    EXPECT_EQ(build_polygon_atlas(faces, grid_uv, AtlasOptions{}).corner_uv, atlas.corner_uv) << "not the same twice";
    std::cout << name << ": " << faces.num_faces() << " triangles, " << atlas.num_charts << " charts, "
              << atlas.texels_per_quad << " texels per quad, " << atlas.seam_edges << " seam edges, texture use "
              << atlas.texture_use << " (" << double(covered) / (1024.0 * 1024.0) << " by texel centres)\n";
  }
}

TEST(PolygonAtlas, BadInputIsRefused) {
  PolygonSoup one;
  one.positions.resize(3);
  const int triangle[3] = {0, 1, 2};
  one.add_face(triangle, 3);
  const std::vector<CornerUv> uv = {{0, 0}, {1, 0}, {0, 1}};
  EXPECT_EQ(build_polygon_atlas(one, uv, AtlasOptions{64, 64, 0, 2}).num_charts, 1);
  EXPECT_THROW(build_polygon_atlas(one, {{0, 0}, {1, 0}}, AtlasOptions{}), Error);
  EXPECT_THROW(build_polygon_atlas(one, {{0, 0}, {1, std::nan("")}, {0, 1}}, AtlasOptions{}), Error);
  EXPECT_THROW(build_polygon_atlas(PolygonSoup{}, {}, AtlasOptions{}), Error);
  EXPECT_THROW(build_polygon_atlas(one, uv, AtlasOptions{0, 64, 0, 2}), Error);
}

}  // namespace
}  // namespace qgp

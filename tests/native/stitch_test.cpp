// Seam stitching (atlas/stitch_seams.h) on quad atlases (atlas/quad_atlas.h) of real and generated quad
// meshes. Every atlas texel inside a quad is painted with a smooth function of the surface point at its
// centre (a stand-in for a baked 3D texture). After stitching, bilinear samples at 1 000 random seam
// points, read from the two sides of the seam, agree to float rounding away from irregular and boundary
// vertices (not within one texel of them); texels inside quads never change; the same image every run.
// With mip levels, the same holds at levels 1 .. L of the box-filtered image. With gutters filled from
// the nearest texel only (as a bake's margin does), the sides differ by more than 1/255: the check can fail.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <iostream>
#include <map>
#include <memory>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "atlas/quad_atlas.h"
#include "atlas/stitch_seams.h"
#include "core/error.h"
#include "metrics/quad_metrics.h"
#include "quad_extraction/split_triangles.h"
#include "test_support.h"

namespace qgp {
namespace {

using Uv = std::array<double, 2>;

std::vector<Uv> corner_uvs(const QuadAtlas& atlas) {
  std::vector<Uv> uv(atlas.corner_uv.rows());
  for (size_t c = 0; c < uv.size(); ++c) uv[c] = {atlas.corner_uv(c, 0), atlas.corner_uv(c, 1)};
  return uv;
}

// Paints every texel inside a quad with smooth colours of the surface point at its centre (the quad's
// bilinear interpolation at the texel's place in the K x K square); other texels stay 0.
AtlasImage painted_atlas(const QuadMesh& quads, const QuadAtlas& atlas) {
  AtlasImage image{atlas.texture_width, atlas.texture_height, 3, {}};
  image.texels.assign(static_cast<size_t>(image.width) * image.height * 3, 0.0f);
  const double size = (quads.V.colwise().maxCoeff() - quads.V.colwise().minCoeff()).norm();
  const int k = atlas.texels_per_quad;
  for (int q = 0; q < quads.num_quads(); ++q) {
    const Uv o = {atlas.corner_uv(4 * q, 0) * image.width, atlas.corner_uv(4 * q, 1) * image.height};
    const Uv s = {atlas.corner_uv(4 * q + 1, 0) * image.width - o[0],
                  atlas.corner_uv(4 * q + 1, 1) * image.height - o[1]};
    const Uv t = {-s[1], s[0]};  // counter-clockwise squares: corner 3 - corner 0
    for (int i = 0; i < k; ++i)
      for (int j = 0; j < k; ++j) {
        const double a = (i + 0.5) / k, b = (j + 0.5) / k;
        const Vec3 p = (1 - a) * (1 - b) * quads.V.row(quads.Q(q, 0)) + a * (1 - b) * quads.V.row(quads.Q(q, 1)) +
                       a * b * quads.V.row(quads.Q(q, 2)) + (1 - a) * b * quads.V.row(quads.Q(q, 3));
        const int x = static_cast<int>(std::floor(o[0] + a * s[0] + b * t[0]));
        const int y = static_cast<int>(std::floor(o[1] + a * s[1] + b * t[1]));
        float* texel = image.texel(x, y);
        for (int c = 0; c < 3; ++c)
          texel[c] = static_cast<float>(0.5 + 0.5 * std::sin(25.0 * p[c] / size + 6.0 * p[(c + 1) % 3] / size + c));
      }
  }
  return image;
}

// Bilinear sample at (u, v) in [0,1]^2 (texel centres at (x + 0.5) / W), clamped at the borders.
std::array<double, 3> bilinear(const AtlasImage& image, const Uv& uv) {
  const double x = uv[0] * image.width - 0.5, y = uv[1] * image.height - 0.5;
  const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
  const double fx = x - x0, fy = y - y0;
  auto at = [&](int xi, int yi) {
    return image.texel(std::clamp(xi, 0, image.width - 1), std::clamp(yi, 0, image.height - 1));
  };
  std::array<double, 3> result{};
  for (int c = 0; c < 3; ++c)
    result[c] = (1 - fx) * (1 - fy) * at(x0, y0)[c] + fx * (1 - fy) * at(x0 + 1, y0)[c] +
                (1 - fx) * fy * at(x0, y0 + 1)[c] + fx * fy * at(x0 + 1, y0 + 1)[c];
  return result;
}

// A seam side: quad corner c (edge from corner c to the next) and the corner of the other side's start.
struct SeamEdge {
  int side, twin;
};

std::vector<SeamEdge> seam_edges(const QuadMesh& quads, const QuadAtlas& atlas) {
  std::map<std::pair<int, int>, int> corner_of_edge;
  for (int q = 0; q < quads.num_quads(); ++q)
    for (int c = 0; c < 4; ++c) corner_of_edge[{quads.Q(q, c), quads.Q(q, (c + 1) % 4)}] = 4 * q + c;
  std::vector<SeamEdge> seams;
  for (const auto& [edge, c] : corner_of_edge) {
    const auto twin = corner_of_edge.find({edge.second, edge.first});
    if (twin != corner_of_edge.end() && atlas.quad_chart[c / 4] != atlas.quad_chart[twin->second / 4])
      seams.push_back({c, twin->second});
  }
  return seams;
}

int next_corner(int c) { return 4 * (c / 4) + (c % 4 + 1) % 4; }

// The largest colour difference between the two sides of 1 000 random seam points of `image` (a mip level
// whose texels are `scale` level-0 texels), skipping points within one texel of an irregular or boundary
// vertex; -1 when no seam point qualifies.
double largest_seam_difference(const QuadMesh& quads, const QuadAtlas& atlas, const AtlasImage& image, int scale) {
  const std::vector<SeamEdge> seams = seam_edges(quads, atlas);
  if (seams.empty()) return -1;
  const QuadTopology topology = quad_topology(quads);
  auto special = [&](int v) { return topology.on_boundary[v] || topology.valence[v] != 4; };
  const double edge_texels = double(atlas.texels_per_quad) / scale;
  std::mt19937 random(7);
  double largest = -1;
  for (int sample = 0, tries = 0; sample < 1000 && tries < 100000; ++tries) {
    const SeamEdge& e = seams[random() % seams.size()];
    const double s = std::uniform_real_distribution<double>(0, 1)(random);
    const int a = quads.Q(e.side / 4, e.side % 4), b = quads.Q(e.twin / 4, e.twin % 4);
    if ((special(a) && s * edge_texels < 1) || (special(b) && (1 - s) * edge_texels < 1)) continue;
    auto point = [&](int from, int to, double t) {
      return Uv{(1 - t) * atlas.corner_uv(from, 0) + t * atlas.corner_uv(to, 0),
                (1 - t) * atlas.corner_uv(from, 1) + t * atlas.corner_uv(to, 1)};
    };
    const auto one = bilinear(image, point(e.side, next_corner(e.side), s));
    const auto other = bilinear(image, point(next_corner(e.twin), e.twin, s));
    for (int c = 0; c < 3; ++c) largest = std::max(largest, std::abs(one[c] - other[c]));
    ++sample;
  }
  return largest;
}

// The next mip level: each texel the mean of 2 x 2.
AtlasImage halved(const AtlasImage& image) {
  AtlasImage next{image.width / 2, image.height / 2, image.channels, {}};
  next.texels.resize(static_cast<size_t>(next.width) * next.height * next.channels);
  for (int y = 0; y < next.height; ++y)
    for (int x = 0; x < next.width; ++x)
      for (int c = 0; c < image.channels; ++c)
        next.texel(x, y)[c] = 0.25f * (image.texel(2 * x, 2 * y)[c] + image.texel(2 * x + 1, 2 * y)[c] +
                                       image.texel(2 * x, 2 * y + 1)[c] + image.texel(2 * x + 1, 2 * y + 1)[c]);
  return next;
}

// Stitches the painted atlas and checks the header's claims.
void expect_invisible_seams(const QuadMesh& quads, const AtlasOptions& options, const std::string& name) {
  SCOPED_TRACE(name);
  const QuadAtlas atlas = build_quad_atlas(quads, options);
  const PolygonSoup faces = test::polygon_soup(quads);
  const AtlasImage painted = painted_atlas(quads, atlas);
  AtlasImage image = painted;
  const StitchReport report = stitch_seams(faces, corner_uvs(atlas), image);
  EXPECT_EQ(report.seam_edges, atlas.seam_edges);
  EXPECT_EQ(report.unmatched_seam_edges, 0);
  EXPECT_EQ(report.charts, atlas.num_charts);
  EXPECT_EQ(report.covered_texels,
            static_cast<long long>(quads.num_quads()) * atlas.texels_per_quad * atlas.texels_per_quad);
  for (size_t i = 0; i < image.texels.size(); ++i)
    if (painted.texels[i] != 0.0f) ASSERT_EQ(image.texels[i], painted.texels[i]) << "a covered texel changed";
  AtlasImage dilated = painted;  // gutters filled from the nearest texel only: the quads as unconnected faces
  PolygonSoup unconnected;
  for (int c = 0; c < 4 * quads.num_quads(); ++c) unconnected.face_vertices.push_back(c);
  for (int q = 1; q <= quads.num_quads(); ++q) unconnected.face_start.push_back(4 * q);
  EXPECT_EQ(stitch_seams(unconnected, corner_uvs(atlas), dilated).seam_edges, 0);
  const double before = largest_seam_difference(quads, atlas, dilated, 1);
  const double after = largest_seam_difference(quads, atlas, image, 1);
  std::cout << name << ": " << atlas.num_charts << " charts, " << report.seam_edges << " seam edges, "
            << report.seam_texels << " texels stitched; largest seam difference " << before << " before, " << after
            << " after\n";
  if (atlas.seam_edges > 0) {
    EXPECT_GT(before, 1.0 / 255) << "the sides of the unstitched seams already agree: the check cannot fail";
    EXPECT_LE(after, 1e-5);
  }
  AtlasImage again = painted;
  stitch_seams(faces, corner_uvs(atlas), again);
  EXPECT_EQ(again.texels, image.texels) << "not the same image twice";
  AtlasImage level = image;
  for (int l = 1; l <= options.mip_levels; ++l) {
    level = halved(level);
    EXPECT_LE(largest_seam_difference(quads, atlas, level, 1 << l), 1e-5) << "mip level " << l;
  }
}

TEST(StitchSeams, RemeshedMeshes) {
  for (const auto& [name, sharp_angle] :
       {std::pair{"spot.obj", -1.0}, {"fandisk.obj", 40.0}, {"camelhead.off", -1.0}}) {
    const std::unique_ptr<Session> session = test::remeshed_session(name, 1000, sharp_angle);
    expect_invisible_seams(*session->quad_result(), AtlasOptions{}, name);
    expect_invisible_seams(*session->quad_result(), AtlasOptions{1024, 1024, 0, 2, 3},
                           std::string(name) + ", 3 mip levels");
  }
}

// Quads with irregular vertices everywhere, a many-part mesh, a torus of regular quads (charts stop where
// they would wind around), gutters of 1 and 0 texels (stitching then only fills what it can).
TEST(StitchSeams, GeneratedCases) {
  for (const std::string name : {"joint.obj", "truck.obj"})
    expect_invisible_seams(split_triangles_into_quads(test::load_mesh(name).mesh), AtlasOptions{2048, 2048, 0, 2},
                           name + " split");
  const QuadMesh torus = split_triangles_into_quads(test::make_grid_torus(24, 8).mesh);
  expect_invisible_seams(torus, AtlasOptions{512, 512, 0, 4, 1}, "grid torus split, 1 mip level");
  const QuadAtlas narrow = build_quad_atlas(torus, AtlasOptions{512, 512, 0, 0});
  AtlasImage image = painted_atlas(torus, narrow);
  const StitchReport report = stitch_seams(test::polygon_soup(torus), corner_uvs(narrow), image);
  EXPECT_EQ(report.seam_edges, narrow.seam_edges);
}

TEST(StitchSeams, BadInputIsRefused) {
  const QuadMesh torus = split_triangles_into_quads(test::make_grid_torus(8, 4).mesh);
  const QuadAtlas atlas = build_quad_atlas(torus, AtlasOptions{64, 64, 0, 2});
  const PolygonSoup faces = test::polygon_soup(torus);
  AtlasImage empty;
  EXPECT_THROW(stitch_seams(faces, corner_uvs(atlas), empty), Error);
  AtlasImage image{64, 64, 3, std::vector<float>(64 * 64 * 3, 0.0f)};
  std::vector<Uv> short_uv = corner_uvs(atlas);
  short_uv.pop_back();
  EXPECT_THROW(stitch_seams(faces, short_uv, image), Error);
  std::vector<Uv> nan_uv = corner_uvs(atlas);
  nan_uv[5][1] = std::nan("");
  EXPECT_THROW(stitch_seams(faces, nan_uv, image), Error);
  std::vector<Uv> shifted = corner_uvs(atlas);  // a third of a texel off the grid: seams cannot be matched
  for (int c = 0; c < 4; ++c) shifted[c][0] += 1.0 / (3 * 64);
  const StitchReport report = stitch_seams(faces, shifted, image);
  EXPECT_GT(report.unmatched_seam_edges, 0);
}

}  // namespace
}  // namespace qgp

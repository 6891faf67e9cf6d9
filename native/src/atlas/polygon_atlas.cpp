#include "atlas/polygon_atlas.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <deque>
#include <string>
#include <unordered_map>

#include "core/error.h"

namespace qgp {
namespace {

constexpr double kSameUv = 1e-4;      // grid units: corners this close are one point (float UV maps)
constexpr double kOverlap = 1e-7;     // grid units of overlap that do not count (faces meeting at a side)
constexpr double kLargestGrid = 1e7;  // grid coordinates beyond are refused
constexpr int64_t kMostCells = 4096;  // grid cells a face's bounding box may span and still join a chart

using Triangle = std::array<CornerUv, 3>;
// A face joins a chart only while the chart's bounding box (in whole grid cells) stays within kFill times
// its area, or within kSmallBox cells: charts of mostly empty boxes pack badly. Texture use at 1 000 quads
// in 1 024^2 (spot, fandisk, camelhead, joint, bunny, cow): 43 42 49 50 22 34 % with these; 39 46 45 24 39
// 27 % with 1.6 and 16; 43 28 49 46 22 - % without the rule.
constexpr double kFill = 2.0;
constexpr double kSmallBox = 64;

bool same(const CornerUv& a, const CornerUv& b) {
  return std::abs(a[0] - b[0]) <= kSameUv && std::abs(a[1] - b[1]) <= kSameUv;
}

double signed_area(const Triangle& t) {
  return 0.5 * ((t[1][0] - t[0][0]) * (t[2][1] - t[0][1]) - (t[1][1] - t[0][1]) * (t[2][0] - t[0][0]));
}

// The face as a fan of triangles from its first corner.
std::vector<Triangle> face_triangles(const CornerFaces& faces, int f) {
  std::vector<Triangle> triangles;
  const int first = faces.soup.face_start[f], end = faces.soup.face_start[f + 1];
  for (int c = first + 1; c + 1 < end; ++c) triangles.push_back({faces.uv[first], faces.uv[c], faces.uv[c + 1]});
  return triangles;
}

// True when the interiors of a and b overlap by more than kOverlap across every edge direction of both
// (the separating axis theorem; a degenerate triangle overlaps nothing).
bool overlap(const Triangle& a, const Triangle& b) {
  for (const Triangle* t : {&a, &b})
    for (int k = 0; k < 3; ++k) {
      const CornerUv &p = (*t)[k], &q = (*t)[(k + 1) % 3];
      const double nx = q[1] - p[1], ny = p[0] - q[0], length = std::hypot(nx, ny);
      if (length == 0) return false;
      double lo[2] = {1e300, 1e300}, hi[2] = {-1e300, -1e300};
      for (int s = 0; s < 2; ++s)
        for (const CornerUv& r : s == 0 ? a : b) {
          const double d = (r[0] * nx + r[1] * ny) / length;
          lo[s] = std::min(lo[s], d), hi[s] = std::max(hi[s], d);
        }
      if (hi[0] <= lo[1] + kOverlap || hi[1] <= lo[0] + kOverlap) return false;
    }
  return true;
}

// The grid cells under a triangle's bounding box (none when they are more than kMostCells).
std::vector<uint64_t> cells_under(const Triangle& t) {
  double lo[2] = {1e300, 1e300}, hi[2] = {-1e300, -1e300};
  for (const CornerUv& p : t)
    for (int d = 0; d < 2; ++d) lo[d] = std::min(lo[d], p[d]), hi[d] = std::max(hi[d], p[d]);
  const int64_t x0 = static_cast<int64_t>(std::floor(lo[0])), x1 = static_cast<int64_t>(std::floor(hi[0]));
  const int64_t y0 = static_cast<int64_t>(std::floor(lo[1])), y1 = static_cast<int64_t>(std::floor(hi[1]));
  std::vector<uint64_t> cells;
  if ((x1 - x0 + 1) * (y1 - y0 + 1) > kMostCells) return cells;
  for (int64_t y = y0; y <= y1; ++y)
    for (int64_t x = x0; x <= x1; ++x)
      cells.push_back((static_cast<uint64_t>(static_cast<uint32_t>(x)) << 32) | static_cast<uint32_t>(y));
  return cells;
}

// The triangles of the chart being grown, by grid cell, to test a new face against its neighbours only.
class ChartFootprint {
 public:
  void clear() { triangles_.clear(), by_cell_.clear(), lo_ = {1e300, 1e300}, hi_ = {-1e300, -1e300}, area_ = 0; }
  // Whether the face's triangles (positive, not too large) overlap none of the chart's, and the chart's box stays
  // filled (kFill). (Capping a chart's side instead, at 0.15 / 0.25 / 0.4 of the square root of the grid area, made
  // 4-6 / 3-4 / 2-4 times as many seam edges for a texture use of 19-46 % against 28-49 % uncapped.)
  bool fits(const std::vector<Triangle>& face) const {
    CornerUv lo = lo_, hi = hi_;
    double area = area_;
    for (const Triangle& t : face) {
      area += std::abs(signed_area(t));
      for (const CornerUv& p : t)
        for (int d = 0; d < 2; ++d) lo[d] = std::min(lo[d], p[d]), hi[d] = std::max(hi[d], p[d]);
    }
    const double box = (std::ceil(hi[0]) - std::floor(lo[0])) * (std::ceil(hi[1]) - std::floor(lo[1]));
    if (!triangles_.empty() && box > kSmallBox && box > kFill * area) return false;
    for (const Triangle& t : face) {
      if (signed_area(t) < 0) return false;
      const std::vector<uint64_t> cells = cells_under(t);
      if (cells.empty()) return false;
      for (uint64_t cell : cells) {
        const auto found = by_cell_.find(cell);
        if (found == by_cell_.end()) continue;
        for (int other : found->second)
          if (overlap(t, triangles_[other])) return false;
      }
    }
    return true;
  }
  void add(const std::vector<Triangle>& face) {
    for (const Triangle& t : face) {
      for (uint64_t cell : cells_under(t)) by_cell_[cell].push_back(static_cast<int>(triangles_.size()));
      triangles_.push_back(t);
      area_ += std::abs(signed_area(t));
      for (const CornerUv& p : t)
        for (int d = 0; d < 2; ++d) lo_[d] = std::min(lo_[d], p[d]), hi_[d] = std::max(hi_[d], p[d]);
    }
  }

 private:
  std::vector<Triangle> triangles_;
  std::unordered_map<uint64_t, std::vector<int>> by_cell_;
  CornerUv lo_{1e300, 1e300}, hi_{-1e300, -1e300};
  double area_ = 0;
};

// Charts grown breadth-first from the lowest unassigned face across continuous sides (see the header).
std::vector<int> grow_charts(const CornerFaces& faces, const std::vector<int>& across, int* count) {
  const int nf = faces.soup.num_faces();
  std::vector<int> chart(nf, -1);
  ChartFootprint footprint;
  *count = 0;
  for (int seed = 0; seed < nf; ++seed) {
    if (chart[seed] >= 0) continue;
    const int id = (*count)++;
    chart[seed] = id;
    footprint.clear();
    const std::vector<Triangle> first = face_triangles(faces, seed);
    if (!footprint.fits(first)) continue;  // flipped or huge in the map: a chart of its own
    footprint.add(first);
    std::deque<int> queue = {seed};
    while (!queue.empty()) {
      const int f = queue.front();
      queue.pop_front();
      for (int c = faces.soup.face_start[f]; c < faces.soup.face_start[f + 1]; ++c) {
        const int o = across[c];
        if (o < 0 || chart[faces.corner_face[o]] >= 0) continue;
        if (!same(faces.uv[c], faces.uv[faces.next(o)]) || !same(faces.uv[faces.next(c)], faces.uv[o])) continue;
        const int g = faces.corner_face[o];
        const std::vector<Triangle> triangles = face_triangles(faces, g);
        if (!footprint.fits(triangles)) continue;
        footprint.add(triangles);
        chart[g] = id;
        queue.push_back(g);
      }
    }
  }
  return chart;
}

// Per chart, the grid point below-left of its corners (lo) and its size in cells.
void chart_boxes(const CornerFaces& faces, const std::vector<int>& chart, int count, std::vector<TexelPoint>* lo,
                 std::vector<TexelPoint>* size) {
  std::vector<std::array<double, 4>> box(count, {1e300, 1e300, -1e300, -1e300});
  for (size_t c = 0; c < faces.uv.size(); ++c) {
    auto& b = box[chart[faces.corner_face[c]]];
    for (int d = 0; d < 2; ++d) b[d] = std::min(b[d], faces.uv[c][d]), b[2 + d] = std::max(b[2 + d], faces.uv[c][d]);
  }
  lo->resize(count);
  size->resize(count);
  for (int k = 0; k < count; ++k)
    for (int d = 0; d < 2; ++d) {
      (*lo)[k][d] = static_cast<int>(std::floor(box[k][d]));
      (*size)[k][d] = std::max(1, static_cast<int>(std::ceil(box[k][2 + d])) - (*lo)[k][d]);
    }
}

void check_inputs(const PolygonSoup& faces, const std::vector<CornerUv>& grid_uv) {
  if (faces.num_faces() == 0) throw Error(ErrorCode::InvalidArgument, "atlas: there are no faces");
  if (grid_uv.size() != faces.face_vertices.size())
    throw Error(ErrorCode::InvalidArgument, "atlas: " + std::to_string(grid_uv.size()) + " grid coordinates for " +
                                                std::to_string(faces.face_vertices.size()) + " face corners");
  for (size_t c = 0; c < grid_uv.size(); ++c)
    if (!(std::abs(grid_uv[c][0]) <= kLargestGrid && std::abs(grid_uv[c][1]) <= kLargestGrid))
      throw Error(ErrorCode::InvalidArgument,
                  "atlas: face corner " + std::to_string(c) + " has no finite grid coordinate within 1e7 units");
}

double grid_area(const CornerFaces& faces) {
  double area = 0;
  for (int f = 0; f < faces.soup.num_faces(); ++f)
    for (const Triangle& t : face_triangles(faces, f)) area += std::abs(signed_area(t));
  return area;
}

}  // namespace

PolygonAtlas build_polygon_atlas(const PolygonSoup& soup, const std::vector<CornerUv>& grid_uv,
                                 const AtlasOptions& options) {
  check_atlas_options(options);
  check_inputs(soup, grid_uv);
  const CornerFaces faces(soup, grid_uv);
  const std::vector<int> across = sides_across(faces);
  PolygonAtlas atlas;
  const double area = grid_area(faces);
  atlas.face_chart = grow_charts(faces, across, &atlas.num_charts);
  std::vector<TexelPoint> lo, size;
  chart_boxes(faces, atlas.face_chart, atlas.num_charts, &lo, &size);
  const AtlasPacking packing =
      pack_atlas(size, area, options,
                 std::to_string(atlas.num_charts) + " charts of " + std::to_string(soup.num_faces()) + " faces");
  const int k = packing.texels_per_quad, W = options.texture_width, H = options.texture_height;
  atlas.corner_uv.resize(grid_uv.size());
  for (size_t c = 0; c < grid_uv.size(); ++c) {
    const int chart = atlas.face_chart[faces.corner_face[c]];
    const ChartPlacement& p = packing.placements[chart];
    const CornerUv r = quarter_turns(CornerUv{grid_uv[c][0] - lo[chart][0], grid_uv[c][1] - lo[chart][1]}, p.turns);
    const CornerUv box_lo = {p.turns == 1 ? -double(size[chart][1]) : 0.0, 0.0};  // the turned box's lowest corner
    for (int d = 0; d < 2; ++d)
      atlas.corner_uv[c][d] = (k * (r[d] - box_lo[d]) + p.offset[d] + packing.gutter / 2) / (d == 0 ? W : H);
  }
  for (size_t c = 0; c < across.size(); ++c) {  // sides whose two corners lie apart in the atlas
    const int o = across[c];
    auto apart = [&](const CornerUv& a, const CornerUv& b) {
      return std::abs(a[0] - b[0]) * W > 0.01 || std::abs(a[1] - b[1]) * H > 0.01;  // texels
    };
    if (o > static_cast<int>(c) && (apart(atlas.corner_uv[c], atlas.corner_uv[faces.next(o)]) ||
                                    apart(atlas.corner_uv[faces.next(static_cast<int>(c))], atlas.corner_uv[o])))
      ++atlas.seam_edges;
  }
  atlas.texels_per_quad = k;
  atlas.texture_width = W;
  atlas.texture_height = H;
  atlas.gutter = packing.gutter;
  atlas.mip_levels = options.mip_levels;
  atlas.texture_use = area * k * k / (double(W) * H);
  return atlas;
}

}  // namespace qgp

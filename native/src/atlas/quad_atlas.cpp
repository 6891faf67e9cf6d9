#include "atlas/quad_atlas.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <deque>
#include <map>
#include <string>
#include <tuple>
#include <unordered_map>
#include <unordered_set>

#include "atlas/packing.h"
#include "core/error.h"

namespace qgp {
namespace {

using Point = std::array<int, 2>;  // a corner of the integer grid (chart or texture cells)

uint64_t point_key(const Point& p) {
  return (static_cast<uint64_t>(static_cast<uint32_t>(p[0])) << 32) | static_cast<uint32_t>(p[1]);
}

// Per quad side (4q + k: from corner k to k + 1), the side of the quad across it (4q' + k'), or -1
// on the boundary and where an edge has more than two quads or two quads facing the same way.
std::vector<int> quad_neighbours(const QuadMesh& quads) {
  std::unordered_map<uint64_t, std::vector<int>> sides;
  for (int q = 0; q < quads.num_quads(); ++q)
    for (int k = 0; k < 4; ++k) {
      const int a = quads.Q(q, k), b = quads.Q(q, (k + 1) % 4);
      sides[point_key({std::min(a, b), std::max(a, b)})].push_back(4 * q + k);
    }
  std::vector<int> across(4 * quads.num_quads(), -1);
  for (const auto& [key, list] : sides) {
    if (list.size() != 2) continue;
    const int s = list[0], t = list[1];
    if (quads.Q(s / 4, s % 4) != quads.Q(t / 4, (t % 4 + 1) % 4)) continue;  // same direction: not oriented
    across[s] = t;
    across[t] = s;
  }
  return across;
}

// Quads around each vertex, and whether the vertex is on the boundary (a side without a quad across).
struct VertexStar {
  std::vector<int> quads;
  std::vector<char> boundary;
};

VertexStar vertex_stars(const QuadMesh& quads, const std::vector<int>& across) {
  VertexStar star{std::vector<int>(quads.num_vertices(), 0), std::vector<char>(quads.num_vertices(), 0)};
  for (int q = 0; q < quads.num_quads(); ++q)
    for (int k = 0; k < 4; ++k) {
      ++star.quads[quads.Q(q, k)];
      if (across[4 * q + k] < 0) star.boundary[quads.Q(q, k)] = star.boundary[quads.Q(q, (k + 1) % 4)] = 1;
    }
  return star;
}

// Marks the sides along the separatrices of the quad mesh's irregular vertices (inside: not 4 quads;
// on the boundary: not 2), traced as a motorcycle graph: every trace goes straight through regular
// vertices, one edge per round, and stops at the boundary, an irregular vertex or a vertex another
// trace has reached. The regions between them are grid rectangles (the layout's patches), so charts
// grown inside them are compact. Returns per side (4q + k) 1 where it is cut.
std::vector<char> separatrix_cuts(const QuadMesh& quads, const std::vector<int>& across) {
  const VertexStar star = vertex_stars(quads, across);
  auto irregular = [&](int v) { return star.quads[v] != (star.boundary[v] ? 2 : 4); };
  std::vector<char> cut(across.size(), 0), reached(quads.num_vertices(), 0);
  std::vector<int> traces;  // the next side to cut per running trace: Q[k] = its start, Q[k + 1] = its end
  for (int q = 0; q < quads.num_quads(); ++q)
    for (int k = 0; k < 4; ++k)
      if (irregular(quads.Q(q, k))) {
        traces.push_back(4 * q + k);
        reached[quads.Q(q, k)] = 1;
      }
  while (!traces.empty()) {
    std::vector<int> running;
    for (int side : traces) {
      if (cut[side]) continue;  // another trace took this edge (the other way, or from the same vertex)
      cut[side] = 1;
      if (across[side] >= 0) cut[across[side]] = 1;
      const int end = quads.Q(side / 4, (side % 4 + 1) % 4);
      if (reached[end] || star.boundary[end] || irregular(end)) continue;
      reached[end] = 1;
      const int turn = across[4 * (side / 4) + (side % 4 + 1) % 4];  // the side after `end` in the next quad
      if (turn >= 0) running.push_back(4 * (turn / 4) + (turn % 4 + 1) % 4);
    }
    traces = std::move(running);
  }
  return cut;
}

// Charts grown over the quads: chart of every quad, and the grid corner of every quad corner.
struct Charts {
  std::vector<int> quad_chart;
  std::vector<Point> corner;  // 4q + k
  int count = 0;
};

// The four corners of the cell across side k of a placed quad, for the quad whose side k2 is that edge.
std::array<Point, 4> corners_across(const std::array<Point, 4>& placed, int k, int k2) {
  const Point a = placed[k], b = placed[(k + 1) % 4];
  const Point out = {b[1] - a[1], a[0] - b[0]};  // right of a -> b, away from the placed cell
  std::array<Point, 4> result;
  result[k2] = b;
  result[(k2 + 1) % 4] = a;
  result[(k2 + 2) % 4] = {a[0] + out[0], a[1] + out[1]};
  result[(k2 + 3) % 4] = {b[0] + out[0], b[1] + out[1]};
  return result;
}

Point cell_of(const std::array<Point, 4>& c) {
  return {std::min({c[0][0], c[1][0], c[2][0], c[3][0]}), std::min({c[0][1], c[1][1], c[2][1], c[3][1]})};
}

// One chart being grown: its occupied cells, and the one place of each vertex and at each point.
class ChartGrowth {
 public:
  explicit ChartGrowth(const QuadMesh& quads) : quads_(quads) {}
  bool fits(int q, const std::array<Point, 4>& c) const {
    if (cells_.count(point_key(cell_of(c)))) return false;
    for (int k = 0; k < 4; ++k) {
      const auto v = vertex_at_.find(point_key(c[k]));
      if (v != vertex_at_.end() && v->second != quads_.Q(q, k)) return false;
      const auto p = place_of_.find(quads_.Q(q, k));
      if (p != place_of_.end() && p->second != c[k]) return false;
    }
    return true;
  }
  void add(int q, const std::array<Point, 4>& c) {
    cells_.insert(point_key(cell_of(c)));
    for (int k = 0; k < 4; ++k) {
      vertex_at_[point_key(c[k])] = quads_.Q(q, k);
      place_of_[quads_.Q(q, k)] = c[k];
    }
  }

 private:
  const QuadMesh& quads_;
  std::unordered_set<uint64_t> cells_;
  std::unordered_map<uint64_t, int> vertex_at_;
  std::unordered_map<int, Point> place_of_;
};

void grow_chart(const QuadMesh& quads, const std::vector<int>& across, const std::vector<char>& cut, int seed,
                Charts& charts) {
  const int id = charts.count++;
  ChartGrowth growth(quads);
  auto place = [&](int q, const std::array<Point, 4>& c) {
    growth.add(q, c);
    charts.quad_chart[q] = id;
    for (int k = 0; k < 4; ++k) charts.corner[4 * q + k] = c[k];
  };
  place(seed, {Point{0, 0}, Point{1, 0}, Point{1, 1}, Point{0, 1}});
  std::deque<int> queue = {seed};
  while (!queue.empty()) {
    const int q = queue.front();
    queue.pop_front();
    std::array<Point, 4> placed;
    for (int k = 0; k < 4; ++k) placed[k] = charts.corner[4 * q + k];
    for (int k = 0; k < 4; ++k) {
      const int side = across[4 * q + k];
      if (side < 0 || cut[4 * q + k] || charts.quad_chart[side / 4] >= 0) continue;
      const std::array<Point, 4> c = corners_across(placed, k, side % 4);
      if (!growth.fits(side / 4, c)) continue;
      place(side / 4, c);
      queue.push_back(side / 4);
    }
  }
}

Point rotate(const Point& p, int turns) { return quarter_turns(p, turns); }

// A chart's cells and the one place of each vertex, for trying a union with another chart.
struct ChartShape {
  std::unordered_set<uint64_t> cells;
  std::unordered_map<uint64_t, int> vertex_at;
  std::unordered_map<int, Point> place_of;
  Point lo{INT32_MAX, INT32_MAX}, hi{INT32_MIN, INT32_MIN};
  void add(const QuadMesh& quads, int q, const std::array<Point, 4>& c) {
    cells.insert(point_key(cell_of(c)));
    for (int k = 0; k < 4; ++k) {
      vertex_at[point_key(c[k])] = quads.Q(q, k);
      place_of[quads.Q(q, k)] = c[k];
      for (int d = 0; d < 2; ++d) lo[d] = std::min(lo[d], c[k][d]), hi[d] = std::max(hi[d], c[k][d]);
    }
  }
};

// Where chart b's corners go in chart a's frame when they are glued along side `side` (of a quad of a) and
// the side across it (of a quad of b): p -> rotate(p, turns) + shift.
struct Glue {
  int turns = 0;
  Point shift{0, 0};
  Point apply(const Point& p) const {
    const Point r = rotate(p, turns);
    return {r[0] + shift[0], r[1] + shift[1]};
  }
};

Glue glue_across(const Charts& charts, int side, int twin) {
  const Point a0 = charts.corner[side], a1 = charts.corner[4 * (side / 4) + (side % 4 + 1) % 4];
  const Point b0 = charts.corner[twin], b1 = charts.corner[4 * (twin / 4) + (twin % 4 + 1) % 4];
  Glue glue;
  while (glue.turns < 4 && rotate({b1[0] - b0[0], b1[1] - b0[1]}, glue.turns) != Point{a0[0] - a1[0], a0[1] - a1[1]})
    ++glue.turns;
  const Point r = rotate(b0, glue.turns);
  glue.shift = {a1[0] - r[0], a1[1] - r[1]};
  return glue;
}

// True (and b's corners moved into a's frame, its quads given to a) when a and b glued along the given
// sides are still injective (no cell twice, each vertex at one place, each place one vertex) and their
// union is a rectangle of cells (so it packs as well as its parts).
bool merge_if_rectangle(const QuadMesh& quads, const std::vector<int>& quads_a, const std::vector<int>& quads_b,
                        const Glue& glue, Charts& charts) {
  ChartShape shape;
  for (int q : quads_a)
    shape.add(quads, q,
              {charts.corner[4 * q], charts.corner[4 * q + 1], charts.corner[4 * q + 2], charts.corner[4 * q + 3]});
  for (int q : quads_b) {
    std::array<Point, 4> c;
    for (int k = 0; k < 4; ++k) c[k] = glue.apply(charts.corner[4 * q + k]);
    if (shape.cells.count(point_key(cell_of(c)))) return false;
    for (int k = 0; k < 4; ++k) {
      const auto v = shape.vertex_at.find(point_key(c[k]));
      if (v != shape.vertex_at.end() && v->second != quads.Q(q, k)) return false;
      const auto p = shape.place_of.find(quads.Q(q, k));
      if (p != shape.place_of.end() && p->second != c[k]) return false;
    }
    shape.add(quads, q, c);
  }
  const long long area = static_cast<long long>(shape.hi[0] - shape.lo[0]) * (shape.hi[1] - shape.lo[1]);
  if (area != static_cast<long long>(shape.cells.size())) return false;
  const int a = charts.quad_chart[quads_a.front()];
  for (int q : quads_b) {
    charts.quad_chart[q] = a;
    for (int k = 0; k < 4; ++k) charts.corner[4 * q + k] = glue.apply(charts.corner[4 * q + k]);
  }
  return true;
}

// Renumbers charts 0.. in the order of their first quad; returns the quads of each.
std::vector<std::vector<int>> renumber_charts(Charts& charts) {
  std::unordered_map<int, int> id;
  std::vector<std::vector<int>> chart_quads;
  for (size_t q = 0; q < charts.quad_chart.size(); ++q) {
    const auto [it, added] = id.emplace(charts.quad_chart[q], static_cast<int>(id.size()));
    if (added) chart_quads.emplace_back();
    charts.quad_chart[q] = it->second;
    chart_quads[it->second].push_back(static_cast<int>(q));
  }
  charts.count = static_cast<int>(chart_quads.size());
  return chart_quads;
}

// One round of merging neighbouring charts into rectangles, pairs sharing the most sides first, each chart
// at most once; returns whether any merged.
bool merge_round(const QuadMesh& quads, const std::vector<int>& across, Charts& charts) {
  const std::vector<std::vector<int>> chart_quads = renumber_charts(charts);
  std::map<std::pair<int, int>, std::pair<int, int>> shared;  // (a, b), a < b -> (sides, one side of a)
  for (size_t s = 0; s < across.size(); ++s) {
    if (across[s] < 0) continue;
    const int a = charts.quad_chart[s / 4], b = charts.quad_chart[across[s] / 4];
    if (a >= b) continue;
    auto& entry = shared.try_emplace({a, b}, 0, static_cast<int>(s)).first->second;
    ++entry.first;
  }
  std::vector<std::tuple<int, int, int, int>> pairs;  // (-sides, a, b, side)
  for (const auto& [ab, entry] : shared) pairs.emplace_back(-entry.first, ab.first, ab.second, entry.second);
  std::sort(pairs.begin(), pairs.end());
  std::vector<char> touched(charts.count, 0);
  bool merged = false;
  for (const auto& [minus_sides, a, b, side] : pairs) {
    if (touched[a] || touched[b]) continue;
    if (!merge_if_rectangle(quads, chart_quads[a], chart_quads[b], glue_across(charts, side, across[side]), charts))
      continue;
    touched[a] = touched[b] = 1;
    merged = true;
  }
  return merged;
}

Charts grow_charts(const QuadMesh& quads, const std::vector<int>& across) {
  const std::vector<char> cut = separatrix_cuts(quads, across);
  Charts charts;
  charts.quad_chart.assign(quads.num_quads(), -1);
  charts.corner.resize(4 * quads.num_quads());
  for (int q = 0; q < quads.num_quads(); ++q)
    if (charts.quad_chart[q] < 0) grow_chart(quads, across, cut, q, charts);
  while (merge_round(quads, across, charts)) {
  }
  renumber_charts(charts);
  return charts;
}

// The lowest corner and the size (in cells) of the chart's corners turned by `turns` * 90 degrees.
void turned_bounds(const Charts& charts, const std::vector<int>& quads, int turns, Point* lo, Point* size) {
  *lo = {INT32_MAX, INT32_MAX};
  Point hi{INT32_MIN, INT32_MIN};
  for (int q : quads)
    for (int k = 0; k < 4; ++k) {
      const Point r = rotate(charts.corner[4 * q + k], turns);
      for (int d = 0; d < 2; ++d) {
        (*lo)[d] = std::min((*lo)[d], r[d]);
        hi[d] = std::max(hi[d], r[d]);
      }
    }
  *size = {hi[0] - (*lo)[0], hi[1] - (*lo)[1]};
}

// Corner coordinates in [0,1]^2 of every quad, from the charts' placements.
void write_corner_uv(const Charts& charts, const std::vector<std::vector<int>>& chart_quads,
                     const std::vector<ChartPlacement>& placements, int texels, QuadAtlas& atlas) {
  atlas.corner_uv.resize(4 * static_cast<int>(charts.quad_chart.size()), 2);
  for (size_t c = 0; c < chart_quads.size(); ++c) {
    const ChartPlacement& p = placements[c];
    Point lo, size;
    turned_bounds(charts, chart_quads[c], p.turns, &lo, &size);
    for (int q : chart_quads[c])
      for (int k = 0; k < 4; ++k) {
        const Point r = rotate(charts.corner[4 * q + k], p.turns);
        const int margin = atlas.gutter / 2;  // the chart's own share of the gutter, left of and below it
        atlas.corner_uv(4 * q + k, 0) = double(texels * (r[0] - lo[0]) + p.offset[0] + margin) / atlas.texture_width;
        atlas.corner_uv(4 * q + k, 1) = double(texels * (r[1] - lo[1]) + p.offset[1] + margin) / atlas.texture_height;
      }
  }
}

int count_seam_edges(const std::vector<int>& across, const std::vector<int>& quad_chart) {
  int seams = 0;
  for (size_t s = 0; s < across.size(); ++s)
    if (across[s] > static_cast<int>(s) && quad_chart[s / 4] != quad_chart[across[s] / 4]) ++seams;
  return seams;
}

void check_quads(const QuadMesh& quads) {
  if (quads.num_quads() == 0) throw Error(ErrorCode::InvalidArgument, "atlas: the quad mesh has no quads");
}

}  // namespace

QuadAtlas build_quad_atlas(const QuadMesh& quads, const AtlasOptions& options) {
  check_atlas_options(options);
  check_quads(quads);
  const std::vector<int> across = quad_neighbours(quads);
  const Charts charts = grow_charts(quads, across);
  std::vector<std::vector<int>> chart_quads(charts.count);
  for (int q = 0; q < quads.num_quads(); ++q) chart_quads[charts.quad_chart[q]].push_back(q);
  std::vector<Point> chart_size(charts.count);  // unturned bounding boxes, in cells
  for (int c = 0; c < charts.count; ++c) {
    Point lo;
    turned_bounds(charts, chart_quads[c], 0, &lo, &chart_size[c]);
  }
  const AtlasPacking packing =
      pack_atlas(chart_size, quads.num_quads(), options,
                 std::to_string(charts.count) + " charts of " + std::to_string(quads.num_quads()) + " quads");
  const int W = options.texture_width, H = options.texture_height, k = packing.texels_per_quad;
  QuadAtlas atlas;
  atlas.quad_chart = charts.quad_chart;
  atlas.num_charts = charts.count;
  atlas.texels_per_quad = k;
  atlas.texture_width = W;
  atlas.texture_height = H;
  atlas.gutter = packing.gutter;
  atlas.mip_levels = options.mip_levels;
  write_corner_uv(charts, chart_quads, packing.placements, k, atlas);
  atlas.seam_edges = count_seam_edges(across, charts.quad_chart);
  atlas.texture_use = double(quads.num_quads()) * k * k / (double(W) * H);
  return atlas;
}

}  // namespace qgp

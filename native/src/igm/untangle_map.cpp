#include "igm/untangle_map.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/error.h"
#include "core/max_min_lp.h"
#include "core/timer.h"

namespace qgp {

namespace {

__int128 doubled_area(const IVec2& a, const IVec2& b, const IVec2& c) {
  return static_cast<__int128>(b[0] - a[0]) * (c[1] - a[1]) - static_cast<__int128>(b[1] - a[1]) * (c[0] - a[0]);
}

// Fewer non-positive triangles, then a larger smallest doubled area, is better.
struct RingKey {
  int bad = 0;
  __int128 smallest = 0;
  bool better_than(const RingKey& o) const { return bad < o.bad || (bad == o.bad && smallest > o.smallest); }
};

}  // namespace

MapUntangleStats untangle_map(const TriMesh& mesh, const std::vector<char>& feature_edges, ExactParametrization& param,
                              Progress& progress, int max_rings) {
  Timer timer;
  MapUntangleStats stats;
  const int nv = mesh.num_vertices(), nf = mesh.num_faces();
  if (static_cast<int>(param.uv.size()) != 3 * nf || static_cast<int>(param.is_cut.size()) != mesh.num_edges())
    throw Error(ErrorCode::Internal, "map untangle: the map does not match the mesh");
  if (!feature_edges.empty() && static_cast<int>(feature_edges.size()) != mesh.num_edges())
    throw Error(ErrorCode::Internal, "map untangle: the feature edges do not match the mesh");
  // Marks the flipped and degenerate triangles of the current map and counts them.
  std::vector<char> bad(nf, 0);
  auto count_bad = [&](int* flipped, int* degenerate) {
    *flipped = *degenerate = 0;
    for (int f = 0; f < nf; ++f) {
      const int s = orient2d_exact(param.uv[3 * f], param.uv[3 * f + 1], param.uv[3 * f + 2]);
      bad[f] = s <= 0;
      *flipped += s < 0;
      *degenerate += s == 0;
    }
  };
  count_bad(&stats.flipped_before, &stats.degenerate_before);
  stats.flipped_after = stats.flipped_before;
  stats.degenerate_after = stats.degenerate_before;
  if (stats.flipped_before + stats.degenerate_before == 0) {
    stats.seconds = timer.seconds();
    return stats;
  }

  // Corners of each vertex; free vertices: no boundary, cut or feature edge, one uv.
  std::vector<std::vector<int>> corners(nv);
  for (int c = 0; c < 3 * nf; ++c) corners[mesh.F(c / 3, c % 3)].push_back(c);
  std::vector<char> free(nv, 1);
  for (int h = 0; h < 3 * nf; ++h) {
    const int e = mesh.edge_of[h];
    if (mesh.is_boundary_edge(e) || param.is_cut[e] || (!feature_edges.empty() && feature_edges[e]))
      free[mesh.from(h)] = free[mesh.to(h)] = 0;
  }
  for (int v = 0; v < nv; ++v)
    for (int c : corners[v])
      if (param.uv[c] != param.uv[corners[v][0]]) free[v] = 0;

  auto ring_key = [&](int v, const IVec2& p) {
    RingKey key;
    bool first = true;
    for (int c : corners[v]) {
      const int f = c / 3, k = c % 3;
      const __int128 area = doubled_area(p, param.uv[3 * f + (k + 1) % 3], param.uv[3 * f + (k + 2) % 3]);
      key.bad += area <= 0;
      if (first || area < key.smallest) key.smallest = area;
      first = false;
    }
    return key;
  };
  // Angle sum of an interior vertex in quarter turns (4 where the map is locally injective and not
  // singular; the corner angles do not depend on the chart).
  std::vector<char> interior(nv, 1);
  for (int h = 0; h < 3 * nf; ++h)
    if (mesh.opposite[h] < 0) interior[mesh.from(h)] = interior[mesh.to(h)] = 0;
  // The rotations of the transitions around an interior vertex, in quarter turns mod 4, fix its
  // angle sum up to whole turns: 4 where they add up to 0, 3 or 5 (index ±1) where odd, 2 or 6 where
  // 2. Those are the sums a locally injective map has.
  std::vector<int> rotation_sum(nv, 0);
  for (int u = 0; u < nv; ++u) {
    for (int c : corners[u]) rotation_sum[u] += param.rotation[c];  // corner c's outgoing halfedge is c
    rotation_sum[u] %= 4;
  }
  auto injective_sum = [&](int u, int turns) {
    const int r = rotation_sum[u];
    return r == 0 ? turns == 4 : r == 2 ? (turns == 2 || turns == 6) : (turns == 3 || turns == 5);
  };
  auto quarter_turns = [&](int u) {
    double sum = 0;
    for (int c : corners[u]) {
      const int f = c / 3, k = c % 3;
      const IVec2 &p = param.uv[c], &a = param.uv[3 * f + (k + 1) % 3], &b = param.uv[3 * f + (k + 2) % 3];
      const double ax = a[0] - p[0], ay = a[1] - p[1], bx = b[0] - p[0], by = b[1] - p[1];
      sum += std::atan2(ax * by - ay * bx, ax * bx + ay * by);
    }
    return static_cast<int>(std::lround(sum / (M_PI / 2)));
  };
  std::vector<double> c_terms;
  std::vector<Vec2> g_terms;
  std::vector<char> moved(nv, 0);
  auto improve = [&](int v) {
    const IVec2 p0 = param.uv[corners[v][0]];
    double scale = 0;
    for (int c : corners[v]) {
      const IVec2& a = param.uv[3 * (c / 3) + (c % 3 + 1) % 3];
      scale += std::hypot(static_cast<double>(a[0] - p0[0]), static_cast<double>(a[1] - p0[1]));
    }
    scale /= corners[v].size();
    if (!(scale > 0)) return false;
    // Areas in units of scale^2, linear in the move d (units of scale).
    c_terms.clear();
    g_terms.clear();
    for (int c : corners[v]) {
      const int f = c / 3, k = c % 3;
      const IVec2& ia = param.uv[3 * f + (k + 1) % 3];
      const IVec2& ib = param.uv[3 * f + (k + 2) % 3];
      const Vec2 a((ia[0] - p0[0]) / scale, (ia[1] - p0[1]) / scale), b((ib[0] - p0[0]) / scale, (ib[1] - p0[1]) / scale);
      c_terms.push_back(a.x() * b.y() - a.y() * b.x());
      g_terms.emplace_back(a.y() - b.y(), b.x() - a.x());
    }
    const Vec2 d = maximize_worst_term(c_terms, g_terms, Vec2::Zero(), 1.0);
    if (d.isZero()) return false;
    const RingKey now = ring_key(v, p0);
    // The interior vertices of v's triangles keep their angle sums, or get one a locally injective
    // map has: no cone appears (a ring wound twice has positive triangles but 8 quarter turns).
    std::vector<int> ring;
    for (int c : corners[v])
      for (int j = 0; j < 3; ++j) {
        const int u = mesh.F(c / 3, j);
        if (interior[u] && std::find(ring.begin(), ring.end(), u) == ring.end()) ring.push_back(u);
      }
    std::vector<int> turns_now(ring.size());
    for (size_t i = 0; i < ring.size(); ++i) turns_now[i] = quarter_turns(ring[i]);
    for (double step = 1; step > 0.1; step *= 0.5) {
      const IVec2 p{p0[0] + static_cast<int64_t>(std::llround(step * d.x() * scale)),
                    p0[1] + static_cast<int64_t>(std::llround(step * d.y() * scale))};
      if (p == p0 || !ring_key(v, p).better_than(now)) continue;
      for (int c : corners[v]) param.uv[c] = p;
      bool cones_kept = true;
      for (size_t i = 0; i < ring.size() && cones_kept; ++i) {
        const int turns = quarter_turns(ring[i]);
        cones_kept = turns == turns_now[i] || injective_sum(ring[i], turns);
      }
      if (cones_kept) {
        moved[v] = 1;
        return true;
      }
      for (int c : corners[v]) param.uv[c] = p0;
    }
    return false;
  };

  // Moves are never undone: the counts after the last round are the result's.
  int fewest = stats.flipped_before + stats.degenerate_before;
  for (int rings = 0; rings <= max_rings && stats.flipped_after + stats.degenerate_after > 0;) {
    progress.check_cancel();
    std::vector<char> in_region(nv, 0);
    for (int f = 0; f < nf; ++f)
      if (bad[f])
        for (int k = 0; k < 3; ++k) in_region[mesh.F(f, k)] = 1;
    for (int r = 0; r < rings; ++r) {
      std::vector<char> next = in_region;
      for (int f = 0; f < nf; ++f)
        if (in_region[mesh.F(f, 0)] || in_region[mesh.F(f, 1)] || in_region[mesh.F(f, 2)])
          for (int k = 0; k < 3; ++k) next[mesh.F(f, k)] = 1;
      in_region.swap(next);
    }
    std::vector<int> movable;
    for (int v = 0; v < nv; ++v)
      if (in_region[v] && free[v]) movable.push_back(v);
    for (int sweep = 0; sweep < 30; ++sweep) {
      progress.check_cancel();
      bool any = false;
      for (int v : movable) any = improve(v) || any;
      if (!any) break;
    }
    count_bad(&stats.flipped_after, &stats.degenerate_after);
    if (stats.flipped_after + stats.degenerate_after < fewest)
      fewest = stats.flipped_after + stats.degenerate_after;
    else
      ++rings;
  }
  stats.moved_vertices = static_cast<int>(std::count(moved.begin(), moved.end(), 1));
  stats.seconds = timer.seconds();
  return stats;
}

}  // namespace qgp

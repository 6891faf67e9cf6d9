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
  int flipped = 0;
  int bad = 0;
  __int128 smallest = 0;
  bool better_than(const RingKey& o) const { return bad < o.bad || (bad == o.bad && smallest > o.smallest); }
};

// How a vertex may move, in the chart of its first corner.
struct Freedom {
  enum Kind { Pinned, Line, Plane } kind = Plane;
  int axis = 0;  // Line: the coordinate that may change
};

// The corners around each vertex and the rotation (quarter turns) that takes the chart of the
// vertex's first corner to each corner's chart; false where the rotations around an interior vertex
// do not add up to none (a cone: it has no consistent move).
bool corner_turns(const TriMesh& mesh, const ExactParametrization& param, const std::vector<int>& corners,
                  std::vector<int8_t>& turn) {
  turn[corners[0]] = 0;
  std::vector<int> stack{corners[0]};
  bool consistent = true;
  auto reach = [&](int c, int r) {
    r = ((r % 4) + 4) % 4;
    if (turn[c] < 0) {
      turn[c] = static_cast<int8_t>(r);
      stack.push_back(c);
    } else if (turn[c] != r) {
      consistent = false;
    }
  };
  while (!stack.empty()) {
    const int c = stack.back();
    stack.pop_back();
    const int f = c / 3, k = c % 3;
    const int out = c, in = 3 * f + (k + 2) % 3;  // the halfedges of f leaving and entering the vertex
    if (const int o = mesh.opposite[out]; o >= 0) reach(3 * (o / 3) + (o % 3 + 1) % 3, turn[c] + param.rotation[out]);
    if (const int o = mesh.opposite[in]; o >= 0) reach(o, turn[c] + param.rotation[in]);
  }
  return consistent;
}

}  // namespace

MapUntangleStats untangle_map(const TriMesh& mesh, const std::vector<char>& pinned,
                              const std::vector<IsolineConstraint>& isolines, ExactParametrization& param,
                              Progress& progress, const MapUntangleOptions& options) {
  const int max_rings = options.max_rings;
  Timer timer;
  MapUntangleStats stats;
  const int nv = mesh.num_vertices(), nf = mesh.num_faces();
  if (static_cast<int>(param.uv.size()) != 3 * nf || static_cast<int>(param.rotation.size()) != 3 * nf)
    throw Error(ErrorCode::Internal, "map untangle: the map does not match the mesh");
  if (!options.cone_turns.empty() && static_cast<int>(options.cone_turns.size()) != nv)
    throw Error(ErrorCode::Internal, "map untangle: the cone angles do not match the mesh");
  if (!pinned.empty() && static_cast<int>(pinned.size()) != nv)
    throw Error(ErrorCode::Internal, "map untangle: the pinned vertices do not match the mesh");
  for (const IsolineConstraint& c : isolines)
    if (c.halfedge < 0 || c.halfedge >= 3 * nf || c.axis < 0 || c.axis > 1)
      throw Error(ErrorCode::Internal, "map untangle: an isoline does not match the mesh");
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

  // Corners of each vertex, their charts' rotations, and how each vertex may move.
  std::vector<std::vector<int>> corners(nv);
  for (int c = 0; c < 3 * nf; ++c) corners[mesh.F(c / 3, c % 3)].push_back(c);
  std::vector<int8_t> turn(3 * nf, -1);
  std::vector<Freedom> freedom(nv);
  for (int v = 0; v < nv; ++v)
    if (corners[v].empty() || (!pinned.empty() && pinned[v]) || !corner_turns(mesh, param, corners[v], turn))
      freedom[v].kind = Freedom::Pinned;
  // An isoline keeps the coordinate `axis` of its corners in its face's chart: in the first
  // corner's chart, the coordinate (axis + turn) % 2.
  std::vector<int> blocked(nv, 0);  // bit a: coordinate a is fixed
  for (const IsolineConstraint& iso : isolines) {
    const int f = iso.halfedge / 3, k = iso.halfedge % 3;
    for (const int c : {3 * f + k, 3 * f + (k + 1) % 3})
      if (turn[c] >= 0) blocked[mesh.F(f, c % 3)] |= 1 << ((iso.axis + turn[c]) % 2);
  }
  for (int v = 0; v < nv; ++v) {
    if (freedom[v].kind == Freedom::Pinned || blocked[v] == 0) continue;
    if (blocked[v] == 3) {
      freedom[v].kind = Freedom::Pinned;
    } else {
      freedom[v].kind = Freedom::Line;
      freedom[v].axis = blocked[v] == 1 ? 1 : 0;
    }
  }

  // The uv of v's corner c after v moves by d in its first corner's chart.
  auto moved_corner = [&](int c, const IVec2& d) {
    const IVec2 r = rotate_quarter(d, turn[c]);
    return IVec2{param.uv[c][0] + r[0], param.uv[c][1] + r[1]};
  };
  auto ring_key = [&](int v, const IVec2& d) {
    RingKey key;
    bool first = true;
    for (int c : corners[v]) {
      const int f = c / 3, k = c % 3;
      const __int128 area = doubled_area(moved_corner(c, d), param.uv[3 * f + (k + 1) % 3], param.uv[3 * f + (k + 2) % 3]);
      key.bad += area <= 0;
      key.flipped += area < 0;
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
    for (int c : corners[u]) sum += exact_corner_angle(param, c);
    return static_cast<int>(std::lround(sum / (M_PI / 2)));
  };
  auto ring_positive = [&](int u) {
    for (int c : corners[u])
      if (orient2d_exact(param.uv[c], param.uv[3 * (c / 3) + (c % 3 + 1) % 3], param.uv[3 * (c / 3) + (c % 3 + 2) % 3]) <= 0)
        return false;
    return true;
  };
  std::vector<double> c_terms, g_line;
  std::vector<Vec2> g_terms;
  std::vector<IVec2> old_uv;
  std::vector<char> moved(nv, 0);
  auto improve = [&](int v) {
    const Freedom& free = freedom[v];
    double scale = 0;
    for (int c : corners[v]) {
      const IVec2 &p = param.uv[c], &a = param.uv[3 * (c / 3) + (c % 3 + 1) % 3];
      scale += std::hypot(static_cast<double>(a[0] - p[0]), static_cast<double>(a[1] - p[1]));
    }
    scale /= corners[v].size();
    if (!(scale > 0)) return false;
    // Areas in units of scale^2, linear in the move d (units of scale, first corner's chart).
    c_terms.clear();
    g_terms.clear();
    g_line.clear();
    for (int c : corners[v]) {
      const int f = c / 3, k = c % 3;
      const IVec2 &p = param.uv[c], &ia = param.uv[3 * f + (k + 1) % 3], &ib = param.uv[3 * f + (k + 2) % 3];
      const Vec2 a((ia[0] - p[0]) / scale, (ia[1] - p[1]) / scale), b((ib[0] - p[0]) / scale, (ib[1] - p[1]) / scale);
      c_terms.push_back(a.x() * b.y() - a.y() * b.x());
      g_terms.push_back(rotate_quarter(Vec2(a.y() - b.y(), b.x() - a.x()), -turn[c]));
      g_line.push_back(g_terms.back()[free.axis]);
    }
    Vec2 d = Vec2::Zero();
    if (free.kind == Freedom::Plane) d = maximize_worst_term(c_terms, g_terms, Vec2::Zero(), 1.0);
    if (free.kind == Freedom::Line) d[free.axis] = maximize_worst_term_1d(c_terms, g_line);
    if (d.isZero()) return false;
    const RingKey now = ring_key(v, IVec2{0, 0});
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
    old_uv.clear();
    for (int c : corners[v]) old_uv.push_back(param.uv[c]);
    for (double step = 1; step > 0.1; step *= 0.5) {
      const IVec2 move{static_cast<int64_t>(std::llround(step * d.x() * scale)),
                       static_cast<int64_t>(std::llround(step * d.y() * scale))};
      if (move == IVec2{0, 0}) continue;
      const RingKey after = ring_key(v, move);
      if (!after.better_than(now) || (options.never_flip && after.flipped > now.flipped)) continue;
      for (int c : corners[v]) param.uv[c] = moved_corner(c, move);
      bool cones_kept = true;
      for (size_t i = 0; i < ring.size() && cones_kept; ++i) {
        const int turns = quarter_turns(ring[i]);
        cones_kept = turns == turns_now[i] || injective_sum(ring[i], turns);
        if (!options.cone_turns.empty() && turns != options.cone_turns[ring[i]] && ring_positive(ring[i])) cones_kept = false;
      }
      if (cones_kept) {
        moved[v] = 1;
        return true;
      }
      for (size_t i = 0; i < corners[v].size(); ++i) param.uv[corners[v][i]] = old_uv[i];
    }
    return false;
  };

  // A vertex whose move failed fails again until something within two rings of it moves (its
  // triangles and its neighbours' angle sums are all the move looks at): it is skipped till then.
  std::vector<char> dirty(nv, 1);
  auto try_improve = [&](int v) {
    if (!dirty[v]) return false;
    if (!improve(v)) {
      dirty[v] = 0;
      return false;
    }
    for (int c : corners[v])
      for (int j = 0; j < 3; ++j)
        for (int c2 : corners[mesh.F(c / 3, j)])
          for (int i = 0; i < 3; ++i) dirty[mesh.F(c2 / 3, i)] = 1;
    return true;
  };
  // Rounds of single-vertex moves over growing regions; `allowed` vertices only. Moves are never
  // undone: the counts after the last round are the result's.
  auto run_rounds = [&](const std::vector<char>& allowed) {
    int fewest = stats.flipped_after + stats.degenerate_after;
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
        if (in_region[v] && allowed[v]) movable.push_back(v);
      for (int sweep = 0; sweep < 30; ++sweep) {
        progress.check_cancel();
        bool any = false;
        for (int v : movable) any = try_improve(v) || any;
        if (!any) break;
      }
      count_bad(&stats.flipped_after, &stats.degenerate_after);
      if (stats.flipped_after + stats.degenerate_after < fewest)
        fewest = stats.flipped_after + stats.degenerate_after;
      else
        ++rings;
    }
  };
  std::vector<char> movable(nv, 0), simple(nv, 0);  // simple: one uv, no constraint
  for (int v = 0; v < nv; ++v) {
    movable[v] = freedom[v].kind != Freedom::Pinned;
    simple[v] = freedom[v].kind == Freedom::Plane && interior[v];
    for (int c : corners[v]) simple[v] = simple[v] && param.uv[c] == param.uv[corners[v][0]];
  }
  // Two orders from the same start, the better result kept (fewer bad triangles; on a tie the
  // first, whose moves stay closer to the folds): every movable vertex at once, or the simple ones
  // first (moving cut and isoline vertices from the start ends worse on some maps, e.g. camelhead
  // at 2 000 and 8 000 quads).
  const ExactParametrization start = param;
  run_rounds(movable);
  if (stats.flipped_after + stats.degenerate_after > 0) {
    const ExactParametrization first = param;
    const MapUntangleStats first_stats = stats;
    const std::vector<char> first_moved = moved;
    param = start;
    std::fill(moved.begin(), moved.end(), 0);
    std::fill(dirty.begin(), dirty.end(), 1);
    count_bad(&stats.flipped_after, &stats.degenerate_after);
    run_rounds(simple);
    run_rounds(movable);
    if (stats.flipped_after + stats.degenerate_after >= first_stats.flipped_after + first_stats.degenerate_after) {
      param = first;
      stats = first_stats;
      moved = first_moved;
      count_bad(&stats.flipped_after, &stats.degenerate_after);
    }
  }
  stats.moved_vertices = static_cast<int>(std::count(moved.begin(), moved.end(), 1));
  stats.seconds = timer.seconds();
  return stats;
}

}  // namespace qgp

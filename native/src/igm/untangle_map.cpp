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

// The state of one untangle: each vertex's corners, their charts and how it may move, and the
// moves made so far. Vertices move one at a time; param is changed in place.
class MapUntangler {
 public:
  MapUntangler(const TriMesh& mesh, ExactParametrization& param, Progress& progress, const MapUntangleOptions& options)
      : mesh_(mesh),
        param_(param),
        progress_(progress),
        options_(options),
        nv_(mesh.num_vertices()),
        nf_(mesh.num_faces()),
        bad_(nf_, 0) {
    count_bad(&stats_.flipped_before, &stats_.degenerate_before);
    stats_.flipped_after = stats_.flipped_before;
    stats_.degenerate_after = stats_.degenerate_before;
  }

  // The counts so far (before any move: the map as given).
  const MapUntangleStats& stats() const { return stats_; }
  bool anything_bad() const { return stats_.flipped_after + stats_.degenerate_after > 0; }

  // Analyses the vertices, then moves them in the two orders and keeps the better result.
  void untangle(const std::vector<char>& pinned, const std::vector<IsolineConstraint>& isolines);

 private:
  void count_bad(int* flipped, int* degenerate);
  void find_corners(const std::vector<char>& pinned);
  void block_isoline_coordinates(const std::vector<IsolineConstraint>& isolines);
  void find_interior_and_rotation_sums();
  IVec2 moved_corner(int c, const IVec2& d) const;
  RingKey ring_key(int v, const IVec2& d) const;
  bool injective_sum(int u, int turns) const;
  int quarter_turns(int u) const;
  bool ring_positive(int u) const;
  double mean_edge_length(int v) const;
  Vec2 best_direction(int v, double scale);
  std::vector<int> interior_ring(int v) const;
  bool step_towards(int v, const Vec2& d, double scale);
  bool improve(int v);
  bool try_improve(int v);
  std::vector<int> region_vertices(int rings, const std::vector<char>& allowed) const;
  void run_rounds(const std::vector<char>& allowed);
  void run_both_orders();

  const TriMesh& mesh_;
  ExactParametrization& param_;
  Progress& progress_;
  const MapUntangleOptions& options_;
  const int nv_, nf_;
  MapUntangleStats stats_;
  std::vector<char> bad_;                  // #F: flipped or degenerate in the current map
  std::vector<std::vector<int>> corners_;  // #V: the corners of each vertex
  std::vector<int8_t> turn_;               // 3#F: quarter turns from the vertex's first corner's chart
  std::vector<Freedom> freedom_;           // #V
  std::vector<char> interior_;             // #V
  std::vector<int> rotation_sum_;          // #V: the transitions' rotations around it, mod 4
  std::vector<char> moved_;                // #V: moved by a kept move
  std::vector<char> dirty_;                // #V: something within two rings moved since it last failed
  std::vector<double> c_terms_, g_line_;   // scratch of best_direction
  std::vector<Vec2> g_terms_;
  std::vector<IVec2> old_uv_;  // scratch of step_towards
};

// Marks the flipped and degenerate triangles of the current map and counts them.
void MapUntangler::count_bad(int* flipped, int* degenerate) {
  *flipped = *degenerate = 0;
  for (int f = 0; f < nf_; ++f) {
    const int s = orient2d_exact(param_.uv[3 * f], param_.uv[3 * f + 1], param_.uv[3 * f + 2]);
    bad_[f] = s <= 0;
    *flipped += s < 0;
    *degenerate += s == 0;
  }
}

// Corners of each vertex, their charts' rotations, and which vertices are pinned.
void MapUntangler::find_corners(const std::vector<char>& pinned) {
  corners_.assign(nv_, {});
  for (int c = 0; c < 3 * nf_; ++c) corners_[mesh_.F(c / 3, c % 3)].push_back(c);
  turn_.assign(3 * nf_, -1);
  freedom_.assign(nv_, Freedom{});
  for (int v = 0; v < nv_; ++v)
    if (corners_[v].empty() || (!pinned.empty() && pinned[v]) || !corner_turns(mesh_, param_, corners_[v], turn_))
      freedom_[v].kind = Freedom::Pinned;
}

// Vertices on isolines slide along them (or stay where two directions meet).
void MapUntangler::block_isoline_coordinates(const std::vector<IsolineConstraint>& isolines) {
  // An isoline keeps the coordinate `axis` of its corners in its face's chart: in the first
  // corner's chart, the coordinate (axis + turn) % 2.
  std::vector<int> blocked(nv_, 0);  // bit a: coordinate a is fixed
  for (const IsolineConstraint& iso : isolines) {
    const int f = iso.halfedge / 3, k = iso.halfedge % 3;
    for (const int c : {3 * f + k, 3 * f + (k + 1) % 3})
      if (turn_[c] >= 0) blocked[mesh_.F(f, c % 3)] |= 1 << ((iso.axis + turn_[c]) % 2);
  }
  for (int v = 0; v < nv_; ++v) {
    if (freedom_[v].kind == Freedom::Pinned || blocked[v] == 0) continue;
    if (blocked[v] == 3) {
      freedom_[v].kind = Freedom::Pinned;
    } else {
      freedom_[v].kind = Freedom::Line;
      freedom_[v].axis = blocked[v] == 1 ? 1 : 0;
    }
  }
}

// The interior vertices and the rotation sums of their transitions.
void MapUntangler::find_interior_and_rotation_sums() {
  // Angle sum of an interior vertex in quarter turns (4 where the map is locally injective and not
  // singular; the corner angles do not depend on the chart).
  interior_.assign(nv_, 1);
  for (int h = 0; h < 3 * nf_; ++h)
    if (mesh_.opposite[h] < 0) interior_[mesh_.from(h)] = interior_[mesh_.to(h)] = 0;
  // The rotations of the transitions around an interior vertex, in quarter turns mod 4, fix its
  // angle sum up to whole turns: 4 where they add up to 0, 3 or 5 (index ±1) where odd, 2 or 6 where
  // 2. Those are the sums a locally injective map has.
  rotation_sum_.assign(nv_, 0);
  for (int u = 0; u < nv_; ++u) {
    for (int c : corners_[u]) rotation_sum_[u] += param_.rotation[c];  // corner c's outgoing halfedge is c
    rotation_sum_[u] %= 4;
  }
}

// The uv of v's corner c after v moves by d in its first corner's chart.
IVec2 MapUntangler::moved_corner(int c, const IVec2& d) const {
  const IVec2 r = rotate_quarter(d, turn_[c]);
  return IVec2{param_.uv[c][0] + r[0], param_.uv[c][1] + r[1]};
}

// How good v's triangles are after v moves by d.
RingKey MapUntangler::ring_key(int v, const IVec2& d) const {
  RingKey key;
  bool first = true;
  for (int c : corners_[v]) {
    const int f = c / 3, k = c % 3;
    const __int128 area =
        doubled_area(moved_corner(c, d), param_.uv[3 * f + (k + 1) % 3], param_.uv[3 * f + (k + 2) % 3]);
    key.bad += area <= 0;
    key.flipped += area < 0;
    if (first || area < key.smallest) key.smallest = area;
    first = false;
  }
  return key;
}

// Whether `turns` is an angle sum a locally injective map has at u.
bool MapUntangler::injective_sum(int u, int turns) const {
  const int r = rotation_sum_[u];
  return r == 0 ? turns == 4 : r == 2 ? (turns == 2 || turns == 6) : (turns == 3 || turns == 5);
}

// The angle sum at u in quarter turns (rounded).
int MapUntangler::quarter_turns(int u) const {
  double sum = 0;
  for (int c : corners_[u]) sum += exact_corner_angle(param_, c);
  return static_cast<int>(std::lround(sum / (M_PI / 2)));
}

// Whether every triangle around u is positive.
bool MapUntangler::ring_positive(int u) const {
  for (int c : corners_[u])
    if (orient2d_exact(param_.uv[c], param_.uv[3 * (c / 3) + (c % 3 + 1) % 3],
                       param_.uv[3 * (c / 3) + (c % 3 + 2) % 3]) <= 0)
      return false;
  return true;
}

// The mean length of v's outgoing uv edges (the unit of its move).
double MapUntangler::mean_edge_length(int v) const {
  double scale = 0;
  for (int c : corners_[v]) {
    const IVec2 &p = param_.uv[c], &a = param_.uv[3 * (c / 3) + (c % 3 + 1) % 3];
    scale += std::hypot(static_cast<double>(a[0] - p[0]), static_cast<double>(a[1] - p[1]));
  }
  scale /= corners_[v].size();
  return scale;
}

// The move of v (units of scale, first corner's chart) that maximizes the smallest area of its
// triangles within its freedom; zero where there is none.
Vec2 MapUntangler::best_direction(int v, double scale) {
  const Freedom& free = freedom_[v];
  // Areas in units of scale^2, linear in the move d (units of scale, first corner's chart).
  c_terms_.clear();
  g_terms_.clear();
  g_line_.clear();
  for (int c : corners_[v]) {
    const int f = c / 3, k = c % 3;
    const IVec2 &p = param_.uv[c], &ia = param_.uv[3 * f + (k + 1) % 3], &ib = param_.uv[3 * f + (k + 2) % 3];
    const Vec2 a((ia[0] - p[0]) / scale, (ia[1] - p[1]) / scale), b((ib[0] - p[0]) / scale, (ib[1] - p[1]) / scale);
    c_terms_.push_back(a.x() * b.y() - a.y() * b.x());
    g_terms_.push_back(rotate_quarter(Vec2(a.y() - b.y(), b.x() - a.x()), -turn_[c]));
    g_line_.push_back(g_terms_.back()[free.axis]);
  }
  Vec2 d = Vec2::Zero();
  if (free.kind == Freedom::Plane) d = maximize_worst_term(c_terms_, g_terms_, Vec2::Zero(), 1.0);
  if (free.kind == Freedom::Line) d[free.axis] = maximize_worst_term_1d(c_terms_, g_line_);
  return d;
}

// The interior vertices of v's triangles (v included where interior), each once.
std::vector<int> MapUntangler::interior_ring(int v) const {
  std::vector<int> ring;
  for (int c : corners_[v])
    for (int j = 0; j < 3; ++j) {
      const int u = mesh_.F(c / 3, j);
      if (interior_[u] && std::find(ring.begin(), ring.end(), u) == ring.end()) ring.push_back(u);
    }
  return ring;
}

// Moves v by d * scale, or by half, a quarter, an eighth of it: the first rounded move that makes
// its triangles better and keeps the cones is kept. false (v unmoved) where none does.
bool MapUntangler::step_towards(int v, const Vec2& d, double scale) {
  const RingKey now = ring_key(v, IVec2{0, 0});
  // The interior vertices of v's triangles keep their angle sums, or get one a locally injective
  // map has: no cone appears (a ring wound twice has positive triangles but 8 quarter turns).
  const std::vector<int> ring = interior_ring(v);
  std::vector<int> turns_now(ring.size());
  for (size_t i = 0; i < ring.size(); ++i) turns_now[i] = quarter_turns(ring[i]);
  old_uv_.clear();
  for (int c : corners_[v]) old_uv_.push_back(param_.uv[c]);
  for (double step = 1; step > 0.1; step *= 0.5) {
    const IVec2 move{static_cast<int64_t>(std::llround(step * d.x() * scale)),
                     static_cast<int64_t>(std::llround(step * d.y() * scale))};
    if (move == IVec2{0, 0}) continue;
    const RingKey after = ring_key(v, move);
    if (!after.better_than(now) || (options_.never_flip && after.flipped > now.flipped)) continue;
    for (int c : corners_[v]) param_.uv[c] = moved_corner(c, move);
    bool cones_kept = true;
    for (size_t i = 0; i < ring.size() && cones_kept; ++i) {
      const int turns = quarter_turns(ring[i]);
      cones_kept = turns == turns_now[i] || injective_sum(ring[i], turns);
      if (!options_.cone_turns.empty() && turns != options_.cone_turns[ring[i]] && ring_positive(ring[i]))
        cones_kept = false;
    }
    if (cones_kept) {
      moved_[v] = 1;
      return true;
    }
    for (size_t i = 0; i < corners_[v].size(); ++i) param_.uv[corners_[v][i]] = old_uv_[i];
  }
  return false;
}

// One move of v towards the best smallest area of its triangles; false where none is kept.
bool MapUntangler::improve(int v) {
  const double scale = mean_edge_length(v);
  if (!(scale > 0)) return false;
  const Vec2 d = best_direction(v, scale);
  if (d.isZero()) return false;
  return step_towards(v, d, scale);
}

// improve(v), skipping v while nothing near it changed since it last failed.
bool MapUntangler::try_improve(int v) {
  // A vertex whose move failed fails again until something within two rings of it moves (its
  // triangles and its neighbours' angle sums are all the move looks at): it is skipped till then.
  if (!dirty_[v]) return false;
  if (!improve(v)) {
    dirty_[v] = 0;
    return false;
  }
  for (int c : corners_[v])
    for (int j = 0; j < 3; ++j)
      for (int c2 : corners_[mesh_.F(c / 3, j)])
        for (int i = 0; i < 3; ++i) dirty_[mesh_.F(c2 / 3, i)] = 1;
  return true;
}

// The `allowed` vertices within `rings` rings of the bad triangles, in index order.
std::vector<int> MapUntangler::region_vertices(int rings, const std::vector<char>& allowed) const {
  std::vector<char> in_region(nv_, 0);
  for (int f = 0; f < nf_; ++f)
    if (bad_[f])
      for (int k = 0; k < 3; ++k) in_region[mesh_.F(f, k)] = 1;
  for (int r = 0; r < rings; ++r) {
    std::vector<char> next = in_region;
    for (int f = 0; f < nf_; ++f)
      if (in_region[mesh_.F(f, 0)] || in_region[mesh_.F(f, 1)] || in_region[mesh_.F(f, 2)])
        for (int k = 0; k < 3; ++k) next[mesh_.F(f, k)] = 1;
    in_region.swap(next);
  }
  std::vector<int> movable;
  for (int v = 0; v < nv_; ++v)
    if (in_region[v] && allowed[v]) movable.push_back(v);
  return movable;
}

// Rounds of single-vertex moves over growing regions; `allowed` vertices only. Moves are never
// undone: the counts after the last round are the result's.
void MapUntangler::run_rounds(const std::vector<char>& allowed) {
  int fewest = stats_.flipped_after + stats_.degenerate_after;
  for (int rings = 0; rings <= options_.max_rings && stats_.flipped_after + stats_.degenerate_after > 0;) {
    progress_.check_cancel();
    const std::vector<int> movable = region_vertices(rings, allowed);
    for (int sweep = 0; sweep < 30; ++sweep) {
      progress_.check_cancel();
      bool any = false;
      for (int v : movable) any = try_improve(v) || any;
      if (!any) break;
    }
    count_bad(&stats_.flipped_after, &stats_.degenerate_after);
    if (stats_.flipped_after + stats_.degenerate_after < fewest)
      fewest = stats_.flipped_after + stats_.degenerate_after;
    else
      ++rings;
  }
}

// Two orders from the same start, the better result kept.
void MapUntangler::run_both_orders() {
  std::vector<char> movable(nv_, 0), simple(nv_, 0);  // simple: one uv, no constraint
  for (int v = 0; v < nv_; ++v) {
    movable[v] = freedom_[v].kind != Freedom::Pinned;
    simple[v] = freedom_[v].kind == Freedom::Plane && interior_[v];
    for (int c : corners_[v]) simple[v] = simple[v] && param_.uv[c] == param_.uv[corners_[v][0]];
  }
  // Two orders from the same start, the better result kept (fewer bad triangles; on a tie the
  // first, whose moves stay closer to the folds): every movable vertex at once, or the simple ones
  // first (moving cut and isoline vertices from the start ends worse on some maps, e.g. camelhead
  // at 2 000 and 8 000 quads).
  const ExactParametrization start = param_;
  run_rounds(movable);
  if (stats_.flipped_after + stats_.degenerate_after > 0) {
    const ExactParametrization first = param_;
    const MapUntangleStats first_stats = stats_;
    const std::vector<char> first_moved = moved_;
    param_ = start;
    std::fill(moved_.begin(), moved_.end(), 0);
    std::fill(dirty_.begin(), dirty_.end(), 1);
    count_bad(&stats_.flipped_after, &stats_.degenerate_after);
    run_rounds(simple);
    run_rounds(movable);
    if (stats_.flipped_after + stats_.degenerate_after >= first_stats.flipped_after + first_stats.degenerate_after) {
      param_ = first;
      stats_ = first_stats;
      moved_ = first_moved;
      count_bad(&stats_.flipped_after, &stats_.degenerate_after);
    }
  }
}

void MapUntangler::untangle(const std::vector<char>& pinned, const std::vector<IsolineConstraint>& isolines) {
  // Corners of each vertex, their charts' rotations, and how each vertex may move.
  find_corners(pinned);
  block_isoline_coordinates(isolines);
  find_interior_and_rotation_sums();
  moved_.assign(nv_, 0);
  dirty_.assign(nv_, 1);
  run_both_orders();
  stats_.moved_vertices = static_cast<int>(std::count(moved_.begin(), moved_.end(), 1));
}

// The checks of untangle_map's arguments (Error(Internal) where they do not match the mesh).
void check_untangle_inputs(const TriMesh& mesh, const std::vector<char>& pinned,
                           const std::vector<IsolineConstraint>& isolines, const ExactParametrization& param,
                           const MapUntangleOptions& options) {
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
}

}  // namespace

MapUntangleStats untangle_map(const TriMesh& mesh, const std::vector<char>& pinned,
                              const std::vector<IsolineConstraint>& isolines, ExactParametrization& param,
                              Progress& progress, const MapUntangleOptions& options) {
  Timer timer;
  check_untangle_inputs(mesh, pinned, isolines, param, options);
  MapUntangler untangler(mesh, param, progress, options);
  if (untangler.anything_bad()) untangler.untangle(pinned, isolines);
  MapUntangleStats stats = untangler.stats();
  stats.seconds = timer.seconds();
  return stats;
}

}  // namespace qgp

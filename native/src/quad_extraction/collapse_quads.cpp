#include "quad_extraction/collapse_quads.h"

#include <algorithm>
#include <array>
#include <numeric>
#include <optional>

#include "core/timer.h"
#include "metrics/quad_metrics.h"
#include "quad_extraction/feature_curves.h"
#include "quad_extraction/surface_projection.h"

namespace qgp {

namespace {

// Parts with more flipped quads than this after the untangle are not collapsed: their flips are
// not local (cycloidal's gear parts keep dozens at every density).
constexpr int kMaxFlippedToCollapse = 32;

// #V: the vertex v and the vertices of the quads around it.
std::vector<char> near_vertex(const QuadMesh& quads, int v) {
  std::vector<char> near(quads.num_vertices(), 0);
  near[v] = 1;
  for (int q = 0; q < quads.num_quads(); ++q)
    if ((quads.Q.row(q).array() == v).any())
      for (int k = 0; k < 4; ++k) near[quads.Q(q, k)] = 1;
  return near;
}

struct Collapsed {
  QuadMesh quads;
  std::vector<int> old_quad;  // per quad: its index before the collapse
  int merged = -1;            // the vertex the diagonal's two corners became
  std::vector<int> touched;   // vertices whose quads changed (merged, dissolved doublets' neighbours)
};

// A quad mesh being edited: quads and vertices are marked dropped, then compacted away.
struct QuadEdit {
  QuadMesh quads;
  std::vector<char> dropped_quad, dropped_vertex;
  std::vector<int> touched;   // vertices whose valence changed
  std::vector<int> old_quad;  // after compact(): per quad, its index before

  explicit QuadEdit(const QuadMesh& q)
      : quads(q), dropped_quad(q.num_quads(), 0), dropped_vertex(q.num_vertices(), 0) {}

  // The quads left around v (v first in each, counter-clockwise).
  std::vector<std::array<int, 4>> quads_at(int v) const {
    std::vector<std::array<int, 4>> around;
    for (int f = 0; f < quads.num_quads(); ++f)
      for (int k = 0; k < 4 && !dropped_quad[f]; ++k)
        if (quads.Q(f, k) == v)
          around.push_back({f, quads.Q(f, (k + 1) % 4), quads.Q(f, (k + 2) % 4), quads.Q(f, (k + 3) % 4)});
    return around;  // {quad, next, opposite, previous}
  }

  // An inner vertex with two quads (v, x, p, y) and (v, y, r, x) left: they become (x, p, y, r) and
  // v goes. False when they do not share both edges at v.
  bool dissolve_doublet(int v) {
    const std::vector<std::array<int, 4>> around = quads_at(v);
    if (around.size() != 2 || around[0][1] != around[1][3] || around[0][3] != around[1][1]) return false;
    const int f = around[0][0], x = around[0][1], p = around[0][2], y = around[0][3], r = around[1][2];
    quads.Q.row(f) << x, p, y, r;
    dropped_quad[around[1][0]] = 1;
    dropped_vertex[v] = 1;
    touched.insert(touched.end(), {x, y});
    return true;
  }

  // Drops the marked quads and vertices; returns each old vertex's new index (-1: dropped).
  std::vector<int> compact() {
    const int nv = quads.num_vertices(), nq = quads.num_quads();
    std::vector<int> index(nv, -1);
    int kept = 0;
    for (int v = 0; v < nv; ++v)
      if (!dropped_vertex[v]) index[v] = kept++;
    QuadMesh out;
    out.V.resize(kept, 3);
    out.vertex_face.resize(kept);
    const bool singular = static_cast<int>(quads.vertex_singular.size()) == nv;
    if (singular) out.vertex_singular.resize(kept);
    for (int v = 0; v < nv; ++v) {
      if (index[v] < 0) continue;
      out.V.row(index[v]) = quads.V.row(v);
      out.vertex_face[index[v]] = quads.vertex_face[v];
      if (singular) out.vertex_singular[index[v]] = quads.vertex_singular[v];
    }
    const bool components = static_cast<int>(quads.component.size()) == nq;
    out.Q.resize(nq - std::count(dropped_quad.begin(), dropped_quad.end(), 1), 4);
    for (int f = 0, row = 0; f < nq; ++f) {
      if (dropped_quad[f]) continue;
      for (int k = 0; k < 4; ++k) out.Q(row, k) = index[quads.Q(f, k)];
      if (components) out.component.push_back(quads.component[f]);
      old_quad.push_back(f);
      ++row;
    }
    quads = std::move(out);
    return index;
  }
};

// A consistently oriented manifold of Euler characteristic `euler`, every vertex in a quad, none of
// the vertices the edit touched (new indices) an inner one with fewer than 3 edges.
bool valid_after_collapse(const QuadTopology& t, int euler, const std::vector<int>& touched) {
  if (t.non_manifold_edges + t.inconsistent_edges + t.degenerate_quads + t.unreferenced_vertices > 0 ||
      t.euler_characteristic != euler)
    return false;
  for (int v : touched)
    if (v >= 0 && !t.on_boundary[v] && t.valence[v] < 3) return false;
  return true;
}

// The quads around v form one fan (a cycle inside, a path on the boundary): merging two vertices
// can join two fans at one vertex, which the edges alone do not show.
bool one_fan(const QuadMesh& quads, int v) {
  std::vector<std::array<int, 2>> around;  // per quad at v: its corners after and before v
  for (int f = 0; f < quads.num_quads(); ++f)
    for (int k = 0; k < 4; ++k)
      if (quads.Q(f, k) == v) around.push_back({quads.Q(f, (k + 1) % 4), quads.Q(f, (k + 3) % 4)});
  if (around.empty()) return false;
  // Start where the fan starts on the boundary (a quad whose corner before v follows none), if anywhere.
  size_t at = 0;
  for (size_t i = 0; i < around.size(); ++i)
    if (std::none_of(around.begin(), around.end(), [&](const std::array<int, 2>& o) { return o[0] == around[i][1]; }))
      at = i;
  std::vector<char> seen(around.size(), 0);
  size_t count = 0;
  while (!seen[at]) {
    seen[at] = 1;
    ++count;
    auto next =
        std::find_if(around.begin(), around.end(), [&](const std::array<int, 2>& o) { return o[1] == around[at][0]; });
    if (next == around.end()) break;
    at = next - around.begin();
  }
  return count == around.size();
}

// Quad q with corners a, c (diagonal 0: corners 0 and 2; 1: corners 1 and 3) merged into one vertex:
// q disappears, every other face stays a quad; a corner between them left with two quads (an inner
// vertex of 3 edges before) is dissolved, its two quads made one (and so on, where that leaves
// another inner vertex with two). Refused (nullopt) when a and c are
// both on the quads' boundary or on a feature or boundary curve of the surface, or when the result
// is not a consistently oriented manifold of the same Euler characteristic. The merged
// vertex takes the place of the one on a curve or boundary, else the surface point nearest the
// middle of the diagonal.
// topology: quad_topology(quads).
std::optional<Collapsed> collapse_diagonal(const QuadMesh& quads, const QuadTopology& topology, int q, int diagonal,
                                           const FeatureCurves& curves, const TriangleBvh& bvh) {
  const int a = quads.Q(q, diagonal), b = quads.Q(q, diagonal + 1), c = quads.Q(q, diagonal + 2),
            d = quads.Q(q, (diagonal + 3) % 4);
  auto constrained = [&](int v) {
    return topology.on_boundary[v] ||
           curves.locate(quads.V.row(v).transpose(), quads.vertex_face[v]).kind != FeatureCurves::Place::kFree;
  };
  const bool a_stays = constrained(a), c_stays = constrained(c);
  if (a_stays && c_stays) return std::nullopt;
  // c goes; a, at its new place, takes its quads.
  QuadEdit edit(quads);
  QuadMesh& m = edit.quads;
  if (c_stays) {
    m.V.row(a) = quads.V.row(c);
    m.vertex_face[a] = quads.vertex_face[c];
  } else if (!a_stays) {
    const TriangleBvh::Hit hit = bvh.closest_point(0.5 * (quads.V.row(a) + quads.V.row(c)).transpose());
    if (hit.triangle < 0) return std::nullopt;
    m.V.row(a) = hit.point.transpose();
    m.vertex_face[a] = hit.triangle;
  }
  for (int f = 0; f < m.num_quads(); ++f)
    for (int k = 0; k < 4; ++k)
      if (m.Q(f, k) == c) m.Q(f, k) = a;
  edit.dropped_quad[q] = 1;
  edit.dropped_vertex[c] = 1;
  edit.touched = {a, b, d};
  // Inner vertices left with two quads are dissolved, and so on where that leaves more.
  for (size_t i = 0; i < edit.touched.size(); ++i) {
    const int v = edit.touched[i];
    if (edit.dropped_vertex[v] || topology.on_boundary[v] || edit.quads_at(v).size() != 2) continue;
    if (!edit.dissolve_doublet(v)) return std::nullopt;
  }
  const std::vector<int> index = edit.compact();
  std::vector<int> touched;
  for (int v : edit.touched) touched.push_back(index[v]);
  const QuadTopology after = quad_topology(m);
  if (!valid_after_collapse(after, topology.euler_characteristic, touched) || !one_fan(m, index[a]))
    return std::nullopt;
  if (!m.vertex_singular.empty())
    for (int v : touched)
      if (v >= 0) m.vertex_singular[v] = after.valence[v] != (after.on_boundary[v] ? 3 : 4);
  Collapsed out;
  out.quads = std::move(m);
  out.merged = index[a];
  for (int v : touched)
    if (v >= 0) out.touched.push_back(v);
  out.old_quad = std::move(edit.old_quad);
  return out;
}

// A quad whose shorter diagonal is under this share of its longer is a sliver: nearly degenerate
// (corner angles under about 11 degrees), and whether it faces with the surface or against it is a
// matter of round-off where it lies along a crease (wingnut with edges over 40 degrees). So is a
// quad with a collapsed edge (metrics/quad_metrics.h), a triangle to the eye, whose two corners the
// untangle could not move apart: cycloidal's 2 000 quads kept 33 such quads without their collapse,
// none with it (and 4.1 % of the diagonal from the surface instead of 3.3 %).
constexpr double kSliverDiagonalRatio = 0.1;
bool is_sliver(const QuadMesh& quads, int q) {
  const double d0 = (quads.V.row(quads.Q(q, 2)) - quads.V.row(quads.Q(q, 0))).norm();
  const double d1 = (quads.V.row(quads.Q(q, 3)) - quads.V.row(quads.Q(q, 1))).norm();
  return std::min(d0, d1) < kSliverDiagonalRatio * std::max(d0, d1) || quad_has_collapsed_edge(quads, q);
}

// Flipped quads, then slivers: fewer is better.
struct Badness {
  int flipped = 0, slivers = 0;
  bool operator<(const Badness& o) const {
    return flipped < o.flipped || (flipped == o.flipped && slivers < o.slivers);
  }
};

// collapse_folded_quads: each flipped or sliver quad, in turn, collapsed along the diagonal that
// leaves the fewest bad quads, if it leaves fewer.
class FoldCollapser {
 public:
  FoldCollapser(QuadMesh& quads, const TriMesh& surface, const std::vector<char>& feature_edges, Progress& progress)
      : quads_(quads), surface_(surface), bvh_(surface), curves_(surface, feature_edges), progress_(progress) {
    flipped_.resize(quads.num_quads());
    for (int q = 0; q < quads.num_quads(); ++q) {
      if ((q & 1023) == 0) progress.check_cancel();
      flipped_[q] = quad_is_flipped(quads, q, surface, bvh_);
    }
    badness_ = {static_cast<int>(std::count(flipped_.begin(), flipped_.end(), 1)), count_slivers(quads)};
    original_.resize(quads.num_quads());
    std::iota(original_.begin(), original_.end(), 0);
    tried_.assign(quads.num_quads(), 0);
    topology_ = quad_topology(quads);
  }

  const Badness& badness() const { return badness_; }

  // The untangle of every quad with a collapsed edge (and every flipped one), before any collapse.
  UntangleStats separate_collapsed_edges() {
    const UntangleStats stats =
        untangle_flipped_quads_near(quads_, surface_, bvh_, curves_, {}, flipped_, progress_, kSeparateRings, true);
    badness_ = {stats.flipped_after, count_slivers(quads_)};
    return stats;
  }

  // Returns the number of quads collapsed.
  int run() {
    // The untangle after each trial collapse reaches a ring of quads around the flipped ones (most
    // folds unfold so, in milliseconds); where quads stay flipped, their trials are repeated with
    // three rings (dragon-genus1 at 500 quads: 1 flipped quad left after one ring, none after three;
    // at 2 000 quads, three rings for every trial took 16 s, one ring 5 s).
    int collapsed = pass(1, false);
    if (badness_.flipped > 0) {
      std::fill(tried_.begin(), tried_.end(), 0);
      collapsed += pass(3, true);
    }
    return collapsed;
  }

 private:
  // One pass over the flipped (and, unless flipped_only, sliver) quads; returns how many collapsed.
  int pass(int rings, bool flipped_only) {
    rings_ = rings;
    flipped_only_ = flipped_only;
    int collapsed = 0;
    for (int q = next_candidate(); q >= 0; q = next_candidate()) {
      tried_[original_[q]] = 1;
      std::optional<Trial> best = best_collapse_of(q);
      // A flipped quad that no diagonal of its own unfolds: a quad beside it may (the fold spans both;
      // in the second pass, also a quad at one of its corners).
      if (!best && flipped_[q])
        for (int n : neighbours(q, flipped_only ? 1 : 2)) {
          std::optional<Trial> trial = best_collapse_of(n);
          if (trial && trial->badness < (best ? best->badness : badness_)) best = std::move(trial);
        }
      if (!best) continue;
      accept(std::move(*best));
      ++collapsed;
    }
    return collapsed;
  }

  struct Trial {
    Collapsed collapsed;
    std::vector<char> flipped;  // per quad of collapsed.quads
    Badness badness;
  };

  static int count_slivers(const QuadMesh& quads) {
    int slivers = 0;
    for (int q = 0; q < quads.num_quads(); ++q) slivers += is_sliver(quads, q);
    return slivers;
  }

  // Quad q's collapse along the diagonal that leaves the fewest bad quads, if fewer than now.
  std::optional<Trial> best_collapse_of(int q) {
    std::optional<Trial> best;
    for (int diagonal : shorter_diagonal_first(q)) {
      std::optional<Trial> trial = try_collapse(q, diagonal);
      if (trial && trial->badness < (best ? best->badness : badness_)) best = std::move(trial);
    }
    return best;
  }

  // The quads sharing at least `min_shared_corners` corners with q (2: an edge).
  std::vector<int> neighbours(int q, int min_shared_corners) const {
    std::vector<int> found;
    for (int f = 0; f < quads_.num_quads(); ++f) {
      int shared = 0;
      for (int k = 0; k < 4; ++k)
        for (int j = 0; j < 4; ++j) shared += quads_.Q(f, k) == quads_.Q(q, j);
      if (f != q && shared >= min_shared_corners) found.push_back(f);
    }
    return found;
  }

  // Of two diagonals as good, the shorter one goes (its corners are the closer ones).
  std::array<int, 2> shorter_diagonal_first(int q) const {
    const double d0 = (quads_.V.row(quads_.Q(q, 2)) - quads_.V.row(quads_.Q(q, 0))).norm();
    const double d1 = (quads_.V.row(quads_.Q(q, 3)) - quads_.V.row(quads_.Q(q, 1))).norm();
    return d1 < d0 ? std::array<int, 2>{1, 0} : std::array<int, 2>{0, 1};
  }

  // The first flipped or sliver quad whose collapse was not tried yet, or -1.
  int next_candidate() const {
    for (int q = 0; q < quads_.num_quads(); ++q)
      if (!tried_[original_[q]] && (flipped_[q] || (!flipped_only_ && is_sliver(quads_, q)))) return q;
    return -1;
  }

  // Quad q collapsed along a diagonal, then untangled around the merged vertex.
  std::optional<Trial> try_collapse(int q, int diagonal) {
    std::optional<Collapsed> collapsed = collapse_diagonal(quads_, topology_, q, diagonal, curves_, bvh_);
    if (!collapsed) return std::nullopt;
    Trial trial;
    QuadMesh& quads = collapsed->quads;
    std::vector<char> touched(quads.num_vertices(), 0);
    for (int v : collapsed->touched) touched[v] = 1;
    trial.flipped.resize(quads.num_quads());
    for (int f = 0; f < quads.num_quads(); ++f) {
      bool changed = false;
      for (int k = 0; k < 4; ++k) changed |= touched[quads.Q(f, k)];
      trial.flipped[f] = changed ? quad_is_flipped(quads, f, surface_, bvh_) : flipped_[collapsed->old_quad[f]];
    }
    const UntangleStats untangle = untangle_flipped_quads_near(
        quads, surface_, bvh_, curves_, near_vertex(quads, collapsed->merged), trial.flipped, progress_, rings_, true);
    trial.badness = {untangle.flipped_after, count_slivers(quads)};
    trial.collapsed = std::move(*collapsed);
    return trial;
  }

  void accept(Trial trial) {
    quads_ = std::move(trial.collapsed.quads);
    std::vector<int> original(trial.collapsed.old_quad.size());
    for (size_t f = 0; f < original.size(); ++f) original[f] = original_[trial.collapsed.old_quad[f]];
    original_ = std::move(original);
    flipped_ = std::move(trial.flipped);
    badness_ = trial.badness;
    topology_ = quad_topology(quads_);
  }

  static constexpr int kSeparateRings = 3;  // as untangle_flipped_quads' default
  int rings_ = 1;                           // of the untangle after a trial collapse
  bool flipped_only_ = false;               // slivers are not candidates
  QuadMesh& quads_;
  const TriMesh& surface_;
  const TriangleBvh bvh_;
  const FeatureCurves curves_;
  Progress& progress_;
  std::vector<char> flipped_;  // per quad
  Badness badness_;
  std::vector<int> original_;  // per quad: its index before any collapse
  std::vector<char> tried_;    // per such index
  QuadTopology topology_;      // of quads_, for every trial until one is kept
};

}  // namespace

bool has_slivers(const QuadMesh& quads) {
  for (int q = 0; q < quads.num_quads(); ++q)
    if (is_sliver(quads, q)) return true;
  return false;
}

UntangleStats collapse_folded_quads(QuadMesh& quads, const TriMesh& surface, const std::vector<char>& feature_edges,
                                    Progress& progress) {
  Timer timer;
  check_untangle_inputs(quads, surface, feature_edges);
  UntangleStats stats;
  FoldCollapser collapser(quads, surface, feature_edges, progress);
  stats.flipped_before = collapser.badness().flipped;
  const UntangleStats separated = collapser.separate_collapsed_edges();
  stats.collapsed_before = separated.collapsed_before;
  if (stats.flipped_before <= kMaxFlippedToCollapse) stats.collapsed_quads = collapser.run();
  stats.flipped_after = collapser.badness().flipped;
  stats.collapsed_after = quads_with_a_collapsed_edge(quads);
  stats.moved_vertices = separated.moved_vertices;
  stats.seconds = timer.seconds();
  return stats;
}

}  // namespace qgp

#include "quad_extraction/untangle_quads.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "core/error.h"
#include "core/max_min_lp.h"
#include "core/timer.h"
#include "metrics/quad_metrics.h"
#include "quad_extraction/feature_curves.h"
#include "quad_extraction/surface_projection.h"

namespace qgp {

namespace {

// How far a free vertex may go from where it started, in its mean edge lengths: the short reach
// first (it keeps the surface best), the longer ones only where quads stay flipped.
constexpr double kReaches[] = {0.5, 1.0, 2.0};
// Gauss-Seidel passes over the free vertices of a region per round.
constexpr int kSweeps = 30;

// The quads around one free vertex v, each as (v, a, b, c) counter-clockwise, with its reference
// normal (unit) and 1 / (its mean edge length)^2, both taken at the start of the round.
struct Star {
  std::vector<std::array<int, 4>> quads;
  std::vector<Vec3> normal;
  std::vector<double> scale;
};

// Five figures per quad of the star, each linear in the position x of its vertex: the four corner
// areas and half the cross product of the diagonals, along the quad's normal, scaled.
void quality_terms(const QuadMesh& quads, const Star& star, const Vec3& x, std::vector<double>& terms) {
  terms.clear();
  for (size_t i = 0; i < star.quads.size(); ++i) {
    Vec3 p[4];
    p[0] = x;
    for (int k = 1; k < 4; ++k) p[k] = quads.V.row(star.quads[i][k]).transpose();
    const Vec3& n = star.normal[i];
    for (int k = 0; k < 4; ++k)
      terms.push_back((p[(k + 1) % 4] - p[k]).cross(p[(k + 3) % 4] - p[k]).dot(n) * star.scale[i]);
    terms.push_back(0.5 * (p[2] - p[0]).cross(p[3] - p[1]).dot(n) * star.scale[i]);
  }
}

// Quads flipped against the surface, then quads with a collapsed edge: fewer is better.
struct Defects {
  int flipped = 0, collapsed = 0;
  bool operator<(const Defects& o) const {
    return flipped < o.flipped || (flipped == o.flipped && collapsed < o.collapsed);
  }
  bool any() const { return flipped + collapsed > 0; }
};

// Fewer defects in the star (a flip: a non-positive diagonal term), then a larger worst term, is
// better. A collapsed edge makes two corner terms zero, which is better than a negative worst term:
// without its own rank the untangle would draw vertices onto their neighbours.
struct StarKey {
  Defects defects;
  double worst = std::numeric_limits<double>::infinity();
  bool better_than(const StarKey& o) const {
    if (defects < o.defects) return true;
    if (o.defects < defects) return false;
    return worst > o.worst + 1e-12;
  }
};
// collapsed: the star's quads with a collapsed edge.
StarKey star_key(const std::vector<double>& terms, int collapsed) {
  StarKey key;
  key.defects.collapsed = collapsed;
  for (size_t i = 0; i < terms.size(); ++i) {
    key.worst = std::min(key.worst, terms[i]);
    if (i % 5 == 4 && !(terms[i] > 0)) ++key.defects.flipped;
  }
  return key;
}

// The star's quads with a collapsed edge (metrics/quad_metrics.h) when its vertex is at x.
int collapsed_edges_in_star(const QuadMesh& quads, const Star& star, const Vec3& x) {
  int collapsed = 0;
  for (const std::array<int, 4>& quad : star.quads) {
    Vec3 p[4];
    p[0] = x;
    for (int k = 1; k < 4; ++k) p[k] = quads.V.row(quad[k]).transpose();
    collapsed += quad_has_collapsed_edge(p);
  }
  return collapsed;
}

// One untangle run over a quad mesh: its adjacency, which vertices may move, and how far.
class Untangler {
 public:
  // flipped: per quad, whether it is flipped, when known (else empty). collapsed_edges: quads with a
  // collapsed edge are untangled too (else they count as any other quad).
  Untangler(QuadMesh& quads, const TriMesh& surface, const TriangleBvh& bvh, const FeatureCurves& curves,
            const std::vector<char>& near, std::vector<char> flipped, bool collapsed_edges, Progress& progress)
      : collapsed_edges_(collapsed_edges),
        quads_(quads),
        surface_(surface),
        bvh_(bvh),
        near_(near),
        curves_(curves),
        progress_(progress),
        start_(quads.V),
        flipped_(std::move(flipped)) {
    const int nv = quads.num_vertices(), nq = quads.num_quads();
    if (static_cast<int>(flipped_.size()) != nq) {
      flipped_.assign(nq, 0);
      for (int q = 0; q < nq; ++q) {
        if ((q & 1023) == 0) progress.check_cancel();
        flipped_[q] = is_flipped(q);
      }
    }
    collapsed_.assign(nq, 0);
    for (int q = 0; q < nq && collapsed_edges_; ++q) collapsed_[q] = quad_has_collapsed_edge(quads, q);
    count_.flipped = static_cast<int>(std::count(flipped_.begin(), flipped_.end(), 1));
    count_.collapsed = static_cast<int>(std::count(collapsed_.begin(), collapsed_.end(), 1));
    if (!count_.any()) return;
    vertex_quads_.resize(nv);
    neighbours_.resize(nv);
    for (int q = 0; q < nq; ++q)
      for (int k = 0; k < 4; ++k) {
        const int v = quads.Q(q, k);
        vertex_quads_[v].push_back(q);
        for (int w : {quads.Q(q, (k + 1) % 4), quads.Q(q, (k + 3) % 4)})
          if (std::find(neighbours_[v].begin(), neighbours_[v].end(), w) == neighbours_[v].end())
            neighbours_[v].push_back(w);
      }
    const QuadTopology topology = quad_topology(quads);
    place_.resize(nv);
    fixed_.assign(nv, 0);
    mean_edge_.assign(nv, 0);
    for (int v = 0; v < nv; ++v) {
      place_[v] = curves_.locate(quads.V.row(v).transpose(), quads.vertex_face[v]);
      // Corners stay; so do vertices of the quads' boundary that are not on the surface's.
      fixed_[v] = place_[v].kind == FeatureCurves::Place::kCorner ||
                  (topology.on_boundary[v] && place_[v].kind != FeatureCurves::Place::kOnCurve) ||
                  vertex_quads_[v].empty();
      for (int w : neighbours_[v]) mean_edge_[v] += (quads.V.row(w) - quads.V.row(v)).norm();
      if (!neighbours_[v].empty()) mean_edge_[v] /= neighbours_[v].size();
    }
    quad_normal_.assign(nq, Vec3::Zero());
    quad_scale_.assign(nq, 0);
    if (collapsed_edges_) release_shared_corners();
  }

  const Defects& defects() const { return count_; }
  const std::vector<char>& flipped() const { return flipped_; }
  // Vertices away from where they started.
  int moved_vertices() const {
    int moved = 0;
    for (int v = 0; v < quads_.num_vertices(); ++v) moved += (quads_.V.row(v) != start_.row(v));
    return moved;
  }

  // One round within `reach` mean edge lengths of the start: the free vertices of the flipped quads
  // and of those with a collapsed edge, and `rings` rings around them, improve their stars in turn;
  // kept only if fewer quads are flipped, or as many and fewer have a collapsed edge.
  bool round(double reach, int rings) {
    progress_.check_cancel();
    const int nv = quads_.num_vertices(), nq = quads_.num_quads();
    std::vector<char> in_region(nv, 0);
    std::vector<int> frontier;
    for (int q = 0; q < nq; ++q)
      if ((flipped_[q] || collapsed_[q]) && seeds(q))
        for (int k = 0; k < 4; ++k)
          if (!in_region[quads_.Q(q, k)]) in_region[quads_.Q(q, k)] = 1, frontier.push_back(quads_.Q(q, k));
    for (int r = 0; r < rings; ++r) {
      std::vector<int> next;
      for (int v : frontier)
        for (int w : neighbours_[v])
          if (!in_region[w]) in_region[w] = 1, next.push_back(w);
      frontier.swap(next);
    }
    std::vector<int> movable, affected;
    std::vector<char> is_affected(nq, 0);
    for (int v = 0; v < nv; ++v)
      if (in_region[v] && !fixed_[v] && mean_edge_[v] > 0) {
        movable.push_back(v);
        for (int q : vertex_quads_[v])
          if (!is_affected[q]) is_affected[q] = 1, affected.push_back(q);
      }
    Defects before;
    for (int q : affected) before.flipped += flipped_[q], before.collapsed += collapsed_[q];
    if (movable.empty() || !before.any()) return false;

    std::vector<Vec3> old_position(movable.size());
    std::vector<int> old_face(movable.size());
    std::vector<FeatureCurves::Place> old_place(movable.size());
    for (size_t i = 0; i < movable.size(); ++i) {
      old_position[i] = quads_.V.row(movable[i]).transpose();
      old_face[i] = quads_.vertex_face[movable[i]];
      old_place[i] = place_[movable[i]];
    }
    for (int q : affected) {
      Vec3 p[4];
      corners(q, p);
      const Vec3 reference = quad_reference_normal(p, surface_, bvh_);
      quad_normal_[q] = reference.norm() > 0 ? reference.normalized() : Vec3::Zero();
      double perimeter = 0;
      for (int k = 0; k < 4; ++k) perimeter += (p[(k + 1) % 4] - p[k]).norm();
      quad_scale_[q] = perimeter > 0 ? 16 / (perimeter * perimeter) : 0;
    }
    // A vertex whose star is as it was when it last found no better place finds none again: only
    // vertices beside one that moved are tried again (the same moves as trying every vertex).
    std::vector<char> stale(nv, 0);
    for (int v : movable) stale[v] = 1;
    for (int sweep = 0; sweep < kSweeps; ++sweep) {
      progress_.check_cancel();
      bool any = false;
      for (int v : movable) {
        if (!stale[v]) continue;
        stale[v] = 0;
        if (!improve_vertex(v, reach * mean_edge_[v])) continue;
        any = true;
        for (int q : vertex_quads_[v])
          for (int k = 0; k < 4; ++k) stale[quads_.Q(q, k)] = 1;
      }
      if (!any) break;
    }
    std::vector<char> now_flipped(affected.size()), now_collapsed(affected.size());
    Defects after;
    for (size_t i = 0; i < affected.size(); ++i) {
      after.flipped += now_flipped[i] = is_flipped(affected[i]);
      after.collapsed += now_collapsed[i] = collapsed_edges_ && quad_has_collapsed_edge(quads_, affected[i]);
    }
    if (after < before) {
      for (size_t i = 0; i < affected.size(); ++i) {
        flipped_[affected[i]] = now_flipped[i];
        collapsed_[affected[i]] = now_collapsed[i];
      }
      count_.flipped -= before.flipped - after.flipped;
      count_.collapsed -= before.collapsed - after.collapsed;
      return true;
    }
    for (size_t i = 0; i < movable.size(); ++i) {
      quads_.V.row(movable[i]) = old_position[i].transpose();
      quads_.vertex_face[movable[i]] = old_face[i];
      place_[movable[i]] = old_place[i];
    }
    return false;
  }

 private:
  // A flipped quad, or one with a collapsed edge, starts a region when it has a vertex in near_ (every
  // such quad when empty).
  bool seeds(int q) const {
    if (near_.empty()) return true;
    for (int k = 0; k < 4; ++k)
      if (near_[quads_.Q(q, k)]) return true;
    return false;
  }
  void corners(int q, Vec3 p[4]) const {
    for (int k = 0; k < 4; ++k) p[k] = quads_.V.row(quads_.Q(q, k)).transpose();
  }
  bool is_flipped(int q) const { return quad_is_flipped(quads_, q, surface_, bvh_); }

  // A vertex on a curve corner that a neighbour shares (a slide stops at a corner, so a second
  // vertex can come to rest there: a collapsed edge that neither could leave) may leave it along the
  // curve edge there that points most towards one of its other neighbours on a curve; the
  // neighbour with the lower index keeps the corner.
  void release_shared_corners() {
    for (int v = 0; v < quads_.num_vertices(); ++v) {
      if (place_[v].kind != FeatureCurves::Place::kCorner || !shares_its_point(v)) continue;
      const Vec3 at = quads_.V.row(v).transpose();
      double best = 0;
      for (const FeatureCurves::Place& exit : curves_.corner_exits(at, quads_.vertex_face[v]))
        for (int w : neighbours_[v]) {
          const Vec3 towards = quads_.V.row(w).transpose() - at;
          if (place_[w].kind == FeatureCurves::Place::kFree || coincident(v, quads_.V.row(w).transpose())) continue;
          const double alignment = curves_.direction_from_end(exit).dot(towards.normalized());
          if (alignment <= best) continue;
          best = alignment;
          place_[v] = exit;
          fixed_[v] = 0;
        }
    }
  }
  // A neighbour with a lower index is coincident with v.
  bool shares_its_point(int v) const {
    for (int w : neighbours_[v])
      if (w < v && coincident(v, quads_.V.row(w).transpose())) return true;
    return false;
  }
  // x lies within kCollapsedEdgeShare of v's mean edge length of v: their edge would be collapsed.
  bool coincident(int v, const Vec3& x) const {
    return (x - quads_.V.row(v).transpose()).norm() <= kCollapsedEdgeShare * mean_edge_[v];
  }
  int collapsed_in_star(const Star& star, const Vec3& x) const {
    return collapsed_edges_ ? collapsed_edges_in_star(quads_, star, x) : 0;
  }
  StarKey key_at(const Star& star, const Vec3& x) {
    quality_terms(quads_, star, x, terms_);
    return star_key(terms_, collapsed_in_star(star, x));
  }
  // Puts v at x (in surface triangle `face`; at `place` on its curve when given) if its star is
  // better there than `now`.
  bool move_if_better(int v, const Star& star, const StarKey& now, const Vec3& x, int face,
                      const FeatureCurves::Place* place = nullptr) {
    if (!key_at(star, x).better_than(now)) return false;
    quads_.V.row(v) = x.transpose();
    quads_.vertex_face[v] = face;
    if (place) place_[v] = *place;
    return true;
  }

  Star star_of(int v) const {
    Star star;
    for (int q : vertex_quads_[v]) {
      int k = 0;
      while (quads_.Q(q, k) != v) ++k;
      star.quads.push_back({v, quads_.Q(q, (k + 1) % 4), quads_.Q(q, (k + 2) % 4), quads_.Q(q, (k + 3) % 4)});
      star.normal.push_back(quad_normal_[q]);
      star.scale.push_back(quad_scale_[q]);
    }
    return star;
  }

  // Moves v, within `reach` of its start, to where the worst quality term of its quads is largest:
  // in its tangent plane and back onto the surface, or along its feature or boundary curve (never
  // onto a corner); true if its star got better.
  bool improve_vertex(int v, double reach) {
    const Star star = star_of(v);
    const Vec3 x0 = quads_.V.row(v).transpose();
    quality_terms(quads_, star, x0, c_);
    const StarKey now = star_key(c_, collapsed_in_star(star, x0));
    const bool spread = now.defects.collapsed > 0;
    if (place_[v].kind == FeatureCurves::Place::kOnCurve)
      return slide_vertex(v, reach, star, now) || (spread && spread_on_curve(v, reach, star, now));
    return move_vertex(v, reach, star, now) || (spread && spread_on_surface(v, reach, star, now));
  }

  // The linear program's move of a free vertex (improve_vertex; c_ holds the star's terms now).
  bool move_vertex(int v, double reach, const Star& star, const StarKey& now) {
    const Vec3 x0 = quads_.V.row(v).transpose(), origin = start_.row(v).transpose();
    const Vec3 n = surface_.face_normal_unnormalized(quads_.vertex_face[v]);
    if (!(n.norm() > 0)) return false;
    // Tangent axes of length `reach`: the linear program works in units of the reach.
    const Vec3 t1 = n.cross(std::abs(n.x()) < 0.9 * n.norm() ? Vec3::UnitX() : Vec3::UnitY()).normalized();
    const Vec3 t2 = n.normalized().cross(t1);
    const Vec3 a1 = reach * t1, a2 = reach * t2;
    g_.assign(c_.size(), Vec2::Zero());
    quality_terms(quads_, star, x0 + a1, terms_);
    for (size_t i = 0; i < c_.size(); ++i) g_[i].x() = terms_[i] - c_[i];
    quality_terms(quads_, star, x0 + a2, terms_);
    for (size_t i = 0; i < c_.size(); ++i) g_[i].y() = terms_[i] - c_[i];
    const Vec2 centre((origin - x0).dot(t1) / reach, (origin - x0).dot(t2) / reach);
    const Vec2 d = maximize_worst_term(c_, g_, centre, std::max(1.0, centre.norm()));
    if (d.isZero()) return false;
    const double allowed = std::max(reach, (x0 - origin).norm());
    for (double step = 1; step > 0.1; step *= 0.5)
      if (project_if_better(v, star, now, x0 + step * (d.x() * a1 + d.y() * a2), origin, allowed)) return true;
    return false;
  }
  // Moves v to the surface point closest to `target` if that is within `allowed` of its origin and
  // better for its star.
  bool project_if_better(int v, const Star& star, const StarKey& now, const Vec3& target, const Vec3& origin,
                         double allowed) {
    const TriangleBvh::Hit hit = bvh_.closest_point(target);
    return hit.triangle >= 0 && (hit.point - origin).norm() <= allowed &&
           move_if_better(v, star, now, hit.point, hit.triangle);
  }

  // A vertex of a collapsed edge whose linear program found no better place (the worst term of its
  // star is elsewhere) goes part of the way towards the middle of its other neighbours, or along its
  // curve either way, where its star gets better (untangling with collapsed_edges only).
  bool spread_on_surface(int v, double reach, const Star& star, const StarKey& now) {
    const Vec3 x0 = quads_.V.row(v).transpose(), origin = start_.row(v).transpose();
    Vec3 middle = Vec3::Zero();
    int count = 0;
    for (int w : neighbours_[v]) {
      const Vec3 x = quads_.V.row(w).transpose();
      if (!coincident(v, x)) middle += x, ++count;
    }
    if (count == 0) return false;
    middle /= count;
    const double allowed = std::max(reach, (x0 - origin).norm());
    for (double step = 0.5; step > 0.05; step *= 0.5)
      if (project_if_better(v, star, now, x0 + step * (middle - x0), origin, allowed)) return true;
    return false;
  }
  bool spread_on_curve(int v, double reach, const Star& star, const StarKey& now) {
    const Vec3 x0 = quads_.V.row(v).transpose(), origin = start_.row(v).transpose();
    const double allowed = std::max(reach, (x0 - origin).norm());
    for (double step = 0.5; step > 0.05; step *= 0.5)
      for (double sign : {1.0, -1.0})
        if (slide_if_better(v, star, now, curves_.walk(place_[v], sign * step * reach), origin, allowed)) return true;
    return false;
  }
  // Slides v to `place` on its curve if that is within `allowed` of its origin, not on a corner (where
  // a quad vertex stays: sliding onto it would collapse their edge), and better for its star.
  bool slide_if_better(int v, const Star& star, const StarKey& now, const FeatureCurves::Place& place,
                       const Vec3& origin, double allowed) {
    const Vec3 x = curves_.point(place);
    return (x - origin).norm() <= allowed && !curves_.at_corner(place) &&
           move_if_better(v, star, now, x, curves_.face(place), &place);
  }

  // The 1-d linear program's slide of a vertex on a curve (improve_vertex; c_ holds the star's terms).
  bool slide_vertex(int v, double reach, const Star& star, const StarKey& now) {
    const Vec3 x0 = quads_.V.row(v).transpose(), origin = start_.row(v).transpose();
    quality_terms(quads_, star, x0 + reach * curves_.direction(place_[v]), terms_);
    std::vector<double> g(c_.size());
    for (size_t i = 0; i < c_.size(); ++i) g[i] = terms_[i] - c_[i];
    const double d = maximize_worst_term_1d(c_, g);
    if (d == 0) return false;
    const double allowed = std::max(reach, (x0 - origin).norm());
    for (double step = 1; step > 0.1; step *= 0.5)
      if (slide_if_better(v, star, now, curves_.walk(place_[v], step * d * reach), origin, allowed)) return true;
    return false;
  }

  const bool collapsed_edges_;
  QuadMesh& quads_;
  const TriMesh& surface_;
  const TriangleBvh& bvh_;
  const std::vector<char>& near_;
  const FeatureCurves& curves_;
  Progress& progress_;
  const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> start_;
  std::vector<char> flipped_, collapsed_;  // per quad: flipped; with a collapsed edge
  Defects count_;
  std::vector<std::vector<int>> vertex_quads_, neighbours_;
  std::vector<FeatureCurves::Place> place_;  // per quad vertex: free, on a curve, or at a corner
  std::vector<char> fixed_;
  std::vector<double> mean_edge_;
  std::vector<Vec3> quad_normal_;  // per quad, at the start of the current round
  std::vector<double> quad_scale_;
  std::vector<double> c_, terms_;  // scratch
  std::vector<Vec2> g_;
};

}  // namespace

UntangleStats untangle_flipped_quads(QuadMesh& quads, const TriMesh& surface, const std::vector<char>& feature_edges,
                                     Progress& progress, int max_rings) {
  check_untangle_inputs(quads, surface, feature_edges);
  const TriangleBvh bvh(surface);
  const FeatureCurves curves(surface, feature_edges);
  std::vector<char> flipped;
  return untangle_flipped_quads_near(quads, surface, bvh, curves, {}, flipped, progress, max_rings, false);
}

void check_untangle_inputs(const QuadMesh& quads, const TriMesh& surface, const std::vector<char>& feature_edges) {
  if (static_cast<int>(quads.vertex_face.size()) != quads.num_vertices())
    throw Error(ErrorCode::Internal, "untangle: the quads have no surface triangle per vertex");
  if (!feature_edges.empty() && static_cast<int>(feature_edges.size()) != surface.num_edges())
    throw Error(ErrorCode::Internal, "untangle: the feature edges do not match the surface");
}

UntangleStats untangle_flipped_quads_near(QuadMesh& quads, const TriMesh& surface, const TriangleBvh& bvh,
                                          const FeatureCurves& curves, const std::vector<char>& near,
                                          std::vector<char>& flipped, Progress& progress, int max_rings,
                                          bool collapsed_edges) {
  Timer timer;
  Untangler untangler(quads, surface, bvh, curves, near, std::move(flipped), collapsed_edges, progress);
  UntangleStats stats;
  stats.flipped_before = untangler.defects().flipped;
  stats.collapsed_before = untangler.defects().collapsed;
  // A round that helped is repeated on what is left; one that did not widens the region.
  for (double reach : kReaches)
    for (int rings = 0; rings <= max_rings && untangler.defects().any();) {
      ++stats.rounds;
      if (untangler.round(reach, rings))
        ++stats.accepted_rounds;
      else
        ++rings;
    }
  stats.flipped_after = untangler.defects().flipped;
  stats.collapsed_after = untangler.defects().collapsed;
  stats.moved_vertices = untangler.moved_vertices();
  stats.seconds = timer.seconds();
  flipped = untangler.flipped();
  return stats;
}

}  // namespace qgp

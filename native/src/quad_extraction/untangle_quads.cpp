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

// Fewer flipped quads (non-positive diagonal term), then a larger worst term, is better.
struct StarKey {
  int flipped = 0;
  double worst = std::numeric_limits<double>::infinity();
  bool better_than(const StarKey& o) const {
    return flipped < o.flipped || (flipped == o.flipped && worst > o.worst + 1e-12);
  }
};
StarKey star_key(const std::vector<double>& terms) {
  StarKey key;
  for (size_t i = 0; i < terms.size(); ++i) {
    key.worst = std::min(key.worst, terms[i]);
    if (i % 5 == 4 && !(terms[i] > 0)) ++key.flipped;
  }
  return key;
}

// One untangle run over a quad mesh: its adjacency, which vertices may move, and how far.
class Untangler {
 public:
  // flipped: per quad, whether it is flipped, when known (else empty).
  Untangler(QuadMesh& quads, const TriMesh& surface, const TriangleBvh& bvh, const FeatureCurves& curves,
            const std::vector<char>& near, std::vector<char> flipped, Progress& progress)
      : quads_(quads),
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
    flipped_count_ = static_cast<int>(std::count(flipped_.begin(), flipped_.end(), 1));
    if (flipped_count_ == 0) return;
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
  }

  int flipped_count() const { return flipped_count_; }
  const std::vector<char>& flipped() const { return flipped_; }
  // Vertices away from where they started.
  int moved_vertices() const {
    int moved = 0;
    for (int v = 0; v < quads_.num_vertices(); ++v) moved += (quads_.V.row(v) != start_.row(v));
    return moved;
  }

  // One round within `reach` mean edge lengths of the start: the free vertices of the flipped quads
  // and `rings` rings around them improve their stars in turn; kept only if fewer quads are flipped.
  bool round(double reach, int rings) {
    progress_.check_cancel();
    const int nv = quads_.num_vertices(), nq = quads_.num_quads();
    std::vector<char> in_region(nv, 0);
    std::vector<int> frontier;
    for (int q = 0; q < nq; ++q)
      if (flipped_[q] && seeds(q))
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
    int before = 0;
    for (int q : affected) before += flipped_[q];
    if (movable.empty() || before == 0) return false;

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
    std::vector<char> now(affected.size());
    int after = 0;
    for (size_t i = 0; i < affected.size(); ++i) after += now[i] = is_flipped(affected[i]);
    if (after < before) {
      for (size_t i = 0; i < affected.size(); ++i) flipped_[affected[i]] = now[i];
      flipped_count_ -= before - after;
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
  // A flipped quad starts a region when it has a vertex in near_ (every flipped quad when empty).
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
  // in its tangent plane and back onto the surface, or along its feature or boundary curve; true if
  // its star got better.
  bool improve_vertex(int v, double reach) {
    if (place_[v].kind == FeatureCurves::Place::kOnCurve) return slide_vertex(v, reach);
    const Star star = star_of(v);
    const Vec3 x0 = quads_.V.row(v).transpose(), origin = start_.row(v).transpose();
    const Vec3 n = surface_.face_normal_unnormalized(quads_.vertex_face[v]);
    if (!(n.norm() > 0)) return false;
    // Tangent axes of length `reach`: the linear program works in units of the reach.
    const Vec3 t1 = n.cross(std::abs(n.x()) < 0.9 * n.norm() ? Vec3::UnitX() : Vec3::UnitY()).normalized();
    const Vec3 t2 = n.normalized().cross(t1);
    const Vec3 a1 = reach * t1, a2 = reach * t2;
    quality_terms(quads_, star, x0, c_);
    const StarKey now = star_key(c_);
    g_.assign(c_.size(), Vec2::Zero());
    quality_terms(quads_, star, x0 + a1, terms_);
    for (size_t i = 0; i < c_.size(); ++i) g_[i].x() = terms_[i] - c_[i];
    quality_terms(quads_, star, x0 + a2, terms_);
    for (size_t i = 0; i < c_.size(); ++i) g_[i].y() = terms_[i] - c_[i];
    const Vec2 centre((origin - x0).dot(t1) / reach, (origin - x0).dot(t2) / reach);
    const Vec2 d = maximize_worst_term(c_, g_, centre, std::max(1.0, centre.norm()));
    if (d.isZero()) return false;
    const double allowed = std::max(reach, (x0 - origin).norm());
    for (double step = 1; step > 0.1; step *= 0.5) {
      const TriangleBvh::Hit hit = bvh_.closest_point(x0 + step * (d.x() * a1 + d.y() * a2));
      if (hit.triangle < 0 || (hit.point - origin).norm() > allowed) continue;
      quality_terms(quads_, star, hit.point, terms_);
      if (!star_key(terms_).better_than(now)) continue;
      quads_.V.row(v) = hit.point.transpose();
      quads_.vertex_face[v] = hit.triangle;
      return true;
    }
    return false;
  }

  bool slide_vertex(int v, double reach) {
    const Star star = star_of(v);
    const Vec3 x0 = quads_.V.row(v).transpose(), origin = start_.row(v).transpose();
    quality_terms(quads_, star, x0, c_);
    const StarKey now = star_key(c_);
    quality_terms(quads_, star, x0 + reach * curves_.direction(place_[v]), terms_);
    std::vector<double> g(c_.size());
    for (size_t i = 0; i < c_.size(); ++i) g[i] = terms_[i] - c_[i];
    const double d = maximize_worst_term_1d(c_, g);
    if (d == 0) return false;
    const double allowed = std::max(reach, (x0 - origin).norm());
    for (double step = 1; step > 0.1; step *= 0.5) {
      const FeatureCurves::Place place = curves_.walk(place_[v], step * d * reach);
      const Vec3 x = curves_.point(place);
      if ((x - origin).norm() > allowed) continue;
      quality_terms(quads_, star, x, terms_);
      if (!star_key(terms_).better_than(now)) continue;
      quads_.V.row(v) = x.transpose();
      quads_.vertex_face[v] = curves_.face(place);
      place_[v] = place;
      return true;
    }
    return false;
  }

  QuadMesh& quads_;
  const TriMesh& surface_;
  const TriangleBvh& bvh_;
  const std::vector<char>& near_;
  const FeatureCurves& curves_;
  Progress& progress_;
  const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> start_;
  std::vector<char> flipped_;  // per quad
  int flipped_count_ = 0;
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
  return untangle_flipped_quads_near(quads, surface, bvh, curves, {}, flipped, progress, max_rings);
}

void check_untangle_inputs(const QuadMesh& quads, const TriMesh& surface, const std::vector<char>& feature_edges) {
  if (static_cast<int>(quads.vertex_face.size()) != quads.num_vertices())
    throw Error(ErrorCode::Internal, "untangle: the quads have no surface triangle per vertex");
  if (!feature_edges.empty() && static_cast<int>(feature_edges.size()) != surface.num_edges())
    throw Error(ErrorCode::Internal, "untangle: the feature edges do not match the surface");
}

UntangleStats untangle_flipped_quads_near(QuadMesh& quads, const TriMesh& surface, const TriangleBvh& bvh,
                                          const FeatureCurves& curves, const std::vector<char>& near,
                                          std::vector<char>& flipped, Progress& progress, int max_rings) {
  Timer timer;
  Untangler untangler(quads, surface, bvh, curves, near, std::move(flipped), progress);
  UntangleStats stats;
  stats.flipped_before = untangler.flipped_count();
  // A round that helped is repeated on what is left; one that did not widens the region.
  for (double reach : kReaches)
    for (int rings = 0; rings <= max_rings && untangler.flipped_count() > 0;) {
      ++stats.rounds;
      if (untangler.round(reach, rings))
        ++stats.accepted_rounds;
      else
        ++rings;
    }
  stats.flipped_after = untangler.flipped_count();
  stats.moved_vertices = untangler.moved_vertices();
  stats.seconds = timer.seconds();
  flipped = untangler.flipped();
  return stats;
}

}  // namespace qgp

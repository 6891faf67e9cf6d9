#include "intake/edge_collapse.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <tuple>

namespace qgp {

namespace {

// Symmetric 4x4 quadric of squared distances to planes, upper triangle row by row.
struct Quadric {
  std::array<double, 10> q{};

  static Quadric of_plane(const Vec3& n, double d, double weight) {
    Quadric p;
    p.q = {n.x() * n.x(), n.x() * n.y(), n.x() * n.z(), n.x() * d, n.y() * n.y(),
           n.y() * n.z(), n.y() * d,     n.z() * n.z(), n.z() * d, d * d};
    for (double& x : p.q) x *= weight;
    return p;
  }
  void add(const Quadric& o) {
    for (int i = 0; i < 10; ++i) q[i] += o.q[i];
  }
  double at(const Vec3& p) const {
    const double x = p.x(), y = p.y(), z = p.z();
    return q[0] * x * x + 2 * q[1] * x * y + 2 * q[2] * x * z + 2 * q[3] * x + q[4] * y * y + 2 * q[5] * y * z +
           2 * q[6] * y + q[7] * z * z + 2 * q[8] * z + q[9];
  }
  double at_sum(const Quadric& o, const Vec3& p) const {
    Quadric s = *this;
    s.add(o);
    return s.at(p);
  }
};

// One candidate collapse: `from` goes into `to` (which stays where it is).
struct Candidate {
  double error;
  int from, to;
  bool operator<(const Candidate& o) const { return std::tie(error, from, to) < std::tie(o.error, o.from, o.to); }
};

// Longest edge over its height (2 area = |normal|); infinite for a degenerate triangle.
double aspect_ratio(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& normal) {
  const double longest = std::max({(b - a).squaredNorm(), (c - b).squaredNorm(), (a - c).squaredNorm()});
  const double twice_area = normal.norm();
  return twice_area > 0 ? longest / twice_area : INFINITY;
}

// A pass tries the lowest quarter of the candidates (and at least as many as collapses are needed),
// past that only until an eighth of the needed collapses are made; the passes stop when one over
// every candidate removes less than 0.1 % of the faces.
constexpr double kPassWindow = 0.25;
constexpr double kPassMinimum = 0.125;
constexpr double kStallFraction = 1e-3;

class EdgeCollapser {
 public:
  EdgeCollapser(const TriMesh& mesh, const std::vector<char>& locked, const EdgeCollapseOptions& options)
      : mesh_(mesh),
        options_(options),
        min_cos_(std::cos(options.max_normal_deviation_deg * M_PI / 180.0)),
        locked_(locked),
        changed_(mesh.num_vertices(), 0),
        removed_(mesh.num_vertices(), 0),
        stamp_(mesh.num_vertices(), 0) {
    faces_.resize(mesh.num_faces());
    for (int f = 0; f < mesh.num_faces(); ++f) faces_[f] = {mesh.F(f, 0), mesh.F(f, 1), mesh.F(f, 2)};
    face_alive_.assign(faces_.size(), 1);
    alive_faces_ = mesh.num_faces();
    accumulate_quadrics();
  }

  // Passes until the budget is met or a pass over every candidate removes almost nothing (the
  // checks refuse the rest: a noisy scan's spikes).
  void run(Progress& progress) {
    while (alive_faces_ > options_.max_faces) {
      progress.check_cancel();
      const int before = alive_faces_;
      const bool scanned_all = collapse_one_pass();
      if (alive_faces_ == before || (scanned_all && before - alive_faces_ < before * kStallFraction)) break;
    }
  }

  FaceMatrix remaining_faces() const {
    FaceMatrix F(alive_faces_, 3);
    int row = 0;
    for (size_t f = 0; f < faces_.size(); ++f)
      if (face_alive_[f]) F.row(row++) << faces_[f][0], faces_[f][1], faces_[f][2];
    return F;
  }

 private:
  Vec3 position(int v) const { return mesh_.position(v); }

  Vec3 normal(const std::array<int, 3>& t) const {
    return (position(t[1]) - position(t[0])).cross(position(t[2]) - position(t[0]));
  }

  void accumulate_quadrics() {
    quadrics_.assign(mesh_.num_vertices(), Quadric{});
    for (const auto& t : faces_) {
      const Vec3 n = normal(t);
      const double twice_area = n.norm();
      if (twice_area <= 0) continue;
      const Vec3 unit = n / twice_area;
      const Quadric plane = Quadric::of_plane(unit, -unit.dot(position(t[0])), 0.5 * twice_area);
      for (int v : t) quadrics_[v].add(plane);
    }
  }

  // Vertex -> alive faces, packed; a collapse appends the survivor's new list at the end.
  void index_vertex_faces() {
    first_.assign(mesh_.num_vertices() + 1, 0);
    for (size_t f = 0; f < faces_.size(); ++f)
      if (face_alive_[f])
        for (int v : faces_[f]) ++first_[v + 1];
    for (int v = 0; v < mesh_.num_vertices(); ++v) first_[v + 1] += first_[v];
    count_.assign(mesh_.num_vertices(), 0);
    refs_.assign(first_.back(), 0);
    for (size_t f = 0; f < faces_.size(); ++f)
      if (face_alive_[f])
        for (int v : faces_[f]) refs_[first_[v] + count_[v]++] = static_cast<int>(f);
  }

  template <class Visit>
  void for_each_face(int v, Visit visit) const {
    for (int i = first_[v], end = first_[v] + count_[v]; i < end; ++i)
      if (face_alive_[refs_[i]]) visit(refs_[i]);
  }

  // Both directions of every edge whose removed endpoint is free (unsorted).
  std::vector<Candidate> collapse_candidates() const {
    std::vector<Candidate> candidates;
    for (size_t f = 0; f < faces_.size(); ++f) {
      if (!face_alive_[f]) continue;
      for (int k = 0; k < 3; ++k) {
        const int a = faces_[f][k], b = faces_[f][(k + 1) % 3];
        if (a > b) continue;  // an interior edge's other half (boundary edges are locked)
        if (!locked_[a]) candidates.push_back({quadrics_[a].at_sum(quadrics_[b], position(b)), a, b});
        if (!locked_[b]) candidates.push_back({quadrics_[b].at_sum(quadrics_[a], position(a)), b, a});
      }
    }
    return candidates;
  }

  // One pass in error order, each vertex in at most one collapse. It tries the lowest
  // kPassWindow of the candidates (at least as many as collapses are still needed), and past them
  // only until kPassMinimum of the needed collapses are made. True when it tried every candidate.
  bool collapse_one_pass() {
    index_vertex_faces();
    std::fill(changed_.begin(), changed_.end(), 0);
    std::vector<Candidate> candidates = collapse_candidates();
    const int needed = (alive_faces_ - options_.max_faces + 1) / 2;
    const size_t window = std::min(candidates.size(), std::max(static_cast<size_t>(2 * needed),
                                                               static_cast<size_t>(kPassWindow * candidates.size())));
    const int minimum = std::max(1, static_cast<int>(kPassMinimum * needed));
    int collapses = 0;
    // Sorted up to the window first; the rest only if the pass goes past it.
    std::nth_element(candidates.begin(), candidates.begin() + window, candidates.end());
    std::sort(candidates.begin(), candidates.begin() + window);
    bool rest_sorted = false;
    size_t i = 0;
    for (; i < candidates.size() && alive_faces_ > options_.max_faces; ++i) {
      if (i >= window) {
        if (collapses >= minimum) break;
        if (!rest_sorted) std::sort(candidates.begin() + window, candidates.end());
        rest_sorted = true;
      }
      const Candidate& c = candidates[i];
      if (removed_[c.from] || removed_[c.to] || changed_[c.from] || changed_[c.to]) continue;
      if (!link_condition_holds(c.from, c.to) || !geometry_allows(c.from, c.to)) continue;
      collapse(c.from, c.to);
      ++collapses;
    }
    return i == candidates.size();
  }

  int alive_face_count(int v) const {
    int n = 0;
    for_each_face(v, [&](int) { ++n; });
    return n;
  }

  // The endpoints' one-rings share exactly the edge's two opposite vertices.
  // Neither opposite vertex is left with fewer than three faces (a tetrahedron would fold into two
  // faces back to back).
  bool link_condition_holds(int from, int to) {
    bool opposite_too_thin = false;
    for_each_face(from, [&](int f) {
      for (int w : faces_[f])
        if (w != from && w != to && (faces_[f][0] == to || faces_[f][1] == to || faces_[f][2] == to))
          opposite_too_thin |= alive_face_count(w) <= 3;
    });
    if (opposite_too_thin) return false;
    const int mark = ++stamp_value_, seen = ++stamp_value_;
    for_each_face(from, [&](int f) {
      for (int w : faces_[f])
        if (w != from) stamp_[w] = mark;
    });
    int common = 0;
    for_each_face(to, [&](int f) {
      for (int w : faces_[f])
        if (w != to && w != from && stamp_[w] == mark) stamp_[w] = seen, ++common;
    });
    return common == 2;
  }

  // No face of `from` turns by more than the allowed angle or degenerates, and the worst aspect
  // ratio stays acceptable.
  bool geometry_allows(int from, int to) const {
    const Vec3 target = position(to);
    double worst_before = 0, worst_after = 0;
    bool allowed = true;
    for_each_face(from, [&](int f) {
      const std::array<int, 3>& t = faces_[f];
      const Vec3 before = normal(t);
      worst_before = std::max(worst_before, aspect_ratio(position(t[0]), position(t[1]), position(t[2]), before));
      if (!allowed || t[0] == to || t[1] == to || t[2] == to) return;
      std::array<Vec3, 3> p = {position(t[0]), position(t[1]), position(t[2])};
      for (int k = 0; k < 3; ++k)
        if (t[k] == from) p[k] = target;
      const Vec3 after = (p[1] - p[0]).cross(p[2] - p[0]);
      const double norms = before.norm() * after.norm();
      if (before.norm() == 0) {
        allowed = after.norm() > 0;  // a degenerate face may only become a proper one
      } else if (!(norms > 0) || before.dot(after) < min_cos_ * norms) {
        allowed = false;
      }
      worst_after = std::max(worst_after, aspect_ratio(p[0], p[1], p[2], after));
    });
    return allowed && (worst_after < options_.max_aspect_ratio || worst_after < worst_before);
  }

  void collapse(int from, int to) {
    const int start = static_cast<int>(refs_.size());
    for_each_face(to, [&](int f) {
      for (int w : faces_[f])
        if (w == from) {
          face_alive_[f] = 0;
          --alive_faces_;
          return;
        }
      refs_.push_back(f);
    });
    for_each_face(from, [&](int f) {
      for (int& w : faces_[f])
        if (w == from) w = to;
      refs_.push_back(f);
    });
    first_[to] = start;
    count_[to] = static_cast<int>(refs_.size()) - start;
    count_[from] = 0;
    quadrics_[to].add(quadrics_[from]);
    removed_[from] = changed_[to] = 1;
  }

  const TriMesh& mesh_;
  const EdgeCollapseOptions options_;
  const double min_cos_;
  const std::vector<char>& locked_;
  std::vector<std::array<int, 3>> faces_;
  std::vector<char> face_alive_;
  int alive_faces_ = 0;
  std::vector<Quadric> quadrics_;
  std::vector<char> changed_;  // survivor of a collapse in this pass
  std::vector<char> removed_;
  std::vector<int> first_, count_, refs_;
  std::vector<int> stamp_;
  int stamp_value_ = 0;
};

}  // namespace

FaceMatrix collapse_edges(const TriMesh& mesh, const std::vector<char>& locked, const EdgeCollapseOptions& options,
                          Progress& progress) {
  EdgeCollapseOptions checked = options;
  checked.max_faces = std::max(checked.max_faces, 0);
  EdgeCollapser collapser(mesh, locked, checked);
  collapser.run(progress);
  return collapser.remaining_faces();
}

}  // namespace qgp

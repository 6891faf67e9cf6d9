#include "core/max_min_lp.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace qgp {

namespace {

struct Octagon {
  Vec2 centre;
  double radius = 1;
  Vec2 corner[8], side[8];
  Octagon(const Vec2& c, double r) : centre(c), radius(r) {
    for (int k = 0; k < 8; ++k) {
      side[k] = Vec2(std::cos(k * M_PI / 4), std::sin(k * M_PI / 4));
      corner[k] = c + r / std::cos(M_PI / 8) * Vec2(std::cos((k + 0.5) * M_PI / 4), std::sin((k + 0.5) * M_PI / 4));
    }
  }
};

struct Candidate {
  Vec2 d;
  double worst;
};

// The candidates of the octagon (corners, sides) in their order, each judged by all terms: the
// first strictly best one. `ceiling`: no point's worst term exceeds it, so the first candidate that
// reaches it is that one and the enumeration ends there.
class CandidateSearch {
 public:
  CandidateSearch(const std::vector<double>& c, const std::vector<Vec2>& g, const Octagon& octagon, double ceiling)
      : c_(c), g_(g), octagon_(octagon), m_(c.size()), ceiling_(ceiling), rounding_(m_) {
    best_value_ = worst(best_);
    // A bound on each term's rounding anywhere in the octagon, far above the error of any sum of its
    // parts there.
    double extent = 0;  // the largest coordinate of a point of the octagon
    for (const Vec2& corner : octagon_.corner) extent = std::max(extent, corner.cwiseAbs().maxCoeff());
    for (size_t i = 0; i < m_; ++i) rounding_[i] = 1e-9 * (1 + std::abs(c_[i]) + g_[i].cwiseAbs().sum() * extent);
  }

  Candidate run() {
    if (best_value_ < ceiling_ && !corners_and_sides()) three_term_points();
    return {best_, best_value_};
  }

 private:
  bool inside(const Vec2& d) const {
    for (const Vec2& u : octagon_.side)
      if (u.dot(d - octagon_.centre) > octagon_.radius * (1 + 1e-9)) return false;
    return true;
  }
  double term(size_t i, const Vec2& d) const { return c_[i] + g_[i].dot(d); }
  double worst(const Vec2& d) const {
    double w = std::numeric_limits<double>::infinity();
    for (size_t i = 0; i < m_; ++i) w = std::min(w, term(i, d));
    return w;
  }
  // d replaces the best when its worst term is larger. The terms are tried from the one that was
  // worst at the last best point, and the first at or below the best value rules d out: the same
  // answer as evaluating them all, without the O(m) cost for almost every candidate.
  bool beats_best(const Vec2& d) {
    if (term(first_, d) <= best_value_) return false;
    for (size_t i = 0; i < m_; ++i)
      if (term(i, d) <= best_value_) {
        first_ = i;
        return false;
      }
    return true;
  }
  // d becomes the best; true once the best reaches the ceiling.
  bool take(const Vec2& d) {
    best_value_ = worst(d);
    best_ = d;
    return best_value_ >= ceiling_;
  }
  bool consider(const Vec2& d) { return beats_best(d) && take(d); }

  // Each corner, then the points of the side before it where two terms are equal. True once the
  // best reaches the ceiling.
  bool corners_and_sides() {
    at_corner_.resize(8 * m_);
    for (int k = 0; k < 8; ++k)
      for (size_t i = 0; i < m_; ++i) at_corner_[k * m_ + i] = term(i, octagon_.corner[k]);
    for (int k = 0; k < 8; ++k) {
      if (consider(octagon_.corner[k])) return true;
      const Vec2 a = octagon_.corner[(k + 7) % 8], b = octagon_.corner[k];
      index_side((k + 7) % 8, k);
      for (size_t p = 0; p < alive_.size(); ++p) {
        const size_t i = alive_[p];
        for (size_t q = p + 1; q < alive_.size(); ++q) {
          const size_t j = alive_[q];
          if (!may_meet_on_side(i, j)) continue;
          const Vec2 dg = g_[i] - g_[j];
          const double slope = dg.dot(b - a);
          if (std::abs(slope) < 1e-14) continue;
          const double s = -(c_[i] - c_[j] + dg.dot(a)) / slope;
          if (s >= 0 && s <= 1 && consider(a + s * (b - a))) return true;
        }
      }
    }
    return false;
  }
  // The side from corner a to corner b: each term at its ends (at_a_, at_b_) and alive_, the terms
  // above_best_on_side, in order.
  void index_side(int a, int b) {
    at_a_ = &at_corner_[a * m_], at_b_ = &at_corner_[b * m_];
    alive_.clear();
    for (size_t i = 0; i < m_; ++i)
      if (above_best_on_side(i)) alive_.push_back(i);
  }
  // Skipping the candidates these two rule out leaves the answer unchanged (the best value only
  // grows). False where term i may not exceed the best value anywhere on the side (a candidate must
  // exceed it in every term)...
  bool above_best_on_side(size_t i) const { return std::max(at_a_[i], at_b_[i]) + rounding_[i] > best_value_; }
  // ...or terms i and j are unequal all along it (one exceeds the other at both ends by far more
  // than rounding).
  bool may_meet_on_side(size_t i, size_t j) const {
    const double da = at_a_[i] - at_a_[j], db = at_b_[i] - at_b_[j], margin = rounding_[i] + rounding_[j];
    return !((da > margin && db > margin) || (da < -margin && db < -margin));
  }
  // The points inside where three terms are equal.
  void three_term_points() {
    for (size_t i = 0; i < m_; ++i)
      for (size_t j = i + 1; j < m_; ++j) {
        const Vec2 r0 = g_[i] - g_[j];
        for (size_t l = j + 1; l < m_; ++l) {
          const Vec2 r1 = g_[i] - g_[l];
          const double det = r0.x() * r1.y() - r0.y() * r1.x();
          if (std::abs(det) < 1e-14) continue;
          const double b0 = c_[j] - c_[i], b1 = c_[l] - c_[i];
          const Vec2 d((b0 * r1.y() - r0.y() * b1) / det, (r0.x() * b1 - b0 * r1.x()) / det);
          // Most points are ruled out by a term at once: that test comes before the octagon's sides.
          if (beats_best(d) && inside(d) && take(d)) return;
        }
      }
  }

  const std::vector<double>& c_;
  const std::vector<Vec2>& g_;
  const Octagon& octagon_;
  const size_t m_;
  const double ceiling_;
  std::vector<double> rounding_;  // per term
  Vec2 best_ = Vec2::Zero();
  double best_value_ = 0;
  size_t first_ = 0;
  std::vector<double> at_corner_;                   // each term at each corner, corner by corner
  const double *at_a_ = nullptr, *at_b_ = nullptr;  // see index_side
  std::vector<size_t> alive_;
};

Candidate best_candidate(const std::vector<double>& c, const std::vector<Vec2>& g, const Octagon& octagon,
                         double ceiling = std::numeric_limits<double>::infinity()) {
  return CandidateSearch(c, g, octagon, ceiling).run();
}

// The terms that can be the smallest somewhere in the octagon, in their order. Let U be the
// smallest of the terms' largest values there: a term whose least value exceeds U is larger
// everywhere than the term whose largest value is U, so it is never the worst term (judged over a
// slightly larger octagon, as candidates up to 1e-9 outside count as inside).
void keep_terms_that_can_be_worst(const std::vector<double>& c, const std::vector<Vec2>& g, const Octagon& octagon,
                                  std::vector<double>& kept_c, std::vector<Vec2>& kept_g) {
  const size_t m = c.size();
  Vec2 wider[8];
  for (int k = 0; k < 8; ++k) wider[k] = octagon.centre + (1 + 1e-6) * (octagon.corner[k] - octagon.centre);
  thread_local std::vector<double> least;
  least.resize(m);
  double bound = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < m; ++i) {
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (const Vec2& corner : wider) {
      const double v = c[i] + g[i].dot(corner);
      lo = std::min(lo, v), hi = std::max(hi, v);
    }
    least[i] = lo;
    bound = std::min(bound, hi);
  }
  const double margin = 1e-9 * (1 + std::abs(bound));
  kept_c.clear(), kept_g.clear();
  for (size_t i = 0; i < m; ++i)
    if (!(least[i] > bound + margin)) kept_c.push_back(c[i]), kept_g.push_back(g[i]);
}

// The least term that does not depend on d (the corner of a quad opposite the moving vertex;
// infinity without one): no point's worst term exceeds it. Where it is within a margin of the
// optimum, the optimum may be a plateau, on which the order of the candidates decides.
double least_constant_term(const std::vector<double>& c, const std::vector<Vec2>& g) {
  double least = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < c.size(); ++i)
    if (g[i].isZero()) least = std::min(least, c[i]);
  return least;
}

}  // namespace

// The optimum over the terms that can be the worst (O(k^3) for k of them instead of m) is the
// optimum of all terms where it is unique. Where a constant term may be the worst, the candidates
// are judged again in the full order, so the answer is always that of the full enumeration; when
// the optimum is exactly the least constant term, no candidate can beat the first that reaches it,
// and the enumeration ends there.
Vec2 maximize_worst_term(const std::vector<double>& c, const std::vector<Vec2>& g, const Vec2& centre, double radius) {
  const Octagon octagon(centre, radius);
  thread_local std::vector<double> kept_c;
  thread_local std::vector<Vec2> kept_g;
  keep_terms_that_can_be_worst(c, g, octagon, kept_c, kept_g);
  const Candidate fast = best_candidate(kept_c, kept_g, octagon);
  if (kept_c.size() == c.size()) return fast.d;
  const double ceiling = least_constant_term(c, g);
  if (!(ceiling <= fast.worst + 1e-9 * (1 + std::abs(fast.worst)))) return fast.d;
  return best_candidate(c, g, octagon, fast.worst == ceiling ? ceiling : std::numeric_limits<double>::infinity()).d;
}

double maximize_worst_term_1d(const std::vector<double>& c, const std::vector<double>& g) {
  const size_t m = c.size();
  auto worst = [&](double d) {
    double w = std::numeric_limits<double>::infinity();
    for (size_t i = 0; i < m; ++i) w = std::min(w, c[i] + g[i] * d);
    return w;
  };
  double best = 0, best_value = worst(0);
  auto consider = [&](double d) {
    const double w = worst(d);
    if (w > best_value) best_value = w, best = d;
  };
  consider(-1);
  consider(1);
  for (size_t i = 0; i < m; ++i)
    for (size_t j = i + 1; j < m; ++j)
      if (std::abs(g[i] - g[j]) > 1e-14) {
        const double d = (c[j] - c[i]) / (g[i] - g[j]);
        if (d > -1 && d < 1) consider(d);
      }
  return best;
}

}  // namespace qgp

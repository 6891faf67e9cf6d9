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
Candidate best_candidate(const std::vector<double>& c, const std::vector<Vec2>& g, const Octagon& octagon,
                         double ceiling = std::numeric_limits<double>::infinity()) {
  const size_t m = c.size();
  const Vec2(&corner)[8] = octagon.corner;
  const Vec2(&side)[8] = octagon.side;
  const Vec2& centre = octagon.centre;
  const double radius = octagon.radius;
  auto inside = [&](const Vec2& d) {
    for (const Vec2& u : side)
      if (u.dot(d - centre) > radius * (1 + 1e-9)) return false;
    return true;
  };
  auto worst = [&](const Vec2& d) {
    double w = std::numeric_limits<double>::infinity();
    for (size_t i = 0; i < m; ++i) w = std::min(w, c[i] + g[i].dot(d));
    return w;
  };
  Vec2 best = Vec2::Zero();
  double best_value = worst(best);
  // d replaces the best when its worst term is larger. The terms are tried from the one that was
  // worst at the last best point, and the first at or below the best value rules d out: the same
  // answer as evaluating them all, without the O(m) cost for almost every candidate.
  size_t first = 0;
  auto beats_best = [&](const Vec2& d) {
    if (c[first] + g[first].dot(d) <= best_value) return false;
    for (size_t i = 0; i < m; ++i)
      if (c[i] + g[i].dot(d) <= best_value) {
        first = i;
        return false;
      }
    return true;
  };
  // True once the best reaches the ceiling.
  auto consider = [&](const Vec2& d) {
    if (!beats_best(d)) return false;
    best_value = worst(d);
    best = d;
    return best_value >= ceiling;
  };
  if (best_value >= ceiling) return {best, best_value};
  for (int k = 0; k < 8; ++k) {
    if (consider(corner[k])) return {best, best_value};
    const Vec2 a = corner[(k + 7) % 8], b = corner[k];
    for (size_t i = 0; i < m; ++i)
      for (size_t j = i + 1; j < m; ++j) {
        const Vec2 dg = g[i] - g[j];
        const double slope = dg.dot(b - a);
        if (std::abs(slope) < 1e-14) continue;
        const double s = -(c[i] - c[j] + dg.dot(a)) / slope;
        if (s >= 0 && s <= 1 && consider(a + s * (b - a))) return {best, best_value};
      }
  }
  for (size_t i = 0; i < m; ++i)
    for (size_t j = i + 1; j < m; ++j) {
      const Vec2 r0 = g[i] - g[j];
      for (size_t l = j + 1; l < m; ++l) {
        const Vec2 r1 = g[i] - g[l];
        const double det = r0.x() * r1.y() - r0.y() * r1.x();
        if (std::abs(det) < 1e-14) continue;
        const double b0 = c[j] - c[i], b1 = c[l] - c[i];
        const Vec2 d((b0 * r1.y() - r0.y() * b1) / det, (r0.x() * b1 - b0 * r1.x()) / det);
        if (inside(d) && consider(d)) return {best, best_value};
      }
    }
  return {best, best_value};
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

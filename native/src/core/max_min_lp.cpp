#include "core/max_min_lp.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace qgp {

Vec2 maximize_worst_term(const std::vector<double>& c, const std::vector<Vec2>& g, const Vec2& centre, double radius) {
  const size_t m = c.size();
  Vec2 corner[8], side[8];
  for (int k = 0; k < 8; ++k) {
    side[k] = Vec2(std::cos(k * M_PI / 4), std::sin(k * M_PI / 4));
    corner[k] =
        centre + radius / std::cos(M_PI / 8) * Vec2(std::cos((k + 0.5) * M_PI / 4), std::sin((k + 0.5) * M_PI / 4));
  }
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
  auto consider = [&](const Vec2& d) {
    if (!beats_best(d)) return;
    best_value = worst(d);
    best = d;
  };
  for (int k = 0; k < 8; ++k) {
    consider(corner[k]);
    const Vec2 a = corner[(k + 7) % 8], b = corner[k];
    for (size_t i = 0; i < m; ++i)
      for (size_t j = i + 1; j < m; ++j) {
        const Vec2 dg = g[i] - g[j];
        const double slope = dg.dot(b - a);
        if (std::abs(slope) < 1e-14) continue;
        const double s = -(c[i] - c[j] + dg.dot(a)) / slope;
        if (s >= 0 && s <= 1) consider(a + s * (b - a));
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
        if (inside(d)) consider(d);
      }
    }
  return best;
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

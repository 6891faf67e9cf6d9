// The untangle steps' max-min linear programs (core/max_min_lp.h): the answer is the one of
// evaluating every term at every candidate point, and no point of the region is better.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "core/max_min_lp.h"

namespace qgp {
namespace {

double worst_term(const std::vector<double>& c, const std::vector<Vec2>& g, const Vec2& d) {
  double w = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < c.size(); ++i) w = std::min(w, c[i] + g[i].dot(d));
  return w;
}

// The candidates of maximize_worst_term in its order, each judged by all its terms: the first
// strictly best one wins.
Vec2 reference_argmax(const std::vector<double>& c, const std::vector<Vec2>& g, const Vec2& centre, double radius) {
  const size_t m = c.size();
  Vec2 corner[8], side[8];
  for (int k = 0; k < 8; ++k) {
    side[k] = Vec2(std::cos(k * M_PI / 4), std::sin(k * M_PI / 4));
    corner[k] =
        centre + radius / std::cos(M_PI / 8) * Vec2(std::cos((k + 0.5) * M_PI / 4), std::sin((k + 0.5) * M_PI / 4));
  }
  Vec2 best = Vec2::Zero();
  double best_value = worst_term(c, g, best);
  auto consider = [&](const Vec2& d) {
    const double w = worst_term(c, g, d);
    if (w > best_value) best_value = w, best = d;
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
    for (size_t j = i + 1; j < m; ++j)
      for (size_t l = j + 1; l < m; ++l) {
        const Vec2 r0 = g[i] - g[j], r1 = g[i] - g[l];
        const double det = r0.x() * r1.y() - r0.y() * r1.x();
        if (std::abs(det) < 1e-14) continue;
        const double b0 = c[j] - c[i], b1 = c[l] - c[i];
        const Vec2 d((b0 * r1.y() - r0.y() * b1) / det, (r0.x() * b1 - b0 * r1.x()) / det);
        bool inside = true;
        for (const Vec2& u : side) inside = inside && !(u.dot(d - centre) > radius * (1 + 1e-9));
        if (inside) consider(d);
      }
  return best;
}

// Stars of 2 to 8 quads (5 terms each), as the untangle builds them, around varied centres; some
// with two terms equal at a corner of the octagon (the end of two of its sides), some with terms far
// above the others (never the worst: left out of the first enumeration) and some
// with constant terms (the corner opposite the moving vertex: a plateau of optima where one is the
// worst, on which the full order of the candidates decides).
TEST(MaxMinLp, SameAnswerAsEvaluatingEveryTermAndNoBetterPoint) {
  std::mt19937 rng(11);
  std::normal_distribution<double> normal(0, 1);
  std::uniform_int_distribution<int> quads(2, 8);
  std::uniform_real_distribution<double> unit(-1, 1);
  for (int instance = 0; instance < 400; ++instance) {
    const int m = 5 * quads(rng);
    std::vector<double> c(m);
    std::vector<Vec2> g(m);
    for (int i = 0; i < m; ++i) {
      c[i] = normal(rng);
      g[i] = Vec2(normal(rng), normal(rng));
    }
    if (instance % 4 == 0) g[1] = g[0];  // parallel terms
    if (instance % 3 == 0)
      for (int i = 0; i < m; i += 2) c[i] += 20;  // never the worst
    if (instance % 5 < 2)
      for (int i = 2; i < m; i += 5) g[i] = Vec2::Zero(), c[i] -= instance % 5 == 0 ? 3 : 0.5;  // constant
    const Vec2 centre(0.5 * unit(rng), 0.5 * unit(rng));
    const double radius = std::max(1.0, centre.norm());
    if (instance % 7 == 0) {  // two terms equal at an octagon corner: a candidate at a side's end
      const int k = instance % 8;
      const Vec2 corner =
          centre + radius / std::cos(M_PI / 8) * Vec2(std::cos((k + 0.5) * M_PI / 4), std::sin((k + 0.5) * M_PI / 4));
      c[4] = c[3] + (g[3] - g[4]).dot(corner);
    }
    const Vec2 d = maximize_worst_term(c, g, centre, radius);
    const Vec2 expected = reference_argmax(c, g, centre, radius);
    ASSERT_EQ(d.x(), expected.x()) << "instance " << instance;
    ASSERT_EQ(d.y(), expected.y()) << "instance " << instance;
    const double value = worst_term(c, g, d);
    for (int k = 0; k < 200; ++k) {
      const Vec2 p = centre + radius * M_SQRT1_2 * Vec2(unit(rng), unit(rng));  // inside the octagon
      EXPECT_LE(worst_term(c, g, p), value + 1e-9) << "instance " << instance;
    }
  }
}

}  // namespace
}  // namespace qgp

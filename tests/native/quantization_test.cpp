// Quantization (paper §6): hand-built T-meshes with known optimal answers, the validity test
// (§5.2, §9.1), generating vectors (§6.2, §9.2), and property tests over synthetic T-meshes of
// several kinds at four densities.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <functional>
#include <limits>
#include <random>
#include <set>

#include "core/error.h"
#include "quantization/cell_system.h"
#include "quantization/generating_vectors.h"
#include "quantization/quantization.h"
#include "quantization/round_quantization.h"
#include "quantization/validity.h"
#include "synthetic_tmesh.h"
#include "test_support.h"

namespace qgp {
namespace {

// ---------------------------------------------------------------------------------------------
// Independent checks (written against the TMesh only).

int64_t side_sum(const TMesh& tm, const std::vector<int64_t>& x, int c, int s) {
  int64_t sum = 0;
  for (int e : tm.cells[c].sides[s]) sum += x[e];
  return sum;
}

bool consistent(const TMesh& tm, const std::vector<int64_t>& x) {
  for (size_t c = 0; c < tm.cells.size(); ++c)
    for (int s = 0; s < 2; ++s)
      if (side_sum(tm, x, c, s) != side_sum(tm, x, c, s + 2)) return false;
  return true;
}

double objective(const TMesh& tm, const std::vector<int64_t>& x, double scale) {
  double sum = 0;
  for (size_t e = 0; e < tm.edges.size(); ++e) {
    const double d = static_cast<double>(x[e]) / std::max(scale * tm.edges[e].length, 1e-3) - 1;
    sum += d * d;
  }
  return sum;
}

// Exhaustive search over x in [0, limit]^E with Ax = 0, valid; returns the best objective.
double brute_force_optimum(const TMesh& tm, double scale, int limit, std::vector<int64_t>* best_x = nullptr) {
  const int E = static_cast<int>(tm.edges.size());
  // Check each cell once its last edge is assigned.
  std::vector<std::vector<int>> cells_done_at(E);
  for (size_t c = 0; c < tm.cells.size(); ++c) {
    int last = 0;
    for (const auto& side : tm.cells[c].sides)
      for (int e : side) last = std::max(last, e);
    cells_done_at[last].push_back(static_cast<int>(c));
  }
  const CellSystem system(tm);
  ValidityChecker checker(system);
  std::vector<int64_t> x(E, 0);
  double best = std::numeric_limits<double>::infinity();
  std::function<void(int)> assign = [&](int e) {
    if (e == E) {
      if (!checker.check(x).valid) return;
      const double f = objective(tm, x, scale);
      if (f < best) {
        best = f;
        if (best_x) *best_x = x;
      }
      return;
    }
    for (int v = 0; v <= limit; ++v) {
      x[e] = v;
      bool ok = true;
      for (int c : cells_done_at[e])
        for (int s = 0; s < 2 && ok; ++s) ok = side_sum(tm, x, c, s) == side_sum(tm, x, c, s + 2);
      if (ok) assign(e + 1);
    }
    x[e] = 0;
  };
  assign(0);
  return best;
}

QuantizationResult run_greedy(const TMesh& tm, double scale, bool recompute = true) {
  QuantizationOptions options;
  options.scale = scale;
  options.recompute_objective_each_step = recompute;
  Progress progress;
  return quantize(tm, options, progress);
}

// Every invariant of a greedy result.
void expect_result_invariants(const TMesh& tm, const QuantizationResult& r, const std::string& what) {
  SCOPED_TRACE(what);
  ASSERT_EQ(r.x.size(), tm.edges.size());
  for (int64_t v : r.x) ASSERT_GE(v, 0);
  EXPECT_TRUE(consistent(tm, r.x));
  EXPECT_EQ(r.consistency_residual, 0);
  EXPECT_TRUE(r.valid);
  EXPECT_TRUE(check_quantization_validity(tm, r.x).valid);
  int64_t quads = 0;
  for (size_t c = 0; c < tm.cells.size(); ++c) quads += side_sum(tm, r.x, c, 0) * side_sum(tm, r.x, c, 1);
  EXPECT_EQ(r.quads_expected, quads);
  EXPECT_GT(quads, 0);
  EXPECT_NEAR(r.objective, objective(tm, r.x, r.scale), 1e-9 * (1 + r.objective));
  ASSERT_FALSE(r.objective_history.empty());
  EXPECT_EQ(static_cast<int>(r.objective_history.size()), r.stage2_steps + 1);
  for (size_t k = 1; k < r.objective_history.size(); ++k)
    ASSERT_LE(r.objective_history[k], r.objective_history[k - 1] * (1 + 1e-12) + 1e-12) << "step " << k;
  EXPECT_NEAR(r.objective_history.back(), r.objective, 1e-9 * (1 + r.objective));
  EXPECT_EQ(r.zero_edges, std::count(r.x.begin(), r.x.end(), 0));
  EXPECT_EQ(r.unreachable_edges, 0);
}

// Lengths in the T-mesh satisfy the cell equations exactly in ticks; Euler characteristic.
void expect_tmesh_invariants(const TMesh& tm, int chi) {
  EXPECT_EQ(tm.euler_characteristic(), chi);
  for (const auto& cell : tm.cells)
    for (int s = 0; s < 2; ++s) {
      double a = 0, b = 0;
      for (int e : cell.sides[s]) a += tm.edges[e].length;
      for (int e : cell.sides[s + 2]) b += tm.edges[e].length;
      EXPECT_NEAR(a, b, 1e-9 * (1 + a));
    }
  int singular_sum = 0;
  for (const auto& n : tm.nodes) singular_sum += n.index;
  EXPECT_EQ(singular_sum, 4 * chi);  // Poincaré–Hopf in quarter turns
}

// ---------------------------------------------------------------------------------------------
// Synthetic T-mesh families.

std::vector<int64_t> random_sizes(int n, int64_t lo, int64_t hi, std::mt19937& rng) {
  std::vector<int64_t> v(n);
  for (auto& x : v) x = std::uniform_int_distribution<int64_t>(lo, hi)(rng);
  return v;
}

struct Family {
  std::string name;
  int chi;
  std::function<TMesh(int splits, unsigned seed)> make;
};

std::vector<Family> families() {
  return {
      {"planar", 1,
       [](int splits, unsigned seed) {
         std::mt19937 rng(seed);
         PatchLayout layout =
             make_grid_layout(random_sizes(3, 20, 60, rng), random_sizes(2, 20, 60, rng), false, false);
         // An interior feature curve (patch side) ending at two virtual singularities.
         layout.feature_side.assign(4 * layout.patches.size(), 0);
         layout.feature_side[4 * 1 + 2] = 1;
         layout.feature_side[4 * 4 + 0] = 1;
         layout.unit = 0.1;
         return build_patch_tmesh(layout, splits, seed);
       }},
      {"torus", 0,
       [](int splits, unsigned seed) {
         std::mt19937 rng(seed);
         PatchLayout layout = make_grid_layout(random_sizes(3, 20, 60, rng), random_sizes(4, 20, 60, rng), true, true);
         layout.unit = 0.1;
         return build_patch_tmesh(layout, splits, seed);
       }},
      {"box", 2,
       [](int splits, unsigned seed) {
         std::mt19937 rng(seed);
         PatchLayout layout = make_polycube_layout({{0, 0, 0}}, random_sizes(1, 20, 80, rng),
                                                   random_sizes(1, 20, 80, rng), random_sizes(1, 20, 80, rng), true);
         layout.unit = 0.1;
         return build_patch_tmesh(layout, splits, seed);
       }},
      {"polycube", 0 /* set per instance */,
       [](int splits, unsigned seed) {
         std::mt19937 rng(seed);
         const auto voxels = random_manifold_polycube(8, 4, seed);
         PatchLayout layout = make_polycube_layout(voxels, random_sizes(4, 10, 40, rng), random_sizes(4, 10, 40, rng),
                                                   random_sizes(4, 10, 40, rng), true);
         layout.unit = 0.1;
         return build_patch_tmesh(layout, splits, seed);
       }},
  };
}

// ---------------------------------------------------------------------------------------------
// Hand-built T-meshes with known answers.

TEST(Quantization, SingleCellTorus) {
  // One node, a u-loop and a v-loop, one cell with the same edge on opposite sides.
  TMesh tm;
  tm.nodes.resize(1);
  tm.nodes[0].kind = TMeshNode::Kind::Seed;
  tm.edges.resize(2);
  tm.edges[0] = {0, 0, 0, 3.3, false, {0, 0}, {}};
  tm.edges[1] = {0, 0, 1, 1.8, false, {0, 0}, {}};
  tm.nodes[0].incidences = {{0, 0, true}, {1, 1, true}, {0, 2, false}, {1, 3, false}};
  tm.cells.resize(1);
  tm.cells[0].sides = {std::vector<int>{0}, {1}, {0}, {1}};
  const QuantizationResult r = run_greedy(tm, 1.0);
  expect_result_invariants(tm, r, "single-cell torus");
  EXPECT_EQ(r.x, (std::vector<int64_t>{3, 2}));
}

TEST(Quantization, PureQuadLayoutBoxRoundsEachDualLoop) {
  // A box is a quad layout: its generating vectors are the three dual loops, each controlling the
  // four parallel edges of one box dimension; the optimum rounds each dimension on its own, except
  // that a dimension must not become 0 (the corners would collapse).
  const PatchLayout layout = make_polycube_layout({{0, 0, 0}}, {26}, {13}, {4}, false);
  TMesh tm = build_patch_tmesh(layout, 0, 1);
  expect_tmesh_invariants(tm, 2);
  ASSERT_EQ(tm.edges.size(), 12u);
  const QuantizationResult r = run_greedy(tm, 0.1);  // ideal dimensions 2.6, 1.3, 0.4
  expect_result_invariants(tm, r, "box");
  for (size_t e = 0; e < tm.edges.size(); ++e) {
    const double ideal = 0.1 * tm.edges[e].length;
    const int64_t expected = ideal > 2 ? 3 : 1;
    EXPECT_EQ(r.x[e], expected) << "edge " << e << " ideal " << ideal;
  }
  EXPECT_EQ(r.quads_expected, 2 * (3 * 1 + 1 * 1 + 3 * 1));
  EXPECT_NEAR(r.objective, brute_force_optimum(tm, 0.1, 4), 1e-12);
}

TEST(Quantization, PureQuadLayoutTorusGridRoundsEachColumnAndRow) {
  // Torus of 3 x 4 patches: no singularities, every column/row loop is independent (§10.1).
  const std::vector<int64_t> widths{23, 17, 31}, heights{12, 29, 6, 18};
  PatchLayout layout = make_grid_layout(widths, heights, true, true);
  layout.unit = 0.1;
  const TMesh tm = build_patch_tmesh(layout, 0, 1);
  expect_tmesh_invariants(tm, 0);
  const QuantizationResult r = run_greedy(tm, 1.0);
  expect_result_invariants(tm, r, "torus grid");
  for (size_t e = 0; e < tm.edges.size(); ++e) EXPECT_EQ(r.x[e], std::llround(tm.edges[e].length)) << "edge " << e;
  EXPECT_EQ(r.zero_edges, 0);  // the row of height 0.6 rounds to 1
}

// Planar domain [0,W]x[0,H] with cells LB = [0,a]x[0,h], LT = [0,a]x[h,H], R = [a,W]x[0,H]:
// one T-junction at (a,h).
TMesh single_t_junction(int64_t a, int64_t W, int64_t h, int64_t H) {
  PatchLayout layout = make_grid_layout({W}, {H}, false, false);
  layout.unit = 0.1;
  return build_patch_tmesh(layout, std::vector<PatchRect>{{0, 0, 0, a, h}, {0, 0, h, a, H}, {0, a, 0, W, H}});
}

TEST(Quantization, SingleTJunctionMatchesExhaustiveOptimum) {
  const std::vector<std::array<int64_t, 4>> cases{{13, 31, 14, 28}, {8, 30, 9, 25}, {22, 29, 16, 37}, {15, 26, 5, 33}};
  for (const auto& [a, W, h, H] : cases) {
    const TMesh tm = single_t_junction(a, W, h, H);
    expect_tmesh_invariants(tm, 1);
    ASSERT_EQ(tm.cells.size(), 3u);
    int t_junctions = 0;
    for (const auto& n : tm.nodes) t_junctions += n.kind == TMeshNode::Kind::TJunction && !n.on_feature;
    EXPECT_EQ(t_junctions, 1);
    const QuantizationResult r = run_greedy(tm, 1.0);
    expect_result_invariants(tm, r, "T-junction");
    EXPECT_NEAR(r.objective, brute_force_optimum(tm, 1.0, 5), 1e-12) << a << " " << W << " " << h << " " << H;
  }
}

TEST(Quantization, CellThatMustGetAZeroEdge) {
  // The right cell has height 1.0; the left column splits it into 0.9 + 0.1. The best consistent
  // integer lengths give the 0.1 cell height 0 (its two vertical edges become zero edges), which
  // is valid: no singular corner collapses with another or with a foreign boundary point.
  const TMesh tm = single_t_junction(10, 20, 9, 10);
  const QuantizationResult r = run_greedy(tm, 1.0);
  expect_result_invariants(tm, r, "zero cell");
  int zero_vertical = 0;
  for (size_t e = 0; e < tm.edges.size(); ++e) {
    const double ideal = tm.edges[e].length;
    if (tm.edges[e].axis == 1 && std::abs(ideal - 0.1) < 1e-9) {
      EXPECT_EQ(r.x[e], 0);
      ++zero_vertical;
    }
  }
  EXPECT_EQ(zero_vertical, 2);
  EXPECT_EQ(r.zero_edges, 2);
  EXPECT_NEAR(r.objective, brute_force_optimum(tm, 1.0, 3), 1e-12);
}

TEST(Quantization, SmallLayoutsMatchExhaustiveOptimum) {
  // Tiny random subdivisions of a rectangle (boundary) and of a box (singularities): the greedy
  // result is valid and here also optimal.
  int compared = 0;
  for (unsigned seed = 1; seed <= 12; ++seed) {
    PatchLayout layout = seed % 2 ? make_grid_layout({19, 13}, {11}, false, false)
                                  : make_polycube_layout({{0, 0, 0}}, {17}, {12}, {9}, false);
    layout.unit = 0.1;
    const TMesh tm = build_patch_tmesh(layout, seed % 2 ? 2 : 1, seed);
    if (tm.edges.size() > 20) continue;
    const QuantizationResult r = run_greedy(tm, 1.7);
    expect_result_invariants(tm, r, "small seed " + std::to_string(seed));
    const double best = brute_force_optimum(tm, 1.7, 4);
    EXPECT_LE(r.objective, best * 1.5 + 1e-9) << "seed " << seed;  // greedy, not exact in general
    compared += std::abs(r.objective - best) < 1e-12;
  }
  EXPECT_GE(compared, 8);
}

// ---------------------------------------------------------------------------------------------
// Validity test.

TEST(QuantizationValidity, CollapsedBoxDimensionMakesCornersCollapse) {
  const TMesh tm = build_patch_tmesh(make_polycube_layout({{0, 0, 0}}, {3}, {2}, {1}, false), 0, 1);
  std::vector<int64_t> x(tm.edges.size());
  for (size_t e = 0; e < x.size(); ++e) x[e] = std::llround(tm.edges[e].length);
  EXPECT_TRUE(check_quantization_validity(tm, x).valid);
  for (size_t e = 0; e < x.size(); ++e)
    if (std::llround(tm.edges[e].length) == 1) x[e] = 0;  // the z dimension collapses
  const QuantizationValidity v = check_quantization_validity(tm, x);
  EXPECT_FALSE(v.valid);
  EXPECT_GE(v.other_node, 0);
  EXPECT_TRUE(tm.nodes[v.node].singular() && tm.nodes[v.other_node].singular());
}

// 4 x 2 patches of a rectangle (columns 2,3,2,2, rows 2,3); a feature curve runs along the top of
// patch (1,0) from grid point (1,1) to (2,1) and ends at two virtual singularities.
TMesh feature_rectangle() {
  PatchLayout layout = make_grid_layout({2, 3, 2, 2}, {2, 3}, false, false);
  layout.feature_side.assign(4 * layout.patches.size(), 0);
  layout.feature_side[4 * 1 + 2] = 1;
  layout.feature_side[4 * 5 + 0] = 1;
  return build_patch_tmesh(layout, 0, 1);
}

// Lengths of that (unsplit) grid with column widths cw and row heights rh: cell c is patch
// (c % 4, c / 4); its sides 0/2 have the column's width, 1/3 the row's height.
std::vector<int64_t> grid_lengths(const TMesh& tm, const std::vector<int64_t>& cw, const std::vector<int64_t>& rh) {
  std::vector<int64_t> x(tm.edges.size(), -1);
  for (size_t c = 0; c < tm.cells.size(); ++c)
    for (int s = 0; s < 4; ++s)
      for (int e : tm.cells[c].sides[s]) x[e] = s % 2 == 0 ? cw[c % 4] : rh[c / 4];
  return x;
}

TEST(QuantizationValidity, SingularityCollapsingOntoAFeatureIsDetected) {
  const TMesh tm = feature_rectangle();
  int virtual_singularities = 0;
  for (const auto& n : tm.nodes) virtual_singularities += n.kind == TMeshNode::Kind::FeatureCorner && n.index == 0;
  EXPECT_EQ(virtual_singularities, 2);
  EXPECT_TRUE(check_quantization_validity(tm, grid_lengths(tm, {2, 3, 2, 2}, {2, 3})).valid);
  // Bottom row of height 0: the feature curve's end points fall onto the bottom boundary.
  const QuantizationValidity v = check_quantization_validity(tm, grid_lengths(tm, {2, 3, 2, 2}, {0, 3}));
  EXPECT_FALSE(v.valid);
  EXPECT_EQ(tm.nodes[v.node].kind, TMeshNode::Kind::FeatureCorner);  // an end of the interior curve
  EXPECT_TRUE(v.feature_edge >= 0 || v.other_node >= 0);
  // Left column of width 0: the curve's left end falls onto the left boundary.
  const QuantizationValidity u = check_quantization_validity(tm, grid_lengths(tm, {0, 3, 2, 2}, {2, 3}));
  EXPECT_FALSE(u.valid);
  EXPECT_GE(u.feature_edge, 0);
  EXPECT_TRUE(tm.edges[u.feature_edge].on_feature);
  // Middle column of width 0: the two ends of the feature curve collapse.
  const QuantizationValidity w = check_quantization_validity(tm, grid_lengths(tm, {2, 0, 2, 2}, {2, 3}));
  EXPECT_FALSE(w.valid);
  EXPECT_GE(w.other_node, 0);
  // Right column of width 0: the right boundary meets the isoline u = 7, but no singular node meets
  // another or a foreign feature point (the right corners only reach the zero-length continuation
  // of their own boundary curves): valid.
  EXPECT_TRUE(check_quantization_validity(tm, grid_lengths(tm, {2, 3, 2, 0}, {2, 3})).valid);
}

TEST(QuantizationValidity, ParallelFeatureLoopsMayNotCollapse) {
  // A torus of 3 x 3 patches whose middle row is bounded by two closed feature loops: no singular
  // node anywhere, so only the searches from feature points can see the loops glued together.
  PatchLayout layout = make_grid_layout({2, 2, 2}, {2, 1, 2}, true, true);
  layout.feature_side.assign(4 * layout.patches.size(), 0);
  for (int i = 0; i < 3; ++i) {
    layout.feature_side[4 * i + 2] = layout.feature_side[4 * (3 + i) + 0] = 1;        // lower loop
    layout.feature_side[4 * (3 + i) + 2] = layout.feature_side[4 * (6 + i) + 0] = 1;  // upper loop
  }
  const TMesh tm = build_patch_tmesh(layout, 0, 1);
  for (const auto& n : tm.nodes) ASSERT_TRUE(!n.singular() && n.kind != TMeshNode::Kind::FeatureCorner);
  auto lengths = [&](const std::vector<int64_t>& rh) {
    std::vector<int64_t> x(tm.edges.size(), -1);
    for (size_t c = 0; c < tm.cells.size(); ++c)
      for (int s = 0; s < 4; ++s)
        for (int e : tm.cells[c].sides[s]) x[e] = s % 2 == 0 ? 2 : rh[c / 3];
    return x;
  };
  EXPECT_TRUE(check_quantization_validity(tm, lengths({2, 1, 2})).valid);
  // The middle row of height 0: the two creases would become one.
  const QuantizationValidity v = check_quantization_validity(tm, lengths({2, 0, 2}));
  EXPECT_FALSE(v.valid);
  EXPECT_GE(v.feature_edge, 0);
  EXPECT_NE(v.reason.find("feature node"), std::string::npos) << v.reason;
  // The bottom row of height 0 lays the lower loop onto a plain isoline: valid.
  EXPECT_TRUE(check_quantization_validity(tm, lengths({0, 1, 2})).valid);
}

TEST(QuantizationValidity, PolycubeLayerCollapseIsInvalid) {
  // An L-shaped polycube has convex and concave singular corners on sharp feature curves; a layer
  // of zero thickness makes them collapse.
  const PatchLayout layout = make_polycube_layout({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {2, 3}, {2, 2}, {1}, true);
  const TMesh tm = build_patch_tmesh(layout, 0, 1);
  std::vector<int64_t> x;
  for (const auto& e : tm.edges) x.push_back(std::llround(e.length));
  EXPECT_TRUE(check_quantization_validity(tm, x).valid);
  for (size_t e = 0; e < x.size(); ++e)
    if (tm.edges[e].length == 1) x[e] = 0;  // z extent 0
  EXPECT_FALSE(check_quantization_validity(tm, x).valid);
}

TEST(QuantizationValidity, IncrementalTestAgreesWithTheFullTest) {
  // Random walks through consistent quantizations (adding/subtracting generating vectors at coarse
  // lengths, so that zero edges and collapses are frequent): after every change the incremental
  // test must give the full test's answer; valid states are committed.
  int invalid = 0, checks = 0;
  for (const Family& family : families()) {
    for (unsigned seed = 1; seed <= 2; ++seed) {
      const TMesh tm = family.make(80, seed);
      const CellSystem sys(tm);
      GeneratingVectorSearch search(sys);
      ValidityChecker incremental(sys), full(sys);
      std::mt19937 rng(seed);
      std::vector<int64_t> x(tm.edges.size(), 1);
      // Start from an all-positive consistent x: one generating vector through every edge.
      std::fill(x.begin(), x.end(), 0);
      std::vector<double> weight(tm.edges.size(), 1.0);
      std::vector<int> dnodes;
      for (int e = 0; e < static_cast<int>(x.size()); ++e)
        if (x[e] == 0 && search.find(e, weight, dnodes, nullptr))
          for (int n : dnodes) ++x[n / 2];
      ASSERT_TRUE(incremental.commit_full(x).valid);
      for (int step = 0; step < 400; ++step) {
        const int e = std::uniform_int_distribution<int>(0, static_cast<int>(x.size()) - 1)(rng);
        const int sign = std::uniform_int_distribution<int>(0, 3)(rng) == 0 ? +1 : -1;
        for (size_t f = 0; f < x.size(); ++f)
          weight[f] = sign < 0 && x[f] == 0 ? std::numeric_limits<double>::infinity()
                                            : std::uniform_real_distribution<double>(0.5, 1.5)(rng);
        if (!search.find(e, weight, dnodes, nullptr)) continue;
        std::vector<int64_t> y = x;
        std::vector<int> changed;
        for (int n : dnodes) y[n / 2] += sign, changed.push_back(n / 2);
        if (*std::min_element(y.begin(), y.end()) < 0) continue;
        ASSERT_TRUE(consistent(tm, y));
        const bool expected = full.check(y).valid;
        const bool got = incremental.check_changed(y, changed, nullptr, true).valid;
        ASSERT_EQ(got, expected) << family.name << " seed " << seed << " step " << step;
        ++checks;
        if (got)
          x = y;
        else
          ++invalid;
      }
    }
  }
  EXPECT_GT(checks, 300);
  EXPECT_GT(invalid, 20) << checks;  // the walk does reach invalid states
}

TEST(QuantizationValidity, RejectsInconsistentInput) {
  const TMesh tm = feature_rectangle();
  std::vector<int64_t> x = grid_lengths(tm, {2, 3, 2, 2}, {2, 3});
  x[0] += 1;
  EXPECT_THROW(check_quantization_validity(tm, x), Error);
  x[0] = -1;
  EXPECT_THROW(check_quantization_validity(tm, x), Error);
}

// ---------------------------------------------------------------------------------------------
// Generating vectors.

TEST(GeneratingVectors, CircuitsAndPathsAreInTheNullspace) {
  for (const Family& family : families()) {
    for (unsigned seed = 1; seed <= 3; ++seed) {
      const TMesh tm = family.make(60, seed);
      const CellSystem sys(tm);
      GeneratingVectorSearch search(sys);
      std::mt19937 rng(seed);
      std::vector<double> weight(tm.edges.size());
      for (auto& w : weight) w = std::uniform_real_distribution<double>(0.1, 2.0)(rng);
      std::vector<int> dnodes;
      for (int e = 0; e < static_cast<int>(tm.edges.size()); ++e) {
        ASSERT_TRUE(search.find(e, weight, dnodes, nullptr)) << family.name << " edge " << e;
        std::vector<int64_t> v(tm.edges.size(), 0);
        for (int n : dnodes) ++v[n / 2];
        EXPECT_GE(v[e], 1);
        for (int64_t k : v) EXPECT_LE(k, 2);
        std::vector<int> sorted(dnodes);
        std::sort(sorted.begin(), sorted.end());
        EXPECT_EQ(std::adjacent_find(sorted.begin(), sorted.end()), sorted.end());
        EXPECT_TRUE(consistent(tm, v)) << family.name << " edge " << e;
      }
    }
  }
}

TEST(GeneratingVectors, BoundaryEdgesUsePaths) {
  // On a planar grid a strip from boundary to boundary is the only kind of generating vector.
  const TMesh tm = build_patch_tmesh(make_grid_layout({3, 4, 5}, {2, 6}, false, false), 0, 1);
  const CellSystem sys(tm);
  GeneratingVectorSearch search(sys);
  std::vector<double> weight(tm.edges.size(), 1.0);
  std::vector<int> dnodes;
  for (int e = 0; e < static_cast<int>(tm.edges.size()); ++e) {
    ASSERT_TRUE(search.find(e, weight, dnodes, nullptr));
    // A column/row strip crosses 3 (vertical strips: 2 rows + ... ) parallel edges: rows+1 or cols+1.
    const size_t expected = tm.edges[e].axis == 0 ? 3 : 4;
    EXPECT_EQ(dnodes.size(), expected) << "edge " << e;
    EXPECT_LT(sys.dnode_predecessor_hub(dnodes.front()), 0);  // starts at the boundary
    EXPECT_LT(sys.dnode_successor_hub(dnodes.back()), 0);     // ends at the boundary
  }
}

TEST(GeneratingVectors, ExcludedEdgesAreAvoided) {
  // With infinite weight on one column of a torus grid, circuits through the other columns' edges
  // must not use it.
  PatchLayout layout = make_grid_layout({5, 5, 5}, {5, 5, 5}, true, true);
  const TMesh tm = build_patch_tmesh(layout, 12, 3);
  const CellSystem sys(tm);
  GeneratingVectorSearch search(sys);
  std::vector<double> weight(tm.edges.size(), 1.0);
  const int excluded = 0;
  weight[excluded] = std::numeric_limits<double>::infinity();
  std::vector<int> dnodes;
  EXPECT_FALSE(search.find(excluded, weight, dnodes, nullptr));
  for (int e = 1; e < static_cast<int>(tm.edges.size()); ++e)
    if (search.find(e, weight, dnodes, nullptr))
      for (int n : dnodes) EXPECT_NE(n / 2, excluded);
}

// ---------------------------------------------------------------------------------------------
// Property tests at four densities.

TEST(Quantization, PropertiesOnSyntheticTMeshesAtFourDensities) {
  for (const Family& family : families()) {
    for (unsigned seed = 1; seed <= 4; ++seed) {
      const TMesh tm = family.make(seed <= 2 ? 150 : 600, seed);
      if (family.name != "polycube") expect_tmesh_invariants(tm, family.chi);
      for (double target : {100.0, 500.0, 2000.0, 10000.0}) {
        const double scale = quantization_scale_for_quads(tm, target);
        const QuantizationResult r = run_greedy(tm, scale);
        const std::string what = family.name + " seed " + std::to_string(seed) + " target " + std::to_string(target);
        expect_result_invariants(tm, r, what);
        EXPECT_GT(r.stage1_steps, 0) << what;
        // The quad count follows the target where cells are resolved (at coarser targets most
        // edges are shorter than one quad and the per-edge objective rounds many of them to 0).
        if (target >= 10.0 * tm.cells.size()) {
          EXPECT_GT(r.quads_expected, 0.6 * target) << what;
          EXPECT_LT(r.quads_expected, 1.6 * target) << what;
        }
      }
    }
  }
}

TEST(Quantization, StageTwoImprovesOnStageOne) {
  for (const Family& family : families()) {
    const TMesh tm = family.make(200, 7);
    const QuantizationResult r = run_greedy(tm, quantization_scale_for_quads(tm, 1500), false);
    expect_result_invariants(tm, r, family.name);
    EXPECT_GT(r.stage2_steps, 0) << family.name;
    EXPECT_LT(r.objective, r.objective_history.front()) << family.name;
  }
}

TEST(Quantization, CoarseScalesProduceZeroEdgesAndStayValid) {
  for (const Family& family : families()) {
    for (unsigned seed = 1; seed <= 3; ++seed) {
      const TMesh tm = family.make(300, seed);
      const QuantizationResult r = run_greedy(tm, quantization_scale_for_quads(tm, 60));
      expect_result_invariants(tm, r, family.name + " coarse");
      EXPECT_GT(r.zero_edges, 0) << family.name;
    }
  }
}

// Zero edges of a coarse run, given a minimum length of 1 (bound 1) or 2 (bound 2), and edges of
// length 1 given a minimum of 2, reach their bounds on the next run; the result keeps every
// invariant.
TEST(Quantization, MinimumLengthKeepsMarkedEdgesPositive) {
  for (int64_t bound : {1, 2}) {
    for (const Family& family : families()) {
      const std::string where = family.name + " bound " + std::to_string(bound);
      const TMesh tm = family.make(300, 2);
      const double scale = quantization_scale_for_quads(tm, 60);
      const QuantizationResult first = run_greedy(tm, scale);
      ASSERT_GT(first.zero_edges, 0) << where;
      QuantizationOptions options;
      options.scale = scale;
      options.min_length.assign(tm.edges.size(), 0);
      int marked = 0, marked_ones = 0;
      for (size_t e = 0; e < tm.edges.size(); ++e) {
        if (first.x[e] == 0 && marked < first.zero_edges / 2 + 1) options.min_length[e] = bound, ++marked;
        if (bound == 2 && first.x[e] == 1 && marked_ones < 5) options.min_length[e] = 2, ++marked_ones;
      }
      Progress progress;
      const QuantizationResult second = quantize(tm, options, progress);
      expect_result_invariants(tm, second, where);
      EXPECT_EQ(second.unreachable_edges, 0) << where;
      for (size_t e = 0; e < tm.edges.size(); ++e)
        EXPECT_GE(second.x[e], options.min_length[e]) << where << " edge " << e;
    }
  }
  QuantizationOptions wrong;
  wrong.min_length.assign(3, 0);
  Progress progress;
  EXPECT_THROW(quantize(families()[0].make(300, 2), wrong, progress), Error);
  const TMesh tm = families()[0].make(300, 2);
  QuantizationOptions negative;
  negative.min_length.assign(tm.edges.size(), 0);
  negative.min_length[0] = -1;
  EXPECT_THROW(quantize(tm, negative, progress), Error);
}

// ---------------------------------------------------------------------------------------------
// The `round` baseline's map: independent variables rounded, the map solved again.

std::vector<char> cube_crease_edges(const TriMesh& mesh) {
  std::vector<char> crease(mesh.num_edges(), 0);
  for (int e = 0; e < mesh.num_edges(); ++e) {
    const int h = mesh.edge_halfedge[e], o = mesh.opposite[h];
    if (o >= 0)
      crease[e] = mesh.face_normal_unnormalized(h / 3).normalized().dot(
                      mesh.face_normal_unnormalized(o / 3).normalized()) < 0.5;
  }
  return crease;
}

TEST(RoundQuantization, CubeSidesRoundAndTheMapIsSolvedAgain) {
  const auto cube = test::make_grid_cube(4);
  const std::vector<char> creases = cube_crease_edges(cube.mesh);
  const std::vector<char> snap = independent_vertices(cube.mesh, cube.param, TMesh{});
  EXPECT_EQ(std::count(snap.begin(), snap.end(), 1), 8);  // the corners
  const RoundedMap m = round_parametrization(cube.mesh, cube.param, creases, snap, 0.6, 20);
  EXPECT_EQ(m.unresolved_equations, 0);
  EXPECT_EQ(exact_transition_residual(cube.mesh, m.param), 0);
  EXPECT_EQ(m.flipped_triangles, 0);
  EXPECT_EQ(m.degenerate_triangles, 0);
  const int64_t one = m.param.one();
  for (int h = 0; h < cube.mesh.num_halfedges(); ++h) {
    for (int a = 0; a < 2; ++a) EXPECT_EQ(m.param.translation[h][a] % one, 0);
    const int v = cube.mesh.from(h);
    if (snap[v])
      for (int a = 0; a < 2; ++a) EXPECT_EQ(m.param.uv[h][a] % one, 0);
  }
  // Each side 2.4 rounds to 2 and the solve maps every side affinely onto its 2 x 2 square: the
  // continuous coordinates (0..4 per side, scaled to 0..2.4) become exactly 0..2.
  for (int c = 0; c < 3 * cube.mesh.num_faces(); ++c)
    for (int a = 0; a < 2; ++a) {
      const double expected = cube.param.uv(c, a) * 0.5;  // 4 -> 2
      EXPECT_NEAR(m.param.to_double(m.param.uv[c][a]), expected, 1e-6);
    }
}

TEST(RoundQuantization, TorusTranslationsRound) {
  const auto torus = test::make_grid_torus(10, 7);
  const std::vector<char> snap = independent_vertices(torus.mesh, torus.param, TMesh{});
  EXPECT_EQ(std::count(snap.begin(), snap.end(), 1), 0);  // no singularity: one vertex is pinned
  const RoundedMap m = round_parametrization(torus.mesh, torus.param, {}, snap, 0.33, 20);
  EXPECT_EQ(m.unresolved_equations, 0);
  EXPECT_EQ(exact_transition_residual(torus.mesh, m.param), 0);
  EXPECT_EQ(m.flipped_triangles, 0);
  std::set<std::array<int64_t, 2>> translations;
  for (int h = 0; h < torus.mesh.num_halfedges(); ++h) {
    const IVec2 t = m.param.translation[h];
    if (t[0] != 0 || t[1] != 0) translations.insert({std::abs(t[0]) / m.param.one(), std::abs(t[1]) / m.param.one()});
    for (int a = 0; a < 2; ++a) EXPECT_EQ(t[a] % m.param.one(), 0);
  }
  // 10 * 0.33 = 3.3 -> 3 and 7 * 0.33 = 2.31 -> 2.
  EXPECT_TRUE(translations.count({3, 0}) || translations.count({0, 3}));
  EXPECT_TRUE(translations.count({2, 0}) || translations.count({0, 2}));
}

TEST(RoundQuantization, OpenPatchBoundaryBecomesIntegerIsolines) {
  // A 6 x 4 grid patch with the identity map scaled by 0.55: the boundary sides (3.3 x 2.2) round to
  // 3 x 2; boundary edges stay isolines, now on integers; corners are the independent vertices.
  const int nx = 6, ny = 4;
  TriMesh mesh;
  mesh.V.resize((nx + 1) * (ny + 1), 3);
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) mesh.V.row(j * (nx + 1) + i) << i, j, 0;
  mesh.F.resize(2 * nx * ny, 3);
  int f = 0;
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const int a = j * (nx + 1) + i, b = a + 1, c = a + nx + 2, d = a + nx + 1;
      mesh.F.row(f++) << a, b, c;
      mesh.F.row(f++) << a, c, d;
    }
  build_connectivity(mesh);
  Parametrization param;
  param.uv.resize(3 * mesh.num_faces(), 2);
  for (int c = 0; c < 3 * mesh.num_faces(); ++c) {
    const Vec3 p = mesh.position(mesh.F(c / 3, c % 3));
    param.uv.row(c) << p.x(), p.y();
  }
  param.rotation.assign(3 * mesh.num_faces(), 0);
  param.is_cut.assign(mesh.num_edges(), 0);
  std::vector<char> snap(mesh.num_vertices(), 0);
  for (int v : {0, nx, (nx + 1) * ny, (nx + 1) * (ny + 1) - 1}) snap[v] = 1;
  const RoundedMap m = round_parametrization(mesh, param, {}, snap, 0.55, 20);
  EXPECT_EQ(m.unresolved_equations, 0);
  EXPECT_EQ(m.flipped_triangles, 0);
  const int64_t one = m.param.one();
  for (int h = 0; h < mesh.num_halfedges(); ++h) {
    if (mesh.opposite[h] >= 0) continue;
    const IVec2 a = m.param.uv[h], b = m.param.uv[3 * (h / 3) + (h % 3 + 1) % 3];
    const int axis = a[0] == b[0] ? 0 : 1;  // the constant coordinate
    EXPECT_EQ(a[axis], b[axis]);
    EXPECT_EQ(a[axis] % one, 0);
  }
  EXPECT_EQ(m.param.uv[3 * (mesh.num_faces() - 1) + 1], (IVec2{3 * one, 2 * one}));  // far corner (6,4)
}

TEST(RoundQuantization, TracerFailureCountsAsInvalidWithTheReason) {
  const auto cube = test::make_grid_cube(3);
  const TMesh original = build_patch_tmesh(make_polycube_layout({{0, 0, 0}}, {3}, {3}, {3}, false), 0, 1);
  QuantizationOptions options;
  options.scale = 0.2;  // sides 0.6 -> 1
  Progress progress;
  int traced = 0;
  const RoundingResult r = quantize_by_rounding(
      cube.mesh, cube.param, {}, original, options,
      [&](const ExactParametrization& p, Progress&) -> TMesh {
        ++traced;
        EXPECT_EQ(exact_transition_residual(cube.mesh, p), 0);
        throw Error(ErrorCode::StageFailed, "test tracer refuses");
      },
      progress);
  EXPECT_EQ(traced, 1);
  EXPECT_FALSE(r.quantization.valid);
  EXPECT_NE(r.quantization.invalid_reason.find("test tracer refuses"), std::string::npos);
  EXPECT_EQ(Json(r.quantization)["method"], "round");
  EXPECT_TRUE(Json(r.quantization)["objective"].is_null());
}

TEST(RoundQuantization, LengthsAreReadOffTheRetracedTMesh) {
  // Tracer stand-ins returning box T-meshes: integer lengths are read and checked; a T-mesh with a
  // non-integer length (an isoline that was not rounded) is reported as invalid.
  const auto cube = test::make_grid_cube(2);
  const TMesh original = build_patch_tmesh(make_polycube_layout({{0, 0, 0}}, {2}, {2}, {2}, false), 0, 1);
  QuantizationOptions options;
  options.scale = 0.8;  // sides 1.6 -> 2
  Progress progress;
  const RoundingResult r = quantize_by_rounding(
      cube.mesh, cube.param, {}, original, options,
      [&](const ExactParametrization&, Progress&) {
        return build_patch_tmesh(make_polycube_layout({{0, 0, 0}}, {2}, {2}, {2}, false), 0, 1);
      },
      progress);
  EXPECT_TRUE(r.quantization.valid) << r.quantization.invalid_reason;
  EXPECT_EQ(r.quantization.quads_expected, 24);
  EXPECT_EQ(r.quantization.x, std::vector<int64_t>(12, 2));
  const RoundingResult bad = quantize_by_rounding(
      cube.mesh, cube.param, {}, original, options,
      [&](const ExactParametrization&, Progress&) {
        PatchLayout layout = make_polycube_layout({{0, 0, 0}}, {5}, {4}, {4}, false);
        layout.unit = 0.5;
        return build_patch_tmesh(layout, 0, 1);
      },
      progress);
  EXPECT_FALSE(bad.quantization.valid);
  EXPECT_NE(bad.quantization.invalid_reason.find("non-integer"), std::string::npos);
}

// ---------------------------------------------------------------------------------------------
// Options, errors, report.

TEST(Quantization, ScaleHelpers) {
  const TMesh tm = build_patch_tmesh(make_grid_layout({10, 10}, {10}, false, false), 0, 1);  // 20 x 10
  EXPECT_NEAR(quantization_scale_for_quads(tm, 200), 1.0, 1e-12);
  EXPECT_NEAR(quantization_scale_for_edge_length(tm, 800, 2.0), 1.0, 1e-12);
  EXPECT_THROW(quantization_scale_for_quads(tm, 0), Error);
}

TEST(Quantization, ReportHasTheIssueFields) {
  const TMesh tm = single_t_junction(13, 31, 14, 28);
  const Json j = run_greedy(tm, 1.0);
  for (const char* key : {"method", "scale", "valid", "objective", "zero_edges", "stage1_steps", "stage2_steps",
                          "consistency_residual", "quads_expected", "seconds"})
    EXPECT_TRUE(j.contains(key)) << key;
  EXPECT_EQ(j["method"], "greedy");
  EXPECT_EQ(j["consistency_residual"], 0);
}

TEST(Quantization, MalformedTMeshIsRefusedWithAnError) {
  TMesh tm = single_t_junction(13, 31, 14, 28);
  std::swap(tm.cells[0].sides[0], tm.cells[0].sides[1]);
  QuantizationOptions options;
  Progress progress;
  EXPECT_THROW(quantize(tm, options, progress), Error);
  TMesh tm2 = single_t_junction(13, 31, 14, 28);
  tm2.edges[0].cells = {-1, -1};
  EXPECT_THROW(quantize(tm2, options, progress), Error);
  TMesh tm3 = single_t_junction(13, 31, 14, 28);
  std::reverse(tm3.cells[2].sides[0].begin(), tm3.cells[2].sides[0].end());
  tm3.cells[2].sides[0].push_back(tm3.cells[2].sides[0][0]);
  EXPECT_THROW(quantize(tm3, options, progress), Error);
  options.scale = -1;
  EXPECT_THROW(quantize(single_t_junction(13, 31, 14, 28), options, progress), Error);
}

TEST(Quantization, FailureCacheBudgetDoesNotChangeTheResult) {
  // A tiny cache budget switches to cluster-wise region records early: more searches, same steps.
  for (const Family& family : families()) {
    const TMesh tm = family.make(300, 5);
    QuantizationOptions options;
    options.scale = quantization_scale_for_quads(tm, 2500);
    Progress progress;
    const QuantizationResult exact = quantize(tm, options, progress);
    options.cache_budget = 1000;
    const QuantizationResult coarse = quantize(tm, options, progress);
    EXPECT_EQ(coarse.x, exact.x) << family.name;
    EXPECT_EQ(coarse.objective_history, exact.objective_history) << family.name;
    EXPECT_GE(coarse.searches, exact.searches) << family.name;
  }
}

TEST(Quantization, StageTwoTimeLimitReturnsAValidQuantization) {
  const TMesh tm = families()[0].make(400, 3);
  QuantizationOptions options;
  options.scale = quantization_scale_for_quads(tm, 3000);
  options.stage2_time_limit = 1e-9;
  Progress progress;
  const QuantizationResult r = quantize(tm, options, progress);
  EXPECT_FALSE(r.stage2_converged);
  EXPECT_EQ(r.stage2_steps, 0);
  expect_result_invariants(tm, r, "time limit");
}

TEST(Quantization, CancelStopsWithCancelledError) {
  const TMesh tm = families()[1].make(500, 1);
  std::atomic<bool> cancel{true};
  Progress progress([](const std::string&, double) {}, &cancel);
  QuantizationOptions options;
  options.scale = quantization_scale_for_quads(tm, 5000);
  try {
    quantize(tm, options, progress);
    FAIL() << "expected cancellation";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::Cancelled);
  }
}

}  // namespace
}  // namespace qgp

// Exact sanitization of seamless parametrizations (core/parametrization).
#include <gtest/gtest.h>

#include <random>

#include "core/parametrization.h"
#include "test_support.h"

namespace qgp {
namespace {

void perturb(Parametrization& p, double amount, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> noise(-amount, amount);
  for (int c = 0; c < p.uv.rows(); ++c) p.uv.row(c) += Vec2(noise(rng), noise(rng)).transpose();
}

TEST(Parametrization, SyntheticMapsAreSeamless) {
  for (const auto& s : {test::make_grid_cube(4), test::make_grid_torus(12, 8)}) {
    EXPECT_LT(max_transition_residual(s.mesh, s.param), 1e-12);
    for (double a : parametric_areas(s.param)) EXPECT_GT(a, 0);
  }
}

TEST(Parametrization, CubeHasNinetyDegreeTransitions) {
  const auto cube = test::make_grid_cube(3);
  int rotated = 0;
  for (int h = 0; h < cube.mesh.num_halfedges(); ++h) rotated += cube.param.rotation[h] != 0;
  EXPECT_GT(rotated, 0);
}

TEST(Parametrization, SanitizeMakesTransitionsExact) {
  for (int n : {2, 5}) {
    auto cube = test::make_grid_cube(n);
    perturb(cube.param, 1e-7, 7);
    // Perturbation breaks exact seamlessness (corners of one vertex differ)...
    EXPECT_GT(max_transition_residual(cube.mesh, cube.param), 1e-9);
    SanitizeOptions options;
    options.fraction_bits = 30;
    const SanitizeResult r = sanitize_parametrization(cube.mesh, cube.param, options);
    // ...sanitization restores it exactly, moving every corner by little.
    EXPECT_EQ(r.unresolved_equations, 0);
    EXPECT_EQ(exact_transition_residual(cube.mesh, r.param), 0);
    EXPECT_LT(r.max_change, 1e-6);
    EXPECT_LT(max_transition_residual(cube.mesh, r.param.to_double()), 1e-9);
  }
}

TEST(Parametrization, SanitizeSnapsSingularitiesAndTranslationsToIntegers) {
  auto cube = test::make_grid_cube(4);
  perturb(cube.param, 0.05, 3);
  SanitizeOptions options;
  options.fraction_bits = 20;
  options.snap_bits = 0;
  options.snap_vertex.assign(cube.mesh.num_vertices(), 0);
  for (int v = 0; v < cube.mesh.num_vertices(); ++v) {
    const Vec3 p = cube.mesh.position(v);
    const bool corner = (p.x() == 0 || p.x() == 4) && (p.y() == 0 || p.y() == 4) && (p.z() == 0 || p.z() == 4);
    options.snap_vertex[v] = corner;
  }
  const SanitizeResult r = sanitize_parametrization(cube.mesh, cube.param, options);
  EXPECT_EQ(r.unresolved_equations, 0);
  EXPECT_EQ(exact_transition_residual(cube.mesh, r.param), 0);
  const int64_t one = r.param.one();
  for (int h = 0; h < cube.mesh.num_halfedges(); ++h) {
    EXPECT_EQ(r.param.translation[h][0] % one, 0);
    EXPECT_EQ(r.param.translation[h][1] % one, 0);
  }
  for (int c = 0; c < 3 * cube.mesh.num_faces(); ++c)
    if (options.snap_vertex[cube.mesh.F(c / 3, c % 3)]) {
      EXPECT_EQ(r.param.uv[c][0] % one, 0);
      EXPECT_EQ(r.param.uv[c][1] % one, 0);
    }
}

TEST(Parametrization, SanitizeTorusKeepsLoopTranslations) {
  auto torus = test::make_grid_torus(10, 6);
  perturb(torus.param, 1e-6, 11);
  const SanitizeResult r = sanitize_parametrization(torus.mesh, torus.param, SanitizeOptions{});
  EXPECT_EQ(r.unresolved_equations, 0);
  EXPECT_EQ(exact_transition_residual(torus.mesh, r.param), 0);
  EXPECT_LT(r.max_change, 1e-5);
}

TEST(Parametrization, OrientExact) {
  const int64_t big = int64_t(1) << 60;
  EXPECT_EQ(orient2d_exact({0, 0}, {big, 0}, {0, big}), 1);
  EXPECT_EQ(orient2d_exact({0, 0}, {big, 1}, {big - 1, 1}), 1);
  EXPECT_EQ(orient2d_exact({0, 0}, {big, 1}, {big + 1, 1}), -1);
  EXPECT_EQ(orient2d_exact({-big, -big}, {0, 0}, {big, big}), 0);
  EXPECT_EQ(orient2d_exact({1, 1}, {3, 3}, {big, big - 1}), -1);
}

}  // namespace
}  // namespace qgp

// Exact sanitization with isoline constraints (core/sanitize_isolines): feature and boundary
// edges stay exact isolines, transitions exact, also with singularities snapped to integers.
#include <gtest/gtest.h>

#include <random>

#include "core/parametrization.h"
#include "core/sanitize_isolines.h"
#include "polycube.h"
#include "test_support.h"

namespace qgp {
namespace {

// Independent noise on every corner: the map is neither seamless nor feature aligned any more.
void perturb(Parametrization& p, double amount, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> noise(-amount, amount);
  for (int c = 0; c < p.uv.rows(); ++c) p.uv.row(c) += Vec2(noise(rng), noise(rng)).transpose();
}

int non_isolines(const TriMesh& mesh, const ExactParametrization& ex, const std::vector<IsolineConstraint>& iso) {
  int bad = 0;
  for (const IsolineConstraint& c : iso) {
    const int h = c.halfedge;
    bad += ex.uv[h][c.axis] != ex.uv[TriMesh::next(h)][c.axis];
    // The same edge seen from the other face is an isoline too.
    const int o = mesh.opposite[h];
    if (o >= 0) bad += ex.uv[o][0] != ex.uv[TriMesh::next(o)][0] && ex.uv[o][1] != ex.uv[TriMesh::next(o)][1];
  }
  return bad;
}

test::Polycube featured_staircase(unsigned seed, bool open) {
  auto spec = test::staircase({{3, 2, 1}, {2, 2, 1}, {1, 1, 0}},
                              {std::vector<double>{0, 1.37, 2.91, 3.5}, std::vector<double>{0, 0.8, 2.2, 3.0},
                               std::vector<double>{0, 1.1, 1.9, 3.3}});
  spec.subdivisions = 2;
  spec.jitter = 0.12;
  spec.random_diagonals = true;
  spec.seed = seed;
  if (open)
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) spec.open_faces.insert({{i, j, 0}, 5});
  return test::make_polycube(spec);
}

TEST(SanitizeIsolines, FeatureAndBoundaryEdgesBecomeExactIsolines) {
  for (unsigned seed = 1; seed <= 4; ++seed) {
    test::Polycube pc = featured_staircase(seed, seed % 2 == 0);
    const std::vector<IsolineConstraint> iso = isoline_constraints(pc.mesh, pc.param, pc.crease_edges, true);
    ASSERT_GT(iso.size(), 0u);
    perturb(pc.param, 1e-6, seed);
    SanitizeOptions options;
    options.fraction_bits = 24;
    // Plain sanitization makes transitions exact but leaves the noisy features off their isolines...
    const SanitizeResult plain = sanitize_parametrization(pc.mesh, pc.param, options);
    EXPECT_GT(non_isolines(pc.mesh, plain.param, iso), 0);
    // ...this one makes both exact, moving corners by about the noise only.
    const SanitizeResult r = sanitize_with_isolines(pc.mesh, pc.param, iso, options);
    EXPECT_EQ(r.unresolved_equations, 0);
    EXPECT_EQ(exact_transition_residual(pc.mesh, r.param), 0);
    EXPECT_EQ(non_isolines(pc.mesh, r.param, iso), 0);
    EXPECT_LT(r.max_change, 1e-5);
    for (int f = 0; f < pc.mesh.num_faces(); ++f)
      EXPECT_GT(orient2d_exact(r.param.corner(f, 0), r.param.corner(f, 1), r.param.corner(f, 2)), 0);
  }
}

TEST(SanitizeIsolines, SnappedSingularitiesKeepIsolines) {
  // Singular vertices and translations snapped to integers at a coarser scale, as the integer-grid
  // map and the rounding baseline do, with the features kept on (integer) isolines.
  test::Polycube pc = featured_staircase(3, false);
  const std::vector<IsolineConstraint> iso = isoline_constraints(pc.mesh, pc.param, pc.crease_edges, true);
  pc.param.uv *= 2;
  perturb(pc.param, 0.05, 9);
  SanitizeOptions options;
  options.fraction_bits = 20;
  options.snap_bits = 0;
  options.snap_vertex.assign(pc.mesh.num_vertices(), 0);
  for (int v = 0; v < pc.mesh.num_vertices(); ++v) {
    int crease = 0;
    for (int h : outgoing_halfedges(pc.mesh, v)) crease += pc.crease_edges[pc.mesh.edge_of[h]];
    options.snap_vertex[v] = crease >= 3;  // polycube corners
  }
  const SanitizeResult r = sanitize_with_isolines(pc.mesh, pc.param, iso, options);
  EXPECT_EQ(r.unresolved_equations, 0);
  EXPECT_EQ(exact_transition_residual(pc.mesh, r.param), 0);
  EXPECT_EQ(non_isolines(pc.mesh, r.param, iso), 0);
  const int64_t one = r.param.one();
  for (int h = 0; h < pc.mesh.num_halfedges(); ++h) {
    EXPECT_EQ(r.param.translation[h][0] % one, 0);
    EXPECT_EQ(r.param.translation[h][1] % one, 0);
  }
  for (int c = 0; c < 3 * pc.mesh.num_faces(); ++c)
    if (options.snap_vertex[pc.mesh.F(c / 3, c % 3)]) {
      EXPECT_EQ(r.param.uv[c][0] % one, 0);
      EXPECT_EQ(r.param.uv[c][1] % one, 0);
    }
}

TEST(SanitizeIsolines, WithoutConstraintsItIsAPlainSanitization) {
  auto cube = test::make_grid_cube(4);
  perturb(cube.param, 1e-7, 5);
  SanitizeOptions options;
  options.fraction_bits = 30;
  const SanitizeResult r = sanitize_with_isolines(cube.mesh, cube.param, {}, options);
  EXPECT_EQ(r.unresolved_equations, 0);
  EXPECT_EQ(exact_transition_residual(cube.mesh, r.param), 0);
  EXPECT_LT(r.max_change, 1e-6);
}

}  // namespace
}  // namespace qgp

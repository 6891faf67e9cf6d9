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

// A planar patch whose map is its own xy: a sliver A B C (height 0.004) above A B, with D below
// and E above it. On a grid of 1/16 the sliver's corners round onto one line.
struct SliverPatch {
  TriMesh mesh;
  Parametrization param;
};
SliverPatch sliver_patch() {
  SliverPatch s;
  s.mesh.V.resize(5, 3);
  s.mesh.V << 0, 0, 0, 1, 0, 0, 0.5, 0.004, 0, 0.5, -1, 0, 0.5, 1, 0;  // A B C D E
  s.mesh.F.resize(4, 3);
  s.mesh.F << 0, 1, 2, 0, 3, 1, 0, 2, 4, 2, 1, 4;
  build_connectivity(s.mesh);
  s.param.uv.resize(12, 2);
  for (int c = 0; c < 12; ++c) s.param.uv.row(c) = s.mesh.V.row(s.mesh.F(c / 3, c % 3)).head<2>();
  s.param.rotation.assign(12, 0);
  s.param.is_cut.assign(s.mesh.num_edges(), 0);
  return s;
}

bool all_positive(const TriMesh& mesh, const ExactParametrization& ex) {
  for (int f = 0; f < mesh.num_faces(); ++f)
    if (orient2d_exact(ex.corner(f, 0), ex.corner(f, 1), ex.corner(f, 2)) <= 0) return false;
  return true;
}

TEST(SanitizeIsolines, SliverBelowTheGridStaysPositivelyOriented) {
  const SliverPatch s = sliver_patch();
  SanitizeOptions options;
  options.fraction_bits = 4;
  // Rounding alone collapses the sliver...
  EXPECT_FALSE(all_positive(s.mesh, sanitize_parametrization(s.mesh, s.param, options).param));
  // ...the isoline sanitization moves a free corner by a few grid units instead.
  const SanitizeResult r = sanitize_with_isolines(s.mesh, s.param, {}, options);
  EXPECT_TRUE(all_positive(s.mesh, r.param));
  EXPECT_GE(r.reoriented_faces, 1);
  EXPECT_EQ(r.non_positive_faces, 0);
  EXPECT_LE(r.max_change, 16.0 / 16);
}

TEST(SanitizeIsolines, SliverCornerOnAnIsolineMovesAlongIt) {
  // A B is a v-isoline and C E a u-isoline: C is tied to E, yet its v is free to move.
  const SliverPatch s = sliver_patch();
  SanitizeOptions options;
  options.fraction_bits = 4;
  const std::vector<IsolineConstraint> iso = {{0, 1}, {7, 0}};  // A->B (face 0), C->E (face 2)
  const SanitizeResult r = sanitize_with_isolines(s.mesh, s.param, iso, options);
  EXPECT_EQ(r.unresolved_equations, 0);
  EXPECT_EQ(r.non_positive_faces, 0);
  EXPECT_GE(r.reoriented_faces, 1);
  EXPECT_TRUE(all_positive(s.mesh, r.param));
  EXPECT_EQ(non_isolines(s.mesh, r.param, iso), 0);
}

TEST(SanitizeIsolines, SliverPinnedByIsolinesIsReportedNotMoved) {
  // A C and A B as v-isolines put all three corners of the sliver on one line: no corner may move.
  const SliverPatch s = sliver_patch();
  SanitizeOptions options;
  options.fraction_bits = 4;
  const std::vector<IsolineConstraint> iso = {{0, 1}, {2, 1}};  // halfedges A->B and C->A of face 0
  const SanitizeResult r = sanitize_with_isolines(s.mesh, s.param, iso, options);
  EXPECT_EQ(r.unresolved_equations, 0);
  EXPECT_EQ(r.non_positive_faces, 1);
  EXPECT_EQ(orient2d_exact(r.param.corner(0, 0), r.param.corner(0, 1), r.param.corner(0, 2)), 0);
  EXPECT_EQ(r.param.corner(0, 0)[1], r.param.corner(0, 2)[1]);
}

}  // namespace
}  // namespace qgp

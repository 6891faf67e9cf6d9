// Seamless map (stage 1c): exact elimination, field-guided energy, regularity repair with Ipopt.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <iostream>
#include <limits>
#include <map>
#include <queue>
#include <random>
#include <set>

#include "core/error.h"
#include "core/timer.h"
#include "cross_field/cross_field.h"
#include "cut_graph/cut_graph.h"
#include "intake/read_mesh_file.h"
#include "pipeline/split_faces.h"
#include "seamless_map/linear_elimination.h"
#include "seamless_map/orientation.h"
#include "seamless_map/parametrization_problem.h"
#include "seamless_map/seamless_map.h"
#include "test_support.h"

namespace qgp {
namespace {

// ---------------------------------------------------------------------------------------------
// Synthetic inputs: a cross field and cut graph derived from an exact seamless map.

struct FieldInput {
  CrossField field;
  CutGraph cut;
};

Vec3 face_gradient(const TriMesh& mesh, int f, const double values[3]) {
  const Vec3 p[3] = {mesh.position(mesh.F(f, 0)), mesh.position(mesh.F(f, 1)), mesh.position(mesh.F(f, 2))};
  const Vec3 n = (p[1] - p[0]).cross(p[2] - p[0]);
  const double area2 = n.norm();
  Vec3 g = Vec3::Zero();
  for (int k = 0; k < 3; ++k) g += values[k] * n.normalized().cross(p[(k + 2) % 3] - p[(k + 1) % 3]) / area2;
  return g;
}

// frame_u = direction of grad u of `param` on the mesh's (possibly deformed) geometry; rotations
// from the map. comb: re-comb the charts along a dual spanning tree and prune the cut to a cut
// graph ending at singularities (as the cut-graph stage does).
FieldInput field_from_param(const TriMesh& mesh, const Parametrization& param, bool comb) {
  const int nf = mesh.num_faces();
  FieldInput in;
  in.cut.frame_u.resize(nf);
  for (int f = 0; f < nf; ++f) {
    const double u[3] = {param.uv(3 * f, 0), param.uv(3 * f + 1, 0), param.uv(3 * f + 2, 0)};
    in.cut.frame_u[f] = face_gradient(mesh, f, u).normalized();
  }
  in.cut.rotation = param.rotation;
  in.cut.is_cut.assign(mesh.num_edges(), 0);
  for (int e = 0; e < mesh.num_edges(); ++e) in.cut.is_cut[e] = param.is_cut.empty() ? 0 : param.is_cut[e];
  if (comb) {
    // Chart rotation k_f with k_g = k_f - r across tree edges: new r' = r + k_g - k_f.
    std::vector<int> k(nf, -1);
    std::vector<char> tree_edge(mesh.num_edges(), 0);
    std::queue<int> queue;
    k[0] = 0;
    queue.push(0);
    while (!queue.empty()) {
      const int f = queue.front();
      queue.pop();
      for (int j = 0; j < 3; ++j) {
        const int h = 3 * f + j, o = mesh.opposite[h];
        if (o < 0 || k[o / 3] >= 0) continue;
        k[o / 3] = ((k[f] - param.rotation[h]) % 4 + 4) % 4;
        tree_edge[mesh.edge_of[h]] = 1;
        queue.push(o / 3);
      }
    }
    for (int h = 0; h < 3 * nf; ++h) {
      if (mesh.opposite[h] < 0) continue;
      in.cut.rotation[h] = static_cast<int8_t>(((param.rotation[h] + k[mesh.opposite[h] / 3] - k[h / 3]) % 4 + 4) % 4);
    }
    for (int f = 0; f < nf; ++f) {
      const Vec3 n = mesh.face_normal_unnormalized(f).normalized();
      const Vec3 fu = in.cut.frame_u[f], fv = n.cross(fu);
      const Vec3 options[4] = {fu, -fv, -fu, fv};  // +u axis of the chart rotated by k quarter turns
      in.cut.frame_u[f] = options[k[f]];
    }
    std::vector<int> holonomy(mesh.num_vertices(), 0), degree(mesh.num_vertices(), 0);
    for (int h = 0; h < 3 * nf; ++h)
      if (mesh.opposite[h] >= 0) holonomy[mesh.to(h)] += in.cut.rotation[h];
    for (int e = 0; e < mesh.num_edges(); ++e) {
      in.cut.is_cut[e] = !tree_edge[e] && !mesh.is_boundary_edge(e);
      if (in.cut.is_cut[e]) ++degree[mesh.from(mesh.edge_halfedge[e])], ++degree[mesh.to(mesh.edge_halfedge[e])];
    }
    for (bool changed = true; changed;) {
      changed = false;
      for (int e = 0; e < mesh.num_edges(); ++e) {
        if (!in.cut.is_cut[e]) continue;
        const int h = mesh.edge_halfedge[e];
        for (int v : {mesh.from(h), mesh.to(h)})
          if (degree[v] == 1 && holonomy[v] % 4 == 0 && in.cut.is_cut[e]) {
            in.cut.is_cut[e] = 0;
            --degree[mesh.from(h)], --degree[mesh.to(h)];
            changed = true;
          }
      }
    }
    for (int h = 0; h < 3 * nf; ++h)
      if (mesh.opposite[h] >= 0 && !in.cut.is_cut[mesh.edge_of[h]] && in.cut.rotation[h] != 0)
        throw std::runtime_error("combing left a rotation on a pruned edge");
  }
  in.cut.singular_vertex.assign(mesh.num_vertices(), 0);
  for (int e = 0; e < mesh.num_edges(); ++e) in.cut.num_cut_edges += in.cut.is_cut[e];
  in.field.feature_edge.assign(mesh.num_edges(), 0);
  return in;
}

// Moves vertices (connectivity kept): onto a sphere around the centre, then random noise.
void deform(TriMesh& mesh, double sphere, double noise, unsigned seed) {
  Vec3 centre = Vec3::Zero();
  for (int v = 0; v < mesh.num_vertices(); ++v) centre += mesh.position(v);
  centre /= mesh.num_vertices();
  double radius = 0;
  for (int v = 0; v < mesh.num_vertices(); ++v) radius = std::max(radius, (mesh.position(v) - centre).norm());
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-noise, noise);
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    Vec3 p = mesh.position(v);
    const Vec3 s = centre + (p - centre).normalized() * radius * 0.6;
    p = (1 - sphere) * p + sphere * s + Vec3(u(rng), u(rng), u(rng));
    mesh.V.row(v) = p.transpose();
  }
}

// Rotates frames around the face normals by angle(p) (a localized twist).
void twist(const TriMesh& mesh, CutGraph& cut, const Vec3& centre, double amplitude, double sigma) {
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const Vec3 c = (mesh.position(mesh.F(f, 0)) + mesh.position(mesh.F(f, 1)) + mesh.position(mesh.F(f, 2))) / 3;
    const double angle = amplitude * std::exp(-(c - centre).squaredNorm() / (sigma * sigma));
    const Vec3 n = mesh.face_normal_unnormalized(f).normalized();
    const Vec3 fu = cut.frame_u[f];
    cut.frame_u[f] = std::cos(angle) * fu + std::sin(angle) * n.cross(fu);
  }
}

int count_exact_flips(const TriMesh& mesh, const Parametrization& param, int* degenerate) {
  int flipped = 0;
  *degenerate = 0;
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const int s = orient2d_sign(param.corner(f, 0), param.corner(f, 1), param.corner(f, 2));
    flipped += s < 0;
    *degenerate += s == 0;
  }
  return flipped;
}

double param_diagonal(const Parametrization& param) {
  const Vec2 lo = param.uv.colwise().minCoeff().transpose(), hi = param.uv.colwise().maxCoeff().transpose();
  return (hi - lo).norm();
}

// Invariants every seamless map must satisfy.
void expect_valid_map(const TriMesh& mesh, const SeamlessMap& map, const std::string& what) {
  SCOPED_TRACE(what);
  int degenerate = 0;
  EXPECT_EQ(count_exact_flips(mesh, map.param, &degenerate), 0);
  EXPECT_EQ(degenerate, 0);
  EXPECT_EQ(map.stats.flipped_triangles, 0);
  EXPECT_EQ(map.stats.degenerate_triangles, 0);
  const double diag = param_diagonal(map.param);
  EXPECT_GT(diag, 0);
  EXPECT_LE(max_transition_residual(mesh, map.param), 1e-9 * diag);
  EXPECT_LE(map.stats.max_transition_residual, 1e-9 * diag);
  // Exact sanitization succeeds and keeps every triangle positive.
  SanitizeOptions so;
  so.fraction_bits = 24;
  const SanitizeResult s = sanitize_parametrization(mesh, map.param, so);
  EXPECT_EQ(s.unresolved_equations, 0);
  EXPECT_EQ(exact_transition_residual(mesh, s.param), 0);
  int bad = 0;
  for (int f = 0; f < mesh.num_faces(); ++f)
    bad += orient2d_exact(s.param.corner(f, 0), s.param.corner(f, 1), s.param.corner(f, 2)) <= 0;
  EXPECT_EQ(bad, 0);
}

void print_stats(const std::string& name, const SeamlessMap& m, double seconds) {
  const auto& s = m.stats;
  std::cout << "[seamless] " << name << ": flipped " << s.flipped_before_ipopt << " -> " << s.flipped_triangles
            << ", degenerate " << s.degenerate_before_ipopt << " -> " << s.degenerate_triangles << ", ipopt solves "
            << s.ipopt_solves << " iterations " << s.ipopt_iterations << " rounds "
            << ::testing::PrintToString(s.repair_bad_faces) << ", field-frame solves " << s.field_frame_solves
            << ", winding defects " << s.winding_defects << ", region faces " << s.max_region_faces << ", energy "
            << s.energy << ", min area ratio " << s.min_area_ratio << ", residual " << s.max_transition_residual << ", "
            << seconds << " s\n";
}

SeamlessMap run(const TriMesh& mesh, const FieldInput& in, double edge_length, const std::string& name) {
  Progress progress;
  SeamlessMapOptions o;
  o.edge_length = edge_length;
  Timer t;
  SeamlessMap m = compute_seamless_map(mesh, in.field, in.cut, o, progress);
  print_stats(name, m, t.seconds());
  return m;
}

// ---------------------------------------------------------------------------------------------
// Exact elimination and predicates.

TEST(LinearElimination, UnitPivotsKeepIntegerCoefficients) {
  std::mt19937 rng(5);
  for (int trial = 0; trial < 50; ++trial) {
    const int n = 12;
    LinearElimination elim(n);
    std::vector<std::pair<LinearForm, double>> equations;
    std::uniform_int_distribution<int> var(0, n - 1), coeff(-1, 1), count(2, 4);
    for (int e = 0; e < 8; ++e) {
      LinearForm form;
      for (int k = count(rng); k > 0; --k) form.push_back({var(rng), static_cast<double>(coeff(rng))});
      equations.push_back({form, 0.0});
      elim.add_equation(form, 0.0);
    }
    // Every expansion has integer coefficients and satisfies every equation for any free values.
    std::vector<double> free_value(n);
    for (double& v : free_value) v = std::uniform_real_distribution<double>(-10, 10)(rng);
    std::vector<double> value(n);
    for (int v = 0; v < n; ++v) {
      double constant = 0;
      const LinearForm form = elim.expansion(v, &constant);
      value[v] = constant;
      for (const LinearTerm& t : form) {
        EXPECT_FALSE(elim.is_eliminated(t.var));
        EXPECT_EQ(t.coeff, std::round(t.coeff));
        value[v] += t.coeff * free_value[t.var];
      }
    }
    for (const auto& [form, rhs] : equations) {
      double s = -rhs;
      for (const LinearTerm& t : form) s += t.coeff * value[t.var];
      EXPECT_NEAR(s, 0.0, 1e-12);
    }
    EXPECT_EQ(elim.non_integer_pivots(), 0);
    EXPECT_EQ(elim.num_eliminated() + elim.redundant_equations() + elim.inconsistent_equations(), 8);
  }
}

TEST(LinearElimination, RedundantInconsistentAndCommonFactor) {
  LinearElimination elim(3);
  EXPECT_EQ(elim.add_equation({{0, 1}, {1, -1}}, 2.0), LinearElimination::Outcome::Eliminated);
  EXPECT_EQ(elim.add_equation({{1, 1}, {2, -1}}, 1.0), LinearElimination::Outcome::Eliminated);
  EXPECT_EQ(elim.add_equation({{0, 1}, {2, -1}}, 3.0), LinearElimination::Outcome::Redundant);
  EXPECT_EQ(elim.add_equation({{0, 1}, {2, -1}}, 4.0), LinearElimination::Outcome::Inconsistent);
  LinearElimination two(2);
  EXPECT_EQ(two.add_equation({{0, 2}, {1, -2}}, 6.0), LinearElimination::Outcome::Eliminated);
  double c = 0;
  const LinearForm f = two.expansion(0, &c);
  EXPECT_EQ(two.non_integer_pivots(), 0);
  ASSERT_EQ(f.size(), 1u);
  EXPECT_EQ(f[0].coeff, 1.0);
  EXPECT_EQ(c, 3.0);
}

TEST(LinearElimination, RoundingResidueOfANonIntegerPivotIsNoCoefficient) {
  // 22 x0 + 15 x1 = 0 has no unit coefficient: x0 = -15/22 x1, and substituting it back leaves
  // 22 * (-15/22) + 15 = 1.8e-15 on x1 in floating point. That residue is no coefficient: the same
  // equation again is redundant (not a pivot that pins x1 to 0), with another right-hand side
  // inconsistent (not x1 = 1 / 1.8e-15). block with sharp edges at 60 degrees: 67 such pivots in
  // its integer-grid map's hard constraints made 539 of them "inconsistent" and the map useless.
  ASSERT_NE(22 * (-15.0 / 22) + 15, 0.0);  // the residue this test is about
  for (const double rhs : {0.0, 1.0}) {
    SCOPED_TRACE(rhs);
    LinearElimination elim(3);
    EXPECT_EQ(elim.add_equation({{0, 22}, {1, 15}}, 0.0), LinearElimination::Outcome::Eliminated);
    EXPECT_EQ(elim.non_integer_pivots(), 1);
    EXPECT_EQ(elim.add_equation({{0, 22}, {1, 15}}, rhs),
              rhs == 0 ? LinearElimination::Outcome::Redundant : LinearElimination::Outcome::Inconsistent);
    EXPECT_FALSE(elim.is_eliminated(1));
    // With a third variable the residue does not stay in its definition either.
    EXPECT_EQ(elim.add_equation({{0, 22}, {1, 15}, {2, 1}}, 5.0), LinearElimination::Outcome::Eliminated);
    double c = 0;
    const LinearForm f = elim.expansion(2, &c);
    EXPECT_TRUE(f.empty());
    EXPECT_EQ(c, 5.0);
  }
}

TEST(Orientation, ExactOnNearlyCollinearPoints) {
  // Points on the line y = x through large coordinates, perturbed by one ulp.
  const double big = 1e8;
  const Vec2 a(0.5, 0.5), b(big, big);
  EXPECT_EQ(orient2d_sign(a, b, Vec2(12.0, 12.0)), 0);
  EXPECT_EQ(orient2d_sign(a, b, Vec2(12.0, std::nextafter(12.0, 13.0))), 1);
  EXPECT_EQ(orient2d_sign(a, b, Vec2(12.0, std::nextafter(12.0, 11.0))), -1);
  EXPECT_EQ(orient2d_sign(Vec2(0, 0), Vec2(1, 0), Vec2(0, 1)), 1);
  EXPECT_EQ(orient2d_sign(Vec2(0, 0), Vec2(0, 1), Vec2(1, 0)), -1);
}

// ---------------------------------------------------------------------------------------------
// Synthetic maps.

TEST(SeamlessMap, ReproducesExactGridMaps) {
  // On the exact cube and a torus the field is integrable: the map matches the field exactly.
  auto cube = test::make_grid_cube(6);
  const SeamlessMap c = run(cube.mesh, field_from_param(cube.mesh, cube.param, true), 1.0, "exact cube");
  expect_valid_map(cube.mesh, c, "cube");
  EXPECT_LT(c.stats.energy, 1e-18);
  EXPECT_EQ(c.stats.flipped_before_ipopt, 0);
  EXPECT_EQ(c.stats.ipopt_iterations, 0);
  auto torus = test::make_grid_torus(24, 12, 3, 1);
  // The torus field (grad u of the grid map) is not unit speed: only check validity.
  const SeamlessMap t = run(torus.mesh, field_from_param(torus.mesh, torus.param, true), 0.3, "torus");
  expect_valid_map(torus.mesh, t, "torus");
  // Combed charts: across every non-cut edge the two corners of a vertex agree exactly.
  for (int h = 0; h < torus.mesh.num_halfedges(); ++h) {
    const int o = torus.mesh.opposite[h];
    if (o < 0 || t.param.is_cut[torus.mesh.edge_of[h]]) continue;
    EXPECT_EQ(t.param.corner(h / 3, h % 3), t.param.corner(o / 3, (o % 3 + 1) % 3));
  }
}

// The exact cube map's cone angles in quarter turns (3 at the 8 corners, 4 elsewhere).
std::vector<int> cube_cones(const test::SyntheticParametrized& cube) {
  std::vector<double> angle(cube.mesh.num_vertices(), 0.0);
  for (int f = 0; f < cube.mesh.num_faces(); ++f)
    for (int k = 0; k < 3; ++k) {
      const Vec2 a = cube.param.corner(f, (k + 1) % 3) - cube.param.corner(f, k);
      const Vec2 b = cube.param.corner(f, (k + 2) % 3) - cube.param.corner(f, k);
      angle[cube.mesh.F(f, k)] += std::atan2(a.x() * b.y() - a.y() * b.x(), a.dot(b));
    }
  std::vector<int> cone(cube.mesh.num_vertices());
  for (int v = 0; v < cube.mesh.num_vertices(); ++v) cone[v] = static_cast<int>(std::lround(angle[v] / (M_PI / 2)));
  return cone;
}

TEST(SeamlessMap, WindingDefectsCountOneRingsAFullTurnOffTheirCone) {
  auto cube = test::make_grid_cube(4);
  const FieldInput in = field_from_param(cube.mesh, cube.param, true);
  const SeamlessMap c = run(cube.mesh, in, 1.0, "exact cube");
  EXPECT_EQ(c.stats.winding_defects, 0);  // every one-ring winds as the field's cone
  ParametrizationProblem problem(cube.mesh, in.cut.rotation, in.cut.is_cut, in.cut.frame_u, 1.0);
  std::vector<int> cone = cube_cones(cube);  // the exact cube map's own cones
  int corners = 0;
  for (int k : cone) corners += k == 3;
  EXPECT_EQ(corners, 8);
  problem.set_cone_angles(cone);
  EXPECT_EQ(problem.winding_defects(c.param), 0);
  // Claim a cube corner were a valence-7 cone, and a flat vertex a valence-8 one: both are a full
  // turn off what the map winds.
  std::vector<int> claimed;
  for (int v = 0; v < cube.mesh.num_vertices() && claimed.size() < 2; ++v)
    if ((claimed.empty() && cone[v] == 3) || (claimed.size() == 1 && cone[v] == 4)) cone[v] += 4, claimed.push_back(v);
  problem.set_cone_angles(cone);
  EXPECT_EQ(problem.winding_defects(c.param), 2);
  EXPECT_EQ(problem.wound_vertices(c.param), claimed);
  EXPECT_TRUE(c.bad_vertices.empty());
  EXPECT_THROW(problem.set_cone_angles(std::vector<int>(3, 4)), Error);
}

TEST(SeamlessMap, DeformedSurfacesGiveValidMaps) {
  for (unsigned seed : {1u, 2u}) {
    auto cube = test::make_grid_cube(10);
    deform(cube.mesh, 1.0, 0.15, seed);  // onto a sphere, then noise
    const FieldInput in = field_from_param(cube.mesh, cube.param, true);
    for (double L : {0.25, 1.0, 4.0}) {
      const SeamlessMap m = run(cube.mesh, in, L, "sphere cube L=" + std::to_string(L));
      expect_valid_map(cube.mesh, m, "sphere cube");
    }
    auto torus = test::make_grid_torus(30, 14, 3, 1.2);
    deform(torus.mesh, 0.0, 0.05, seed);
    const SeamlessMap t = run(torus.mesh, field_from_param(torus.mesh, torus.param, true), 0.4, "noisy torus");
    expect_valid_map(torus.mesh, t, "noisy torus");
  }
}

TEST(SeamlessMap, UvUnitIsTheEdgeLength) {
  // Halving the target edge length doubles every parametric length (the energy is scale-free).
  auto cube = test::make_grid_cube(6);
  deform(cube.mesh, 1.0, 0.05, 3);
  const FieldInput in = field_from_param(cube.mesh, cube.param, true);
  const SeamlessMap a = run(cube.mesh, in, 1.0, "L=1"), b = run(cube.mesh, in, 0.5, "L=0.5");
  double worst = 0;
  for (int f = 0; f < cube.mesh.num_faces(); ++f)
    for (int k = 0; k < 3; ++k) {
      const Vec2 ea = a.param.corner(f, (k + 1) % 3) - a.param.corner(f, k);
      const Vec2 eb = b.param.corner(f, (k + 1) % 3) - b.param.corner(f, k);
      worst = std::max(worst, (eb - 2 * ea).norm());
    }
  EXPECT_LT(worst, 1e-9);
  EXPECT_NEAR(b.stats.energy, 4 * a.stats.energy, 1e-9 * (1 + b.stats.energy));  // E ~ 1/L^2
}

TEST(SeamlessMap, IpoptRepairsFlipsOfATwistedField) {
  // A localized twist of the field makes the equality-only optimum fold; the repair removes it.
  int repaired = 0;
  for (double amplitude : {4.0, 6.0, 12.0}) {
    auto cube = test::make_grid_cube(12);
    deform(cube.mesh, 1.0, 0.0, 1);
    FieldInput in = field_from_param(cube.mesh, cube.param, true);
    twist(cube.mesh, in.cut, Vec3(6, 6, 12), amplitude, 2.5);
    const SeamlessMap m = run(cube.mesh, in, 0.5, "twist " + std::to_string(amplitude));
    EXPECT_GT(m.stats.flipped_before_ipopt, 0);
    EXPECT_GT(m.stats.ipopt_iterations, 0);
    expect_valid_map(cube.mesh, m, "twist");
    repaired += m.stats.flipped_triangles == 0;
  }
  EXPECT_EQ(repaired, 3);
}

// ---------------------------------------------------------------------------------------------
// The reusable problem: linear constraints (hard, penalty, paper §7.1) and cancellation.

// Translation of the transition across cut halfedge h, axis a, as a constraint on corners:
// t = p_g(from h) - R^r p_f(from h).
std::vector<CornerTerm> translation_terms(const TriMesh& mesh, const Parametrization& p, int h, int a) {
  const int o = mesh.opposite[h];
  const int r = ((p.rotation[h] % 4) + 4) % 4;
  // (R^r p)[a] = sign * p[source]
  const int source = (r % 2 == 0) ? a : 1 - a;
  const double sign = (r == 0 || (r == 1 && a == 1) || (r == 3 && a == 0)) ? 1.0 : -1.0;
  return {{3 * (o / 3) + (o % 3 + 1) % 3, a, 1.0}, {h, source, -sign}};
}

TEST(ParametrizationProblem, IntegerTranslationsHardPenaltyAndRelinearized) {
  auto torus = test::make_grid_torus(30, 14, 3, 1.2);
  deform(torus.mesh, 0.0, 0.05, 9);
  const FieldInput in = field_from_param(torus.mesh, torus.param, true);
  ParametrizationProblem problem(torus.mesh, in.cut.rotation, in.cut.is_cut, in.cut.frame_u, 0.35);
  Progress progress;
  const ParametrizationSolution free_map = problem.solve({}, progress);
  // Quantize the translation of one halfedge per cut loop (both axes), one unit off the
  // continuous value so that the map has to change.
  std::vector<std::pair<int, double>> targets;
  std::vector<char> loop_done(2, 0);
  int constraints = 0;
  for (int h = 0; h < torus.mesh.num_halfedges() && constraints < 4; ++h) {
    const int o = torus.mesh.opposite[h];
    if (o < 0 || o < h || !free_map.param.is_cut[torus.mesh.edge_of[h]]) continue;
    const Vec2 t = free_map.param.translation(torus.mesh, h);
    const int loop = std::abs(t.x()) > std::abs(t.y()) ? 0 : 1;  // which loop this edge closes
    if (loop_done[loop]) continue;
    loop_done[loop] = 1;
    for (int a = 0; a < 2; ++a, ++constraints)
      problem.add_linear_constraint(translation_terms(torus.mesh, free_map.param, h, a),
                                    std::round(t[a]) + (a == loop ? 1 : 0));
  }
  ASSERT_EQ(constraints, 4);
  ParametrizationSolveOptions hard;
  const ParametrizationSolution h1 = problem.solve(hard, progress);
  EXPECT_LT(h1.stats.constraint_violation, 1e-9);
  EXPECT_EQ(h1.stats.flipped + h1.stats.degenerate, 0);
  EXPECT_EQ(h1.stats.inconsistent_constraints, 0);
  EXPECT_GT(h1.stats.energy, free_map.stats.energy);  // the constraints cost energy
  ParametrizationSolveOptions soft;
  soft.linear_constraints = ConstraintMode::Penalty;
  soft.penalty_weight = 1e6;
  const ParametrizationSolution p1 = problem.solve(soft, progress);
  EXPECT_LT(p1.stats.constraint_violation, 1e-3);
  EXPECT_GT(p1.stats.constraint_violation, 0);
  const ParametrizationSolution r1 = problem.solve_with_relinearization(hard, 1e-4, 5, progress);
  EXPECT_LT(r1.stats.constraint_violation, 1e-9);
  EXPECT_EQ(r1.stats.flipped + r1.stats.degenerate, 0);
  EXPECT_LT(max_transition_residual(torus.mesh, r1.param), 1e-9 * param_diagonal(r1.param));
}

// A deformed 8 x 8 x 8 grid cube as a parametrization problem (edge length 1.5, the field's cut) and
// its unconstrained map.
struct CubeProblem {
  test::SyntheticParametrized cube = deformed_cube();
  FieldInput in = field_from_param(cube.mesh, cube.param, true);
  ParametrizationProblem problem{cube.mesh, in.cut.rotation, in.cut.is_cut, in.cut.frame_u, 1.5};
  Progress progress;
  ParametrizationSolution free_map = problem.solve({}, progress);

  static test::SyntheticParametrized deformed_cube() {
    auto cube = test::make_grid_cube(8);
    deform(cube.mesh, 1.0, 0.1, 4);
    return cube;
  }
};

TEST(ParametrizationProblem, SingularitiesAtIntegerPointsWithoutPin) {
  // Cube corners (the singularities) pinned to integer points in one of their charts; no wedge
  // pinned at the origin: the constraints fix the translation.
  CubeProblem p;
  p.problem.set_pin_translation(false);
  std::vector<char> done(p.cube.mesh.num_vertices(), 0);
  std::vector<int> corners;
  const TriMesh undeformed = test::make_grid_cube(8).mesh;
  for (int c = 0; c < 3 * p.cube.mesh.num_faces(); ++c) {
    const int v = p.cube.mesh.F(c / 3, c % 3);
    const Vec3 x = undeformed.position(v);
    const bool corner = (x.x() == 0 || x.x() == 8) && (x.y() == 0 || x.y() == 8) && (x.z() == 0 || x.z() == 8);
    if (!corner || done[v]) continue;
    done[v] = 1;
    corners.push_back(c);
    for (int a = 0; a < 2; ++a) p.problem.add_linear_constraint({{c, a, 1.0}}, std::round(p.free_map.param.uv(c, a)));
  }
  ASSERT_EQ(corners.size(), 8u);
  const ParametrizationSolution s = p.problem.solve({}, p.progress);
  EXPECT_LT(s.stats.constraint_violation, 1e-9);
  EXPECT_EQ(s.stats.flipped + s.stats.degenerate, 0);
  for (int c : corners)
    for (int a = 0; a < 2; ++a) EXPECT_NEAR(s.param.uv(c, a), std::round(s.param.uv(c, a)), 1e-9);
  // Every copy of a singularity (its other wedges) lands on an integer point too: the transitions
  // carry integer points to integer points once the translations are integral... at least the
  // sanitized map must be exactly seamless.
  const SanitizeResult ex = sanitize_parametrization(p.cube.mesh, s.param, SanitizeOptions{});
  EXPECT_EQ(ex.unresolved_equations, 0);
  EXPECT_EQ(exact_transition_residual(p.cube.mesh, ex.param), 0);
}

TEST(ParametrizationProblem, CancelStopsTheIpoptRepair) {
  auto cube = test::make_grid_cube(12);
  deform(cube.mesh, 1.0, 0.0, 1);
  FieldInput in = field_from_param(cube.mesh, cube.param, true);
  twist(cube.mesh, in.cut, Vec3(6, 6, 12), 6.0, 2.5);
  std::atomic<bool> cancel{false};
  int updates_after_cancel = 0;
  Progress progress(
      [&](const std::string&, double fraction) {
        if (cancel) ++updates_after_cancel;
        if (fraction > 0.35) cancel = true;  // inside the Ipopt repair (after the Cholesky solve)
      },
      &cancel);
  progress.begin_stage("seamless_map");
  SeamlessMapOptions o;
  o.edge_length = 0.5;
  try {
    compute_seamless_map(cube.mesh, in.field, in.cut, o, progress);
    FAIL() << "expected a cancellation";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::Cancelled);
  }
  EXPECT_LE(updates_after_cancel, 1);
}

// Hard constraints pin the three corners of faces 40, 200 and 333 to clockwise triangles: no pose
// unfolds them.
void pin_clockwise_faces(CubeProblem& p) {
  for (int f : {40, 200, 333}) {
    const Vec2 p0(p.free_map.param.uv(3 * f, 0), p.free_map.param.uv(3 * f, 1));
    const Vec2 corner[3] = {p0, p0 + Vec2(0, 0.4), p0 + Vec2(0.4, 0)};  // clockwise
    for (int k = 0; k < 3; ++k)
      for (int a = 0; a < 2; ++a) p.problem.add_linear_constraint({{3 * f + k, a, 1.0}}, corner[k][a]);
  }
}

// pin_clockwise_faces, with the cube's cone angles: the repair then also winds one-rings and, when
// its local rounds leave bad faces, solves globally in the field's frame.
void pin_clockwise_faces_with_cones(CubeProblem& p) {
  pin_clockwise_faces(p);
  p.problem.set_cone_angles(cube_cones(p.cube));
}

void expect_pinned_faces_folded(const ParametrizationSolution& s) {
  EXPECT_LT(s.stats.constraint_violation, 1e-9);
  EXPECT_GE(s.stats.flipped, 3);
  EXPECT_EQ(static_cast<int>(s.stats.bad_after_round.size()), s.stats.repair_rounds);
  EXPECT_EQ(static_cast<int>(s.stats.seconds_of_round.size()), s.stats.repair_rounds);
}

TEST(ParametrizationProblem, CountStagnationEndsARepairThatCannotSucceed) {
  // The full budget ends with only the pinned faces folded (18 rounds here); with
  // count_stagnation_rounds the repair stops one turn of the strategies after the count last dropped
  // (5 rounds here, folds around the pinned faces left): the trade a caller with a fallback makes.
  CubeProblem p;
  ASSERT_EQ(p.free_map.stats.flipped + p.free_map.stats.degenerate, 0);
  pin_clockwise_faces(p);
  ParametrizationSolveOptions plain;
  const ParametrizationSolution unbounded = p.problem.solve(plain, p.progress);
  ParametrizationSolveOptions bounded = plain;
  bounded.count_stagnation_rounds = 4;
  const ParametrizationSolution stopped = p.problem.solve(bounded, p.progress);
  for (const ParametrizationSolution* s : {&unbounded, &stopped}) expect_pinned_faces_folded(*s);
  // At least one turn of the strategies, fewer rounds than the full budget, never a better result.
  EXPECT_GE(stopped.stats.repair_rounds, bounded.count_stagnation_rounds);
  EXPECT_LT(stopped.stats.repair_rounds, unbounded.stats.repair_rounds);
  EXPECT_LE(unbounded.stats.flipped + unbounded.stats.degenerate, stopped.stats.flipped + stopped.stats.degenerate);
}

TEST(ParametrizationProblem, RegionStagnationEndsRoundsOverMostOfTheMesh) {
  // region_stagnation_rounds counts only the rounds without fewer bad faces whose region spans at
  // least half the faces: the repair goes on at least as long as with count_stagnation_rounds (the
  // bad faces' rings double until their regions cover most of this small cube), and still ends
  // before the full budget.
  CubeProblem p;
  pin_clockwise_faces(p);
  ParametrizationSolveOptions plain;
  const ParametrizationSolution unbounded = p.problem.solve(plain, p.progress);
  ParametrizationSolveOptions by_count = plain, by_region = plain;
  by_count.count_stagnation_rounds = 4;
  by_region.region_stagnation_rounds = 4;
  const ParametrizationSolution counted = p.problem.solve(by_count, p.progress);
  const ParametrizationSolution regional = p.problem.solve(by_region, p.progress);
  expect_pinned_faces_folded(regional);
  EXPECT_GE(regional.stats.repair_rounds, counted.stats.repair_rounds);
  EXPECT_LT(regional.stats.repair_rounds, unbounded.stats.repair_rounds);
  // The last four rounds brought no fewer bad faces than the best before them.
  const std::vector<int>& bad = regional.stats.bad_after_round;
  ASSERT_GE(bad.size(), 5u);
  const int before = *std::min_element(bad.begin(), bad.end() - 4);
  for (auto it = bad.end() - 4; it != bad.end(); ++it) EXPECT_GE(*it, before);
}

TEST(ParametrizationProblem, RepairIsDeclinedOverTheCallersShareOfBadFaces) {
  // max_bad_share_to_repair: a start with more bad faces than this share of the faces is returned
  // as solved, unrepaired and marked declined (the pipeline sends such a part on needle triangles
  // to its isotropic remesh); at exactly the share the repair runs.
  CubeProblem p;
  pin_clockwise_faces(p);
  const int nf = p.cube.mesh.num_faces();
  ParametrizationSolveOptions plain;
  const ParametrizationSolution repaired = p.problem.solve(plain, p.progress);
  const ParametrizationSolveStats& first = repaired.stats;
  const int bad_at_start = first.flipped_initial + first.degenerate_initial + first.thin_initial;
  ASSERT_GE(bad_at_start, 3);
  EXPECT_FALSE(first.repair_declined);
  EXPECT_GT(first.repair_rounds, 0);

  ParametrizationSolveOptions below = plain, at = plain;
  below.max_bad_share_to_repair = (bad_at_start - 0.5) / nf;
  at.max_bad_share_to_repair = static_cast<double>(bad_at_start) / nf;
  const ParametrizationSolution declined = p.problem.solve(below, p.progress);
  EXPECT_TRUE(declined.stats.repair_declined);
  EXPECT_EQ(declined.stats.repair_rounds, 0);
  EXPECT_EQ(declined.stats.flipped, declined.stats.flipped_initial);
  EXPECT_EQ(declined.stats.degenerate, declined.stats.degenerate_initial);
  EXPECT_LT(declined.stats.constraint_violation, 1e-9);
  const ParametrizationSolution taken = p.problem.solve(at, p.progress);
  EXPECT_FALSE(taken.stats.repair_declined);
  EXPECT_EQ(taken.stats.repair_rounds, first.repair_rounds);
  EXPECT_EQ(taken.stats.flipped, first.flipped);
}

TEST(ParametrizationProblem, FieldFrameSolveCanBeLeftToTheCaller) {
  // With cone angles, a local repair that leaves bad faces (the pinned folds) is followed by one
  // global solve in the field's frame and more local rounds; without it (a caller with a fallback,
  // as the pipeline's first map of a field with cancelled singularity pairs) the repair ends after
  // the local rounds, and the stagnation bound ends those early.
  CubeProblem p;
  pin_clockwise_faces_with_cones(p);
  ParametrizationSolveOptions full;
  const ParametrizationSolution with_global = p.problem.solve(full, p.progress);
  ParametrizationSolveOptions local = full;
  local.field_frame_solve = false;
  local.count_stagnation_rounds = 4;
  const ParametrizationSolution local_only = p.problem.solve(local, p.progress);
  for (const ParametrizationSolution* s : {&with_global, &local_only}) expect_pinned_faces_folded(*s);
  EXPECT_EQ(with_global.stats.field_frame_solves, 1);
  EXPECT_EQ(local_only.stats.field_frame_solves, 0);
  EXPECT_LT(local_only.stats.repair_rounds, with_global.stats.repair_rounds);
}

TEST(ParametrizationProblem, CallerFinishesARepairAtAPlateau) {
  // caller_finishes is asked once per plateau of the bad faces (the first round that leaves the
  // best pose's count no lower), with that best pose: declining lets the repair run to its other
  // bounds; accepting ends it there (the field-frame solve and later rounds skipped) and the
  // solution is the pose the caller accepted.
  CubeProblem p;
  pin_clockwise_faces_with_cones(p);
  ParametrizationSolveOptions plain;
  const ParametrizationSolution unbounded = p.problem.solve(plain, p.progress);

  ParametrizationSolveOptions declining = plain;
  int asked = 0;
  declining.caller_finishes = [&](const Parametrization& pose) {
    EXPECT_EQ(pose.uv.rows(), 3 * p.cube.mesh.num_faces());
    ++asked;
    return false;
  };
  const ParametrizationSolution declined = p.problem.solve(declining, p.progress);
  EXPECT_FALSE(declined.stats.finished_by_caller);
  EXPECT_EQ(declined.stats.repair_rounds, unbounded.stats.repair_rounds);
  EXPECT_EQ(declined.stats.bad_after_round, unbounded.stats.bad_after_round);
  EXPECT_GE(asked, 1);
  // Never more often than there are rounds without fewer bad faces than the best before them.
  int plateau_rounds = 0, best = std::numeric_limits<int>::max();
  for (int bad : unbounded.stats.bad_after_round) {
    plateau_rounds += bad >= best;
    best = std::min(best, bad);
  }
  EXPECT_LE(asked, plateau_rounds);

  ParametrizationSolveOptions accepting = plain;
  Parametrization accepted;
  accepting.caller_finishes = [&](const Parametrization& pose) {
    accepted = pose;
    return true;
  };
  const ParametrizationSolution finished = p.problem.solve(accepting, p.progress);
  EXPECT_TRUE(finished.stats.finished_by_caller);
  EXPECT_LT(finished.stats.repair_rounds, unbounded.stats.repair_rounds);
  EXPECT_EQ(finished.stats.field_frame_solves, 0);
  ASSERT_EQ(accepted.uv.rows(), finished.param.uv.rows());
  EXPECT_EQ((accepted.uv - finished.param.uv).cwiseAbs().maxCoeff(), 0.0);
}

// ---------------------------------------------------------------------------------------------
// Real meshes: components prepared as the Session does (features, split faces, field, cut).

struct Prepared {
  TriMesh mesh;
  CrossField field;
  CutGraph cut;
  double edge_length = 0;
  double seconds_field = 0;
};

Prepared prepare(const std::string& name, double sharp_angle, double target_faces) {
  const IntakeResult intake = test::load_mesh(name);
  Prepared p;
  std::vector<int> vertex_map, face_map;
  p.mesh = extract_component(intake, 0, &vertex_map, &face_map);
  std::vector<char> features = detect_feature_edges(p.mesh, {}, sharp_angle);
  split_overconstrained_faces(p.mesh, features, vertex_map, face_map);
  double area = 0;
  for (int f = 0; f < p.mesh.num_faces(); ++f) area += 0.5 * p.mesh.face_normal_unnormalized(f).norm();
  p.edge_length = std::sqrt(area / target_faces);
  Progress progress;
  Timer t;
  CrossFieldOptions fo;
  fo.feature_edges = features;
  p.field = compute_cross_field(p.mesh, fo, progress);
  p.cut = compute_cut_graph(p.mesh, p.field, progress);
  p.seconds_field = t.seconds();
  return p;
}

// Known limitations (see the report), with the flipped + degenerate triangles printed above:
// - dragon-genus1.obj: a noisy scan whose field has ~2100 singularities for ~2000 target quads
//   (adjacent singularity pairs everywhere); the equality-only optimum has ~465 folds and the
//   repair, limited to 3 rounds to bound the suite's runtime, removes about half (223-227 on the
//   dev machine, 222 on CI before the elimination change). Bound: it must remove at least a
//   third, and leave fewer than 0.5% of the faces bad. No winding repair here: its global field-frame
//   solve alone takes many minutes and gigabytes on dragon.
// - armadillo.obj: 2 folds next to two adjacent index -1 singularities joined by a cut edge
//   before the elimination change; 0 on the dev machine since. A small allowance stays because
//   the count has differed between machines.
struct KnownIrregular {
  int max_repair_rounds;      // repair budget (0: the default)
  double max_fraction_left;   // bad after / bad before
  double max_fraction_faces;  // bad after / faces
  int max_bad;                // absolute allowance (whichever bound is larger applies)
};
const std::map<std::string, KnownIrregular> kKnownIrregular = {
    {"armadillo.obj", {0, 0.0, 0.0, 2}},
    {"dragon-genus1.obj", {3, 2.0 / 3.0, 0.005, 0}},
};

// Left out of the sweep: nefertiti's full-resolution map (99 938 faces, the grid-UV job's path)
// takes 24 repair rounds and 445 s (2026-11-27), two thirds of the sweep; the remesh job solves it on
// its working mesh, which the LayoutMeshes sweep checks. QGP_TEST_MESHES=nefertiti.obj runs it.
const std::set<std::string> kLeftOut = {"nefertiti.obj"};

TEST(SeamlessMapMeshes, EveryManifoldMeshIsSeamlessAndRegular) {
  std::cout << "[seamless] mesh | faces | singularities | flipped before -> after | degenerate | ipopt "
               "rounds/iterations | field s | seamless s\n";
  for (const std::string& name : test::manifold_mesh_files()) {
    if (kLeftOut.count(name) && !std::getenv("QGP_TEST_MESHES")) continue;
    SCOPED_TRACE(name);
    const Prepared p = prepare(name, -1, 2000);
    SeamlessMapOptions o;
    o.edge_length = p.edge_length;
    const auto known = kKnownIrregular.find(name);
    if (known != kKnownIrregular.end() && known->second.max_repair_rounds > 0) {
      o.max_repair_rounds = known->second.max_repair_rounds;
      o.winding_repair = false;  // the winding repair's global solve alone takes many minutes
    }
    Progress progress;
    Timer t;
    const SeamlessMap m = compute_seamless_map(p.mesh, p.field, p.cut, o, progress);
    const double seconds = t.seconds();
    const auto& s = m.stats;
    std::cout << "[seamless] " << name << " | " << p.mesh.num_faces() << " | " << p.field.num_singularities << " | "
              << s.flipped_before_ipopt << " -> " << s.flipped_triangles << " | " << s.degenerate_triangles << " | "
              << s.repair_rounds << "/" << s.ipopt_iterations << " | " << p.seconds_field << " | " << seconds << "\n";
    const double diag = param_diagonal(m.param);
    EXPECT_LE(s.max_transition_residual, 1e-9 * diag);
    EXPECT_LE(max_transition_residual(p.mesh, m.param), 1e-9 * diag);
    EXPECT_EQ(s.forced_degenerate, 0);
    int degenerate = 0;
    EXPECT_EQ(count_exact_flips(p.mesh, m.param, &degenerate), s.flipped_triangles);
    EXPECT_EQ(degenerate, s.degenerate_triangles);
    if (known == kKnownIrregular.end()) {
      EXPECT_EQ(s.flipped_triangles, 0);
      EXPECT_EQ(s.degenerate_triangles, 0);
      EXPECT_EQ(s.winding_defects, 0);  // every one-ring winds by its cone angle
    } else {
      const KnownIrregular& k = known->second;
      const int bad = s.flipped_triangles + s.degenerate_triangles;
      const int before = s.flipped_before_ipopt + s.degenerate_before_ipopt;
      if (bad > k.max_bad) {
        EXPECT_LE(bad, k.max_fraction_left * before) << "the repair removed too few folds";
        EXPECT_LE(bad, k.max_fraction_faces * p.mesh.num_faces()) << "too many folds left";
      }
    }
    SanitizeOptions so;
    so.fraction_bits = 24;
    const SanitizeResult ex = sanitize_parametrization(p.mesh, m.param, so);
    EXPECT_EQ(ex.unresolved_equations, 0);
    EXPECT_EQ(exact_transition_residual(p.mesh, ex.param), 0);
  }
}

// Feature and boundary edges of p (those the map keeps as isolines: not dropped) in *features;
// returns how many of their halfedges have no constant coordinate in their chart.
int edges_off_isolines(const Prepared& p, const SeamlessMap& m, int* features) {
  const double diag = param_diagonal(m.param);
  std::vector<char> dropped(p.mesh.num_edges(), 0);
  for (int e : m.stats.dropped_isoline_edges) dropped[e] = 1;
  int off = 0;
  *features = 0;
  for (int e = 0; e < p.mesh.num_edges(); ++e) {
    if (!(p.field.feature_edge[e] || p.mesh.is_boundary_edge(e)) || dropped[e]) continue;
    ++*features;
    // In both adjacent charts one coordinate is constant along the edge.
    for (int h : {p.mesh.edge_halfedge[e], p.mesh.opposite[p.mesh.edge_halfedge[e]]}) {
      if (h < 0) continue;
      const Vec2 d = m.param.corner(h / 3, (h % 3 + 1) % 3) - m.param.corner(h / 3, h % 3);
      off += std::min(std::abs(d.x()), std::abs(d.y())) > 1e-9 * diag;
    }
  }
  return off;
}

void expect_regular_with_features_on_isolines(const Prepared& p, const SeamlessMap& m) {
  int features = 0;
  EXPECT_EQ(edges_off_isolines(p, m, &features), 0);
  EXPECT_GT(features, 100);
  EXPECT_LE(m.stats.dropped_isolines * 100, features);  // at most 1%
  EXPECT_EQ(m.stats.flipped_triangles, 0);
  EXPECT_EQ(m.stats.degenerate_triangles, 0);
  EXPECT_EQ(m.stats.winding_defects, 0);
  EXPECT_LE(m.stats.max_transition_residual, 1e-9 * param_diagonal(m.param));
}

TEST(SeamlessMapMeshes, FeatureEdgesLieOnIsolines) {
  for (const std::string name : {"fandisk.obj", "block.obj", "joint.obj", "wingnut.obj"}) {
    SCOPED_TRACE(name);
    const Prepared p = prepare(name, 40, 2000);
    SeamlessMapOptions o;
    o.edge_length = p.edge_length;
    Progress progress;
    Timer t;
    const SeamlessMap m = compute_seamless_map(p.mesh, p.field, p.cut, o, progress);
    print_stats(name + " (sharp 40)", m, t.seconds());
    std::cout << "[seamless] " << name << ": " << m.stats.dropped_isolines << " isoline edges left free\n";
    expect_regular_with_features_on_isolines(p, m);
  }
}

TEST(SeamlessMapMeshes, SharedCoordinatesMoveWhereLocalRegionsCannot) {
  // With sharp edges at 60 degrees, local regions leave folds on these CAD parts that need a
  // feature curve's constant coordinate (one variable along the whole curve) or a cut arc's end
  // to move. The rounds that move such shared variables repair them without the global solve, and
  // the features stay on isolines.
  for (const std::string name : {"fandisk.obj", "mnf07HeadFem_rem_rem_p.obj"}) {
    SCOPED_TRACE(name);
    const Prepared p = prepare(name, 60, 2000);
    SeamlessMapOptions local;
    local.edge_length = p.edge_length;
    local.region_stagnation_rounds = 1;  // as the pipeline: no round over most of the mesh in vain
    local.field_frame_solve = false;
    local.move_shared_coordinates = false;
    Progress progress;
    const SeamlessMap stuck = compute_seamless_map(p.mesh, p.field, p.cut, local, progress);
    const SeamlessMapStats& s0 = stuck.stats;
    EXPECT_GT(s0.flipped_triangles + s0.degenerate_triangles + s0.winding_defects, 0);
    EXPECT_FALSE(s0.moved_shared_coordinates);
    // Its bad vertices: every corner of its non-positive triangles, and no vertex off them but
    // (at most) its wound ones.
    const std::vector<double> area = parametric_areas(stuck.param);
    std::set<int> corners;
    for (int f = 0; f < p.mesh.num_faces(); ++f)
      if (!(area[f] > 0))
        for (int k = 0; k < 3; ++k) corners.insert(p.mesh.F(f, k));
    const std::set<int> bad(stuck.bad_vertices.begin(), stuck.bad_vertices.end());
    EXPECT_EQ(bad.size(), stuck.bad_vertices.size());
    EXPECT_TRUE(std::includes(bad.begin(), bad.end(), corners.begin(), corners.end()));
    EXPECT_LE(bad.size(), corners.size() + s0.winding_defects);
    EXPECT_FALSE(bad.empty());

    SeamlessMapOptions shared = local;
    shared.move_shared_coordinates = true;
    Timer t;
    const SeamlessMap m = compute_seamless_map(p.mesh, p.field, p.cut, shared, progress);
    print_stats(name + " (sharp 60, shared coordinates)", m, t.seconds());
    EXPECT_TRUE(m.stats.moved_shared_coordinates);
    EXPECT_EQ(m.stats.field_frame_solves, 0);
    expect_regular_with_features_on_isolines(p, m);
    EXPECT_TRUE(m.bad_vertices.empty());
  }
}

}  // namespace
}  // namespace qgp

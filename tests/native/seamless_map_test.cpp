// Seamless map (stage 1c): exact elimination, field-guided energy, regularity repair with Ipopt.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <iostream>
#include <map>
#include <queue>
#include <random>

#include "core/error.h"
#include "core/timer.h"
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
  for (int f = 0; f < mesh.num_faces(); ++f) bad += orient2d_exact(s.param.corner(f, 0), s.param.corner(f, 1), s.param.corner(f, 2)) <= 0;
  EXPECT_EQ(bad, 0);
}

void print_stats(const std::string& name, const SeamlessMap& m, double seconds) {
  const auto& s = m.stats;
  std::cout << "[seamless] " << name << ": flipped " << s.flipped_before_ipopt << " -> " << s.flipped_triangles
            << ", degenerate " << s.degenerate_before_ipopt << " -> " << s.degenerate_triangles << ", ipopt solves "
            << s.ipopt_solves << " iterations " << s.ipopt_iterations << ", region faces " << s.max_region_faces
            << ", energy " << s.energy << ", min area ratio " << s.min_area_ratio << ", residual "
            << s.max_transition_residual << ", " << seconds << " s\n";
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

}  // namespace
}  // namespace qgp

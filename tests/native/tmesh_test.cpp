// Motorcycle graph / T-mesh (tmesh/trace_tmesh): invariants on synthetic maps built for the
// degenerate configurations (separatrices along edges and through vertices, nearly parallel
// separatrices, singularities close together or on one isoline, crossings of cuts at vertices,
// boundaries, features, no singularities, flipped maps).
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <map>
#include <random>
#include <sstream>

#include "core/error.h"
#include "core/parametrization.h"
#include "core/sanitize_isolines.h"
#include "intake/read_mesh_file.h"
#include "pipeline/session.h"
#include "polycube.h"
#include "quad_map.h"
#include "test_support.h"
#include "tmesh/tmesh_system.h"
#include "tmesh/trace_tmesh.h"

namespace qgp {
namespace {

struct Case {
  std::string name;
  TriMesh mesh;
  ExactParametrization param;
  std::vector<char> features;  // #E (may be empty)
};

Case make_case(const std::string& name, const TriMesh& mesh, const Parametrization& param,
               std::vector<char> features = {}, int fraction_bits = 24) {
  Case c{name, mesh, {}, std::move(features)};
  SanitizeOptions options;
  options.fraction_bits = fraction_bits;
  const SanitizeResult r = sanitize_parametrization(mesh, param, options);
  EXPECT_EQ(r.unresolved_equations, 0) << name;
  EXPECT_EQ(exact_transition_residual(mesh, r.param), 0) << name;
  c.param = r.param;
  return c;
}

int euler_characteristic(const TriMesh& m) { return m.num_vertices() - m.num_edges() + m.num_faces(); }

// Parametric angle sum of each vertex in quarter turns (rounded), in doubles: an independent
// count to compare the tracer's exact one with.
std::vector<int> quarter_turns(const TriMesh& mesh, const ExactParametrization& ex) {
  const Parametrization p = ex.to_double();
  std::vector<double> sum(mesh.num_vertices(), 0);
  for (int f = 0; f < mesh.num_faces(); ++f)
    for (int k = 0; k < 3; ++k) {
      const Vec2 a = p.corner(f, k), b = p.corner(f, (k + 1) % 3), c = p.corner(f, (k + 2) % 3);
      const Vec2 u = b - a, v = c - a;
      sum[mesh.F(f, k)] += std::atan2(u.x() * v.y() - u.y() * v.x(), u.dot(v));
    }
  std::vector<int> q(mesh.num_vertices());
  for (int v = 0; v < mesh.num_vertices(); ++v) q[v] = static_cast<int>(std::lround(sum[v] / (M_PI / 2)));
  return q;
}

TMesh trace(const Case& c) {
  Progress progress;
  TraceOptions options;
  options.feature_edges = c.features;
  return trace_tmesh(c.mesh, c.param, options, progress);
}

bool is_wall(const Case& c, int e) { return c.mesh.is_boundary_edge(e) || (!c.features.empty() && c.features[e]); }

// The mesh edge a straight piece (two points in one face) lies on, or -1.
int piece_mesh_edge(const TriMesh& mesh, const SurfacePoint& a, const SurfacePoint& b) {
  for (int k = 0; k < 3; ++k)
    if (std::fabs(a.barycentric[k]) < 1e-12 && std::fabs(b.barycentric[k]) < 1e-12)
      return mesh.edge_of[3 * a.face + (k + 1) % 3];
  return -1;
}

void expect_valid(const Case& c, const TMesh& tm) {
  SCOPED_TRACE(c.name);
  const TriMesh& mesh = c.mesh;
  const double tol3 = 1e-9 * mesh.bounding_box_diagonal();
  const TMeshCheck check = check_tmesh(tm);
  EXPECT_EQ(tm.euler_characteristic(), euler_characteristic(mesh));
  EXPECT_EQ(check.cells_not_four_sided, 0);
  EXPECT_LE(check.max_cell_equation_residual, 1e-9);
  EXPECT_LE(check.max_abs_coefficient, 1);
  EXPECT_EQ(check.edges_without_cells, 0);
  EXPECT_GT(tm.cells.size(), 0u);
  EXPECT_EQ(tm.stats.walls_not_isolines, 0);

  // Every singularity (independent double count) is a node with the right index.
  const std::vector<int> q = quarter_turns(mesh, c.param);
  std::map<int, const TMeshNode*> vertex_nodes;
  for (const TMeshNode& n : tm.nodes)
    if (n.mesh_vertex >= 0) vertex_nodes[n.mesh_vertex] = &n;
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    const bool boundary = is_boundary_vertex(mesh, v);
    const int index = (boundary ? 2 : 4) - q[v];
    if (index == 0) continue;
    auto it = vertex_nodes.find(v);
    ASSERT_NE(it, vertex_nodes.end()) << "singular vertex " << v << " is not a node";
    EXPECT_EQ(it->second->index, index) << "vertex " << v;
    if (!boundary && (c.features.empty() || it->second->kind != TMeshNode::Kind::FeatureCorner))
      EXPECT_EQ(it->second->kind, TMeshNode::Kind::Singularity) << "vertex " << v;
  }

  // Edges: incidences consistent, traces continuous, pieces inside one triangle, isolines.
  std::vector<int> seen_out(tm.edges.size(), 0), seen_in(tm.edges.size(), 0);
  for (const TMeshNode& n : tm.nodes)
    for (size_t i = 0; i < n.incidences.size(); ++i) {
      const TMeshIncidence& inc = n.incidences[i];
      ASSERT_GE(inc.edge, 0);
      (inc.outgoing ? seen_out : seen_in)[inc.edge]++;
      if (i > 0) EXPECT_LT(n.incidences[i - 1].direction, inc.direction);
    }
  double wall_length_tmesh = 0;
  for (size_t ei = 0; ei < tm.edges.size(); ++ei) {
    const TMeshEdge& e = tm.edges[ei];
    EXPECT_EQ(seen_out[ei], 1);
    EXPECT_EQ(seen_in[ei], 1);
    EXPECT_GE(e.length, 0);
    ASSERT_GE(e.trace.size(), 2u);
    EXPECT_LT((e.trace.front().position(mesh) - tm.nodes[e.from].point.position(mesh)).norm(), tol3);
    EXPECT_LT((e.trace.back().position(mesh) - tm.nodes[e.to].point.position(mesh)).norm(), tol3);
    for (size_t k = 0; k + 1 < e.trace.size(); ++k) {
      const SurfacePoint& a = e.trace[k];
      const SurfacePoint& b = e.trace[k + 1];
      if (a.face != b.face) {
        EXPECT_LT((a.position(mesh) - b.position(mesh)).norm(), tol3) << "face change away from one point";
        continue;
      }
      for (int j = 0; j < 3; ++j) {
        EXPECT_GE(a.barycentric[j], -1e-9);
        EXPECT_GE(b.barycentric[j], -1e-9);
      }
      const Vec2 d = b.uv - a.uv;
      EXPECT_TRUE(d.x() == 0 || d.y() == 0) << "piece is no isoline";
      const int me = piece_mesh_edge(mesh, a, b);
      if (e.on_feature) {
        EXPECT_GE(me, 0) << "feature edge piece off the mesh edges";
        if (me >= 0) EXPECT_TRUE(is_wall(c, me));
        wall_length_tmesh += (b.position(mesh) - a.position(mesh)).norm();
      } else if (me >= 0 && d.norm() > 0) {
        EXPECT_FALSE(is_wall(c, me)) << "separatrix runs along a feature/boundary";
      }
    }
    // Orientation: positive along its axis in the chart of the first piece, unless the edge
    // crosses a half-turn transition so that its last piece (from -> to) is positive instead.
    int first_sign = 0, last_sign = 0;
    for (size_t k = 0; k + 1 < e.trace.size(); ++k)
      if (e.trace[k].face == e.trace[k + 1].face && (e.trace[k + 1].uv - e.trace[k].uv).norm() > 0) {
        const Vec2 d = e.trace[k + 1].uv - e.trace[k].uv;
        const int sg = d.x() + d.y() > 0 ? 1 : -1;
        if (first_sign == 0) {
          first_sign = sg;
          EXPECT_NE(d[e.axis], 0) << "first piece is not along the edge's axis";
        }
        last_sign = sg;
      }
    EXPECT_TRUE(first_sign > 0 || last_sign > 0) << "edge could have been oriented positively";
  }
  // Features and boundaries are T-mesh edges: total length matches.
  double wall_length_mesh = 0;
  for (int me = 0; me < mesh.num_edges(); ++me)
    if (is_wall(c, me)) wall_length_mesh += mesh.edge_vector(mesh.edge_halfedge[me]).norm();
  EXPECT_NEAR(wall_length_tmesh, wall_length_mesh, 1e-9 * (1 + wall_length_mesh));

  // No two traced edges cross or overlap except at nodes.
  struct Piece {
    int edge, index;
    Vec2 a, b;
  };
  std::map<int, std::vector<Piece>> by_face;
  for (size_t ei = 0; ei < tm.edges.size(); ++ei) {
    const auto& t = tm.edges[ei].trace;
    for (size_t k = 0; k + 1 < t.size(); ++k)
      if (t[k].face == t[k + 1].face && (t[k + 1].uv - t[k].uv).norm() > 0)
        by_face[t[k].face].push_back({static_cast<int>(ei), static_cast<int>(k), t[k].uv, t[k + 1].uv});
  }
  // Node positions in a hash grid (cells of a few tolerances) for "is this point a node?".
  const double cell = 4 * tol3;
  auto cell_of = [&](const Vec3& x) {
    return std::array<long long, 3>{std::llround(x.x() / cell), std::llround(x.y() / cell), std::llround(x.z() / cell)};
  };
  std::map<std::array<long long, 3>, std::vector<Vec3>> node_grid;
  for (const TMeshNode& n : tm.nodes) {
    const Vec3 x = n.point.position(mesh);
    node_grid[cell_of(x)].push_back(x);
  }
  const Parametrization dparam = c.param.to_double();
  auto is_node_point = [&](int face, const Vec2& uv) {
    const Vec2 p0 = dparam.corner(face, 0), e1 = dparam.corner(face, 1) - p0, e2 = dparam.corner(face, 2) - p0;
    const Vec2 r = uv - p0;
    const double det = e1.x() * e2.y() - e1.y() * e2.x();
    const double l1 = (r.x() * e2.y() - r.y() * e2.x()) / det, l2 = (e1.x() * r.y() - e1.y() * r.x()) / det;
    SurfacePoint sp;
    sp.face = face;
    sp.barycentric = Vec3(1 - l1 - l2, l1, l2);
    const Vec3 x = sp.position(mesh);
    const auto k = cell_of(x);
    for (long long dx = -1; dx <= 1; ++dx)
      for (long long dy = -1; dy <= 1; ++dy)
        for (long long dz = -1; dz <= 1; ++dz) {
          auto it = node_grid.find({k[0] + dx, k[1] + dy, k[2] + dz});
          if (it == node_grid.end()) continue;
          for (const Vec3& np : it->second)
            if ((np - x).norm() < tol3) return true;
        }
    return false;
  };
  int violations = 0;
  for (const auto& [face, pieces] : by_face) {
    double scale = 0;
    for (const Piece& p : pieces) scale = std::max({scale, p.a.cwiseAbs().maxCoeff(), p.b.cwiseAbs().maxCoeff()});
    const double eps = 1e-13 * (1 + scale);
    for (size_t i = 0; i < pieces.size(); ++i)
      for (size_t j = i + 1; j < pieces.size(); ++j) {
        const Piece& P = pieces[i];
        const Piece& Q = pieces[j];
        if (P.edge == Q.edge && std::abs(P.index - Q.index) <= 2) continue;  // consecutive pieces
        const bool P_horizontal = P.a.y() == P.b.y(), Q_horizontal = Q.a.y() == Q.b.y();
        if (P_horizontal != Q_horizontal) {
          // Perpendicular isolines: intersection point X.
          const Piece& H = P_horizontal ? P : Q;
          const Piece& V = P_horizontal ? Q : P;
          const Vec2 X(V.a.x(), H.a.y());
          const bool in_h = X.x() >= std::min(H.a.x(), H.b.x()) - eps && X.x() <= std::max(H.a.x(), H.b.x()) + eps;
          const bool in_v = X.y() >= std::min(V.a.y(), V.b.y()) - eps && X.y() <= std::max(V.a.y(), V.b.y()) + eps;
          if (in_h && in_v && !is_node_point(face, X)) ++violations;
        } else {
          // Parallel: overlap on one line is only allowed as touching at a node.
          const int fixed = P_horizontal ? 1 : 0, moving = 1 - fixed;
          if (std::fabs(P.a[fixed] - Q.a[fixed]) > eps) continue;
          const double lo = std::max(std::min(P.a[moving], P.b[moving]), std::min(Q.a[moving], Q.b[moving]));
          const double hi = std::min(std::max(P.a[moving], P.b[moving]), std::max(Q.a[moving], Q.b[moving]));
          if (hi > lo + eps)
            ++violations;
          else if (hi >= lo - eps) {
            Vec2 X = P.a;
            X[moving] = lo;
            if (!is_node_point(face, X)) ++violations;
          }
        }
      }
  }
  EXPECT_EQ(violations, 0) << "traced edges cross or touch away from nodes";
}

// ---------------------------------------------------------------------------------------------

TEST(TMesh, GridCubeIsACube) {
  for (int n : {1, 2, 3, 5}) {
    const auto cube = test::make_grid_cube(n);
    const Case c = make_case("cube" + std::to_string(n), cube.mesh, cube.param);
    const TMesh tm = trace(c);
    expect_valid(c, tm);
    EXPECT_EQ(tm.nodes.size(), 8u);
    EXPECT_EQ(tm.edges.size(), 12u);
    EXPECT_EQ(tm.cells.size(), 6u);
    // Separatrices run along mesh edges (through vertices for n >= 2) and meet head-on.
    EXPECT_EQ(tm.stats.motorcycles, 24);
    EXPECT_EQ(tm.stats.head_on, 12);
    EXPECT_GT(tm.stats.edge_runs, 0);
    if (n >= 3) EXPECT_GT(tm.stats.vertex_passes, 0);
    for (const TMeshEdge& e : tm.edges) EXPECT_NEAR(e.length, n, 1e-12);
    for (const TMeshNode& node : tm.nodes) {
      EXPECT_EQ(node.index, 1);
      EXPECT_EQ(node.incidences.size(), 3u);
    }
  }
}

TEST(TMesh, TorusWithoutSingularitiesUsesASeed) {
  const auto torus = test::make_grid_torus(12, 8);
  const Case c = make_case("torus", torus.mesh, torus.param);
  const TMesh tm = trace(c);
  expect_valid(c, tm);
  EXPECT_EQ(tm.stats.seeds, 1);
  EXPECT_EQ(tm.nodes.size(), 1u);
  EXPECT_EQ(tm.edges.size(), 2u);
  EXPECT_EQ(tm.cells.size(), 1u);
  EXPECT_EQ(tm.nodes[0].kind, TMeshNode::Kind::Seed);
  EXPECT_GT(tm.stats.cut_crossings + tm.stats.cut_vertex_passes, 0);
}

Case polycube_case(const std::string& name, const test::PolycubeSpec& spec, bool creases_as_features = false) {
  const test::Polycube pc = test::make_polycube(spec);
  for (double a : parametric_areas(pc.param)) EXPECT_GT(a, 0) << name << ": generator made a flipped triangle";
  return make_case(name, pc.mesh, pc.param, creases_as_features ? pc.crease_edges : std::vector<char>{});
}

std::vector<double> uniform(int n) {
  std::vector<double> g;
  for (int i = 0; i <= n; ++i) g.push_back(i);
  return g;
}

TEST(TMesh, ConcaveCornersMakeTJunctions) {
  // A 2x2 slab with one voxel on top of a corner: concave corners of valence 5. Uneven sizes,
  // so that separatrices do not arrive at their crossings at the same time.
  auto spec = test::staircase({{2, 1}, {1, 1}}, {std::vector<double>{0, 1, 2.5}, std::vector<double>{0, 1.3, 2},
                                                 std::vector<double>{0, 1, 1.7}});
  for (int s : {1, 2, 3}) {
    spec.subdivisions = s;
    const Case c = polycube_case("slab+voxel s" + std::to_string(s), spec);
    const TMesh tm = trace(c);
    expect_valid(c, tm);
    EXPECT_GT(check_tmesh(tm).t_junctions, 0);
    int valence5 = 0;
    for (const TMeshNode& n : tm.nodes) valence5 += n.index == -1;
    EXPECT_EQ(valence5, 3);
  }
}

TEST(TMesh, StaircasesWithArbitraryOffsetsAndPerturbedInteriors) {
  const std::array<std::vector<double>, 3> grid = {std::vector<double>{0, 1.37, 2.91, 3.5},
                                                   std::vector<double>{0, 0.8, 2.2, 3.0},
                                                   std::vector<double>{0, 1.1, 1.9, 3.3}};
  int through_triangles = 0;
  for (unsigned seed = 1; seed <= 6; ++seed) {
    auto spec = test::staircase({{3, 2, 1}, {2, 2, 1}, {1, 1, 0}}, grid);
    spec.subdivisions = 2 + seed % 3;
    spec.random_diagonals = true;
    spec.jitter = seed % 2 ? 0.15 : 0.0;
    spec.seed = seed;
    const Case c = polycube_case("staircase seed " + std::to_string(seed), spec);
    const TMesh tm = trace(c);
    expect_valid(c, tm);
    through_triangles += tm.stats.steps > tm.stats.edge_runs;
    EXPECT_GT(tm.stats.cut_crossings + tm.stats.cut_vertex_passes, 0);
  }
  EXPECT_GT(through_triangles, 0);
}

TEST(TMesh, NearlyParallelSeparatricesAndSingularitiesCloseTogether) {
  // Grid lines one fixed-point unit (2^-24) apart: steps of the staircase at x = 1 and 1 + eps
  // give parallel separatrices at distance eps and singularities eps apart.
  const double eps = std::ldexp(1.0, -24);
  const std::array<std::vector<double>, 3> grid = {std::vector<double>{0, 1, 1 + eps, 2},
                                                   std::vector<double>{0, 1, 1 + eps, 2},
                                                   std::vector<double>{0, 1, 1 + eps, 2}};
  for (unsigned seed = 1; seed <= 4; ++seed) {
    auto spec = test::staircase({{3, 2, 1}, {2, 2, 1}, {1, 1, 1}}, grid);
    // With 2 subdivisions the eps slab has a grid line at eps / 2: use 2 more fraction bits.
    spec.subdivisions = seed <= 2 ? 1 : 2;
    spec.random_diagonals = seed % 2 == 0;
    spec.jitter = 0.15;
    spec.seed = seed;
    const test::Polycube pc = test::make_polycube(spec);
    const Case c = make_case("eps staircase " + std::to_string(seed), pc.mesh, pc.param, {}, seed <= 2 ? 24 : 26);
    const TMesh tm = trace(c);
    expect_valid(c, tm);
    double shortest = 1e9;
    for (const TMeshEdge& e : tm.edges) shortest = std::min(shortest, e.length);
    EXPECT_NEAR(shortest, eps, 1e-20);  // an edge between singularities eps apart
  }
}

TEST(TMesh, SingularitiesOnOneIsolineMeetHeadOn) {
  // A bar with two towers: the towers' concave corners face each other along one isoline.
  test::PolycubeSpec spec;
  spec.grid = {uniform(5), uniform(1), uniform(2)};
  for (int i = 0; i < 5; ++i) spec.voxels.insert({i, 0, 0});
  spec.voxels.insert({0, 0, 1});
  spec.voxels.insert({4, 0, 1});
  for (int s : {1, 2}) {
    spec.subdivisions = s;
    const Case c = polycube_case("two towers s" + std::to_string(s), spec);
    const TMesh tm = trace(c);
    expect_valid(c, tm);
    EXPECT_GT(tm.stats.head_on, 0);
    EXPECT_GT(tm.stats.merged_nodes, 0);
  }
}

TEST(TMesh, SeparatricesCrossCutsExactlyAtVertices) {
  auto spec = test::staircase({{2, 1}, {1, 1}}, {uniform(2), uniform(2), uniform(2)});
  spec.subdivisions = 2;
  const Case c = polycube_case("aligned staircase", spec);
  const TMesh tm = trace(c);
  expect_valid(c, tm);
  EXPECT_GT(tm.stats.cut_vertex_passes, 0);
  EXPECT_GT(tm.stats.vertex_passes, 0);
}

TEST(TMesh, OpenPatchesWithBoundary) {
  // Flat patches: only the +z faces of one voxel layer. Convex corners q = 1, concave q = 3.
  auto flat = [](const std::vector<std::array<int, 2>>& cells, int n, int s) {
    test::PolycubeSpec spec;
    spec.grid = {uniform(n), uniform(n), uniform(1)};
    spec.subdivisions = s;
    for (const auto& c : cells) {
      spec.voxels.insert({c[0], c[1], 0});
      for (int dir = 0; dir < 6; ++dir)
        if (dir != 4) spec.open_faces.insert({{c[0], c[1], 0}, dir});
    }
    return spec;
  };
  const std::vector<std::array<int, 2>> L = {{0, 0}, {1, 0}, {2, 0}, {0, 1}, {0, 2}};
  const std::vector<std::array<int, 2>> ring = {{0, 0}, {1, 0}, {2, 0}, {0, 1}, {2, 1}, {0, 2}, {1, 2}, {2, 2}};
  for (int s : {1, 3}) {
    for (const auto& [name, cells] : {std::pair{"L patch", L}, std::pair{"annulus", ring}}) {
      const Case c = polycube_case(std::string(name) + " s" + std::to_string(s), flat(cells, 3, s));
      const TMesh tm = trace(c);
      expect_valid(c, tm);
      int corners = 0;
      for (const TMeshNode& n : tm.nodes) corners += n.kind == TMeshNode::Kind::BoundaryNode;
      EXPECT_EQ(corners, cells.size() == 5 ? 6 : 8);
    }
  }
  // An open staircase (bottom faces left out): the rim is straight everywhere in parameter
  // space and gets a virtual boundary node.
  auto spec = test::staircase({{2, 1}, {1, 1}}, {uniform(2), uniform(2), uniform(2)});
  spec.subdivisions = 2;
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 2; ++j) spec.open_faces.insert({{i, j, 0}, 5});
  const Case c = polycube_case("open staircase", spec);
  const TMesh tm = trace(c);
  expect_valid(c, tm);
  EXPECT_EQ(tm.stats.virtual_corners, 1);
}

TEST(TMesh, FeaturesBecomeEdges) {
  // All polycube creases as features (they are exact isolines).
  auto spec = test::staircase({{3, 2, 1}, {2, 2, 1}, {1, 1, 0}},
                              {std::vector<double>{0, 1.37, 2.91, 3.5}, std::vector<double>{0, 0.8, 2.2, 3.0},
                               std::vector<double>{0, 1.1, 1.9, 3.3}});
  spec.subdivisions = 2;
  spec.jitter = 0.15;
  const Case all = polycube_case("staircase creases", spec, true);
  const TMesh tm = trace(all);
  expect_valid(all, tm);
  int feature_edges = 0;
  for (const TMeshEdge& e : tm.edges) feature_edges += e.on_feature;
  EXPECT_GT(feature_edges, 0);

  // Only the vertical creases: the features end at corners where they meet non-features.
  test::Polycube pc = test::make_polycube(spec);
  std::vector<char> vertical(pc.mesh.num_edges(), 0);
  for (int e = 0; e < pc.mesh.num_edges(); ++e) {
    const Vec3 d = pc.mesh.edge_vector(pc.mesh.edge_halfedge[e]);
    vertical[e] = pc.crease_edges[e] && d.x() == 0 && d.y() == 0;
  }
  const Case some = make_case("vertical creases", pc.mesh, pc.param, vertical);
  expect_valid(some, trace(some));

  // A noisy map (features off their isolines by ~1e-6) sanitized with isoline constraints:
  // features are exact isolines again, so the cell equations hold exactly.
  Parametrization noisy = pc.param;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> noise(-1e-6, 1e-6);
  for (int k = 0; k < noisy.uv.rows(); ++k) noisy.uv.row(k) += Vec2(noise(rng), noise(rng)).transpose();
  SanitizeOptions so;
  so.fraction_bits = 24;
  const SanitizeResult r =
      sanitize_with_isolines(pc.mesh, noisy, isoline_constraints(pc.mesh, pc.param, pc.crease_edges, true), so);
  ASSERT_EQ(r.unresolved_equations, 0);
  const Case exact{"noisy creases, isoline sanitization", pc.mesh, r.param, pc.crease_edges};
  expect_valid(exact, trace(exact));
}

TEST(TMesh, FeatureCurveWithoutSingularities) {
  // A feature segment in the middle of a flat patch ends at two vertices of valence 1 on the
  // feature (virtual valence-4 nodes), each emitting three separatrices.
  test::PolycubeSpec spec;
  spec.grid = {uniform(4), uniform(4), uniform(1)};
  spec.subdivisions = 2;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) {
      spec.voxels.insert({i, j, 0});
      for (int dir = 0; dir < 6; ++dir)
        if (dir != 4) spec.open_faces.insert({{i, j, 0}, dir});
    }
  test::Polycube pc = test::make_polycube(spec);
  std::vector<char> feature(pc.mesh.num_edges(), 0);
  for (int e = 0; e < pc.mesh.num_edges(); ++e) {
    const int h = pc.mesh.edge_halfedge[e];
    const Vec3 a = pc.mesh.position(pc.mesh.from(h)), b = pc.mesh.position(pc.mesh.to(h));
    feature[e] = a.x() == 2.5 && b.x() == 2.5 && std::min(a.y(), b.y()) >= 1 && std::max(a.y(), b.y()) <= 3;
  }
  const Case c = make_case("feature segment", pc.mesh, pc.param, feature);
  const TMesh tm = trace(c);
  expect_valid(c, tm);
  int ends = 0;
  for (const TMeshNode& n : tm.nodes)
    if (n.kind == TMeshNode::Kind::FeatureCorner) {
      ++ends;
      EXPECT_EQ(n.incidences.size(), 4u);
      EXPECT_EQ(n.index, 0);
    }
  EXPECT_EQ(ends, 2);

  // A closed feature loop around a tower (no corner on it) gets a virtual node.
  test::PolycubeSpec tower;
  tower.grid = {uniform(1), uniform(1), uniform(3)};
  tower.subdivisions = 2;
  for (int k = 0; k < 3; ++k) tower.voxels.insert({0, 0, k});
  test::Polycube tp = test::make_polycube(tower);
  std::vector<char> ring(tp.mesh.num_edges(), 0);
  for (int e = 0; e < tp.mesh.num_edges(); ++e) {
    const int h = tp.mesh.edge_halfedge[e];
    ring[e] = tp.mesh.position(tp.mesh.from(h)).z() == 1.5 && tp.mesh.position(tp.mesh.to(h)).z() == 1.5;
  }
  const Case t = make_case("tower ring", tp.mesh, tp.param, ring);
  const TMesh ttm = trace(t);
  expect_valid(t, ttm);
  EXPECT_EQ(ttm.stats.virtual_corners, 1);
}

TEST(TMesh, FlippedTriangleOnATraceIsAClearError) {
  auto spec = test::staircase({{2, 1}, {1, 1}}, {uniform(2), uniform(2), uniform(2)});
  spec.subdivisions = 3;
  spec.jitter = 0.15;
  test::Polycube pc = test::make_polycube(spec);
  const Case ok = make_case("before flip", pc.mesh, pc.param);
  const TMesh tm = trace(ok);
  expect_valid(ok, tm);
  // A face crossed by a separatrix through its interior; reflect one of its movable vertices.
  const std::vector<int> q = quarter_turns(pc.mesh, ok.param);
  int target = -1, vertex = -1;
  for (const TMeshEdge& e : tm.edges) {
    if (e.on_feature || target >= 0) continue;
    for (size_t k = 0; k + 1 < e.trace.size() && target < 0; ++k) {
      const SurfacePoint& a = e.trace[k];
      if (a.face != e.trace[k + 1].face || piece_mesh_edge(pc.mesh, a, e.trace[k + 1]) >= 0) continue;
      for (int j = 0; j < 3; ++j) {
        const int v = pc.mesh.F(a.face, j);
        bool single_chart = true;  // all corners of v agree (not on a cut)
        Vec2 uv = Vec2::Zero();
        bool first = true;
        for (int f = 0; f < pc.mesh.num_faces(); ++f)
          for (int i = 0; i < 3; ++i)
            if (pc.mesh.F(f, i) == v) {
              if (!first && (pc.param.corner(f, i) - uv).norm() > 0) single_chart = false;
              uv = pc.param.corner(f, i), first = false;
            }
        if (single_chart && q[v] == 4 && !is_boundary_vertex(pc.mesh, v)) {
          target = a.face, vertex = j;
          break;
        }
      }
    }
  }
  ASSERT_GE(target, 0);
  const int v = pc.mesh.F(target, vertex);
  const Vec2 p = pc.param.corner(target, vertex), b = pc.param.corner(target, (vertex + 1) % 3),
             c = pc.param.corner(target, (vertex + 2) % 3);
  const Vec2 d = (c - b).normalized();
  const Vec2 foot = b + d * (p - b).dot(d);
  const Vec2 reflected = 2 * foot - p;
  for (int f = 0; f < pc.mesh.num_faces(); ++f)
    for (int i = 0; i < 3; ++i)
      if (pc.mesh.F(f, i) == v) pc.param.uv.row(3 * f + i) = reflected.transpose();
  const Case bad = make_case("flipped", pc.mesh, pc.param);
  try {
    trace(bad);
    ADD_FAILURE() << "tracing through a flipped triangle did not fail";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::StageFailed);
    EXPECT_NE(std::string(e.what()).find("flipped"), std::string::npos) << e.what();
    std::cout << "flipped map: " << e.what() << "\n";
  }
}

TEST(TMesh, SnappedMapsTraceOrFailCleanly) {
  // Scaling the map down and snapping singularities to integers makes them coincide: the
  // tracer either produces a valid T-mesh or throws Error(StageFailed), never hangs or crashes.
  auto spec = test::staircase({{3, 2, 1}, {2, 2, 1}, {1, 1, 0}}, {uniform(3), uniform(3), uniform(3)});
  spec.subdivisions = 2;
  spec.jitter = 0.15;
  const test::Polycube pc = test::make_polycube(spec);
  int succeeded = 0, failed = 0;
  for (double scale : {1.0, 0.6, 0.4, 0.25}) {
    Parametrization p = pc.param;
    p.uv *= scale;
    SanitizeOptions options;
    options.fraction_bits = 20;
    options.snap_vertex.assign(pc.mesh.num_vertices(), 0);
    const Case probe = make_case("probe", pc.mesh, p);
    const std::vector<int> q = quarter_turns(pc.mesh, probe.param);
    for (int v = 0; v < pc.mesh.num_vertices(); ++v) options.snap_vertex[v] = q[v] != 4;
    const SanitizeResult r = sanitize_parametrization(pc.mesh, p, options);
    Case c{"snapped x" + std::to_string(scale), pc.mesh, r.param, {}};
    try {
      Progress progress;
      TraceOptions to;
      to.max_steps = 1000000;
      const TMesh tm = trace_tmesh(c.mesh, c.param, to, progress);
      if (scale == 1.0) expect_valid(c, tm);
      const TMeshCheck check = check_tmesh(tm);
      EXPECT_EQ(tm.euler_characteristic(), euler_characteristic(c.mesh)) << c.name;
      EXPECT_EQ(check.cells_not_four_sided, 0) << c.name;
      ++succeeded;
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::StageFailed) << e.what();
      EXPECT_NE(scale, 1.0) << "unsnapped-size map failed: " << e.what();
      ++failed;
    }
  }
  EXPECT_GE(succeeded, 1);
  std::cout << "snapped maps: " << succeeded << " traced, " << failed << " failed cleanly\n";
}

TEST(TMesh, RotatedChartsPutSeparatricesInGeneralPosition) {
  // Rotating every chart by one angle keeps the map seamless but makes isolines oblique: the
  // separatrices cross triangles and cut edges at arbitrary points and end in T-junctions. With
  // tan = 1/2 on a unit grid, singularities land on one isoline up to one fixed-point unit.
  int head_on = 0;
  for (double angle : {std::atan(0.5), std::atan(1.0 / 3), 0.1234, 0.7}) {
    auto spec = test::staircase({{3, 2, 1}, {2, 2, 1}, {1, 1, 0}}, {uniform(3), uniform(3), uniform(3)});
    spec.subdivisions = 3;
    spec.chart_rotation = angle;
    spec.jitter = 0.1;
    const Case c = polycube_case("rotated " + std::to_string(angle), spec);
    const TMesh tm = trace(c);
    expect_valid(c, tm);
    EXPECT_GT(check_tmesh(tm).t_junctions, 20);
    EXPECT_GT(tm.stats.cut_crossings, 0);
    EXPECT_GT(tm.stats.steps, 300);
    head_on += tm.stats.head_on;
  }
  EXPECT_GT(head_on, 0);
}

TEST(TMesh, LargerRotatedStaircase) {
  std::vector<std::vector<int>> h(8, std::vector<int>(8));
  for (int i = 0; i < 8; ++i)
    for (int j = 0; j < 8; ++j) {
      h[i][j] = std::max(0, 9 - i - j - (i * 7 + j * 3) % 3);
      if (i) h[i][j] = std::min(h[i][j], h[i - 1][j]);
      if (j) h[i][j] = std::min(h[i][j], h[i][j - 1]);
    }
  std::array<std::vector<double>, 3> grid;
  for (int a = 0; a < 3; ++a)
    for (int i = 0, x10 = 0; i <= 10; ++i, x10 += 5 + (i * 37 + a * 11) % 17) grid[a].push_back(x10 / 10.0);
  auto spec = test::staircase(h, grid);
  spec.subdivisions = 3;
  spec.jitter = 0.12;
  spec.random_diagonals = true;
  for (double angle : {0.0, 0.3}) {
    spec.chart_rotation = angle;
    const Case c = polycube_case("large staircase " + std::to_string(angle), spec);
    const TMesh tm = trace(c);
    expect_valid(c, tm);
    std::cout << c.name << ": " << c.mesh.num_faces() << " faces, T-mesh " << tm.nodes.size() << " nodes, "
              << tm.edges.size() << " edges, " << tm.cells.size() << " cells, " << tm.stats.trace_seconds << " s\n";
  }
}

// Real meshes (seamless maps from splitting every triangle into three unit quads): genus,
// boundaries, sharp features, singularities of every valence; prints figures per mesh.
void quad_map_case(const std::string& file, double sharp_deg, std::array<int, 3> triple = {1, 0, 1}) {
  const IntakeResult in = test::load_mesh(file);
  const TriMesh tri = test::component_mesh(in, 0);
  const std::vector<char> sharp = sharp_deg > 0 ? test::sharp_edges(tri, sharp_deg) : std::vector<char>{};
  const test::QuadMap qm = test::make_quad_map(tri, sharp, triple);
  Case c{file + (triple[1] != 0 ? " oblique" : "") + (sharp_deg > 0 ? " features" : ""), qm.mesh,
         test::exact_integer_map(qm.mesh, qm.param, 24), sharp_deg > 0 ? qm.features : std::vector<char>{}};
  ASSERT_EQ(exact_transition_residual(c.mesh, c.param), 0) << c.name;
  const TMesh tm = trace(c);
  const TMeshCheck check = check_tmesh(tm);
  int features = 0, boundary = 0;
  for (int e = 0; e < c.mesh.num_edges(); ++e) {
    boundary += c.mesh.is_boundary_edge(e);
    features += !c.features.empty() && c.features[e];
  }
  std::printf(
      "[tmesh] %-24s %7d triangles, %4d feature + %4d boundary edges -> %6zu nodes %6zu edges %6zu cells, "
      "%5d T-junctions, %6d separatrices, trace %.3f s\n",
      c.name.c_str(), c.mesh.num_faces(), features, boundary, tm.nodes.size(), tm.edges.size(), tm.cells.size(),
      check.t_junctions, tm.stats.motorcycles, tm.stats.trace_seconds);
  expect_valid(c, tm);
}

// Sanitizer builds (several times slower) run the smaller meshes only.
#ifdef QGP_SANITIZED
constexpr bool kAllMeshes = false;
#else
constexpr bool kAllMeshes = true;
#endif

TEST(TMesh, QuadMapsOfRealMeshesWithFeaturesAndBoundaries) {
  for (const char* f : {"joint.obj", "block.obj", "fandisk.obj", "wingnut.obj"}) quad_map_case(f, 40);
  quad_map_case("camelhead.off", -1);
  if (!kAllMeshes) return;
  for (const char* f : {"face.obj", "beetle.off"}) quad_map_case(f, -1);
}

TEST(TMesh, ObliqueQuadMapsOfClosedMeshes) {
  quad_map_case("torus.obj", -1, {12, 5, 13});
  quad_map_case("fertility.off", -1, {15, 8, 17});
  if (!kAllMeshes) return;
  quad_map_case("spot.obj", -1, {4, 3, 5});
  quad_map_case("kitten.obj", -1, {21, 20, 29});
}

// The pipeline's own T-meshes: the exact seamless map of the quick meshes of the shared set (on
// the working mesh where the session decimates), without and with features at 40 degrees on the
// CAD meshes; every check of expect_valid, and a row of figures per mesh. The large meshes' T-meshes
// are checked by the LayoutMeshes sweep (its stage invariants at four densities).
void session_tmesh_cases(const std::string& name, double sharp_angle_deg) {
  Session session(read_mesh_file(test::mesh_path(name)));
  RemeshOptions options;
  options.target_faces = 2000;
  options.sharp_angle_deg = sharp_angle_deg;
  session.set_options(options);
  const std::string error = test::run_until_stage(session, "quantization");
  ASSERT_EQ(error, "") << name;
  for (size_t k = 0; k < session.components().size(); ++k) {
    const ComponentState& state = session.components()[k];
    Case c{name + (sharp_angle_deg > 0 ? " features" : ""), state.mesh, state.traced->exact,
           state.traced->isoline_edges};
    const TMesh& tm = state.traced->tmesh;
    const TMeshCheck check = check_tmesh(tm);
    std::printf(
        "[session tmesh] %-32s %7d triangles, %4d singularities -> %6zu nodes %6zu edges %6zu cells, "
        "%5d T-junctions, trace %.3f s\n",
        c.name.c_str(), c.mesh.num_faces(), state.field->num_singularities, tm.nodes.size(), tm.edges.size(),
        tm.cells.size(), check.t_junctions, tm.stats.trace_seconds);
    expect_valid(c, tm);
  }
}

TEST(TMesh, SessionMapsOfTheQuickMeshes) {
  for (const std::string& name : test::quick_mesh_files()) {
    if (!kAllMeshes && name != "spot.obj" && name != "joint.obj") continue;
    session_tmesh_cases(name, -1);
  }
  for (const char* name : {"fandisk.obj", "block.obj", "joint.obj", "wingnut.obj"})
    if (kAllMeshes || std::string(name) == "joint.obj") session_tmesh_cases(name, 40);
}

TEST(TMesh, RandomlyBrokenMapsNeverCrashOrHang) {
  // Noise of up to half a grid cell flips triangles here and there: the tracer either throws
  // Error(StageFailed) or returns a valid T-mesh (flips inside cells do not matter).
  int traced = 0, refused = 0;
  for (unsigned seed = 1; seed <= 24; ++seed) {
    auto spec = test::staircase({{3, 2, 1}, {2, 2, 1}, {1, 1, 0}}, {uniform(3), uniform(3), uniform(3)});
    spec.subdivisions = 2 + seed % 2;
    spec.chart_rotation = seed % 3 == 0 ? 0.0 : 0.25 * seed;
    test::Polycube pc = test::make_polycube(spec);
    std::mt19937 rng(seed);
    const double amount = (0.02 + 0.1 * (seed % 6)) / spec.subdivisions;
    std::uniform_real_distribution<double> noise(-amount, amount);
    for (int k = 0; k < pc.param.uv.rows(); ++k) pc.param.uv.row(k) += Vec2(noise(rng), noise(rng)).transpose();
    SanitizeOptions so;
    so.fraction_bits = 24;
    const SanitizeResult r = sanitize_parametrization(pc.mesh, pc.param, so);
    const Case c{"noisy " + std::to_string(seed), pc.mesh, r.param, {}};
    try {
      Progress progress;
      TraceOptions options;
      options.max_steps = 200000;
      const TMesh tm = trace_tmesh(c.mesh, c.param, options, progress);
      expect_valid(c, tm);
      ++traced;
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::StageFailed) << c.name << ": " << e.what();
      ++refused;
    }
  }
  std::cout << "noisy maps: " << traced << " traced, " << refused << " refused\n";
  EXPECT_GT(refused, 0);
  EXPECT_GT(traced, 0);
}

TEST(TMesh, CancelStopsTracing) {
  const auto cube = test::make_grid_cube(3);
  const Case c = make_case("cube", cube.mesh, cube.param);
  std::atomic<bool> cancel{true};
  Progress progress(nullptr, &cancel);
  try {
    trace_tmesh(c.mesh, c.param, TraceOptions{}, progress);
    ADD_FAILURE() << "cancel ignored";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::Cancelled);
  }
}

TEST(TMesh, InvalidInputIsRefused) {
  const auto cube = test::make_grid_cube(2);
  Case c = make_case("cube", cube.mesh, cube.param);
  Progress progress;
  TraceOptions options;
  options.feature_edges.assign(3, 1);  // wrong size
  EXPECT_THROW(trace_tmesh(c.mesh, c.param, options, progress), Error);
  ExactParametrization short_param = c.param;
  short_param.uv.pop_back();
  EXPECT_THROW(trace_tmesh(c.mesh, short_param, TraceOptions{}, progress), Error);
  ExactParametrization huge = c.param;
  huge.uv[0][0] = int64_t(1) << 62;
  EXPECT_THROW(trace_tmesh(c.mesh, huge, TraceOptions{}, progress), Error);
  huge.uv[0][0] = INT64_MIN;
  EXPECT_THROW(trace_tmesh(c.mesh, huge, TraceOptions{}, progress), Error);
}

TEST(TMesh, CellSystemAndReport) {
  auto spec = test::staircase({{2, 1}, {1, 1}}, {std::vector<double>{0, 1.5, 2.25}, uniform(2), uniform(2)});
  spec.subdivisions = 2;
  const Case c = polycube_case("system", spec);
  const TMesh tm = trace(c);
  expect_valid(c, tm);
  const TMeshCellSystem sys = tmesh_cell_system(tm);
  EXPECT_EQ(sys.A.rows(), 2 * static_cast<int>(tm.cells.size()));
  EXPECT_EQ(sys.A.cols(), static_cast<int>(tm.edges.size()));
  const Eigen::VectorXd r = sys.A.cast<double>() * sys.ideal_lengths;
  EXPECT_LT(r.cwiseAbs().maxCoeff(), 1e-9 * sys.ideal_lengths.maxCoeff());
  // Each edge lies in at most two rows per direction; a T-mesh column has 1 or 2 non-zeros.
  for (int col = 0; col < sys.A.cols(); ++col) {
    int nnz = 0;
    for (int row = 0; row < sys.A.rows(); ++row) nnz += sys.A.coeff(row, col) != 0;
    EXPECT_GE(nnz, 1);
    EXPECT_LE(nnz, 2);
  }
  const Json j = tm;
  for (const char* key : {"nodes", "edges", "cells", "singular_nodes", "t_junctions", "euler_characteristic",
                          "cells_not_four_sided", "max_cell_equation_residual", "trace_seconds"})
    EXPECT_TRUE(j.contains(key)) << key;
  EXPECT_EQ(j["euler_characteristic"].get<int>(), 2);
  std::ostringstream obj;
  long long offset = 0;
  write_layout_obj(obj, c.mesh, tm, offset);
  const std::string text = obj.str();
  EXPECT_NE(text.find("\nl "), std::string::npos);
  EXPECT_NE(text.find("\np "), std::string::npos);
  EXPECT_GE(offset, static_cast<long long>(tm.nodes.size()));
}

}  // namespace
}  // namespace qgp

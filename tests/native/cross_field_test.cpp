// Cross field (stage 1a): Poincare-Hopf, matching conventions, index vs. holonomy, feature
// alignment and smoothness over the shared mesh set plus synthetic cases.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdio>
#include <random>

#include "core/error.h"
#include "cross_field/cross_field.h"
#include "cut_graph/cut_graph.h"
#include "field_test_cases.h"
#include "seamless_map/seamless_map.h"

namespace qgp {
namespace {

constexpr double kQuarter = M_PI / 2;

bool is_constraint_halfedge(const TriMesh& mesh, const CrossField& field, int h) {
  return mesh.opposite[h] < 0 || field.feature_edge[mesh.edge_of[h]];
}

// Checks every invariant of a computed field; failures name the first offending element.
void check_field(const TriMesh& mesh, const CrossField& field, double sharp_angle_deg,
                 const std::vector<char>& caller_features = {}, int collapsed_allowance = 0) {
  const int nv = mesh.num_vertices(), ne = mesh.num_edges(), nf = mesh.num_faces(), nh = mesh.num_halfedges();
  ASSERT_EQ(static_cast<int>(field.direction.size()), nf);
  ASSERT_EQ(static_cast<int>(field.matching.size()), nh);
  ASSERT_EQ(static_cast<int>(field.vertex_index.size()), nv);
  ASSERT_EQ(static_cast<int>(field.feature_edge.size()), ne);
  ASSERT_EQ(static_cast<int>(field.constrained_face.size()), nf);
  ASSERT_EQ(static_cast<int>(field.edge_sector.size()), nh);

  // Poincare-Hopf (boundary version on open meshes).
  const int chi = nv - ne + nf;
  EXPECT_EQ(field.euler_characteristic, chi);
  int sum = 0, singular = 0;
  for (int v = 0; v < nv; ++v) sum += field.vertex_index[v], singular += field.vertex_index[v] != 0;
  EXPECT_EQ(sum, 4 * chi);
  EXPECT_EQ(field.index_sum, 4 * chi);
  EXPECT_EQ(field.num_singularities, singular);

  // Unit tangent directions.
  int bad_direction = -1;
  for (int f = 0; f < nf && bad_direction < 0; ++f)
    if (std::abs(field.direction[f].norm() - 1) > 1e-9 ||
        std::abs(field.direction[f].dot(test::unit_normal(mesh, f))) > 1e-9)
      bad_direction = f;
  EXPECT_EQ(bad_direction, -1) << "direction is not a unit tangent";

  // Features: caller's plus dihedral; boundary edges are not flagged.
  int bad_feature = -1;
  for (int e = 0; e < ne && bad_feature < 0; ++e) {
    const bool boundary = mesh.is_boundary_edge(e);
    bool expected = !boundary && !caller_features.empty() && caller_features[e];
    if (!boundary && sharp_angle_deg >= 0 && test::dihedral_angle(mesh, e) > sharp_angle_deg * M_PI / 180)
      expected = true;
    if (static_cast<bool>(field.feature_edge[e]) != expected) bad_feature = e;
  }
  EXPECT_EQ(bad_feature, -1) << "feature flag differs from the dihedral/caller features";

  // Matching convention: R^r maps the edge's chart vector on this side onto the far side's one,
  // up to at most 45 degrees (90 across feature edges); opposite halfedges carry inverses.
  std::vector<double> eps(nh, 0.0);
  int bad_inverse = -1, bad_nearest = -1, bad_boundary = -1;
  int moved = 0;  // halfedges off the nearest matching / axis (collapsed-sector repair)
  for (int h = 0; h < nh; ++h) {
    const int o = mesh.opposite[h];
    if (o < 0) {
      if (field.matching[h] != 0) bad_boundary = h;
      continue;
    }
    if (field.matching[o] != (4 - field.matching[h]) % 4) bad_inverse = h;
    const double here = test::angle_in_chart(mesh, h, field.direction[h / 3]);
    const double there = test::angle_in_chart(mesh, o, field.direction[o / 3]) + M_PI;
    eps[h] = test::wrap_angle(there - here - field.matching[h] * kQuarter);
    const double limit = field.feature_edge[mesh.edge_of[h]] ? M_PI / 2 : M_PI / 4;
    if (std::abs(eps[h]) > limit + 1e-9) {
      // Moved by the collapsed-sector repair: one quarter turn further, at most.
      ++moved;
      if (std::abs(eps[h]) >= limit + kQuarter) bad_nearest = h;
    }
  }
  EXPECT_EQ(bad_inverse, -1) << "matching[opposite] != (4 - matching[h]) % 4";
  EXPECT_EQ(bad_nearest, -1) << "matching is not the nearest quarter turn";
  EXPECT_EQ(bad_boundary, -1) << "boundary halfedge with a matching";

  // Isoline sectors: present exactly on feature/boundary halfedges, at most 45deg off the chart
  // angle, consistent across interior feature edges.
  std::vector<double> rho(nh, 0.0);
  int bad_sector = -1, bad_sector_pair = -1;
  for (int h = 0; h < nh; ++h) {
    const bool constraint = is_constraint_halfedge(mesh, field, h);
    if (constraint != (field.edge_sector[h] >= 0) || field.edge_sector[h] > 3) {
      bad_sector = h;
      continue;
    }
    if (!constraint) continue;
    rho[h] = test::wrap_angle(test::angle_in_chart(mesh, h, field.direction[h / 3]) - field.edge_sector[h] * kQuarter);
    const int o = mesh.opposite[h];
    if (o >= 0 && field.edge_sector[o] != (field.edge_sector[h] + field.matching[h] + 2) % 4) bad_sector_pair = h;
    if (std::abs(rho[h]) > M_PI / 4 + 1e-9) {
      ++moved;
      if (std::abs(rho[h]) >= M_PI / 2) bad_sector = h;
    }
  }
  // Each repaired sector moves one matching (two halfedges) or one halfedge sector, which may
  // also push the feature edge's matching past 90deg (two more halfedges); each matching a pair
  // cancellation or untwist turned may stay off its nearest quarter turn (two halfedges).
  EXPECT_LE(moved, 4 * field.num_resolved_sectors + 2 * field.num_turned_matchings)
      << "matchings / sectors off the nearest choice";
  EXPECT_EQ(bad_sector, -1) << "edge_sector missing, misplaced or off by more than 45 degrees (90 if repaired)";
  EXPECT_EQ(bad_sector_pair, -1) << "edge sectors inconsistent across a feature edge";

  // Index from angle defect and field rotation, and holonomy: index = sum of matchings mod 4.
  int bad_index = -1, bad_holonomy = -1;
  for (int v = 0; v < nv && bad_index < 0 && bad_holonomy < 0; ++v) {
    const std::vector<int> fan = outgoing_halfedges(mesh, v);
    const bool boundary = is_boundary_vertex(mesh, v);
    double turning = boundary ? M_PI : 2 * M_PI;
    int holonomy = 0;
    for (int h : fan) {
      turning -= corner_angle(mesh, h);
      const int crossing = TriMesh::prev(h);
      if (mesh.opposite[crossing] >= 0) turning -= eps[crossing], holonomy += field.matching[crossing];
    }
    if (boundary) turning += rho[TriMesh::prev(fan.back())] - rho[fan.front()];
    if (std::abs(turning / kQuarter - field.vertex_index[v]) > 1e-6) bad_index = v;
    if (!boundary && ((holonomy - field.vertex_index[v]) % 4 + 4) % 4 != 0) bad_holonomy = v;
  }
  EXPECT_EQ(bad_index, -1) << "index differs from (defect - field rotation) / 90deg";
  EXPECT_EQ(bad_holonomy, -1) << "index is not the holonomy of the matchings mod 4";

  // Hard constraints: a face aligned to its one feature/boundary edge contains its direction
  // (1e-9 rad); a face with two maps them to orthogonal isolines, each off by |45deg - beta/2|.
  int bad_kind = -1, bad_single = -1, bad_double = -1, overconstrained = 0;
  std::vector<char> overconstrained_face(nf, 0);
  for (int f = 0; f < nf; ++f) {
    std::vector<int> constraint;
    for (int k = 0; k < 3; ++k)
      if (is_constraint_halfedge(mesh, field, 3 * f + k)) constraint.push_back(3 * f + k);
    overconstrained += overconstrained_face[f] = constraint.size() == 3;
    const int kind = field.constrained_face[f];
    if (kind < 0 || kind > 3 || (kind == 1) != (constraint.size() == 1 && kind != 3) ||
        (kind == 2) != (constraint.size() >= 2) || (kind == 0 && !constraint.empty()))
      bad_kind = f;
    if (kind == 1) {
      const double a = test::angle_in_chart(mesh, constraint[0], field.direction[f]);
      if (std::abs(std::remainder(a, kQuarter)) > 1e-9) bad_single = f;
    } else if (constraint.size() == 2) {
      // The corner between them: outgoing halfedge h1, incoming h0 = prev(h1).
      int h1 = constraint[0], h0 = constraint[1];
      if (TriMesh::prev(h1) != h0) std::swap(h0, h1);
      const double beta = corner_angle(mesh, h1);
      const double off = std::abs(M_PI / 4 - beta / 2);
      const double a1 = test::angle_in_chart(mesh, h1, field.direction[f]);
      const double a0 = test::angle_in_chart(mesh, h0, field.direction[f]);
      const double r1 = std::remainder(a1, kQuarter), r0 = std::remainder(a0, kQuarter);
      const long q1 = std::lround((a1 - r1) / kQuarter), q0 = std::lround((a0 - r0) / kQuarter);
      if (std::abs(std::abs(r1) - off) > 1e-9 || std::abs(std::abs(r0) - off) > 1e-9 || (q1 - q0) % 2 == 0)
        bad_double = f;
    }
  }
  EXPECT_EQ(field.num_overconstrained_faces, overconstrained);
  EXPECT_EQ(bad_kind, -1) << "constrained_face kind does not match the face's feature edges";
  EXPECT_EQ(bad_single, -1) << "face with one feature edge is not aligned to it";
  EXPECT_EQ(bad_double, -1) << "face with two feature edges does not use the symmetric orthogonal compromise";

  // Feature sectors around each vertex (between consecutive feature/boundary edges) map to whole
  // quarter turns n that add up to the vertex's quad count (4 - index inside, 2 - index on the
  // boundary); n >= 1, and exactly 1 for a sector of one face, except at over-constrained faces.
  int bad_sum = -1, collapsed = 0, collapsed_elsewhere = 0, bad_integral = -1;
  auto is_constraint = [&](int h) { return is_constraint_halfedge(mesh, field, h); };
  for (int v = 0; v < nv; ++v) {
    const std::vector<int> fan = outgoing_halfedges(mesh, v);
    const int k = static_cast<int>(fan.size());
    int start = -1;
    for (int j = 0; j < k && start < 0; ++j)
      if (is_constraint(fan[j])) start = j;
    if (start < 0) continue;
    const bool boundary = is_boundary_vertex(mesh, v);
    int total = 0;
    for (int j0 = start, j1; j0 < (boundary ? k : start + k); j0 = j1 + 1) {
      j1 = j0;
      bool touches_overconstrained = overconstrained_face[fan[j0 % k] / 3];
      double swept = rho[fan[j0 % k]] + corner_angle(mesh, fan[j0 % k]);
      while (!is_constraint(TriMesh::prev(fan[j1 % k]))) {
        swept += eps[TriMesh::prev(fan[j1 % k])];
        ++j1;
        swept += corner_angle(mesh, fan[j1 % k]);
        touches_overconstrained |= overconstrained_face[fan[j1 % k] / 3];
      }
      swept -= rho[TriMesh::prev(fan[j1 % k])];
      const long n = std::lround(swept / kQuarter);
      if (std::abs(swept / kQuarter - n) > 1e-6) bad_integral = v;
      total += n;
      if (n < 1 || (j1 == j0 && n != 1)) ++collapsed, collapsed_elsewhere += !touches_overconstrained;
    }
    if (total != (boundary ? 2 : 4) - field.vertex_index[v]) bad_sum = v;
  }
  EXPECT_EQ(bad_integral, -1) << "sector angle is not a whole number of quarter turns";
  EXPECT_EQ(bad_sum, -1) << "sector quarter turns do not add up to the vertex index";
  EXPECT_EQ(field.num_collapsed_sectors, collapsed);
  EXPECT_LE(collapsed_elsewhere, collapsed_allowance) << "collapsed sectors away from over-constrained faces";
}

int count_features(const CrossField& field) {
  int n = 0;
  for (char f : field.feature_edge) n += f;
  return n;
}

class CrossFieldOverMeshes : public ::testing::TestWithParam<test::FieldCase> {};

TEST_P(CrossFieldOverMeshes, InvariantsPerComponent) {
  const test::FieldCase& c = GetParam();
  const IntakeResult intake = test::load_mesh(c.file);
  int singularities = 0, features = 0, overconstrained = 0, collapsed = 0, resolved = 0, compromises = 0;
  for (int comp = 0; comp < static_cast<int>(intake.components.size()); ++comp) {
    SCOPED_TRACE(c.file + " component " + std::to_string(comp));
    const TriMesh mesh = test::component_mesh(intake, comp);
    CrossFieldOptions options;
    options.sharp_angle_deg = c.sharp_angle_deg;
    Progress progress;
    const CrossField field = compute_cross_field(mesh, options, progress);
    EXPECT_EQ(field.euler_characteristic, intake.components[comp].euler_characteristic);
    check_field(mesh, field, c.sharp_angle_deg, {}, c.collapsed_allowance);
    singularities += field.num_singularities;
    features += count_features(field);
    overconstrained += field.num_overconstrained_faces;
    collapsed += field.num_collapsed_sectors;
    resolved += field.num_resolved_sectors;
    for (char kind : field.constrained_face) compromises += kind >= 2;
    if (HasFailure()) break;
  }
  std::printf(
      "[ figures  ] %-28s sharp %3.0f  components %4zu  faces %7d  singularities %5d  feature edges %5d  "
      "compromise faces %4d  over-constrained faces %3d  collapsed sectors %3d  resolved sectors %3d\n",
      c.file.c_str(), c.sharp_angle_deg, intake.components.size(), intake.mesh.num_faces(), singularities, features,
      compromises, overconstrained, collapsed, resolved);
  if (c.sharp_angle_deg >= 0 && intake.components.size() == 1) EXPECT_GT(features, 0);
}

INSTANTIATE_TEST_SUITE_P(SharedMeshes, CrossFieldOverMeshes, ::testing::ValuesIn(test::field_cases()), test::case_name);

TEST(CrossField, SmoothOnOrganicMeshes) {
  for (const char* file : {"spot.obj", "bunny.off", "kitten.obj"}) {
    const IntakeResult intake = test::load_mesh(file);
    Progress progress;
    const CrossField field = compute_cross_field(test::component_mesh(intake, 0), CrossFieldOptions{}, progress);
    std::printf("[ figures  ] %-12s singularities %d\n", file, field.num_singularities);
    EXPECT_LT(field.num_singularities, 100) << file;
  }
}

TEST(CrossField, CallerFeaturesActLikeDihedralOnes) {
  const IntakeResult intake = test::load_mesh("fandisk.obj");
  const TriMesh mesh = test::component_mesh(intake, 0);
  Progress progress;
  CrossFieldOptions dihedral;
  dihedral.sharp_angle_deg = 40;
  const CrossField a = compute_cross_field(mesh, dihedral, progress);
  CrossFieldOptions caller;
  caller.feature_edges.assign(mesh.num_edges(), 0);
  for (int e = 0; e < mesh.num_edges(); ++e)
    caller.feature_edges[e] = !mesh.is_boundary_edge(e) && test::dihedral_angle(mesh, e) > 40 * M_PI / 180;
  const CrossField b = compute_cross_field(mesh, caller, progress);
  check_field(mesh, b, -1, caller.feature_edges);
  EXPECT_EQ(a.feature_edge, b.feature_edge);
  EXPECT_EQ(a.vertex_index, b.vertex_index);
  EXPECT_EQ(a.matching, b.matching);
}

TEST(CrossField, CubeCornersAreTheSingularities) {
  const test::SyntheticParametrized cube = test::make_grid_cube(4);
  for (double sharp : {-1.0, 40.0}) {
    SCOPED_TRACE("sharp " + std::to_string(sharp));
    CrossFieldOptions options;
    options.sharp_angle_deg = sharp;
    Progress progress;
    const CrossField field = compute_cross_field(cube.mesh, options, progress);
    check_field(cube.mesh, field, sharp);
    EXPECT_EQ(field.num_singularities, 8);
    for (int v = 0; v < cube.mesh.num_vertices(); ++v) {
      const Vec3 p = cube.mesh.position(v);
      const bool corner = (p.x() == 0 || p.x() == 4) && (p.y() == 0 || p.y() == 4) && (p.z() == 0 || p.z() == 4);
      EXPECT_EQ(field.vertex_index[v], corner ? 1 : 0) << "vertex " << v;
    }
    // Without features any global rotation of the parallel field is smoothest; with the cube
    // edges as features the field is the cube's own chart up to a quarter turn k_f per face, so
    // the matchings are the exact parametrization's rotations conjugated by those turns:
    // r = r_param + k_f - k_g.
    if (sharp < 0) continue;
    std::vector<int> k(cube.mesh.num_faces(), -1);
    for (int f = 0; f < cube.mesh.num_faces(); ++f) {
      const int h = 3 * f;
      const Vec2 duv = cube.param.corner(f, 1) - cube.param.corner(f, 0);
      const double param_angle = std::atan2(duv.y(), duv.x());
      const double field_angle = test::angle_in_chart(cube.mesh, h, field.direction[f]);
      const double turns = (param_angle - field_angle) / kQuarter;
      ASSERT_NEAR(turns, std::round(turns), 1e-9);
      k[f] = ((static_cast<int>(std::lround(turns)) % 4) + 4) % 4;
    }
    for (int h = 0; h < cube.mesh.num_halfedges(); ++h) {
      const int o = cube.mesh.opposite[h];
      EXPECT_EQ(field.matching[h], ((cube.param.rotation[h] + k[h / 3] - k[o / 3]) % 4 + 4) % 4) << "halfedge " << h;
    }
  }
}

TEST(CrossField, SmoothTorusAndPlanarGrid) {
  {
    const test::SyntheticParametrized torus = test::make_grid_torus(24, 12);
    Progress progress;
    const CrossField field = compute_cross_field(torus.mesh, CrossFieldOptions{}, progress);
    check_field(torus.mesh, field, -1);
    EXPECT_EQ(field.index_sum, 0);
  }
  {
    // A flat square: boundary-aligned, exactly parallel, singular only at the four corners.
    const TriMesh grid = test::make_planar_grid(6);
    Progress progress;
    const CrossField field = compute_cross_field(grid, CrossFieldOptions{}, progress);
    check_field(grid, field, -1);
    EXPECT_EQ(field.num_singularities, 4);
    for (int v = 0; v < grid.num_vertices(); ++v) {
      const Vec3 p = grid.position(v);
      const bool corner = (p.x() == 0 || p.x() == 6) && (p.y() == 0 || p.y() == 6);
      EXPECT_EQ(field.vertex_index[v], corner ? 1 : 0) << "vertex " << v;
    }
    for (int f = 0; f < grid.num_faces(); ++f)
      EXPECT_NEAR(std::abs(std::remainder(std::atan2(field.direction[f].y(), field.direction[f].x()), kQuarter)), 0,
                  1e-9);
  }
}

// A flat disc: centre vertex 0, then two rings of n vertices (radius 1 and 2; the outer ring
// is the boundary). No interior edge joins two boundary vertices.
TriMesh make_ring_disc(int n) {
  std::vector<Vec3> points{{0, 0, 0}};
  std::vector<std::array<int, 3>> faces;
  for (int ring = 1; ring <= 2; ++ring)
    for (int i = 0; i < n; ++i)
      points.push_back({ring * std::cos(2 * M_PI * i / n), ring * std::sin(2 * M_PI * i / n), 0});
  auto r1 = [&](int i) { return 1 + i % n; };
  auto r2 = [&](int i) { return 1 + n + i % n; };
  for (int i = 0; i < n; ++i) {
    faces.push_back({0, r1(i), r1(i + 1)});
    faces.push_back({r1(i), r2(i), r2(i + 1)});
    faces.push_back({r1(i), r2(i + 1), r1(i + 1)});
  }
  return test::make_triangles(points, faces);
}

// Whether a singularity of index +1 and one of -1 are joined by a path of at most two ordinary
// edges no longer than max_length whose every vertex is more than 4 rings of edges from the
// nearest vertex of a constrained face (the pairs the pipeline cancels; an independent search).
bool has_close_pair(const TriMesh& mesh, const CrossField& field, double max_length) {
  std::vector<int> rings(mesh.num_vertices(), -1), queue;
  for (int f = 0; f < mesh.num_faces(); ++f)
    for (int k = 0; k < 3 && field.constrained_face[f]; ++k)
      if (rings[mesh.F(f, k)] < 0) rings[mesh.F(f, k)] = 0, queue.push_back(mesh.F(f, k));
  for (size_t i = 0; i < queue.size(); ++i)
    for (int h : outgoing_halfedges(mesh, queue[i]))
      if (rings[mesh.to(h)] < 0) rings[mesh.to(h)] = rings[queue[i]] + 1, queue.push_back(mesh.to(h));
  auto far = [&](int v) { return rings[v] < 0 || rings[v] > 4; };
  auto ordinary = [&](int h) { return mesh.opposite[h] >= 0 && !field.feature_edge[mesh.edge_of[h]]; };
  for (int plus = 0; plus < mesh.num_vertices(); ++plus) {
    if (field.vertex_index[plus] != 1 || !far(plus)) continue;
    for (int h : outgoing_halfedges(mesh, plus)) {
      const int w = mesh.to(h);
      const double first = mesh.edge_vector(h).norm();
      if (!ordinary(h) || !far(w) || first > max_length) continue;
      if (field.vertex_index[w] == -1) return true;
      for (int g : outgoing_halfedges(mesh, w))
        if (ordinary(g) && far(mesh.to(g)) && field.vertex_index[mesh.to(g)] == -1 &&
            first + mesh.edge_vector(g).norm() <= max_length)
          return true;
    }
  }
  return false;
}

// Pairs of singularities of index +1 and -1 nearer than the quad edge length the pipeline asks to
// cancel (cow, a scan; a noisy sphere): every field invariant holds, the pairs are gone and no
// other singularity is made or moved, and no such pair is left.
TEST(CrossField, CloseSingularityPairsAreCancelled) {
  struct Case {
    std::string name;
    TriMesh mesh;
  };
  std::vector<Case> cases;
  for (const char* file : {"cow.obj", "stanford-bunny.obj"})
    cases.push_back({file, test::component_mesh(test::load_mesh(file), 0)});
  TriMesh sphere = test::make_grid_cube(16).mesh;
  std::mt19937 random(7);
  std::uniform_real_distribution<double> noise(-0.3, 0.3);
  for (int v = 0; v < sphere.num_vertices(); ++v) {
    const Vec3 p = (sphere.position(v) - Vec3(8, 8, 8)).normalized() * 8;
    sphere.V.row(v) = (p + Vec3(noise(random), noise(random), noise(random))).transpose();
  }
  cases.push_back({"noisy sphere", sphere});
  int cancelled = 0;
  for (const Case& c : cases) {
    double area = 0;
    for (int f = 0; f < c.mesh.num_faces(); ++f) area += 0.5 * c.mesh.face_normal_unnormalized(f).norm();
    Progress progress;
    const CrossField plain = compute_cross_field(c.mesh, CrossFieldOptions{}, progress);
    for (double quads : {500.0, 2000.0, 8000.0}) {
      const std::string name = c.name + " at " + std::to_string(static_cast<int>(quads)) + " quads";
      CrossFieldOptions options;
      options.cancel_pairs_within = std::sqrt(area / quads);
      const CrossField field = compute_cross_field(c.mesh, options, progress);
      check_field(c.mesh, field, -1);
      EXPECT_EQ(field.num_singularities, plain.num_singularities - 2 * field.num_close_pairs) << name;
      for (int v = 0; v < c.mesh.num_vertices(); ++v)
        if (field.vertex_index[v] != 0)
          EXPECT_EQ(field.vertex_index[v], plain.vertex_index[v]) << name << " vertex " << v;
      EXPECT_FALSE(has_close_pair(c.mesh, field, options.cancel_pairs_within)) << name;
      cancelled += field.num_close_pairs;
    }
  }
  EXPECT_GT(cancelled, 30);
}

// Where a seamless map with the close pairs cancelled folded, the pipeline asks for the field again
// with the pairs near the folds kept (keep_pairs_near): given the +1 ends of every other pair the
// field cancelled, none of those singularities is cancelled now, no singularity is made or moved,
// the pairs kept are counted, and the other pairs are still cancelled.
TEST(CrossField, PairsNearGivenVerticesAreKept) {
  std::vector<std::pair<std::string, TriMesh>> cases;
  for (const char* file : {"cow.obj", "stanford-bunny.obj", "dragon-genus1.obj"})
    cases.emplace_back(file, test::component_mesh(test::load_mesh(file), 0));
  for (const auto& [name, mesh] : cases) {
    double area = 0;
    for (int f = 0; f < mesh.num_faces(); ++f) area += 0.5 * mesh.face_normal_unnormalized(f).norm();
    Progress progress;
    const CrossField plain = compute_cross_field(mesh, CrossFieldOptions{}, progress);
    CrossFieldOptions options;
    options.cancel_pairs_within = std::sqrt(area / 2000);
    const CrossField cancelled = compute_cross_field(mesh, options, progress);
    EXPECT_EQ(cancelled.num_pairs_kept_near_folds, 0) << name;
    std::vector<int> gone;  // +1 vertices whose pair was cancelled
    for (int v = 0; v < mesh.num_vertices(); ++v)
      if (plain.vertex_index[v] == 1 && cancelled.vertex_index[v] == 0) gone.push_back(v);
    ASSERT_GE(gone.size(), 2u) << name;
    for (size_t i = 0; i < gone.size(); i += 2) options.keep_pairs_near.push_back(gone[i]);
    const CrossField kept = compute_cross_field(mesh, options, progress);
    check_field(mesh, kept, -1);
    EXPECT_GE(kept.num_pairs_kept_near_folds, static_cast<int>(options.keep_pairs_near.size())) << name;
    EXPECT_GT(kept.num_close_pairs, 0) << name;
    EXPECT_LT(kept.num_close_pairs, cancelled.num_close_pairs) << name;
    EXPECT_EQ(kept.num_singularities, plain.num_singularities - 2 * kept.num_close_pairs) << name;
    for (int v : options.keep_pairs_near) EXPECT_EQ(kept.vertex_index[v], 1) << name << " vertex " << v;
    for (int v = 0; v < mesh.num_vertices(); ++v)
      if (kept.vertex_index[v] != 0) EXPECT_EQ(kept.vertex_index[v], plain.vertex_index[v]) << name << " vertex " << v;
  }
}

// Quarter turns (mod 4) of the matchings around a closed loop of faces, each next to the one before.
int dual_loop_turns(const TriMesh& mesh, const CrossField& field, const std::vector<int>& faces) {
  int turns = 0;
  for (size_t i = 0; i < faces.size(); ++i) {
    const int f = faces[i], g = faces[(i + 1) % faces.size()];
    int crossing = -1;
    for (int k = 0; k < 3; ++k)
      if (mesh.opposite[3 * f + k] >= 0 && mesh.opposite[3 * f + k] / 3 == g) crossing = 3 * f + k;
    EXPECT_GE(crossing, 0) << "faces " << f << " and " << g << " are not neighbours";
    if (crossing >= 0) turns += field.matching[crossing];
  }
  return turns % 4;
}

// Closed tori, coarse to fine, thin to fat: the Knoeppel field of some has exactly one singularity
// of index +1 and one of -1, or none and a quarter turn around a handle loop; no seamless map
// follows such a field without folds (a flat torus without cones has no rotation around a loop;
// no quad mesh of the torus has exactly one vertex of valence 3 and one of valence 5). Every field
// is admissible after compute_cross_field, and every field without singularities gets a seamless
// map free of flips.
TEST(CrossField, ClosedToriGetFieldsASeamlessMapFollows) {
  int cancelled = 0, untwisted = 0, tori = 0, regular = 0;
  for (int nu : {24, 32, 40, 48, 64})
    for (int nv : {8, 10, 12, 16})
      for (double minor : {0.1, 0.2, 0.25, 0.4}) {
        const std::string name =
            "torus " + std::to_string(nu) + " x " + std::to_string(nv) + ", tube " + std::to_string(minor);
        const TriMesh mesh = test::make_grid_torus(nu, nv, 1.0, minor).mesh;
        Progress progress;
        const CrossField field = compute_cross_field(mesh, CrossFieldOptions{}, progress);
        check_field(mesh, field, -1);
        cancelled += field.num_cancelled_pairs;
        untwisted += field.num_untwisted_loops;
        ++tori;
        int plus = 0, minus = 0;
        for (int index : field.vertex_index) plus += index == 1, minus += index == -1;
        EXPECT_FALSE(field.num_singularities == 2 && plus == 1 && minus == 1) << name;
        if (field.num_singularities > 0) continue;  // pairs of +1 outside and -1 inside the ring
        // Faces of quad (i, j): 2 (i nv + j) below its diagonal, + 1 above it.
        std::vector<int> around_ring, around_tube;
        for (int i = 0; i < nu; ++i) around_ring.insert(around_ring.end(), {2 * i * nv + 1, 2 * i * nv});
        for (int j = 0; j < nv; ++j) around_tube.insert(around_tube.end(), {2 * j, 2 * j + 1});
        EXPECT_EQ(dual_loop_turns(mesh, field, around_ring), 0) << name;
        EXPECT_EQ(dual_loop_turns(mesh, field, around_tube), 0) << name;
        // Such a field has the flat torus's map, which the seamless map must find.
        const CutGraph cut = compute_cut_graph(mesh, field, progress);
        SeamlessMapOptions options;
        options.edge_length = 0.1;
        const SeamlessMap map = compute_seamless_map(mesh, field, cut, options, progress);
        EXPECT_EQ(map.stats.flipped_triangles + map.stats.degenerate_triangles + map.stats.winding_defects, 0) << name;
        ++regular;
      }
  EXPECT_EQ(tori, 80);
  EXPECT_GE(regular, 40);
  EXPECT_GT(cancelled, 0);  // the set holds both kinds of inadmissible field
  EXPECT_GT(untwisted, 0);
}

TEST(CrossField, AcuteFeatureSectorMapsToOneQuarterTurn) {
  // Feature edges along the spokes to ring vertices 0 and 2 enclose a 30deg sector of two faces.
  const TriMesh disc = make_ring_disc(24);
  auto r1 = [](int i) { return 1 + i; };
  CrossFieldOptions options;
  options.feature_edges.assign(disc.num_edges(), 0);
  for (int h = 0; h < disc.num_halfedges(); ++h)
    if (disc.from(h) == 0 && (disc.to(h) == r1(0) || disc.to(h) == r1(2))) options.feature_edges[disc.edge_of[h]] = 1;
  Progress progress;
  const CrossField field = compute_cross_field(disc, options, progress);
  check_field(disc, field, -1, options.feature_edges);
  EXPECT_EQ(field.constrained_face[0], 3);  // faces (0, r1(0), r1(1)) and (0, r1(1), r1(2))
  EXPECT_EQ(field.constrained_face[3], 3);
  EXPECT_EQ(field.num_collapsed_sectors, 0);
  // Each spoke is 45deg - 30deg / 2 off its axis (the sector invariants above check the rest).
  const double a = test::angle_in_chart(disc, 0, field.direction[0]);
  EXPECT_NEAR(std::abs(std::remainder(a, kQuarter)), M_PI / 6, 1e-9);
}

TEST(CrossField, FlatPillowWithFoldedRim) {
  // Two copies of a flat disc glued along their boundary, the lower one reversed: a closed
  // sphere of zero volume whose rim edges are 180-degree folds.
  const TriMesh top = make_ring_disc(12);
  std::vector<Vec3> points;
  for (int v = 0; v < top.num_vertices(); ++v) points.push_back(top.position(v));
  std::vector<int> lower(top.num_vertices());
  for (int v = 0; v < top.num_vertices(); ++v) {
    lower[v] = v;
    if (!is_boundary_vertex(top, v)) lower[v] = static_cast<int>(points.size()), points.push_back(top.position(v));
  }
  std::vector<std::array<int, 3>> faces;
  for (int f = 0; f < top.num_faces(); ++f) {
    faces.push_back({top.F(f, 0), top.F(f, 1), top.F(f, 2)});
    faces.push_back({lower[top.F(f, 0)], lower[top.F(f, 2)], lower[top.F(f, 1)]});
  }
  const TriMesh pillow = test::make_triangles(points, faces);
  for (double sharp : {-1.0, 40.0}) {
    CrossFieldOptions options;
    options.sharp_angle_deg = sharp;
    Progress progress;
    const CrossField field = compute_cross_field(pillow, options, progress);
    check_field(pillow, field, sharp);
    EXPECT_EQ(field.index_sum, 8);
  }
}

TEST(CrossField, TinyComponents) {
  // One triangle (three boundary edges), two triangles, an acute and an obtuse triangle.
  const std::vector<TriMesh> meshes = {
      test::make_triangles({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 1, 2}}),
      test::make_triangles({{0, 0, 0}, {1, 0, 0}, {0.5, 0.866, 0}}, {{0, 1, 2}}),
      test::make_triangles({{0, 0, 0}, {1, 0, 0}, {3, 0.2, 0}}, {{0, 1, 2}}),
      test::make_triangles({{0, 0, 0}, {1, 0, 0}, {1, 1, 0.3}, {0, 1, 0}}, {{0, 1, 2}, {0, 2, 3}}),
      // Folded flat onto itself: the two normals are opposite (dihedral angle 180 degrees).
      test::make_triangles({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.5, 1, 0}}, {{0, 1, 2}, {1, 0, 3}})};
  for (size_t i = 0; i < meshes.size(); ++i) {
    SCOPED_TRACE("mesh " + std::to_string(i));
    for (double sharp : {-1.0, 10.0}) {
      CrossFieldOptions options;
      options.sharp_angle_deg = sharp;
      Progress progress;
      const CrossField field = compute_cross_field(meshes[i], options, progress);
      check_field(meshes[i], field, sharp);
      EXPECT_EQ(field.index_sum, 4);
    }
  }
}

TEST(CrossField, RejectsBadOptionsAndHonoursCancel) {
  const TriMesh grid = test::make_planar_grid(3);
  CrossFieldOptions options;
  options.feature_edges.assign(grid.num_edges() + 1, 0);
  Progress progress;
  try {
    compute_cross_field(grid, options, progress);
    ADD_FAILURE() << "wrong feature_edges size accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::InvalidArgument);
  }
  std::atomic<bool> cancel{true};
  Progress cancelled([](const std::string&, double) {}, &cancel);
  try {
    compute_cross_field(test::make_grid_cube(3).mesh, CrossFieldOptions{}, cancelled);
    ADD_FAILURE() << "cancel ignored";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::Cancelled);
  }
}

}  // namespace
}  // namespace qgp

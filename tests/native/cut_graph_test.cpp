// Cut graph (stage 1b): one topological disc per component, combed rotations only on cuts,
// pruned branches, over the shared mesh set plus synthetic cases.
#include <gtest/gtest.h>

#include <cstdio>
#include <numeric>

#include "core/error.h"
#include "cross_field/cross_field.h"
#include "cut_graph/cut_graph.h"
#include "field_test_cases.h"

namespace qgp {
namespace {

constexpr double kQuarter = M_PI / 2;

struct DiscTopology {
  bool connected = false;
  int euler_characteristic = 0;  // of the surface cut open along the cut edges
  int boundary_loops = 0;
};

int find(std::vector<int>& parent, int x) {
  while (parent[x] != x) x = parent[x] = parent[parent[x]];
  return x;
}

// Topology of the mesh cut open along is_cut: vertices are the wedges of corners joined across
// non-cut interior edges, every cut edge becomes two boundary edges.
DiscTopology cut_open_topology(const TriMesh& mesh, const std::vector<char>& is_cut) {
  const int nh = mesh.num_halfedges(), nf = mesh.num_faces();
  // Corner h = the corner of face(h) at from(h).
  std::vector<int> corner(nh), face(nf);
  std::iota(corner.begin(), corner.end(), 0);
  std::iota(face.begin(), face.end(), 0);
  int cuts = 0;
  for (int e = 0; e < mesh.num_edges(); ++e) cuts += is_cut[e];
  for (int h = 0; h < nh; ++h) {
    const int o = mesh.opposite[h];
    if (o < 0 || is_cut[mesh.edge_of[h]]) continue;
    corner[find(corner, h)] = find(corner, TriMesh::next(o));  // both at from(h)
    face[find(face, h / 3)] = find(face, o / 3);
  }
  DiscTopology t;
  int wedges = 0, components = 0;
  for (int h = 0; h < nh; ++h) wedges += find(corner, h) == h;
  for (int f = 0; f < nf; ++f) components += find(face, f) == f;
  t.connected = components == 1;
  t.euler_characteristic = wedges - (mesh.num_edges() + cuts) + nf;
  // Boundary loops of the cut-open mesh: boundary halfedges (original boundary + both sides of
  // cuts).
  auto is_open = [&](int h) { return mesh.opposite[h] < 0 || is_cut[mesh.edge_of[h]]; };
  std::vector<char> seen(nh, 0);
  for (int h = 0; h < nh; ++h) {
    if (!is_open(h) || seen[h]) continue;
    ++t.boundary_loops;
    for (int c = h; !seen[c];) {
      seen[c] = 1;
      // Rotate clockwise around to(c), starting in c's face, to the next open halfedge.
      int out = TriMesh::next(c);
      while (!is_open(out)) out = TriMesh::next(mesh.opposite[out]);
      c = out;
    }
  }
  return t;
}

void check_cut(const TriMesh& mesh, const CrossField& field, const CutGraph& cut) {
  const int nv = mesh.num_vertices(), ne = mesh.num_edges(), nf = mesh.num_faces(), nh = mesh.num_halfedges();
  ASSERT_EQ(static_cast<int>(cut.is_cut.size()), ne);
  ASSERT_EQ(static_cast<int>(cut.rotation.size()), nh);
  ASSERT_EQ(static_cast<int>(cut.frame_u.size()), nf);
  ASSERT_EQ(static_cast<int>(cut.singular_vertex.size()), nv);
  ASSERT_EQ(static_cast<int>(cut.frame_turns.size()), nf);
  ASSERT_EQ(static_cast<int>(cut.edge_sector.size()), nh);

  int cuts = 0, boundary_cut = -1;
  for (int e = 0; e < ne; ++e) {
    cuts += cut.is_cut[e];
    if (cut.is_cut[e] && mesh.is_boundary_edge(e)) boundary_cut = e;
  }
  EXPECT_EQ(cut.num_cut_edges, cuts);
  EXPECT_EQ(boundary_cut, -1) << "a boundary edge is cut";

  // Combed rotations: inverse pairs, zero off the cut, consistent with the frames.
  int bad_inverse = -1, bad_off_cut = -1, bad_chart = -1, moved = 0;
  for (int h = 0; h < nh; ++h) {
    const int o = mesh.opposite[h];
    if (o < 0) {
      if (cut.rotation[h] != 0) bad_inverse = h;
      continue;
    }
    if (cut.rotation[o] != (4 - cut.rotation[h]) % 4) bad_inverse = h;
    if (!cut.is_cut[mesh.edge_of[h]] && cut.rotation[h] != 0) bad_off_cut = h;
    const double here = test::angle_in_chart(mesh, h, cut.frame_u[h / 3]);
    const double there = test::angle_in_chart(mesh, o, cut.frame_u[o / 3]) + M_PI;
    const double limit = field.feature_edge[mesh.edge_of[h]] ? M_PI / 2 : M_PI / 4;  // as the field's matching
    const double residual = std::abs(test::wrap_angle(there - here - cut.rotation[h] * kQuarter));
    if (residual > limit + 1e-9) {
      ++moved;  // a matching moved by the field's collapsed-sector repair: one quarter turn at most
      if (residual >= limit + kQuarter) bad_chart = h;
    }
  }
  EXPECT_LE(moved, 4 * field.num_resolved_sectors) << "rotations off the nearest quarter turn";
  EXPECT_EQ(bad_inverse, -1) << "rotation[opposite] != (4 - rotation[h]) % 4";
  EXPECT_EQ(bad_off_cut, -1) << "non-zero rotation on a non-cut edge";
  EXPECT_EQ(bad_chart, -1) << "rotation does not match the combed frames";

  // Frames are the field's directions turned by whole quarter turns; sectors follow.
  int bad_frame = -1, bad_sector = -1;
  for (int f = 0; f < nf; ++f) {
    const Vec3 n = test::unit_normal(mesh, f), d = field.direction[f];
    const Vec3 turned[4] = {d, n.cross(d), -d, -n.cross(d)};
    if ((cut.frame_u[f] - turned[cut.frame_turns[f]]).norm() > 1e-12) bad_frame = f;
  }
  for (int h = 0; h < nh; ++h) {
    if ((field.edge_sector[h] < 0) != (cut.edge_sector[h] < 0)) bad_sector = h;
    if (cut.edge_sector[h] < 0) continue;
    if ((cut.edge_sector[h] + cut.frame_turns[h / 3]) % 4 != field.edge_sector[h]) bad_sector = h;
    const int o = mesh.opposite[h];
    if (o >= 0 && cut.edge_sector[o] != (cut.edge_sector[h] + cut.rotation[h] + 2) % 4) bad_sector = h;
  }
  EXPECT_EQ(bad_frame, -1) << "frame_u is not direction turned by frame_turns";
  EXPECT_EQ(bad_sector, -1) << "combed edge sectors inconsistent";

  // Holonomy of the combed rotations around interior vertices = index mod 4; the cut graph
  // ends only at singularities or the boundary (pruned), and singular_vertex matches the field.
  std::vector<int> degree(nv, 0);
  for (int e = 0; e < ne; ++e)
    if (cut.is_cut[e]) ++degree[mesh.from(mesh.edge_halfedge[e])], ++degree[mesh.to(mesh.edge_halfedge[e])];
  int bad_holonomy = -1, bad_leaf = -1, bad_singular = -1;
  for (int v = 0; v < nv; ++v) {
    if (static_cast<bool>(cut.singular_vertex[v]) != (field.vertex_index[v] != 0)) bad_singular = v;
    const bool boundary = is_boundary_vertex(mesh, v);
    if (degree[v] == 1 && !boundary && field.vertex_index[v] == 0) bad_leaf = v;
    if (boundary) continue;
    int holonomy = 0;
    for (int h : outgoing_halfedges(mesh, v)) holonomy += cut.rotation[TriMesh::prev(h)];
    if (((holonomy - field.vertex_index[v]) % 4 + 4) % 4 != 0) bad_holonomy = v;
    // A singular interior vertex must be on the cut (its charts cannot close up around it).
    if (field.vertex_index[v] != 0 && degree[v] == 0) bad_leaf = v;
  }
  EXPECT_EQ(bad_singular, -1) << "singular_vertex differs from vertex_index != 0";
  EXPECT_EQ(bad_holonomy, -1) << "combed holonomy differs from the index";
  EXPECT_EQ(bad_leaf, -1) << "dangling cut branch at a regular interior vertex, or singularity off the cut";

  // One topological disc.
  const DiscTopology t = cut_open_topology(mesh, cut.is_cut);
  EXPECT_TRUE(t.connected);
  EXPECT_EQ(t.euler_characteristic, 1);
  EXPECT_EQ(t.boundary_loops, 1);
}

class CutGraphOverMeshes : public ::testing::TestWithParam<test::FieldCase> {};

TEST_P(CutGraphOverMeshes, OneCombedDiscPerComponent) {
  const test::FieldCase& c = GetParam();
  const IntakeResult intake = test::load_mesh(c.file);
  int cut_edges = 0, edges = 0;
  for (int comp = 0; comp < static_cast<int>(intake.components.size()); ++comp) {
    SCOPED_TRACE(c.file + " component " + std::to_string(comp));
    const TriMesh mesh = test::component_mesh(intake, comp);
    CrossFieldOptions options;
    options.sharp_angle_deg = c.sharp_angle_deg;
    Progress progress;
    const CrossField field = compute_cross_field(mesh, options, progress);
    const CutGraph cut = compute_cut_graph(mesh, field, progress);
    check_cut(mesh, field, cut);
    cut_edges += cut.num_cut_edges;
    edges += mesh.num_edges();
    if (HasFailure()) break;
  }
  std::printf("[ figures  ] %-28s sharp %3.0f  edges %7d  cut edges %6d\n", c.file.c_str(), c.sharp_angle_deg, edges,
              cut_edges);
}

INSTANTIATE_TEST_SUITE_P(SharedMeshes, CutGraphOverMeshes, ::testing::ValuesIn(test::field_cases()), test::case_name);

TEST(CutGraph, TorusWithoutSingularitiesKeepsTwoLoops) {
  const test::SyntheticParametrized torus = test::make_grid_torus(16, 8);
  // The grid directions are an exact field: feed them through features on every u-edge ring.
  CrossFieldOptions options;
  options.feature_edges.assign(torus.mesh.num_edges(), 0);
  for (int h = 0; h < torus.mesh.num_halfedges(); ++h) {
    const Vec2 d = torus.param.corner(h / 3, (h % 3 + 1) % 3) - torus.param.corner(h / 3, h % 3);
    if (d.y() == 0) options.feature_edges[torus.mesh.edge_of[h]] = 1;  // rings of constant v
  }
  Progress progress;
  const CrossField field = compute_cross_field(torus.mesh, options, progress);
  EXPECT_EQ(field.num_singularities, 0);
  const CutGraph cut = compute_cut_graph(torus.mesh, field, progress);
  check_cut(torus.mesh, field, cut);
  // Two generator loops through a common point: every cut vertex has even degree >= 2, and the
  // cut-open disc shows that they are not contractible.
  std::vector<int> degree(torus.mesh.num_vertices(), 0);
  for (int e = 0; e < torus.mesh.num_edges(); ++e)
    if (cut.is_cut[e])
      ++degree[torus.mesh.from(torus.mesh.edge_halfedge[e])], ++degree[torus.mesh.to(torus.mesh.edge_halfedge[e])];
  int branch_points = 0;
  for (int d : degree) {
    EXPECT_NE(d, 1);
    branch_points += d > 2;
  }
  EXPECT_LE(branch_points, 2);
  EXPECT_GE(cut.num_cut_edges, 8 + 4);  // at least the two shortest loops of the 16 x 8 grid
}

TEST(CutGraph, DiscWithoutInteriorSingularitiesNeedsNoCut) {
  const TriMesh grid = test::make_planar_grid(8);
  Progress progress;
  const CrossField field = compute_cross_field(grid, CrossFieldOptions{}, progress);
  const CutGraph cut = compute_cut_graph(grid, field, progress);
  check_cut(grid, field, cut);
  EXPECT_EQ(cut.num_cut_edges, 0);
}

TEST(CutGraph, CubeCutJoinsTheEightCorners) {
  const test::SyntheticParametrized cube = test::make_grid_cube(5);
  CrossFieldOptions options;
  options.sharp_angle_deg = 40;
  Progress progress;
  const CrossField field = compute_cross_field(cube.mesh, options, progress);
  const CutGraph cut = compute_cut_graph(cube.mesh, field, progress);
  check_cut(cube.mesh, field, cut);
  // A tree spanning the 8 corners of a 5-cube along mesh edges needs at least 7 * 5 edges.
  EXPECT_GE(cut.num_cut_edges, 35);
  EXPECT_LE(cut.num_cut_edges, 60);
}

TEST(CutGraph, TinyComponents) {
  const std::vector<TriMesh> meshes = {
      test::make_triangles({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 1, 2}}),
      test::make_triangles({{0, 0, 0}, {1, 0, 0}, {1, 1, 0.3}, {0, 1, 0}}, {{0, 1, 2}, {0, 2, 3}})};
  for (const TriMesh& mesh : meshes) {
    Progress progress;
    const CrossField field = compute_cross_field(mesh, CrossFieldOptions{}, progress);
    const CutGraph cut = compute_cut_graph(mesh, field, progress);
    check_cut(mesh, field, cut);
    EXPECT_EQ(cut.num_cut_edges, 0);
  }
}

TEST(CutGraph, RejectsAFieldOfAnotherMesh) {
  Progress progress;
  const CrossField field = compute_cross_field(test::make_planar_grid(3), CrossFieldOptions{}, progress);
  EXPECT_THROW(compute_cut_graph(test::make_planar_grid(4), field, progress), Error);
}

}  // namespace
}  // namespace qgp

// Mirror symmetry (symmetry/symmetry.h, through the Session): the cut to the positive half on
// generated meshes (every kept point on the positive side, cut points exactly on the plane, the
// half's area exact), the mirror and weld of quads (a doublet dissolved), and symmetric remeshes of
// real meshes: exactly mirror-symmetric, welded on the planes (no boundary there), a valid quad
// mesh with the input's topology where the input is symmetric, the count asked for.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <map>
#include <set>
#include <tuple>

#include "core/error.h"
#include "intake/read_mesh_file.h"
#include "metrics/polygon_metrics.h"
#include "pipeline/layout_lines.h"
#include "pipeline/session.h"
#include "symmetry/symmetry.h"
#include "test_support.h"

namespace qgp {
namespace {

// The generated grid cube [0, n]^3 scaled to [0, 2]^3 and moved by `offset`, as a triangle soup.
PolygonSoup moved_grid_cube(int n, const Vec3& offset) {
  const TriMesh mesh = test::make_grid_cube(n).mesh;
  PolygonSoup soup;
  for (int v = 0; v < mesh.num_vertices(); ++v) soup.positions.push_back(mesh.position(v) * (2.0 / n) + offset);
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const int corners[3] = {mesh.F(f, 0), mesh.F(f, 1), mesh.F(f, 2)};
    soup.add_face(corners, 3);
  }
  return soup;
}

double polygon_area(const PolygonSoup& soup, int f) {
  const int* c = soup.face_vertices.data() + soup.face_start[f];
  Vec3 twice = Vec3::Zero();
  for (int k = 1; k + 1 < soup.face_size(f); ++k)
    twice += (soup.positions[c[k]] - soup.positions[c[0]]).cross(soup.positions[c[k + 1]] - soup.positions[c[0]]);
  return 0.5 * twice.norm();
}

// A cube [0, 2]^3 moved to [-0.7, 1.3] x [-1, 1] x [-1.1, 0.9], in a 6 x 6 grid per side: the planes
// x = 0 and z = 0 cross grid faces. The half keeps exactly the positive parts.
TEST(SymmetryCut, HalfKeepsThePositiveSideWithTheCutOnThePlane) {
  const PolygonSoup cube = moved_grid_cube(6, Vec3(-0.7, -1, -1.1));
  for (const std::string axes_name : {"x", "xz"}) {
    const SymmetryAxes axes = parse_symmetry_axes(axes_name);
    const std::vector<std::array<int, 2>> features = {{cube.face_vertices[0], cube.face_vertices[1]}};
    const HalfSoup half = cut_to_positive_half(cube, features, axes, 1e-9);
    EXPECT_GT(half.cut_faces, 0) << axes_name;
    EXPECT_GT(half.dropped_faces, 0) << axes_name;
    ASSERT_EQ(half.input_face.size(), static_cast<size_t>(half.soup.num_faces()));
    ASSERT_EQ(half.input_vertex.size(), static_cast<size_t>(half.soup.num_vertices()));
    std::vector<char> used(half.soup.num_vertices(), 0);
    for (int v : half.soup.face_vertices) used[v] = 1;
    int on_plane = 0;
    for (int v = 0; v < half.soup.num_vertices(); ++v) {
      EXPECT_TRUE(used[v]) << "unused vertex " << v;
      for (int a = 0; a < 3; ++a)
        if (axes.axis[a]) EXPECT_GE(half.soup.positions[v][a], 0.0);
      if (half.input_vertex[v] < 0) {
        on_plane += 1;
        bool on_a_plane = false;
        for (int a = 0; a < 3; ++a) on_a_plane = on_a_plane || (axes.axis[a] && half.soup.positions[v][a] == 0.0);
        EXPECT_TRUE(on_a_plane) << "cut point " << v << " is not exactly on a plane";
      } else {
        EXPECT_EQ(half.soup.positions[v], cube.positions[half.input_vertex[v]]);
      }
    }
    EXPECT_GT(on_plane, 0);
    double area = 0;
    for (int f = 0; f < half.soup.num_faces(); ++f) {
      area += polygon_area(half.soup, f);
      ASSERT_GE(half.input_face[f], 0);
      ASSERT_LT(half.input_face[f], cube.num_faces());
    }
    // x >= 0: the side x = 1.3 (2 x 2) and four sides 1.3 x 2; with z >= 0 as well: the side
    // x = 1.3 (2 x 0.9), the sides y = -1 and y = 1 (1.3 x 0.9 each) and the top z = 0.9 (1.3 x 2).
    const double expected = axes_name == "x" ? 4 + 4 * 2.6 : 2 * 0.9 + 2 * (1.3 * 0.9) + 1.3 * 2;
    EXPECT_NEAR(area, expected, 1e-9) << axes_name;
    // The feature edge (on the cube's side z = -1.1 or wherever face 0 lies) is kept where positive.
    for (const auto& e : half.feature_edges) {
      EXPECT_GE(e[0], 0);
      EXPECT_LT(e[1], half.soup.num_vertices());
    }
  }
  EXPECT_THROW(parse_symmetry_axes("xx"), Error);
  EXPECT_THROW(parse_symmetry_axes("w"), Error);
  EXPECT_EQ(parse_symmetry_axes("ZX").name(), "xz");
  EXPECT_EQ(parse_symmetry_axes("xyz").copies(), 8);
}

// A half made of a 2 x 1 strip of quads on y >= 0 and a quad whose corner at 180 degrees sits on
// the plane y = 0 (one quad at a straight boundary): mirrored, the strip welds along y = 0 and the
// lone corner's two quads (sharing two edges) become one.
TEST(SymmetryMirror, WeldsOnThePlaneAndDissolvesDoublets) {
  Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> V(9, 3);
  V << 0, 0, 0, 1, 0, 0, 2, 0, 0, 0, 1, 0, 1, 1, 0, 2, 1, 0,  // the strip
      4, 0, 0, 5, 0, 0, 3, 0, 0;                              // the lone corner's plane vertices
  V.conservativeResize(10, 3);
  V.row(9) << 4, 1, 0;
  Eigen::Matrix<int, Eigen::Dynamic, 4, Eigen::RowMajor> Q(3, 4);
  Q << 0, 1, 4, 3, 1, 2, 5, 4,  // strip, counter-clockwise seen from +z
      6, 7, 9, 8;               // corner 6 at 180 degrees between 7 (x = 5) and 8 (x = 3)
  std::vector<int> origin;
  const MirrorStats stats = mirror_across_planes<4>(V, Q, parse_symmetry_axes("y"), 1e-9, origin);
  EXPECT_EQ(stats.welded_vertices, 6);
  EXPECT_EQ(stats.dissolved_doublets, 1);
  EXPECT_EQ(stats.open_edges_on_plane, 0);
  ASSERT_EQ(Q.rows(), 5);          // 2 strip quads, their 2 images, 1 merged
  EXPECT_EQ(V.rows(), 6 + 3 + 4);  // the strip, its 3 images off the plane; 7, 8, 9 and 9's image
  ASSERT_EQ(origin.size(), 5u);
  // Every vertex's mirror image is a vertex; every edge is shared by two quads or is a boundary
  // edge off the plane.
  std::set<std::array<double, 3>> points;
  for (int v = 0; v < V.rows(); ++v) points.insert({V(v, 0), V(v, 1), V(v, 2)});
  for (int v = 0; v < V.rows(); ++v) EXPECT_TRUE(points.count({V(v, 0), -V(v, 1), V(v, 2)})) << v;
  std::map<std::pair<int, int>, int> directed;
  for (int q = 0; q < Q.rows(); ++q) {
    const Vec3 n = (V.row(Q(q, 2)) - V.row(Q(q, 0))).transpose().cross((V.row(Q(q, 3)) - V.row(Q(q, 1))).transpose());
    EXPECT_GT(n.z(), 0) << "quad " << q << " faces down";
    for (int k = 0; k < 4; ++k) ++directed[{Q(q, k), Q(q, (k + 1) % 4)}];
  }
  for (const auto& [edge, count] : directed) {
    EXPECT_EQ(count, 1) << "edge used twice in one direction";
    if (!directed.count({edge.second, edge.first}))
      EXPECT_FALSE(V(edge.first, 1) == 0 && V(edge.second, 1) == 0) << "open edge on the plane";
  }
}

struct SymmetricRun {
  std::string mesh;
  std::string axes;
  double sharp_angle;
  bool input_symmetric;  // mirror-symmetric about those planes (then the topology is the input's)
};

// Exact mirror symmetry of the quads about each plane asked: every vertex's image is a vertex.
int vertices_without_mirror_image(const QuadMesh& quads, const SymmetryAxes& axes) {
  std::set<std::array<double, 3>> points;
  for (int v = 0; v < quads.num_vertices(); ++v) points.insert({quads.V(v, 0), quads.V(v, 1), quads.V(v, 2)});
  int missing = 0;
  for (int a = 0; a < 3; ++a) {
    if (!axes.axis[a]) continue;
    for (int v = 0; v < quads.num_vertices(); ++v) {
      std::array<double, 3> image = {quads.V(v, 0), quads.V(v, 1), quads.V(v, 2)};
      image[a] = -image[a];
      missing += points.count(image) == 0;
    }
  }
  return missing;
}

void expect_symmetric_remesh(const SymmetricRun& run, double target) {
  const std::string name = run.mesh + " " + run.axes + "@" + std::to_string(static_cast<int>(target));
  const PolygonSoup input = read_mesh_file(test::mesh_path(run.mesh));
  Session session(input);
  RemeshOptions options;
  options.target_faces = target;
  options.sharp_angle_deg = run.sharp_angle;
  options.symmetry = parse_symmetry_axes(run.axes);
  session.set_options(options);
  Progress progress;
  ASSERT_NO_THROW(session.run(Job::Remesh, progress)) << name << ": " << session.report().dump();
  const QuadMesh& quads = *session.quad_result();
  const Json& report = session.report();
  EXPECT_EQ(vertices_without_mirror_image(quads, options.symmetry), 0) << name;
  EXPECT_EQ(report["symmetry"]["open_edges_on_plane"], 0) << name;
  EXPECT_GT(report["symmetry"]["welded_vertices"].get<int>(), 0) << name;
  EXPECT_EQ(quads.num_quads(), report["quantization"]["quads_expected"].get<int>()) << name;
  const double quads_made = quads.num_quads();
  EXPECT_TRUE(std::abs(quads_made - target) <= 0.05 * target || report["quantization"]["count"].contains("note"))
      << name << ": " << quads_made;
  ASSERT_EQ(session.quad_source_face().size(), static_cast<size_t>(quads.num_quads()));
  for (int f : session.quad_source_face()) ASSERT_TRUE(f >= 0 && f < input.num_faces()) << name;
  // A valid quad mesh (measured against the whole input).
  const IntakeResult whole = test::load_mesh(run.mesh);
  const PolygonMeshMetrics m = measure_polygon_mesh(test::polygon_soup(quads), whole.mesh, run.sharp_angle, progress);
  EXPECT_EQ(m.non_quads, 0) << name;
  EXPECT_EQ(m.non_manifold_edges, 0) << name;
  EXPECT_EQ(m.quad.topology.inconsistent_edges, 0) << name;
  EXPECT_EQ(m.quad.topology.degenerate_quads, 0) << name;
  EXPECT_EQ(m.quad.topology.unreferenced_vertices, 0) << name;
  EXPECT_EQ(report["quad"]["flipped_quads"], 0) << name;
  std::cout << name << ": " << quads.num_quads() << " quads, " << report["symmetry"]["welded_vertices"]
            << " vertices welded, " << report["symmetry"]["dissolved_doublets"] << " doublets dissolved, Hausdorff "
            << m.quad.hausdorff << ", " << report["timings_s"]["total"] << " s\n";
  if (!run.input_symmetric) return;
  EXPECT_EQ(m.quad.flipped_quads(), 0) << name;
  EXPECT_EQ(m.euler_characteristic, m.reference_euler_characteristic) << name;
  EXPECT_LT(m.quad.hausdorff, 0.05) << name;  // as the plain remesh's sweep asks, coarse or fine
  if (run.sharp_angle > 0) EXPECT_GT(m.sharp_edge_coverage, 0.95) << name;
}

// Symmetric inputs (the planes through their origin: spot, beetle, camelhead and wingnut's x, the
// block's and the torus's three), one with a boundary (camelhead) and CAD parts with sharp edges;
// and inputs that are not symmetric (the bunny, the joint): their positive halves mirrored.
TEST(SymmetryMeshes, SymmetricQuadsWeldedOnThePlanes) {
  const std::vector<SymmetricRun> runs = {
      {"spot.obj", "x", -1, true},    {"block.obj", "xyz", 40, true},         {"torus.obj", "xyz", -1, true},
      {"beetle.off", "x", -1, true},  {"camelhead.off", "x", -1, true},       {"wingnut.obj", "x", 40, true},
      {"joint.obj", "xz", 40, false}, {"stanford-bunny.obj", "x", -1, false}, {"fandisk.obj", "x", 40, false},
  };
  for (const SymmetricRun& run : runs)
    for (double target : {500.0, 2000.0}) expect_symmetric_remesh(run, target);
}

// Symmetry is for quads: a grid-UV job refuses it by name; a plane with nothing on its positive side
// is refused by name; symmetry off again gives the plain remesh.
TEST(SymmetrySession, RefusalsNameTheCauseAndTurningItOffRestores) {
  Session session(read_mesh_file(test::mesh_path("fandisk.obj")));
  RemeshOptions options;
  options.target_faces = 500;
  options.symmetry = parse_symmetry_axes("z");
  try {
    session.set_options(options);
    FAIL() << "fandisk lies on the negative side of z = 0";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::InvalidArgument);
    EXPECT_NE(std::string(e.what()).find("positive side of z = 0"), std::string::npos) << e.what();
  }
  options.symmetry = parse_symmetry_axes("x");
  session.set_options(options);
  Progress progress;
  try {
    session.run(Job::GridUV, progress);
    FAIL() << "grid UVs with symmetry";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::InvalidArgument);
    EXPECT_NE(std::string(e.what()).find("symmetry applies to quad remeshing"), std::string::npos) << e.what();
  }
  session.run(Job::Remesh, progress);
  EXPECT_TRUE(session.report().contains("symmetry"));
  // The layout shown (Show Layout) is mirrored like the quads: every point's image is a point.
  const LayoutLines lines = compose_layout_lines(session);
  ASSERT_GT(lines.segments.size(), 0u);
  EXPECT_EQ(lines.segments.size() % 2, 0u);
  std::set<std::array<double, 3>> points;
  for (const Vec3& p : lines.points) points.insert({p.x(), p.y(), p.z()});
  for (const Vec3& p : lines.points) EXPECT_TRUE(points.count({-p.x(), p.y(), p.z()}));
  options.symmetry = SymmetryAxes();
  session.set_options(options);
  session.run(Job::Remesh, progress);
  EXPECT_FALSE(session.report().contains("symmetry"));
  const IntakeResult whole = test::load_mesh("fandisk.obj");
  EXPECT_EQ(session.intake()->mesh.num_faces(), whole.mesh.num_faces());
}

}  // namespace
}  // namespace qgp

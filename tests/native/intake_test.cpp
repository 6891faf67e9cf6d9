// Intake over the whole shared mesh set: classification as in the meshes' README, repairs
// reported, broken meshes refused with clear messages, plus focused repair cases.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <vector>

#include "core/error.h"
#include "intake/intake.h"
#include "intake/read_mesh_file.h"
#include "test_support.h"

namespace qgp {
namespace {

struct Expected {
  int components;
  std::vector<int> genus;           // per component (empty: not checked)
  std::vector<int> boundary_loops;  // per component (empty: not checked)
};

// From ../shared/meshes/README.md (manifold meshes; genus and boundary loops per component).
const std::map<std::string, Expected>& expected_table() {
  static const std::map<std::string, Expected> table = {
      {"spot.obj", {1, {0}, {0}}},
      {"bunny.off", {1, {0}, {0}}},
      {"armadillo.obj", {1, {0}, {0}}},
      {"nefertiti.obj", {1, {0}, {0}}},
      {"igea.ply", {1, {0}, {0}}},
      {"dragon-genus1.obj", {1, {1}, {0}}},
      {"torus.obj", {1, {1}, {0}}},
      {"rocker-arm.obj", {1, {1}, {0}}},
      {"kitten.obj", {1, {1}, {0}}},
      {"fertility.off", {1, {4}, {0}}},
      {"mnf07HeadFem_rem_rem_p.obj", {1, {9}, {0}}},
      {"fandisk.obj", {1, {0}, {0}}},
      {"block.obj", {1, {3}, {0}}},
      {"joint.obj", {1, {2}, {0}}},
      {"joint_rem_p.obj", {1, {2}, {0}}},
      {"wingnut.obj", {1, {0}, {0}}},
      {"stanford-bunny.obj", {1, {0}, {5}}},
      {"face.obj", {1, {0}, {1}}},
      {"camelhead.off", {1, {0}, {1}}},
      {"decimated-max.obj", {1, {0}, {0}}},
      {"beetle.off", {1, {0}, {11}}},
      {"cow.obj", {1, {0}, {0}}},
      {"featuretype.ply", {1, {}, {}}},  // 852 parts in the README: the faces are not welded
  };
  return table;
}

int repair_count(const IntakeResult& r, const std::string& kind) {
  for (const Repair& rep : r.repairs)
    if (rep.kind == kind) return rep.count;
  return 0;
}

class IntakeOverMeshes : public ::testing::TestWithParam<std::string> {};

TEST_P(IntakeOverMeshes, ClassifiesOrRefusesClearly) {
  const std::string name = GetParam();
  Progress progress;
  PolygonSoup soup = read_mesh_file(test::mesh_path(name));
  if (name == "truck.obj" || name == "cycloidal.ply") {  // non-manifold edges: cut by default
    IntakeOptions refuse;
    refuse.refuse_non_manifold = true;
    try {
      run_intake(soup, refuse, progress);
      FAIL() << name << " has non-manifold edges and must be refused with refuse_non_manifold";
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::InvalidMesh);
      EXPECT_NE(std::string(e.what()).find("non-manifold edge"), std::string::npos) << e.what();
    }
    refuse.drop_bad_components = true;
    const IntakeResult kept = run_intake(soup, refuse, progress);
    EXPECT_GT(repair_count(kept, "dropped_nonmanifold_components"), 0);
    EXPECT_FALSE(kept.warnings.empty());
    EXPECT_GT(repair_count(run_intake(soup, IntakeOptions{}, progress), "cut_nonmanifold_edges"), 0);
  }
  const IntakeResult r = run_intake(soup, IntakeOptions{}, progress);
  // Invariants of every accepted mesh: manifold, oriented, consistent Euler characteristic.
  int faces = 0;
  for (const ComponentInfo& c : r.components) {
    faces += c.num_faces;
    EXPECT_EQ(c.euler_characteristic, 2 - 2 * c.genus - c.boundary_loops);
    EXPECT_GE(c.genus, 0);
  }
  EXPECT_EQ(faces, r.mesh.num_faces());
  for (int h = 0; h < r.mesh.num_halfedges(); ++h) {
    const int o = r.mesh.opposite[h];
    if (o >= 0) EXPECT_EQ(r.mesh.from(h), r.mesh.to(o));
  }
  auto it = expected_table().find(name);
  if (it == expected_table().end()) return;
  const Expected& e = it->second;
  ASSERT_EQ(static_cast<int>(r.components.size()), e.components) << name;
  for (size_t c = 0; c < e.genus.size(); ++c) EXPECT_EQ(r.components[c].genus, e.genus[c]) << name;
  for (size_t c = 0; c < e.boundary_loops.size(); ++c)
    EXPECT_EQ(r.components[c].boundary_loops, e.boundary_loops[c]) << name;
}

INSTANTIATE_TEST_SUITE_P(SharedMeshes, IntakeOverMeshes, ::testing::ValuesIn(test::all_mesh_files()),
                         [](const auto& info) { return test::identifier(info.param); });

// Triangles of the file that are degenerate by IntakeOptions' definition (area <= zero_area * diag^2,
// or height below flatness times the longest edge), counted here from the raw soup.
int degenerate_triangles_in_file(const std::string& name) {
  const PolygonSoup soup = read_mesh_file(test::mesh_path(name));
  Vec3 lo = Vec3::Constant(INFINITY), hi = Vec3::Constant(-INFINITY);
  for (const Vec3& p : soup.positions) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  const double diag2 = (hi - lo).squaredNorm();
  const IntakeOptions defaults;
  int n = 0;
  for (int f = 0; f < soup.num_faces(); ++f) {
    EXPECT_EQ(soup.face_size(f), 3) << name;
    const Vec3 p[3] = {soup.positions[soup.face_vertices[soup.face_start[f]]],
                       soup.positions[soup.face_vertices[soup.face_start[f] + 1]],
                       soup.positions[soup.face_vertices[soup.face_start[f] + 2]]};
    const double area = 0.5 * (p[1] - p[0]).cross(p[2] - p[0]).norm();
    double longest2 = 0;
    for (int k = 0; k < 3; ++k) longest2 = std::max(longest2, (p[(k + 1) % 3] - p[k]).squaredNorm());
    n += area <= defaults.zero_area * diag2 || 2 * area <= defaults.flatness * longest2;
  }
  return n;
}

// Counts from the meshes' README (measured by whoever curated them) and, for degenerate faces,
// from the file itself: every degenerate triangle is repaired, one repair each.
TEST(Intake, SpecificRepairs) {
  EXPECT_EQ(repair_count(test::load_mesh("cow.obj"), "nonmanifold_vertices"), 1);
  EXPECT_EQ(repair_count(test::load_mesh("stanford-bunny.obj"), "unreferenced_vertices"), 1113);
  // teapot: 403 duplicate positions (welded: 4 parts as in the README); unwelded, 38 non-manifold
  // vertices.
  const IntakeResult teapot = test::load_mesh("teapot.obj");
  EXPECT_EQ(repair_count(teapot, "welded_vertices"), 403);
  EXPECT_EQ(teapot.components.size(), 4u);
  IntakeOptions no_weld;
  no_weld.weld_tolerance = 0;
  Progress progress;
  const IntakeResult unwelded = run_intake(read_mesh_file(test::mesh_path("teapot.obj")), no_weld, progress);
  EXPECT_EQ(repair_count(unwelded, "nonmanifold_vertices"), 38);
  EXPECT_EQ(repair_count(unwelded, "welded_vertices"), 0);
  for (const char* name : {"block.obj", "ogre.obj"}) {
    const int degenerate = degenerate_triangles_in_file(name);
    EXPECT_GT(degenerate, 0) << name;
    EXPECT_EQ(repair_count(test::load_mesh(name), "zero_area_faces"), degenerate) << name;
  }
}

TEST(Intake, ReadsPlyTriangleStrips) {
  // igea.ply stores its faces as one triangle strip; all 268,686 triangles must come back.
  const PolygonSoup soup = read_mesh_file(test::mesh_path("igea.ply"));
  EXPECT_EQ(soup.num_vertices(), 134345);
  EXPECT_EQ(soup.num_faces(), 268686);
}

PolygonSoup quad_soup() {  // two triangles forming a square
  PolygonSoup s;
  s.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  const int f0[3] = {0, 1, 2}, f1[3] = {0, 2, 3};
  s.add_face(f0, 3);
  s.add_face(f1, 3);
  return s;
}

ErrorCode intake_error(const PolygonSoup& soup, std::string* message = nullptr) {
  Progress progress;
  try {
    run_intake(soup, IntakeOptions{}, progress);
  } catch (const Error& e) {
    if (message) *message = e.what();
    return e.code();
  }
  return ErrorCode::Internal;  // means: no error
}

TEST(Intake, RejectsBadInputWithClearMessages) {
  std::string msg;
  PolygonSoup nan = quad_soup();
  nan.positions[2].y() = std::nan("");
  EXPECT_EQ(intake_error(nan, &msg), ErrorCode::InvalidMesh);
  EXPECT_NE(msg.find("vertex 2"), std::string::npos) << msg;

  PolygonSoup range = quad_soup();
  range.face_vertices[4] = 9;
  EXPECT_EQ(intake_error(range, &msg), ErrorCode::InvalidMesh);
  EXPECT_NE(msg.find("refers to vertex 9"), std::string::npos) << msg;

  PolygonSoup repeated = quad_soup();
  repeated.face_vertices[1] = 0;
  EXPECT_EQ(intake_error(repeated, &msg), ErrorCode::InvalidMesh);
  EXPECT_NE(msg.find("repeats vertex 0"), std::string::npos) << msg;

  EXPECT_EQ(intake_error(PolygonSoup{}, &msg), ErrorCode::InvalidMesh);
  EXPECT_NE(msg.find("no faces"), std::string::npos) << msg;
}

TEST(Intake, RepairsOrientationDuplicatesAndPolygons) {
  PolygonSoup s;
  s.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {2, 0, 0}, {2, 1, 0}, {5, 5, 5}};
  const int a[4] = {0, 1, 2, 3};  // a quad
  const int b[3] = {1, 2, 4};     // inconsistently oriented w.r.t. the quad
  const int c[3] = {2, 4, 5};     // wait: consistent with b
  const int d[3] = {4, 2, 1};     // duplicate of b (other orientation)
  s.add_face(a, 4);
  s.add_face(b, 3);
  s.add_face(c, 3);
  s.add_face(d, 3);
  Progress progress;
  const IntakeResult r = run_intake(s, IntakeOptions{}, progress);
  EXPECT_EQ(repair_count(r, "triangulated_polygons"), 1);
  EXPECT_EQ(repair_count(r, "duplicate_faces"), 1);
  EXPECT_EQ(repair_count(r, "unreferenced_vertices"), 1);
  EXPECT_GE(repair_count(r, "inconsistent_orientation"), 1);
  EXPECT_EQ(r.mesh.num_faces(), 4);
  ASSERT_EQ(r.components.size(), 1u);
  EXPECT_EQ(r.components[0].boundary_loops, 1);
}

TEST(Intake, TriangulationAvoidsDiagonalsThatAreEdges) {
  // A square whose 0-2 diagonal is already an edge of two other triangles: splitting the square
  // along 0-2 would make that edge non-manifold, so 1-3 must be used even though 0-2 is better.
  PolygonSoup s;
  s.positions = {{0, 0, 0}, {1, 0, 0}, {2, 2, 0}, {0, 1, 0}, {1, 1, 1}, {1, 1, -1}};
  const int quad[4] = {0, 1, 2, 3}, t0[3] = {0, 2, 4}, t1[3] = {2, 0, 5};
  s.add_face(quad, 4);
  s.add_face(t0, 3);
  s.add_face(t1, 3);
  Progress progress;
  const IntakeResult r = run_intake(s, IntakeOptions{}, progress);
  EXPECT_EQ(repair_count(r, "triangulated_polygons"), 1);
  EXPECT_EQ(r.mesh.num_faces(), 4);
}

TEST(Intake, RefusesNonOrientableMoebiusStrip) {
  PolygonSoup s = test::moebius_strip();
  std::string msg;
  EXPECT_EQ(intake_error(s, &msg), ErrorCode::InvalidMesh);
  EXPECT_NE(msg.find("non-orientable"), std::string::npos) << msg;
}

// Zero-area is judged against each part's own size: a tetrahedron a millionth the size of another
// keeps its four faces (it used to collapse, judged against the whole mesh's diagonal).
TEST(Intake, TinyPartKeepsItsFaces) {
  PolygonSoup s;
  const int faces[4][3] = {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {0, 3, 2}};
  for (const double size : {1e-6, 1.0}) {
    const int base = s.num_vertices();
    const Vec3 at(size < 1 ? 0.0 : 5.0, 0, 0);
    for (const Vec3& p : {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)})
      s.positions.push_back(at + size * p);
    for (const auto& f : faces) {
      const int t[3] = {base + f[0], base + f[1], base + f[2]};
      s.add_face(t, 3);
    }
  }
  Progress progress;
  const IntakeResult r = run_intake(s, IntakeOptions{}, progress);
  EXPECT_EQ(repair_count(r, "zero_area_faces"), 0);
  ASSERT_EQ(r.components.size(), 2u);
  EXPECT_EQ(r.mesh.num_faces(), 8);
  for (const ComponentInfo& c : r.components) EXPECT_EQ(c.euler_characteristic, 2);
}

TEST(Intake, UnreadableFilesAreNamed) {
  try {
    read_mesh_file("/nonexistent/mesh.obj");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::UnreadableFile);
  }
  try {
    read_mesh_file(test::mesh_path("README.md"));
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::UnreadableFile);
    EXPECT_NE(std::string(e.what()).find("unsupported extension"), std::string::npos);
  }
}

TEST(Intake, MapsFeatureEdgesThroughRepairs) {
  const IntakeResult r = test::load_mesh("stanford-bunny.obj");  // 1113 unreferenced vertices removed
  const TriMesh& m = r.mesh;
  std::vector<std::array<int, 2>> pairs;
  for (int e = 0; e < 50; ++e) {
    const int h = m.edge_halfedge[e];
    pairs.push_back({r.input_vertex[m.from(h)], r.input_vertex[m.to(h)]});
  }
  pairs.push_back({0, 1});  // most likely not an edge
  int unmatched = 0;
  const auto marked = map_input_edges(r, pairs, &unmatched);
  for (int e = 0; e < 50; ++e) EXPECT_TRUE(marked[e]);
  EXPECT_LE(unmatched, 1);
}

// ---- Welding and non-manifold edges (issue 23) ----

// Every triangle of the mesh with its own three vertices (as exporters write meshes split at UV
// seams or hard normals); each position moved by up to `jitter` per coordinate.
PolygonSoup unwelded_soup(const TriMesh& mesh, double jitter = 0) {
  PolygonSoup s;
  unsigned state = 12345;
  auto noise = [&] {
    state = state * 1103515245u + 12345u;
    return jitter * ((state >> 8) / double(1u << 24) * 2 - 1);
  };
  for (int f = 0; f < mesh.num_faces(); ++f) {
    int corners[3];
    for (int k = 0; k < 3; ++k) {
      corners[k] = s.num_vertices();
      s.positions.push_back(mesh.V.row(mesh.F(f, k)).transpose() + Vec3(noise(), noise(), noise()));
    }
    s.add_face(corners, 3);
  }
  return s;
}

IntakeResult intake_with(const PolygonSoup& soup, const IntakeOptions& options) {
  Progress progress;
  return run_intake(soup, options, progress);
}

const Repair* find_repair(const IntakeResult& r, const std::string& kind) {
  for (const Repair& rep : r.repairs)
    if (rep.kind == kind) return &rep;
  return nullptr;
}

TEST(IntakeWeld, UnweldedSoupBecomesTheOriginalMeshAgain) {
  const IntakeResult original = test::load_mesh("torus.obj");
  ASSERT_EQ(original.components.size(), 1u);
  const double diag = (original.mesh.V.colwise().maxCoeff() - original.mesh.V.colwise().minCoeff()).norm();
  for (double jitter : {0.0, 1e-8 * diag}) {  // exact duplicates, and within the 1e-6 tolerance
    const PolygonSoup soup = unwelded_soup(original.mesh, jitter);
    const IntakeResult r = intake_with(soup, IntakeOptions{});
    EXPECT_EQ(r.mesh.num_vertices(), original.mesh.num_vertices()) << jitter;
    EXPECT_EQ(r.mesh.num_faces(), original.mesh.num_faces()) << jitter;
    ASSERT_EQ(r.components.size(), 1u) << jitter;
    EXPECT_EQ(r.components[0].euler_characteristic, original.components[0].euler_characteristic);
    EXPECT_EQ(r.components[0].genus, 1);
    EXPECT_EQ(r.components[0].boundary_loops, 0);
    const Repair* weld = find_repair(r, "welded_vertices");
    ASSERT_NE(weld, nullptr);
    EXPECT_EQ(weld->count, soup.num_vertices() - original.mesh.num_vertices());
    EXPECT_EQ(weld->input_vertices.size(), 10u);
    EXPECT_EQ(find_repair(r, "cut_nonmanifold_edges"), nullptr);
    // Input vertices welded away stand for the vertex they were merged into.
    for (int v = 0; v < soup.num_vertices(); ++v)
      EXPECT_EQ((soup.positions[v] - soup.positions[r.weld_target[v]]).norm() <= 1e-6 * diag, true);
  }
}

TEST(IntakeWeld, FacesCollapsedByTheWeldAreDropped) {
  // The torus soup plus a sliver along the first triangle's side p0-p1 whose third corner is within
  // the tolerance of p0: welding makes it (p0, p0, p1), which is dropped and counted.
  const IntakeResult original = test::load_mesh("torus.obj");
  PolygonSoup soup = unwelded_soup(original.mesh);
  const double diag = (original.mesh.V.colwise().maxCoeff() - original.mesh.V.colwise().minCoeff()).norm();
  const int n = soup.num_vertices();
  soup.positions.push_back(soup.positions[0]);
  soup.positions.push_back(soup.positions[0] + Vec3(1e-8 * diag, 0, 0));
  soup.positions.push_back(soup.positions[1]);
  const int sliver[3] = {n, n + 2, n + 1};
  soup.add_face(sliver, 3);
  const IntakeResult r = intake_with(soup, IntakeOptions{});
  EXPECT_EQ(repair_count(r, "collapsed_faces"), 1);
  ASSERT_NE(find_repair(r, "collapsed_faces"), nullptr);
  EXPECT_EQ(find_repair(r, "collapsed_faces")->input_vertices.size(), 1u);
  EXPECT_EQ(r.mesh.num_vertices(), original.mesh.num_vertices());
  EXPECT_EQ(r.mesh.num_faces(), original.mesh.num_faces());
  ASSERT_EQ(r.components.size(), 1u);
  EXPECT_EQ(r.components[0].genus, 1);
}

TEST(IntakeWeld, FeatureEdgesOfWeldedCopiesAreFound) {
  const IntakeResult original = test::load_mesh("spot.obj");
  const PolygonSoup soup = unwelded_soup(original.mesh);
  const IntakeResult r = intake_with(soup, IntakeOptions{});
  std::vector<std::array<int, 2>> pairs;  // the first side of every input triangle (its own copies)
  for (int f = 0; f < soup.num_faces(); f += 97) pairs.push_back({3 * f, 3 * f + 1});
  int unmatched = -1;
  const std::vector<char> marked = map_input_edges(r, pairs, &unmatched);
  EXPECT_EQ(unmatched, 0);
  EXPECT_GE(std::count(marked.begin(), marked.end(), 1), static_cast<long>(pairs.size()) / 2);
}

TEST(IntakeWeld, ToleranceZeroKeepsTheSoupApart) {
  const IntakeResult original = test::load_mesh("torus.obj");
  const PolygonSoup soup = unwelded_soup(original.mesh);
  IntakeOptions off;
  off.weld_tolerance = 0;
  const IntakeResult r = intake_with(soup, off);
  EXPECT_EQ(r.mesh.num_vertices(), soup.num_vertices());
  EXPECT_EQ(static_cast<int>(r.components.size()), soup.num_faces());
  EXPECT_EQ(find_repair(r, "welded_vertices"), nullptr);
  // Positions farther apart than the tolerance are not welded either.
  const double diag = (original.mesh.V.colwise().maxCoeff() - original.mesh.V.colwise().minCoeff()).norm();
  const IntakeResult apart = intake_with(unwelded_soup(original.mesh, 1e-3 * diag), IntakeOptions{});
  EXPECT_GT(static_cast<int>(apart.components.size()), soup.num_faces() / 2);
}

TEST(IntakeWeld, CleanMeshesAreUnchanged) {
  IntakeOptions off;
  off.weld_tolerance = 0;
  for (const std::string& name : test::manifold_mesh_files()) {
    const PolygonSoup soup = read_mesh_file(test::mesh_path(name));
    const IntakeResult welded = intake_with(soup, IntakeOptions{}), plain = intake_with(soup, off);
    EXPECT_EQ(find_repair(welded, "welded_vertices"), nullptr) << name;
    EXPECT_TRUE(welded.mesh.V == plain.mesh.V) << name;
    EXPECT_TRUE(welded.mesh.F == plain.mesh.F) << name;
    EXPECT_EQ(welded.input_vertex, plain.input_vertex) << name;
  }
}

// Appends a polygon given by positions, reusing vertices at exactly the same position.
void add_polygon(PolygonSoup& s, std::map<std::array<double, 3>, int>& index, const std::vector<Vec3>& corners) {
  std::vector<int> ids;
  for (const Vec3& p : corners) {
    auto it = index.emplace(std::array<double, 3>{p.x(), p.y(), p.z()}, s.num_vertices()).first;
    if (it->second == s.num_vertices()) s.positions.push_back(p);
    ids.push_back(it->second);
  }
  s.add_face(ids.data(), static_cast<int>(ids.size()));
}

// Box at `origin` with the given side lengths, as six outward-oriented quads.
void add_cube(PolygonSoup& s, std::map<std::array<double, 3>, int>& index, const Vec3& origin,
              const Vec3& size = Vec3(1, 1, 1)) {
  static const int sides[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& side : sides) {
    std::vector<Vec3> corners;
    for (int c : side) corners.push_back(origin + Vec3(c & 1, (c >> 1) & 1, (c >> 2) & 1).cwiseProduct(size));
    add_polygon(s, index, corners);
  }
}

TEST(IntakeCut, TwoCubesSharingAnEdgeBecomeTwoClosedSheets) {
  PolygonSoup s;
  std::map<std::array<double, 3>, int> index;
  add_cube(s, index, Vec3(0, 0, 0));
  add_cube(s, index, Vec3(1, 1, 0));  // shares the edge x = y = 1
  ASSERT_EQ(s.num_vertices(), 14);
  const IntakeResult r = intake_with(s, IntakeOptions{});
  EXPECT_EQ(repair_count(r, "cut_nonmanifold_edges"), 1);
  EXPECT_EQ(repair_count(r, "inconsistent_orientation"), 0);
  EXPECT_EQ(r.mesh.num_vertices(), 16);
  ASSERT_EQ(r.components.size(), 2u);
  for (const ComponentInfo& c : r.components) {
    EXPECT_EQ(c.num_faces, 12);
    EXPECT_TRUE(c.closed());
    EXPECT_EQ(c.genus, 0);
  }
  const Repair* cut = find_repair(r, "cut_nonmanifold_edges");
  ASSERT_NE(cut, nullptr);
  ASSERT_EQ(cut->input_vertices.size(), 1u);
  EXPECT_EQ(s.positions[cut->input_vertices[0]].head<2>(), Vec2(1, 1));

  IntakeOptions refuse;
  refuse.refuse_non_manifold = true;
  Progress progress;
  try {
    run_intake(s, refuse, progress);
    FAIL() << "refuse_non_manifold must refuse the shared edge";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::InvalidMesh);
    EXPECT_NE(std::string(e.what()).find("non-manifold edge"), std::string::npos) << e.what();
  }
}

TEST(IntakeCut, InsideOutCubesSharingAnEdgeStillGiveAManifold) {
  // One or both cubes inside out: around the shared edge the preferred pairing no longer bounds the
  // two solids (both inside out: it bounds the outside, and the two sheets meet again around the
  // edge's ends, where the extra triangles are detached). Intake still ends edge-manifold (it
  // throws Internal otherwise) with every face kept.
  for (int first_inverted : {6, 0}) {
    PolygonSoup s;
    std::map<std::array<double, 3>, int> index;
    add_cube(s, index, Vec3(0, 0, 0));
    add_cube(s, index, Vec3(1, 1, 0));
    for (int f = first_inverted; f < 12; ++f)
      std::reverse(&s.face_vertices[s.face_start[f]], &s.face_vertices[s.face_start[f + 1]]);
    const IntakeResult r = intake_with(s, IntakeOptions{});
    EXPECT_EQ(repair_count(r, "cut_nonmanifold_edges"), 1);
    EXPECT_EQ(r.mesh.num_faces(), 24);
    int faces = 0;
    for (const ComponentInfo& c : r.components) {
      faces += c.num_faces;
      EXPECT_EQ(c.euler_characteristic, 2 - 2 * c.genus - c.boundary_loops);
    }
    EXPECT_EQ(faces, 24);
  }
}

TEST(IntakeCut, BoxesTouchingAlongAPlaneStaySeparateSolids) {
  // The unit cube and the box [-1,1] x [1,2] x [0,1] touch along the plane y = 1 and share the edge
  // x = y = 1: two of its four faces lie at the same angle around it (as 200 of cycloidal's 242
  // non-manifold edges); the face ending one solid goes before the face starting the other.
  PolygonSoup s;
  std::map<std::array<double, 3>, int> index;
  add_cube(s, index, Vec3(0, 0, 0));
  add_cube(s, index, Vec3(-1, 1, 0), Vec3(2, 1, 1));
  ASSERT_EQ(s.num_vertices(), 14);
  const IntakeResult r = intake_with(s, IntakeOptions{});
  EXPECT_EQ(repair_count(r, "cut_nonmanifold_edges"), 1);
  EXPECT_EQ(repair_count(r, "inconsistent_orientation"), 0);
  ASSERT_EQ(r.components.size(), 2u);
  for (const ComponentInfo& c : r.components) {
    EXPECT_EQ(c.num_faces, 12);
    EXPECT_TRUE(c.closed());
    EXPECT_EQ(c.genus, 0);
  }
}

TEST(IntakeCut, BookWithThreePagesKeepsOnePairAndOneLoosePage) {
  PolygonSoup s;
  std::map<std::array<double, 3>, int> index;
  for (int page = 0; page < 3; ++page) {
    const double a = 2 * M_PI * page / 3;
    const Vec3 out(std::cos(a), std::sin(a), 0);
    add_polygon(s, index, {Vec3(0, 0, 0), out, out + Vec3(0, 0, 1), Vec3(0, 0, 1)});
  }
  ASSERT_EQ(s.num_vertices(), 8);
  const IntakeResult r = intake_with(s, IntakeOptions{});  // build_connectivity: edge-manifold
  EXPECT_EQ(repair_count(r, "cut_nonmanifold_edges"), 1);
  EXPECT_EQ(r.mesh.num_faces(), 6);
  EXPECT_EQ(r.mesh.num_vertices(), 10);
  ASSERT_EQ(r.components.size(), 2u);
  std::vector<int> faces = {r.components[0].num_faces, r.components[1].num_faces};
  std::sort(faces.begin(), faces.end());
  EXPECT_EQ(faces, (std::vector<int>{2, 4}));
  for (const ComponentInfo& c : r.components) EXPECT_EQ(c.boundary_loops, 1);
}

TEST(IntakeCut, MoebiusSoupIsWeldedThenRefusedOrDropped) {
  PolygonSoup strip = test::moebius_strip();
  TriMesh m;
  m.V.resize(strip.num_vertices(), 3);
  for (int v = 0; v < strip.num_vertices(); ++v) m.V.row(v) = strip.positions[v].transpose();
  m.F.resize(strip.num_faces(), 3);
  for (int f = 0; f < strip.num_faces(); ++f)
    for (int k = 0; k < 3; ++k) m.F(f, k) = strip.face_vertices[3 * f + k];
  PolygonSoup soup = unwelded_soup(m);
  std::string msg;
  EXPECT_EQ(intake_error(soup, &msg), ErrorCode::InvalidMesh);
  EXPECT_NE(msg.find("non-orientable"), std::string::npos) << msg;

  const int far[3] = {soup.num_vertices(), soup.num_vertices() + 1, soup.num_vertices() + 2};
  soup.positions.insert(soup.positions.end(), {{10, 0, 0}, {11, 0, 0}, {10, 1, 0}});
  soup.add_face(far, 3);
  IntakeOptions drop;
  drop.drop_bad_components = true;
  const IntakeResult r = intake_with(soup, drop);
  EXPECT_EQ(repair_count(r, "dropped_nonorientable_components"), 1);
  EXPECT_GT(repair_count(r, "welded_vertices"), 0);
  EXPECT_EQ(r.mesh.num_faces(), 1);
  EXPECT_FALSE(find_repair(r, "dropped_nonorientable_components")->input_vertices.empty());
  EXPECT_TRUE(r.non_orientable_parts.empty());
  // By default the welded strip is set aside as its triangles, the far triangle goes on.
  const IntakeResult kept = intake_with(soup, IntakeOptions{});
  EXPECT_EQ(kept.mesh.num_faces(), 1);
  ASSERT_EQ(kept.non_orientable_parts.size(), 1u);
  EXPECT_EQ(kept.non_orientable_parts[0].triangles.size(), 16u);
  EXPECT_EQ(kept.non_orientable_parts[0].positions.size(), 16u);  // welded: the strip's 16 corners
}

// A non-orientable part beside orientable ones is set aside with its input triangles, faces and
// positions unchanged; the report names the repair and where, and warns.
TEST(IntakeCut, NonOrientablePartBesideOthersIsSetAside) {
  PolygonSoup soup = test::moebius_strip(Vec3(10, 0, 0));
  const PolygonSoup second = test::moebius_strip(Vec3(-10, 0, 0));
  const int base = soup.num_vertices();
  for (const Vec3& p : second.positions) soup.positions.push_back(p);
  for (int f = 0; f < second.num_faces(); ++f) {
    const int t[3] = {base + second.face_vertices[3 * f], base + second.face_vertices[3 * f + 1],
                      base + second.face_vertices[3 * f + 2]};
    soup.add_face(t, 3);
  }
  const int v0 = soup.num_vertices();  // and an orientable tetrahedron
  for (const Vec3& p : {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)}) soup.positions.push_back(p);
  for (const std::array<int, 3>& t : {std::array<int, 3>{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {0, 3, 2}}) {
    const int f[3] = {v0 + t[0], v0 + t[1], v0 + t[2]};
    soup.add_face(f, 3);
  }
  const IntakeResult r = intake_with(soup, IntakeOptions{});
  ASSERT_EQ(r.components.size(), 1u);
  EXPECT_EQ(r.mesh.num_faces(), 4);
  EXPECT_EQ(r.components[0].genus, 0);
  ASSERT_EQ(r.non_orientable_parts.size(), 2u);
  EXPECT_EQ(repair_count(r, "kept_nonorientable_components"), 2);
  EXPECT_EQ(find_repair(r, "kept_nonorientable_components")->input_vertices.size(), 2u);
  ASSERT_FALSE(r.warnings.empty());
  EXPECT_NE(r.warnings.back().find("non-orientable"), std::string::npos) << r.warnings.back();
  for (size_t k = 0; k < 2; ++k) {
    const NonOrientablePart& part = r.non_orientable_parts[k];
    ASSERT_EQ(part.triangles.size(), 16u);
    for (size_t t = 0; t < part.triangles.size(); ++t) {
      const int f = part.input_face[t];
      ASSERT_TRUE(f >= 16 * static_cast<int>(k) && f < 16 * static_cast<int>(k + 1)) << f;
      for (int j = 0; j < 3; ++j)  // the input triangle, corner by corner, in its input orientation
        EXPECT_EQ(part.positions[part.triangles[t][j]], soup.positions[soup.face_vertices[3 * f + j]]);
    }
  }
}

TEST(IntakeReport, RepairsNameWhereTheyHappened) {
  const IntakeResult r = test::load_mesh("stanford-bunny.obj");  // 1113 unreferenced vertices
  Json j;
  to_json(j, r);
  ASSERT_FALSE(j["repairs"].empty());
  for (const Json& rep : j["repairs"]) {
    EXPECT_TRUE(rep.contains("kind") && rep.contains("count"));
    ASSERT_TRUE(rep.contains("input_vertices"));
    EXPECT_GE(rep["input_vertices"].size(), 1u);
    EXPECT_LE(rep["input_vertices"].size(), 10u);
  }
}

}  // namespace
}  // namespace qgp

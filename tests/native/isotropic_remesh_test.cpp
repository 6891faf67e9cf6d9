// Isotropic remeshing of needle-covered components (intake/isotropic_remesh.h): on the CAD meshes of
// the shared set, on smooth ones and on a generated CAD-style cylinder whose faces are fans of
// needles, the remeshed surface keeps the topology, every feature curve and its corners, stays on
// the input surface, has no needle left and no face turned against the input, and is the same on a
// second run.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <string>
#include <vector>

#include "cross_field/cross_field.h"
#include "intake/isotropic_remesh.h"
#include "intake/working_mesh.h"
#include "quad_extraction/surface_projection.h"
#include "test_support.h"

namespace qgp {
namespace {

double surface_area(const TriMesh& mesh) {
  double area = 0;
  for (int f = 0; f < mesh.num_faces(); ++f) area += 0.5 * mesh.face_normal_unnormalized(f).norm();
  return area;
}

double feature_length(const TriMesh& mesh, const std::vector<char>& features) {
  double length = 0;
  for (int e = 0; e < mesh.num_edges(); ++e)
    if (features[e]) length += mesh.edge_vector(mesh.edge_halfedge[e]).norm();
  return length;
}

// Vertices where other than two feature edges meet (feature curves end or cross there).
std::vector<int> feature_corners(const TriMesh& mesh, const std::vector<char>& features) {
  std::vector<int> degree(mesh.num_vertices(), 0), corners;
  for (int e = 0; e < mesh.num_edges(); ++e)
    if (features[e]) {
      ++degree[mesh.from(mesh.edge_halfedge[e])];
      ++degree[mesh.to(mesh.edge_halfedge[e])];
    }
  for (int v = 0; v < mesh.num_vertices(); ++v)
    if (degree[v] != 0 && degree[v] != 2) corners.push_back(v);
  return corners;
}

// Asserts the remeshing invariants of `out` against `mesh` remeshed at `length`.
void expect_remeshing_invariants(const std::string& name, const TriMesh& mesh, const std::vector<char>& features,
                                 const RemeshedSurface& out, double length) {
  const int chi = mesh.num_vertices() - mesh.num_edges() + mesh.num_faces();
  EXPECT_EQ(out.mesh.num_vertices() - out.mesh.num_edges() + out.mesh.num_faces(), chi) << name;
  EXPECT_EQ(count_boundary_loops(out.mesh), count_boundary_loops(mesh)) << name;
  EXPECT_LT(needle_area_share(out.mesh), 0.01) << name;
  // About as many faces as equilateral triangles of that edge length cover the area.
  const double expected_faces = surface_area(mesh) / (std::sqrt(3.0) / 4 * length * length);
  EXPECT_GT(out.mesh.num_faces(), 0.5 * expected_faces) << name;
  EXPECT_LT(out.mesh.num_faces(), 2.0 * expected_faces) << name;
  // Feature curves: as long as before (chords of curved ones a little shorter), every corner kept.
  const double before = feature_length(mesh, features), after = feature_length(out.mesh, out.feature_edges);
  EXPECT_LE(after, before * (1 + 1e-9)) << name;
  EXPECT_GE(after, before * 0.99) << name;
  const TriangleBvh output_surface(out.mesh);
  for (int v : feature_corners(mesh, features)) {
    const TriangleBvh::Hit hit = output_surface.closest_point(mesh.position(v));
    double nearest = std::numeric_limits<double>::infinity();
    for (int k = 0; k < 3; ++k)
      nearest = std::min(nearest, (out.mesh.position(out.mesh.F(hit.triangle, k)) - mesh.position(v)).norm());
    EXPECT_EQ(nearest, 0.0) << name << ": feature corner " << v << " is not a vertex";
  }
  // On the input surface, and no face turned against it.
  const TriangleBvh input_surface(mesh);
  double farthest = 0;
  int turned = 0;
  for (int v = 0; v < out.mesh.num_vertices(); ++v)
    farthest = std::max(farthest, std::sqrt(input_surface.closest_point(out.mesh.position(v)).squared_distance));
  for (int f = 0; f < out.mesh.num_faces(); ++f) {
    const Vec3 centroid = (out.mesh.position(out.mesh.F(f, 0)) + out.mesh.position(out.mesh.F(f, 1)) +
                           out.mesh.position(out.mesh.F(f, 2))) /
                          3;
    const int t = input_surface.closest_point(centroid).triangle;
    turned += out.mesh.face_normal_unnormalized(f).dot(mesh.face_normal_unnormalized(t)) <= 0;
  }
  std::cout << name << ": " << mesh.num_faces() << " -> " << out.mesh.num_faces() << " faces, farthest vertex "
            << farthest / length << " edge lengths off the input, " << turned << " faces turned" << std::endl;
  EXPECT_LE(farthest, 1e-8 * length) << name;
  EXPECT_EQ(turned, 0) << name;
}

class IsotropicRemeshMeshes : public ::testing::TestWithParam<std::string> {};

TEST_P(IsotropicRemeshMeshes, KeepsTopologyFeaturesAndSurface) {
  const std::string name = GetParam();
  const TriMesh mesh = test::component_mesh(test::load_mesh(name), 0);
  const std::vector<char> features = detect_feature_edges(mesh, {}, 40);
  IsotropicRemeshOptions options;
  options.edge_length = std::sqrt(surface_area(mesh) / (20000 * std::sqrt(3.0) / 4));
  const std::optional<RemeshedSurface> out = remesh_isotropic(mesh, features, options);
  ASSERT_TRUE(out.has_value()) << name;
  expect_remeshing_invariants(name, mesh, features, *out, options.edge_length);
  const std::optional<RemeshedSurface> again = remesh_isotropic(mesh, features, options);
  ASSERT_TRUE(again.has_value()) << name;
  EXPECT_EQ(again->mesh.F, out->mesh.F) << name;
  EXPECT_EQ(again->mesh.V, out->mesh.V) << name;
}

// The CAD parts of the shared set (needles over much of their area) and smooth meshes.
INSTANTIATE_TEST_SUITE_P(Shared, IsotropicRemeshMeshes,
                         ::testing::Values("featuretype.ply", "joint.obj", "block.obj", "fandisk.obj", "spot.obj",
                                           "fertility.off"),
                         [](const auto& info) { return test::identifier(info.param); });

TEST(IsotropicRemeshGenerated, FanCylinderLosesItsNeedles) {
  const TriMesh mesh = test::make_fan_cylinder(48, 1, 3);
  const std::vector<char> features = detect_feature_edges(mesh, {}, 40);
  EXPECT_GT(needle_area_share(mesh), 0.5);
  IsotropicRemeshOptions options;
  options.edge_length = 0.1;
  const std::optional<RemeshedSurface> out = remesh_isotropic(mesh, features, options);
  ASSERT_TRUE(out.has_value());
  expect_remeshing_invariants("fan cylinder", mesh, features, *out, options.edge_length);
}

// The pipeline's choice: a needle-covered component with features may be remeshed (the policy's
// predicate), the same without features or a smooth one not; asked to, the working mesh remeshes it
// to its budget.
TEST(IsotropicRemeshGenerated, WorkingMeshRemeshesNeedleCoveredComponentsWithFeatures) {
  Progress progress;
  const TriMesh cylinder = test::make_fan_cylinder(48, 1, 3);
  const std::vector<char> rims = detect_feature_edges(cylinder, {}, 40);
  EXPECT_TRUE(has_needles_across_features(cylinder, rims));
  const WorkingMesh remeshed = make_working_mesh(cylinder, rims, 20000, 5000, progress);
  EXPECT_TRUE(remeshed.remeshed);
  EXPECT_GT(remeshed.mesh.num_faces(), 2500);
  EXPECT_LT(remeshed.mesh.num_faces(), 10000);
  ASSERT_EQ(remeshed.vertex_of_input.size(), static_cast<size_t>(remeshed.mesh.num_vertices()));
  EXPECT_FALSE(make_working_mesh(cylinder, rims, 20000, 0, progress).remeshed);
  EXPECT_FALSE(has_needles_across_features(cylinder, std::vector<char>(rims.size(), 0)));
  const TriMesh spot = test::component_mesh(test::load_mesh("spot.obj"), 0);
  EXPECT_FALSE(has_needles_across_features(spot, detect_feature_edges(spot, {}, 40)));
}

}  // namespace
}  // namespace qgp

// The sizing field (sizing/sizing.h) and the quads that follow it: face sizes keep the quad count
// (sum of area / size^2 = area), are smaller where the surface curves more (adaptive) and where a
// density is painted; through the Session, the quads are smaller there, a valid quad mesh, of the
// count asked, on generated shapes and real meshes; a painted density survives the symmetry cut.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>

#include "core/error.h"
#include "intake/read_mesh_file.h"
#include "metrics/polygon_metrics.h"
#include "pipeline/session.h"
#include "sizing/sizing.h"
#include "symmetry/symmetry.h"
#include "test_support.h"

namespace qgp {
namespace {

// A latitude-longitude sphere (nu x nv) scaled by (1, 1, stretch), as a triangle soup.
PolygonSoup stretched_sphere(int nu, int nv, double stretch) {
  PolygonSoup soup;
  soup.positions.push_back(Vec3(0, 0, -stretch));
  for (int j = 1; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      const double theta = M_PI * j / nv, phi = 2 * M_PI * i / nu;
      soup.positions.push_back(
          Vec3(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), -stretch * std::cos(theta)));
    }
  soup.positions.push_back(Vec3(0, 0, stretch));
  auto ring = [&](int j, int i) { return 1 + j * nu + (i % nu); };
  for (int i = 0; i < nu; ++i) {
    const int t[3] = {0, ring(0, i + 1), ring(0, i)};
    soup.add_face(t, 3);
  }
  for (int j = 0; j + 2 < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      const int a = ring(j, i), b = ring(j, i + 1), c = ring(j + 1, i), d = ring(j + 1, i + 1);
      const int t0[3] = {a, b, d}, t1[3] = {a, d, c};
      soup.add_face(t0, 3);
      soup.add_face(t1, 3);
    }
  const int top = static_cast<int>(soup.positions.size()) - 1;
  for (int i = 0; i < nu; ++i) {
    const int t[3] = {ring(nv - 2, i), ring(nv - 2, i + 1), top};
    soup.add_face(t, 3);
  }
  return soup;
}

TriMesh trimesh_of(const PolygonSoup& soup) {
  TriMesh mesh;
  mesh.V.resize(soup.num_vertices(), 3);
  for (int v = 0; v < soup.num_vertices(); ++v) mesh.V.row(v) = soup.positions[v].transpose();
  mesh.F.resize(soup.num_faces(), 3);
  for (int f = 0; f < soup.num_faces(); ++f)
    for (int k = 0; k < 3; ++k) mesh.F(f, k) = soup.face_vertices[soup.face_start[f] + k];
  build_connectivity(mesh);
  return mesh;
}

// Area-weighted mean of `values` per face over faces whose centroid's z passes `keep`.
template <class Keep>
double mean_over(const TriMesh& mesh, const std::vector<double>& values, Keep keep) {
  double sum = 0, area = 0;
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const Vec3 c = (mesh.position(mesh.F(f, 0)) + mesh.position(mesh.F(f, 1)) + mesh.position(mesh.F(f, 2))) / 3;
    if (!keep(c.z())) continue;
    const double a = 0.5 * mesh.face_normal_unnormalized(f).norm();
    sum += a * values[f], area += a;
  }
  return sum / area;
}

void expect_count_kept(const TriMesh& mesh, const std::vector<double>& sizes, const std::string& what) {
  double area = 0, sized = 0;
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const double a = 0.5 * mesh.face_normal_unnormalized(f).norm();
    area += a, sized += a / (sizes[f] * sizes[f]);
  }
  EXPECT_NEAR(sized / area, 1.0, 1e-9) << what;
}

TEST(Sizing, FaceSizesFollowCurvatureAndPaintAndKeepTheCount) {
  const TriMesh ellipsoid = trimesh_of(stretched_sphere(96, 48, 3));
  EXPECT_TRUE(face_sizes(ellipsoid, {}, SizingOptions{}).empty()) << "uniform asks no sizes";
  SizingOptions adaptive;
  adaptive.adaptive = 1;
  const std::vector<double> curved = face_sizes(ellipsoid, {}, adaptive);
  ASSERT_EQ(curved.size(), static_cast<size_t>(ellipsoid.num_faces()));
  expect_count_kept(ellipsoid, curved, "adaptive");
  // The tips (radius of curvature 1/3) against the middle (radius 1 around, 9 along).
  const double tips = mean_over(ellipsoid, curved, [](double z) { return std::abs(z) > 2.8; });
  const double middle = mean_over(ellipsoid, curved, [](double z) { return std::abs(z) < 0.5; });
  EXPECT_LT(tips / middle, 0.5) << tips << " / " << middle;
  for (double s : curved) EXPECT_TRUE(s > 0 && std::isfinite(s));

  const TriMesh sphere = trimesh_of(stretched_sphere(96, 48, 1));
  SizingOptions painted;
  for (int v = 0; v < sphere.num_vertices(); ++v) painted.vertex_density.push_back(sphere.V(v, 2) > 0 ? 2.0 : 1.0);
  const std::vector<double> sizes = face_sizes(sphere, {}, painted);
  expect_count_kept(sphere, sizes, "painted");
  const double dense = mean_over(sphere, sizes, [](double z) { return z > 0.3; });
  const double coarse = mean_over(sphere, sizes, [](double z) { return z < -0.3; });
  EXPECT_NEAR(dense / coarse, 0.5, 0.01) << "away from the painted edge, quads half as long";
  painted.vertex_density.assign(sphere.num_vertices(), 1000.0);  // clamped, and uniform: the count keeps it 1
  for (double s : face_sizes(sphere, {}, painted)) EXPECT_NEAR(s, 1.0, 1e-9);
}

// Mean quad edge length over edges whose midpoint's z passes `keep`.
template <class Keep>
double mean_edge(const QuadMesh& quads, Keep keep) {
  double sum = 0;
  int n = 0;
  for (int q = 0; q < quads.num_quads(); ++q)
    for (int k = 0; k < 4; ++k) {
      const Vec3 a = quads.V.row(quads.Q(q, k)).transpose(), b = quads.V.row(quads.Q(q, (k + 1) % 4)).transpose();
      if (!keep(0.5 * (a.z() + b.z()))) continue;
      sum += (a - b).norm(), ++n;
    }
  return sum / n;
}

const QuadMesh& remesh(Session& session, double target, double adaptive, std::vector<double> density = {},
                       double sharp_angle = -1) {
  RemeshOptions options;
  options.target_faces = target;
  options.adaptive = adaptive;
  options.density = std::move(density);
  options.sharp_angle_deg = sharp_angle;
  session.set_options(options);
  Progress progress;
  session.run(Job::Remesh, progress);
  return *session.quad_result();
}

// A valid quad mesh of the count asked (or the count's note), against the session's input.
void expect_valid(const std::string& name, const Session& session, double target, double sharp_angle) {
  const QuadMesh& quads = *session.quad_result();
  const Json& report = session.report();
  Progress progress;
  const PolygonMeshMetrics m =
      measure_polygon_mesh(test::polygon_soup(quads), session.intake()->mesh, sharp_angle, progress);
  EXPECT_EQ(m.non_quads + m.non_manifold_edges + m.quad.topology.inconsistent_edges, 0) << name;
  EXPECT_EQ(m.quad.topology.degenerate_quads, 0) << name;
  EXPECT_EQ(m.euler_characteristic, m.reference_euler_characteristic) << name;
  EXPECT_EQ(m.quad.flipped_quads(), 0) << name;
  EXPECT_LT(m.quad.hausdorff, 0.05) << name;
  if (sharp_angle > 0) EXPECT_GT(m.sharp_edge_coverage, 0.95) << name;
  EXPECT_TRUE(std::abs(quads.num_quads() - target) <= 0.05 * target || report["quantization"]["count"].contains("note"))
      << name << ": " << quads.num_quads();
  std::cout << name << ": " << quads.num_quads() << " quads, Hausdorff " << m.quad.hausdorff << ", min scaled Jacobian "
            << m.quad.min_scaled_jacobian << ", " << report["timings_s"]["total"] << " s\n";
}

// The ellipsoid's tips get smaller quads with adaptive size than without; a painted half of a
// sphere gets denser quads than the other half; a new adaptivity solves the seamless map again
// (its key has the sizes), the same one does not.
TEST(SizingSession, QuadsFollowCurvatureAndPaint) {
  Session ellipsoid(stretched_sphere(96, 48, 3));
  auto tips = [](double z) { return std::abs(z) > 2.5; };
  auto middle = [](double z) { return std::abs(z) < 1.0; };
  const QuadMesh& uniform = remesh(ellipsoid, 1500, 0);
  const double uniform_ratio = mean_edge(uniform, tips) / mean_edge(uniform, middle);
  expect_valid("ellipsoid, uniform", ellipsoid, 1500, -1);
  const QuadMesh& adapted = remesh(ellipsoid, 1500, 1);
  const double adapted_ratio = mean_edge(adapted, tips) / mean_edge(adapted, middle);
  expect_valid("ellipsoid, adaptive 1", ellipsoid, 1500, -1);
  std::cout << "ellipsoid tips / middle edge length: " << uniform_ratio << " uniform, " << adapted_ratio
            << " adaptive\n";
  EXPECT_LT(adapted_ratio, 0.8 * uniform_ratio);
  const uint64_t solved = ellipsoid.components()[0].seamless.id();
  remesh(ellipsoid, 1600, 1);
  EXPECT_EQ(ellipsoid.components()[0].seamless.id(), solved) << "same sizes, new count: re-quantized only";
  remesh(ellipsoid, 1600, 0.5);
  EXPECT_NE(ellipsoid.components()[0].seamless.id(), solved) << "new sizes: the seamless map solved again";

  const PolygonSoup sphere_soup = stretched_sphere(96, 48, 1);
  std::vector<double> density;
  for (const Vec3& p : sphere_soup.positions) density.push_back(p.z() > 0 ? 4.0 : 1.0);
  Session sphere(sphere_soup);
  const QuadMesh& painted = remesh(sphere, 1500, 0, density);
  const double ratio =
      mean_edge(painted, [](double z) { return z > 0.3; }) / mean_edge(painted, [](double z) { return z < -0.3; });
  std::cout << "sphere painted 4 on top: top / bottom edge length " << ratio << "\n";
  expect_valid("sphere, painted", sphere, 1500, -1);
  EXPECT_LT(ratio, 0.75);
}

// Real meshes at adaptive size 1 (and a painted density on spot): valid quads of the count asked.
TEST(SizingMeshes, AdaptiveQuadsAreValidOnRealMeshes) {
  for (const auto& [name, sharp] : std::vector<std::pair<std::string, double>>{
           {"spot.obj", -1}, {"bunny.off", -1}, {"block.obj", 40}, {"rocker-arm.obj", -1}}) {
    Session session(read_mesh_file(test::mesh_path(name)));
    remesh(session, 1000, 1, {}, sharp);
    expect_valid(name + " adaptive 1", session, 1000, sharp);
  }
  const PolygonSoup spot = read_mesh_file(test::mesh_path("spot.obj"));
  std::vector<double> density;
  for (const Vec3& p : spot.positions) density.push_back(p.y() > 0 ? 3.0 : 1.0);
  Session session(spot);
  remesh(session, 1000, 0, density);
  expect_valid("spot painted", session, 1000, -1);
}

TEST(SizingSession, DensityIsValidatedAndSurvivesTheSymmetryCut) {
  const PolygonSoup sphere = stretched_sphere(24, 12, 1);
  Session session(sphere);
  RemeshOptions options;
  options.density = {1.0, 2.0};
  EXPECT_THROW(session.set_options(options), Error);
  options.density.assign(sphere.num_vertices(), 1.0);
  options.density[3] = -1;
  EXPECT_THROW(session.set_options(options), Error);
  options.density[3] = 1;
  options.adaptive = 1.5;
  EXPECT_THROW(session.set_options(options), Error);
  // A linear density (1 + x + 2y + 3) is linear on the cut: the cut points' values are exact.
  std::vector<double> linear;
  for (const Vec3& p : sphere.positions) linear.push_back(4 + p.x() + 2 * p.y());
  const HalfSoup half = cut_to_positive_half(sphere, {}, parse_symmetry_axes("xy"), 0, linear);
  ASSERT_EQ(half.vertex_values.size(), static_cast<size_t>(half.soup.num_vertices()));
  int cut_points = 0;
  for (int v = 0; v < half.soup.num_vertices(); ++v) {
    const Vec3& p = half.soup.positions[v];
    EXPECT_NEAR(half.vertex_values[v], 4 + p.x() + 2 * p.y(), 1e-12) << v;
    cut_points += half.input_vertex[v] < 0;
  }
  EXPECT_GT(cut_points, 0);
}

}  // namespace
}  // namespace qgp

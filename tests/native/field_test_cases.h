// Mesh cases and geometric helpers shared by the cross field and cut graph tests.
#pragma once
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "core/mesh.h"
#include "test_support.h"

namespace qgp::test {

struct FieldCase {
  std::string file;
  double sharp_angle_deg = -1;  // < 0: no dihedral features
  // Collapsed feature sectors allowed away from over-constrained faces (see CrossField).
  int collapsed_allowance = 0;
};

inline std::string case_name(const ::testing::TestParamInfo<FieldCase>& info) {
  std::string name = test::identifier(info.param.file);
  if (info.param.sharp_angle_deg >= 0) name += "_sharp" + std::to_string(static_cast<int>(info.param.sharp_angle_deg));
  return name;
}

// Every manifold mesh without features, the CAD meshes at --sharp-angle 40, and the accepted
// multi-component / repaired meshes (processed per component).
inline std::vector<FieldCase> field_cases() {
  std::vector<FieldCase> cases;
  for (const std::string& f : manifold_mesh_files()) cases.push_back({f, -1});
  for (const char* f :
       {"fandisk.obj", "joint.obj", "wingnut.obj", "joint_rem_p.obj", "mnf07HeadFem_rem_rem_p.obj", "rocker-arm.obj"})
    cases.push_back({f, 40});
  // One sector between two feature edges at vertex 732 whose rounding ties (read in double
  // precision; in float precision it does not collapse).
  cases.push_back({"block.obj", 40, 1});
  for (const char* f : {"teapot.obj", "ogre.obj", "featuretype.ply", "cow.obj"}) cases.push_back({f, -1});
  cases.push_back({"cow.obj", 40, 2});  // two 72deg sectors between conflicting constraints
  return cases;
}

inline double wrap_angle(double a) {
  a = std::remainder(a, 2 * M_PI);
  return a <= -M_PI ? a + 2 * M_PI : a;
}

inline Vec3 unit_normal(const TriMesh& mesh, int f) { return mesh.face_normal_unnormalized(f).normalized(); }

// Angle of halfedge h's vector in the chart of face(h) whose +u axis is the unit tangent u.
inline double angle_in_chart(const TriMesh& mesh, int h, const Vec3& u) {
  const Vec3 v = mesh.edge_vector(h), n = unit_normal(mesh, h / 3);
  return std::atan2(v.dot(n.cross(u)), v.dot(u));
}

// Angle between the normals of the two faces of interior edge e.
inline double dihedral_angle(const TriMesh& mesh, int e) {
  const int h = mesh.edge_halfedge[e];
  const Vec3 a = unit_normal(mesh, h / 3), b = unit_normal(mesh, mesh.opposite[h] / 3);
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

// Planar n x n grid of squares split into triangles, in the z = 0 plane.
inline TriMesh make_planar_grid(int n) {
  TriMesh m;
  m.V.resize((n + 1) * (n + 1), 3);
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= n; ++j) m.V.row(i * (n + 1) + j) << i, j, 0;
  m.F.resize(2 * n * n, 3);
  int t = 0;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const int a = i * (n + 1) + j, b = (i + 1) * (n + 1) + j, c = (i + 1) * (n + 1) + j + 1, d = i * (n + 1) + j + 1;
      m.F.row(t++) << a, b, c;
      m.F.row(t++) << a, c, d;
    }
  build_connectivity(m);
  return m;
}

inline TriMesh make_triangles(const std::vector<Vec3>& points, const std::vector<std::array<int, 3>>& faces) {
  TriMesh m;
  m.V.resize(static_cast<int>(points.size()), 3);
  for (size_t v = 0; v < points.size(); ++v) m.V.row(v) = points[v].transpose();
  m.F.resize(static_cast<int>(faces.size()), 3);
  for (size_t f = 0; f < faces.size(); ++f) m.F.row(f) << faces[f][0], faces[f][1], faces[f][2];
  build_connectivity(m);
  return m;
}

}  // namespace qgp::test

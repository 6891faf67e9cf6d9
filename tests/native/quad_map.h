// Seamless maps of real meshes for T-mesh tests: every triangle is split into three quads (its
// corner, the two edge midpoints, its centre), each quad is a square in its own chart and is cut
// into two triangles. Singularities: face centres (valence 3) and original vertices of degree
// != 4; boundary and feature edges are isolines. Optionally all charts are rotated by the angle
// of a Pythagorean triple (a, b, c): the square (0,0),(c,0),(c,c),(0,c) turned by atan(b/a) has
// integer corners, so the map stays exactly representable and seamless, but its isolines run in
// general position (closed meshes without features only: boundaries and features would no longer
// be isolines). Every edge is a cut, so the exact map is built directly (exact_integer_map), not
// by sanitize_parametrization.
// Header-only; used by tmesh_test.cpp.
#pragma once
#include <array>
#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

#include "test_support.h"

namespace qgp::test {

struct QuadMap {
  TriMesh mesh;
  Parametrization param;
  std::vector<char> features;  // #E of `mesh`: halves of the original feature edges
};

// tri_features: #E of `tri` (may be empty). triple: {a, b, c} with a^2 + b^2 = c^2, or {1, 0, 1}.
inline QuadMap make_quad_map(const TriMesh& tri, const std::vector<char>& tri_features,
                             std::array<int, 3> triple = {1, 0, 1}, unsigned seed = 1) {
  const int nv = tri.num_vertices(), ne = tri.num_edges(), nf = tri.num_faces();
  std::mt19937 rng(seed);
  QuadMap out;
  TriMesh& m = out.mesh;
  m.V.resize(nv + ne + nf, 3);
  for (int v = 0; v < nv; ++v) m.V.row(v) = tri.V.row(v);
  for (int e = 0; e < ne; ++e) {
    const int h = tri.edge_halfedge[e];
    m.V.row(nv + e) = 0.5 * (tri.V.row(tri.from(h)) + tri.V.row(tri.to(h)));
  }
  for (int f = 0; f < nf; ++f)
    m.V.row(nv + ne + f) = (tri.V.row(tri.F(f, 0)) + tri.V.row(tri.F(f, 1)) + tri.V.row(tri.F(f, 2))) / 3;
  m.F.resize(6 * nf, 3);
  out.param.uv.resize(18 * nf, 2);
  const double c = triple[0], s = triple[1];  // times the square's side triple[2]
  const Vec2 unit[4] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  int t = 0;
  for (int f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) {
      const int h = 3 * f + k;
      const int quad[4] = {tri.F(f, k), nv + tri.edge_of[h], nv + ne + f, nv + tri.edge_of[TriMesh::prev(h)]};
      const bool other_diagonal = rng() & 1;
      const int split[2][2][3] = {{{0, 1, 2}, {0, 2, 3}}, {{0, 1, 3}, {1, 2, 3}}};
      for (const auto& tr : split[other_diagonal]) {
        for (int j = 0; j < 3; ++j) {
          m.F(t, j) = quad[tr[j]];
          const Vec2& p = unit[tr[j]];
          out.param.uv.row(3 * t + j) << c * p.x() - s * p.y(), s * p.x() + c * p.y();
        }
        ++t;
      }
    }
  build_connectivity(m);
  infer_rotations(m, out.param);
  out.features.assign(m.num_edges(), 0);
  if (!tri_features.empty())
    for (int e = 0; e < m.num_edges(); ++e) {
      const int h = m.edge_halfedge[e];
      int a = m.from(h), b = m.to(h);
      if (a > b) std::swap(a, b);
      if (a < nv && b >= nv && b < nv + ne && tri_features[b - nv]) out.features[e] = 1;
    }
  return out;
}

// The exact form of a map whose coordinates are integers: corners times 2^fraction_bits,
// translations from the corners across every interior edge.
inline ExactParametrization exact_integer_map(const TriMesh& mesh, const Parametrization& param, int fraction_bits) {
  ExactParametrization ex;
  ex.fraction_bits = fraction_bits;
  const int nc = 3 * mesh.num_faces();
  ex.uv.resize(nc);
  for (int k = 0; k < nc; ++k)
    for (int a = 0; a < 2; ++a) {
      if (param.uv(k, a) != std::round(param.uv(k, a)))
        throw std::runtime_error("exact_integer_map: non-integer coordinate");
      ex.uv[k][a] = static_cast<int64_t>(std::llround(param.uv(k, a))) * (int64_t(1) << fraction_bits);
    }
  ex.rotation = param.rotation;
  ex.is_cut = param.is_cut;
  ex.translation.assign(nc, {0, 0});
  for (int h = 0; h < nc; ++h) {
    const int o = mesh.opposite[h];
    if (o < 0) continue;
    const IVec2 pf = ex.uv[h], pg = ex.uv[3 * (o / 3) + (o % 3 + 1) % 3];
    const IVec2 r = rotate_quarter(pf, ex.rotation[h]);
    ex.translation[h] = {pg[0] - r[0], pg[1] - r[1]};
  }
  return ex;
}

// Edges whose faces' normals differ by more than `degrees`.
inline std::vector<char> sharp_edges(const TriMesh& mesh, double degrees) {
  std::vector<char> sharp(mesh.num_edges(), 0);
  const double limit = std::cos(degrees * M_PI / 180);
  for (int e = 0; e < mesh.num_edges(); ++e) {
    const int h = mesh.edge_halfedge[e], o = mesh.opposite[h];
    if (o < 0) continue;
    const Vec3 a = mesh.face_normal_unnormalized(h / 3).normalized(),
               b = mesh.face_normal_unnormalized(o / 3).normalized();
    sharp[e] = a.dot(b) < limit;
  }
  return sharp;
}

}  // namespace qgp::test

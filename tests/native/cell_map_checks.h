// Invariants of the fallback cell map (igm/cell_map) of a valid quantization, as GoogleTest
// expectations. Header-only; used by layout_meshes_test.cpp and igm_test.cpp.
#pragma once
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "core/error.h"
#include "core/parametrization.h"
#include "igm/cell_map.h"
#include "quantization/quantization.h"

namespace qgp::test {

// Builds the cell map and expects: no flipped triangle (exact; `known_flipped` where a known
// defect leaves that many), no wound ring (with cone angles
// in the options), every transition exact (each corner
// is the other side's carried across by the edge's quarter turn and integer translation, and the
// doubles agree with it), T-mesh nodes at working-mesh vertices on integer points where they are
// singular, feature corners or boundary nodes, every boundary edge on an integer isoline, the
// exact area == quads_expected, the surface covered once (3D area and Euler characteristic kept).
// Returns its stats (zero ones after a failure).
inline CellMapStats expect_cell_map_invariants(const std::string& where, const TriMesh& mesh, const TMesh& tm,
                                               const QuantizationResult& q, const CellMapOptions& options = {},
                                               int known_flipped = 0) {
  Progress progress;
  CellMap map;
  try {
    map = map_cells_to_rectangles(mesh, tm, q.x, progress, options);
  } catch (const Error& e) {
    ADD_FAILURE() << where << ": " << e.what();
    return {};
  }
  const TriMesh& m = map.mesh;
  const ExactParametrization& p = map.param;
  int flipped = 0, mismatched = 0, off_grid = 0;
  __int128 doubled_area = 0;
  double area = 0, source_area = 0;
  for (int t = 0; t < m.num_faces(); ++t) {
    const IVec2 &a = p.uv[3 * t], &b = p.uv[3 * t + 1], &c = p.uv[3 * t + 2];
    flipped += orient2d_exact(a, b, c) < 0;
    doubled_area +=
        static_cast<__int128>(b[0] - a[0]) * (c[1] - a[1]) - static_cast<__int128>(b[1] - a[1]) * (c[0] - a[0]);
    area += 0.5 * m.face_normal_unnormalized(t).norm();
    EXPECT_TRUE(map.source_face[t] >= 0 && map.source_face[t] < mesh.num_faces()) << where;
  }
  for (int h = 0; h < m.num_halfedges(); ++h) {
    for (int a = 0; a < 2; ++a) mismatched += map.corner_uv[h][a] != p.to_double(p.uv[h][a]);
    const int o = m.opposite[h];
    if (o < 0) continue;
    mismatched += p.transfer(h, p.uv[h]) != p.uv[TriMesh::next(o)] || p.transfer(h, p.uv[TriMesh::next(h)]) != p.uv[o];
    off_grid += p.translation[h][0] % p.one() != 0 || p.translation[h][1] % p.one() != 0;
  }
  for (int f = 0; f < mesh.num_faces(); ++f) source_area += 0.5 * mesh.face_normal_unnormalized(f).norm();
  EXPECT_EQ(flipped, known_flipped) << where;
  EXPECT_EQ(map.stats.flipped_triangles, known_flipped) << where;
  EXPECT_EQ(map.stats.wound_vertices, 0) << where << ": rings wound other than their cone";
  EXPECT_EQ(mismatched, 0) << where << ": transitions not exact";
  EXPECT_EQ(off_grid, 0) << where << ": translations off the integers";
  EXPECT_TRUE(doubled_area == static_cast<__int128>(2 * q.quads_expected) * p.one() * p.one())
      << where << ": area " << static_cast<double>(doubled_area) / 2 / p.one() / p.one() << " for " << q.quads_expected
      << " quads";
  EXPECT_NEAR(area, source_area, 1e-9 * source_area) << where;
  EXPECT_EQ(m.num_vertices() - m.num_edges() + m.num_faces(), mesh.num_vertices() - mesh.num_edges() + mesh.num_faces())
      << where;
  for (const TMeshNode& node : tm.nodes)  // working-mesh vertices keep their index
    if (node.mesh_vertex >= 0 && node.kind != TMeshNode::Kind::TJunction && node.kind != TMeshNode::Kind::Crossing)
      for (int h : outgoing_halfedges(m, node.mesh_vertex))
        EXPECT_TRUE(p.uv[h][0] % p.one() == 0 && p.uv[h][1] % p.one() == 0)
            << where << " node at vertex " << node.mesh_vertex;
  for (int h = 0; h < m.num_halfedges(); ++h)
    if (m.opposite[h] < 0) {
      const IVec2 &a = p.uv[h], &b = p.uv[TriMesh::next(h)];
      EXPECT_TRUE((a[0] == b[0] && a[0] % p.one() == 0) || (a[1] == b[1] && a[1] % p.one() == 0))
          << where << ": boundary off an integer isoline";
    }
  return map.stats;
}

}  // namespace qgp::test

// Synthetic polycube surfaces with exact seamless parametrizations, for T-mesh tests: the union
// of voxels of a (non-uniform) grid, each voxel face split into s x s squares of two triangles;
// every face's chart is its own two in-plane coordinates, so corners of the polycube are
// singularities (valence 3 convex, 5 concave, ...) and their separatrices run along grid lines.
// Header-only; used by tmesh_test.cpp.
#pragma once
#include <array>
#include <cmath>
#include <map>
#include <random>
#include <set>
#include <stdexcept>
#include <vector>

#include "test_support.h"

namespace qgp::test {

struct PolycubeSpec {
  std::array<std::vector<double>, 3> grid;                  // increasing coordinates of the grid lines per axis
  std::set<std::array<int, 3>> voxels;                      // occupied cells (i, j, k)
  std::set<std::pair<std::array<int, 3>, int>> open_faces;  // (voxel, direction 0..5) left out
  int subdivisions = 1;                                     // each voxel face: s x s squares
  bool random_diagonals = false;
  double jitter = 0;  // random move of non-corner vertices (x spacing); <= 0.15 keeps
                      // every triangle positive
  unsigned seed = 1;
  // All charts rotated by this angle: still seamless (the transitions keep their quarter turns),
  // but isolines run obliquely through the triangles; creases are no isolines then.
  double chart_rotation = 0;
};

struct Polycube {
  TriMesh mesh;
  Parametrization param;
  std::vector<char> crease_edges;  // #E: edges between faces of different normals (polycube edges)
};

// direction: 0..5 = +x, -x, +y, -y, +z, -z (axis = direction / 2).
inline Polycube make_polycube(const PolycubeSpec& spec) {
  const int s = spec.subdivisions;
  std::mt19937 rng(spec.seed);
  std::uniform_real_distribution<double> unit(-1, 1);
  std::map<std::array<long, 3>, int> vertex_id;
  std::vector<Vec3> positions;
  std::vector<std::array<int, 3>> tris;
  std::vector<int> tri_direction;
  auto lattice_coord = [&](int axis, long l) {
    const long cell = l / s, sub = l % s;
    const auto& g = spec.grid[axis];
    if (sub == 0) return g.at(cell);
    return g.at(cell) + (g.at(cell + 1) - g.at(cell)) * double(sub) / s;
  };
  auto vertex = [&](const std::array<long, 3>& l) {
    auto it = vertex_id.find(l);
    if (it != vertex_id.end()) return it->second;
    const int id = static_cast<int>(positions.size());
    vertex_id.emplace(l, id);
    positions.push_back(Vec3(lattice_coord(0, l[0]), lattice_coord(1, l[1]), lattice_coord(2, l[2])));
    return id;
  };
  for (const auto& vox : spec.voxels) {
    for (int dir = 0; dir < 6; ++dir) {
      const int a = dir / 2, sgn = dir % 2 == 0 ? 1 : -1;
      std::array<int, 3> nb = vox;
      nb[a] += sgn;
      if (spec.voxels.count(nb) || spec.open_faces.count({vox, dir})) continue;
      // In-plane axes (b, c) with b x c = outward normal.
      const int b = sgn > 0 ? (a + 1) % 3 : (a + 2) % 3, c = sgn > 0 ? (a + 2) % 3 : (a + 1) % 3;
      for (int i = 0; i < s; ++i)
        for (int j = 0; j < s; ++j) {
          int id[4];
          const int di[4] = {0, 1, 1, 0}, dj[4] = {0, 0, 1, 1};
          for (int k = 0; k < 4; ++k) {
            std::array<long, 3> l;
            l[a] = long(vox[a] + (sgn > 0 ? 1 : 0)) * s;
            l[b] = long(vox[b]) * s + i + di[k];
            l[c] = long(vox[c]) * s + j + dj[k];
            id[k] = vertex(l);
          }
          const bool flip = spec.random_diagonals ? (rng() & 1) : ((i + j) % 2 == 1);
          if (!flip) {
            tris.push_back({id[0], id[1], id[2]}), tris.push_back({id[0], id[2], id[3]});
          } else {
            tris.push_back({id[0], id[1], id[3]}), tris.push_back({id[1], id[2], id[3]});
          }
          tri_direction.push_back(dir), tri_direction.push_back(dir);
        }
    }
  }
  // Jitter: vertices of flat regions (all incident faces coplanar) move within their plane,
  // vertices on a crease between two planes (not corners) move along the crease, by up to
  // `jitter` times the smallest adjacent sub-grid spacing; boundary vertices stay. Vertices on
  // grid lines move off them, so separatrices cross triangles and cut edges at arbitrary points.
  if (spec.jitter > 0) {
    std::vector<int> axes_used(positions.size(), 0);  // bit a: a face with normal axis a
    std::vector<char> fixed(positions.size(), 0);
    std::map<std::pair<int, int>, int> edge_count;
    for (size_t t = 0; t < tris.size(); ++t)
      for (int k = 0; k < 3; ++k) {
        const int v = tris[t][k];
        axes_used[v] |= 1 << (tri_direction[t] / 2);
        const int w = tris[t][(k + 1) % 3];
        ++edge_count[{std::min(v, w), std::max(v, w)}];
      }
    // Two faces with the same normal axis but opposite directions meet only at thin features;
    // direction sets are tracked per axis, so also fix vertices seeing both signs of an axis.
    std::vector<int> dirs_used(positions.size(), 0);
    for (size_t t = 0; t < tris.size(); ++t)
      for (int v : tris[t]) dirs_used[v] |= 1 << tri_direction[t];
    for (const auto& [e, n] : edge_count)
      if (n == 1) fixed[e.first] = fixed[e.second] = 1;  // boundary
    for (size_t v = 0; v < positions.size(); ++v) {
      const int naxes = __builtin_popcount(axes_used[v]);
      if (fixed[v] || naxes > 2 || __builtin_popcount(dirs_used[v]) != naxes) continue;
      for (int ax = 0; ax < 3; ++ax) {
        if (axes_used[v] & (1 << ax)) continue;  // a normal axis: stay in that plane
        const auto& g = spec.grid[ax];
        const double x = positions[v][ax];
        double h = 1e300;
        for (size_t cell = 0; cell + 1 < g.size(); ++cell)
          if (g[cell] <= x && x <= g[cell + 1]) h = std::min(h, (g[cell + 1] - g[cell]) / s);
        positions[v][ax] += spec.jitter * h * unit(rng);
      }
    }
  }
  Polycube out;
  out.mesh.V.resize(static_cast<int>(positions.size()), 3);
  for (size_t v = 0; v < positions.size(); ++v) out.mesh.V.row(v) = positions[v].transpose();
  out.mesh.F.resize(static_cast<int>(tris.size()), 3);
  out.param.uv.resize(3 * static_cast<int>(tris.size()), 2);
  for (size_t t = 0; t < tris.size(); ++t) {
    const int dir = tri_direction[t], a = dir / 2, sgn = dir % 2 == 0 ? 1 : -1;
    const int b = sgn > 0 ? (a + 1) % 3 : (a + 2) % 3, c = sgn > 0 ? (a + 2) % 3 : (a + 1) % 3;
    for (int k = 0; k < 3; ++k) {
      out.mesh.F(t, k) = tris[t][k];
      const Vec3& p = positions[tris[t][k]];
      const double cr = std::cos(spec.chart_rotation), sr = std::sin(spec.chart_rotation);
      out.param.uv.row(3 * t + k) << cr * p[b] - sr * p[c], sr * p[b] + cr * p[c];
    }
  }
  build_connectivity(out.mesh);
  infer_rotations(out.mesh, out.param);
  out.crease_edges.assign(out.mesh.num_edges(), 0);
  for (int h = 0; h < out.mesh.num_halfedges(); ++h) {
    const int o = out.mesh.opposite[h];
    if (o >= 0 && tri_direction[h / 3] != tri_direction[o / 3]) out.crease_edges[out.mesh.edge_of[h]] = 1;
  }
  return out;
}

// A monotone staircase (heights non-increasing in x and y, so the union is a manifold solid).
inline PolycubeSpec staircase(const std::vector<std::vector<int>>& heights, std::array<std::vector<double>, 3> grid) {
  PolycubeSpec spec;
  spec.grid = std::move(grid);
  for (size_t i = 0; i < heights.size(); ++i)
    for (size_t j = 0; j < heights[i].size(); ++j)
      for (int k = 0; k < heights[i][j]; ++k) spec.voxels.insert({int(i), int(j), k});
  return spec;
}

}  // namespace qgp::test

#include "core/mesh.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>

#include "core/error.h"

namespace qgp {

Vec3 TriMesh::face_normal_unnormalized(int f) const {
  const Vec3 a = position(F(f, 0)), b = position(F(f, 1)), c = position(F(f, 2));
  return (b - a).cross(c - a);
}

double TriMesh::bounding_box_diagonal() const {
  if (V.rows() == 0) return 0.0;
  return (V.colwise().maxCoeff() - V.colwise().minCoeff()).norm();
}

void sort_by_edge_key(std::vector<std::pair<uint64_t, int>>& keyed, int num_vertices) {
  for (const auto& k : keyed)
    if ((k.first >> 32) >= static_cast<uint64_t>(std::max(num_vertices, 0))) {
      std::sort(keyed.begin(), keyed.end());  // not keys of this many vertices
      return;
    }
  std::vector<size_t> first(static_cast<size_t>(num_vertices) + 1, 0);
  for (const auto& k : keyed) ++first[(k.first >> 32) + 1];
  for (int v = 0; v < num_vertices; ++v) first[v + 1] += first[v];
  std::vector<std::pair<uint64_t, int>> sorted(keyed.size());
  std::vector<size_t> next(first.begin(), first.end() - 1);
  for (const auto& k : keyed) sorted[next[k.first >> 32]++] = k;
  for (int v = 0; v < num_vertices; ++v) std::sort(sorted.begin() + first[v], sorted.begin() + first[v + 1]);
  keyed.swap(sorted);
}

void build_connectivity(TriMesh& mesh) {
  const int nh = mesh.num_halfedges();
  // Sort halfedges by their undirected key so that the (at most two) halfedges of an edge meet.
  std::vector<std::pair<uint64_t, int>> keyed(nh);
  for (int h = 0; h < nh; ++h) {
    const uint64_t a = static_cast<uint32_t>(mesh.from(h)), b = static_cast<uint32_t>(mesh.to(h));
    keyed[h] = {std::min(a, b) << 32 | std::max(a, b), h};
  }
  sort_by_edge_key(keyed, mesh.num_vertices());
  mesh.opposite.assign(nh, -1);
  mesh.edge_of.assign(nh, -1);
  mesh.edge_halfedge.clear();
  for (int i = 0; i < nh;) {
    int j = i + 1;
    while (j < nh && keyed[j].first == keyed[i].first) ++j;
    const int h0 = keyed[i].second;
    if (j - i > 2)
      throw Error(ErrorCode::InvalidMesh, "edge (" + std::to_string(mesh.from(h0)) + ", " +
                                              std::to_string(mesh.to(h0)) + ") has " + std::to_string(j - i) +
                                              " faces");
    const int e = static_cast<int>(mesh.edge_halfedge.size());
    mesh.edge_halfedge.push_back(h0);
    mesh.edge_of[h0] = e;
    if (j - i == 2) {
      const int h1 = keyed[i + 1].second;
      if (mesh.from(h0) == mesh.from(h1))
        throw Error(ErrorCode::InvalidMesh, "faces " + std::to_string(h0 / 3) + " and " + std::to_string(h1 / 3) +
                                                " are inconsistently oriented");
      mesh.opposite[h0] = h1;
      mesh.opposite[h1] = h0;
      mesh.edge_of[h1] = e;
    }
    i = j;
  }
  mesh.vertex_halfedge.assign(mesh.num_vertices(), -1);
  for (int h = 0; h < nh; ++h) {
    int& vh = mesh.vertex_halfedge[mesh.from(h)];
    if (vh < 0 || mesh.opposite[h] < 0) vh = h;
  }
}

std::vector<int> outgoing_halfedges(const TriMesh& mesh, int v) {
  std::vector<int> out;
  const int start = mesh.vertex_halfedge[v];
  if (start < 0) return out;
  int h = start;
  do {
    out.push_back(h);
    h = mesh.rotate_ccw(h);
  } while (h >= 0 && h != start && out.size() <= static_cast<size_t>(mesh.num_halfedges()));
  return out;
}

bool is_boundary_vertex(const TriMesh& mesh, int v) {
  const int h = mesh.vertex_halfedge[v];
  return h >= 0 && mesh.opposite[h] < 0;
}

double corner_angle(const TriMesh& mesh, int h) {
  const Vec3 a = mesh.edge_vector(h), b = -mesh.edge_vector(TriMesh::prev(h));
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

std::vector<double> vertex_angle_sums(const TriMesh& mesh) {
  std::vector<double> sum(mesh.num_vertices(), 0.0);
  for (int h = 0; h < mesh.num_halfedges(); ++h) sum[mesh.from(h)] += corner_angle(mesh, h);
  return sum;
}

int count_boundary_loops(const TriMesh& mesh) {
  // Boundary halfedge h (no opposite) continues at the boundary halfedge leaving to(h).
  const int nh = mesh.num_halfedges();
  std::vector<char> seen(nh, 0);
  int loops = 0;
  for (int h = 0; h < nh; ++h) {
    if (mesh.opposite[h] >= 0 || seen[h]) continue;
    ++loops;
    int c = h;
    while (c >= 0 && !seen[c]) {
      seen[c] = 1;
      c = mesh.vertex_halfedge[mesh.to(c)];  // the boundary outgoing halfedge of the next vertex
    }
  }
  return loops;
}

}  // namespace qgp

#include "metrics/polygon_metrics.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <unordered_map>

#include "cross_field/cross_field.h"

namespace qgp {
namespace {

uint64_t edge_key(int a, int b) {
  return static_cast<uint64_t>(std::min(a, b)) << 32 | static_cast<uint32_t>(std::max(a, b));
}

// Segments hashed into a uniform grid, for "is there a segment within r of p" queries.
class SegmentGrid {
 public:
  SegmentGrid(std::vector<std::array<Vec3, 2>> segments, double cell) : segments_(std::move(segments)), cell_(cell) {
    for (int s = 0; s < static_cast<int>(segments_.size()); ++s) {
      const Vec3 lo = segments_[s][0].cwiseMin(segments_[s][1]), hi = segments_[s][0].cwiseMax(segments_[s][1]);
      const auto a = cell_of(lo), b = cell_of(hi);
      for (int64_t x = a[0]; x <= b[0]; ++x)
        for (int64_t y = a[1]; y <= b[1]; ++y)
          for (int64_t z = a[2]; z <= b[2]; ++z) cells_[key(x, y, z)].push_back(s);
    }
  }
  // Distance from p to the nearest segment, if it is below `cell` (else a value >= cell).
  double near_distance(const Vec3& p) const {
    const auto c = cell_of(p);
    double best = cell_;
    for (int64_t x = c[0] - 1; x <= c[0] + 1; ++x)
      for (int64_t y = c[1] - 1; y <= c[1] + 1; ++y)
        for (int64_t z = c[2] - 1; z <= c[2] + 1; ++z) {
          auto it = cells_.find(key(x, y, z));
          if (it == cells_.end()) continue;
          for (int s : it->second) best = std::min(best, point_segment_distance(p, segments_[s][0], segments_[s][1]));
        }
    return best;
  }

 private:
  std::array<int64_t, 3> cell_of(const Vec3& p) const {
    return {static_cast<int64_t>(std::floor(p.x() / cell_)), static_cast<int64_t>(std::floor(p.y() / cell_)),
            static_cast<int64_t>(std::floor(p.z() / cell_))};
  }
  static uint64_t key(int64_t x, int64_t y, int64_t z) {
    return (static_cast<uint64_t>(x) * 73856093u) ^ (static_cast<uint64_t>(y) * 19349663u) ^
           (static_cast<uint64_t>(z) * 83492791u);
  }
  std::vector<std::array<Vec3, 2>> segments_;
  double cell_;
  std::unordered_map<uint64_t, std::vector<int>> cells_;
};

}  // namespace

PolygonMeshMetrics measure_polygon_mesh(const PolygonSoup& mesh, const TriMesh& reference, double sharp_angle_deg,
                                        Progress& progress) {
  PolygonMeshMetrics m;
  m.faces = mesh.num_faces();
  // Topology over all faces.
  std::vector<char> used(mesh.num_vertices(), 0);
  std::unordered_map<uint64_t, int> edge_faces;
  QuadMesh quads;
  std::vector<std::array<int, 4>> quad_list;
  std::vector<std::array<int, 3>> triangles;  // fan triangulation of every face, for distances
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const int n = mesh.face_size(f);
    const int* idx = &mesh.face_vertices[mesh.face_start[f]];
    for (int i = 0; i < n; ++i) {
      used[idx[i]] = 1;
      ++edge_faces[edge_key(idx[i], idx[(i + 1) % n])];
    }
    for (int i = 1; i + 1 < n; ++i) triangles.push_back({idx[0], idx[i], idx[i + 1]});
    if (n == 4) quad_list.push_back({idx[0], idx[1], idx[2], idx[3]});
  }
  m.quads = static_cast<int>(quad_list.size());
  m.non_quads = m.faces - m.quads;
  m.vertices = static_cast<int>(std::count(used.begin(), used.end(), 1));
  for (const auto& [key, count] : edge_faces) m.non_manifold_edges += count > 2;
  m.euler_characteristic = m.vertices - static_cast<int>(edge_faces.size()) + m.faces;
  m.reference_euler_characteristic = reference.num_vertices() - reference.num_edges() + reference.num_faces();
  progress.check_cancel();

  // Quad quality on the quads; the distance over all faces.
  quads.V.resize(mesh.num_vertices(), 3);
  for (int v = 0; v < mesh.num_vertices(); ++v) quads.V.row(v) = mesh.positions[v].transpose();
  quads.Q.resize(m.quads, 4);
  for (int q = 0; q < m.quads; ++q)
    for (int k = 0; k < 4; ++k) quads.Q(q, k) = quad_list[q][k];
  QuadMetricsOptions options;
  options.hausdorff = false;
  m.quad = compute_quad_metrics(quads, reference, options, progress);
  const double diag = reference.bounding_box_diagonal();
  if (!triangles.empty() && reference.num_faces() > 0 && diag > 0) {
    std::mt19937 rng(1);
    std::vector<Vec3> rv(reference.num_vertices());
    for (int v = 0; v < reference.num_vertices(); ++v) rv[v] = reference.position(v);
    std::vector<std::array<int, 3>> rt(reference.num_faces());
    for (int f = 0; f < reference.num_faces(); ++f) rt[f] = {reference.F(f, 0), reference.F(f, 1), reference.F(f, 2)};
    const TriangleBvh reference_bvh(reference), mesh_bvh(quads.V, triangles);
    m.quad.hausdorff_quads_to_mesh =
        max_distance(sample_surface(mesh.positions, triangles, 100000, rng), reference_bvh, progress) / diag;
    m.quad.hausdorff_mesh_to_quads = max_distance(sample_surface(rv, rt, 100000, rng), mesh_bvh, progress) / diag;
    m.quad.hausdorff = std::max(m.quad.hausdorff_quads_to_mesh, m.quad.hausdorff_mesh_to_quads);
  }

  // Sharp edges of the reference covered by edges of the mesh.
  if (sharp_angle_deg >= 0 && diag > 0) {
    const std::vector<char> sharp = detect_feature_edges(reference, {}, sharp_angle_deg);
    m.sharp_edge_tolerance = 1e-3 * diag;
    std::vector<std::array<Vec3, 2>> segments;
    for (const auto& [key, count] : edge_faces)
      segments.push_back({mesh.positions[key >> 32], mesh.positions[key & 0xffffffffu]});
    const SegmentGrid grid(std::move(segments), m.sharp_edge_tolerance);
    double total = 0, covered = 0;
    for (int e = 0; e < reference.num_edges(); ++e) {
      if (!sharp[e]) continue;
      ++m.sharp_edges;
      const int h = reference.edge_halfedge[e];
      const Vec3 a = reference.position(reference.from(h)), b = reference.position(reference.to(h));
      const double len = (b - a).norm();
      constexpr int kSamples = 8;
      for (int i = 0; i < kSamples; ++i) {
        const Vec3 p = a + (i + 0.5) / kSamples * (b - a);
        total += len / kSamples;
        if (grid.near_distance(p) <= m.sharp_edge_tolerance) covered += len / kSamples;
      }
      if ((e & 1023) == 0) progress.check_cancel();
    }
    m.sharp_edge_coverage = total > 0 ? covered / total : 1.0;
  }
  return m;
}

void to_json(Json& j, const PolygonMeshMetrics& m) {
  j = m.quad;
  j["vertices"] = m.vertices;
  j["faces"] = m.faces;
  j["quads"] = m.quads;
  j["non_quads"] = m.non_quads;
  j["euler_characteristic"] = m.euler_characteristic;
  j["reference_euler_characteristic"] = m.reference_euler_characteristic;
  j["euler_characteristic_preserved"] = m.euler_characteristic == m.reference_euler_characteristic;
  j["non_manifold_edges"] = m.non_manifold_edges;
  j["sharp_edges"] = m.sharp_edges;
  j["sharp_edge_coverage"] = m.sharp_edge_coverage;
  j["sharp_edge_tolerance"] = m.sharp_edge_tolerance;
}

}  // namespace qgp

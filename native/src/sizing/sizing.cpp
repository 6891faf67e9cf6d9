#include "sizing/sizing.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>

namespace qgp {
namespace {

constexpr int kDensitySmoothingRounds = 5;

// Per vertex, a third of the area of its faces.
std::vector<double> vertex_areas(const TriMesh& mesh) {
  std::vector<double> area(mesh.num_vertices(), 0.0);
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const double a = 0.5 * mesh.face_normal_unnormalized(f).norm();
    for (int k = 0; k < 3; ++k) area[mesh.F(f, k)] += a / 3;
  }
  return area;
}

// Per vertex, the surface's bending around it: the sum over its non-feature edges of the dihedral
// angle times the edge length, per unit of the vertex's area: about 3.5 / r on a sphere of radius
// r, 0 on a plane.
std::vector<double> vertex_curvature(const TriMesh& mesh, const std::vector<char>& feature_edges,
                                     const std::vector<double>& area) {
  const int nv = mesh.num_vertices();
  std::vector<double> bending(nv, 0.0);
  for (int e = 0; e < mesh.num_edges(); ++e) {
    const int h = mesh.edge_halfedge[e], o = mesh.opposite[h];
    if (o < 0 || (!feature_edges.empty() && feature_edges[e])) continue;
    const Vec3 n0 = mesh.face_normal_unnormalized(TriMesh::face(h));
    const Vec3 n1 = mesh.face_normal_unnormalized(TriMesh::face(o));
    if (!(n0.norm() > 0) || !(n1.norm() > 0)) continue;
    const double angle = std::atan2(n0.cross(n1).norm(), n0.dot(n1));
    const double b = angle * mesh.edge_vector(h).norm();
    bending[mesh.from(h)] += b, bending[mesh.to(h)] += b;
  }
  std::vector<double> curvature(nv, 0.0);
  for (int v = 0; v < nv; ++v) curvature[v] = area[v] > 0 ? bending[v] / (2 * area[v]) : 0.0;
  return curvature;
}

// Each vertex's value averaged with its neighbours', `rounds` times (noise of a scan or a sculpt
// would otherwise make quads small at every bump).
std::vector<double> smoothed(const TriMesh& mesh, std::vector<double> values, int rounds) {
  for (int r = 0; r < rounds; ++r) {
    std::vector<double> sum(values), count(values.size(), 1.0);
    for (int e = 0; e < mesh.num_edges(); ++e) {
      const int h = mesh.edge_halfedge[e], a = mesh.from(h), b = mesh.to(h);
      sum[a] += values[b], sum[b] += values[a];
      count[a] += 1, count[b] += 1;
    }
    for (size_t v = 0; v < values.size(); ++v) values[v] = sum[v] / count[v];
  }
  return values;
}

// Per vertex, the curvature's edge-length multiple: (curvature / typical)^-adaptive, the ratio
// clamped to kMaxCurvatureRatio either way; typical is the area-weighted median curvature.
std::vector<double> curvature_sizes(const TriMesh& mesh, const std::vector<char>& feature_edges, double adaptive) {
  const std::vector<double> area = vertex_areas(mesh);
  const std::vector<double> curvature = smoothed(mesh, vertex_curvature(mesh, feature_edges, area), 3);
  std::vector<std::pair<double, double>> weighted;  // (curvature, area) per vertex
  double total = 0;
  for (int v = 0; v < mesh.num_vertices(); ++v) weighted.push_back({curvature[v], area[v]}), total += area[v];
  std::sort(weighted.begin(), weighted.end());
  double typical = 0, accumulated = 0;
  for (const auto& [c, a] : weighted)
    if ((accumulated += a) >= 0.5 * total) {
      typical = c;
      break;
    }
  std::vector<double> size(mesh.num_vertices(), 1.0);
  if (!(typical > 0)) return size;  // flat: nothing to adapt to
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    const double ratio = std::clamp(curvature[v] / typical, 1 / kMaxCurvatureRatio, kMaxCurvatureRatio);
    size[v] = std::pow(ratio, -adaptive);
  }
  return size;
}

}  // namespace

std::vector<double> face_sizes(const TriMesh& mesh, const std::vector<char>& feature_edges,
                               const SizingOptions& options) {
  const bool painted = !options.vertex_density.empty();
  if (!(options.adaptive > 0) && !painted) return {};
  std::vector<double> vertex_size(mesh.num_vertices(), 1.0);
  if (options.adaptive > 0) vertex_size = curvature_sizes(mesh, feature_edges, std::min(options.adaptive, 1.0));
  if (painted) {  // in log space, smoothed: a painted step becomes a ramp over a few rings
    std::vector<double> log_density(mesh.num_vertices());
    for (int v = 0; v < mesh.num_vertices(); ++v)
      log_density[v] = std::log(std::clamp(options.vertex_density[v], 1 / kMaxDensityRatio, kMaxDensityRatio));
    log_density = smoothed(mesh, std::move(log_density), kDensitySmoothingRounds);
    for (int v = 0; v < mesh.num_vertices(); ++v) vertex_size[v] /= std::exp(log_density[v]);
  }
  std::vector<double> sizes(mesh.num_faces());
  double area = 0, quads = 0;  // the quads at the target edge length, uniform and sized (times its square)
  for (int f = 0; f < mesh.num_faces(); ++f) {
    sizes[f] = std::cbrt(vertex_size[mesh.F(f, 0)] * vertex_size[mesh.F(f, 1)] * vertex_size[mesh.F(f, 2)]);
    const double a = 0.5 * mesh.face_normal_unnormalized(f).norm();
    area += a;
    quads += a / (sizes[f] * sizes[f]);
  }
  const double keep_count = area > 0 && quads > 0 ? std::sqrt(quads / area) : 1.0;
  for (double& s : sizes) s *= keep_count;
  return sizes;
}

uint64_t sizes_hash(const std::vector<double>& sizes) {
  uint64_t h = sizes.empty() ? 0 : 1469598103934665603ull;  // FNV-1a over the bytes
  for (double s : sizes) {
    uint64_t bits;
    std::memcpy(&bits, &s, sizeof bits);
    for (int i = 0; i < 8; ++i) h = (h ^ ((bits >> (8 * i)) & 0xff)) * 1099511628211ull;
  }
  return h;
}

}  // namespace qgp

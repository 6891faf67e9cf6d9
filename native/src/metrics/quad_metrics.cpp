#include "metrics/quad_metrics.h"

#include <algorithm>
#include <cmath>
#include <deque>
#include <memory>
#include <optional>
#include <random>
#include <unordered_map>

#include "core/parallel.h"
#include "quad_extraction/surface_projection.h"

namespace qgp {

namespace {

// Uses of an undirected edge in each direction (forward = from the lower to the higher index).
struct EdgeUses {
  int forward = 0, backward = 0;
  bool non_manifold() const { return forward + backward > 2; }
  bool inconsistent() const { return forward > 1 || backward > 1; }
};

uint64_t edge_key(int a, int b) { return (uint64_t(std::min(a, b)) << 32) | uint32_t(std::max(a, b)); }

std::unordered_map<uint64_t, EdgeUses> edge_uses(const QuadMesh& quads) {
  std::unordered_map<uint64_t, EdgeUses> edges;
  edges.reserve(4 * static_cast<size_t>(quads.num_quads()));
  for (int q = 0; q < quads.num_quads(); ++q)
    for (int k = 0; k < 4; ++k) {
      const int a = quads.Q(q, k), b = quads.Q(q, (k + 1) % 4);
      EdgeUses& u = edges[edge_key(a, b)];
      (a < b ? u.forward : u.backward)++;
    }
  return edges;
}

bool repeats_a_corner(const QuadMesh& quads, int q) {
  for (int k = 0; k < 4; ++k)
    for (int j = k + 1; j < 4; ++j)
      if (quads.Q(q, k) == quads.Q(q, j)) return true;
  return false;
}

}  // namespace

QuadTopology quad_topology(const QuadMesh& quads) {
  QuadTopology t;
  const int nv = quads.num_vertices(), nq = quads.num_quads();
  t.vertices = nv;
  t.faces = nq;
  const std::unordered_map<uint64_t, EdgeUses> edges = edge_uses(quads);
  std::vector<char> used(nv, 0);
  for (int q = 0; q < nq; ++q) {
    for (int k = 0; k < 4; ++k) used[quads.Q(q, k)] = 1;
    t.degenerate_quads += repeats_a_corner(quads, q);
  }
  t.edges = static_cast<int>(edges.size());
  t.valence.assign(nv, 0);
  t.on_boundary.assign(nv, 0);
  for (const auto& [key, u] : edges) {
    const int a = static_cast<int>(key >> 32), b = static_cast<int>(key & 0xffffffffu);
    ++t.valence[a], ++t.valence[b];
    const int n = u.forward + u.backward;
    if (n == 1) ++t.boundary_edges, t.on_boundary[a] = t.on_boundary[b] = 1;
    t.non_manifold_edges += u.non_manifold();
    t.inconsistent_edges += u.inconsistent();
  }
  for (int v = 0; v < nv; ++v) {
    if (!used[v]) {
      ++t.unreferenced_vertices;
      continue;
    }
    if (t.on_boundary[v])
      t.irregular_boundary += t.valence[v] != 3;
    else
      t.irregular_interior += t.valence[v] != 4;
  }
  t.euler_characteristic = t.vertices - t.edges + t.faces;
  return t;
}

std::vector<char> non_manifold_quads(const QuadMesh& quads) {
  const std::unordered_map<uint64_t, EdgeUses> edges = edge_uses(quads);
  std::vector<char> bad(quads.num_quads(), 0);
  for (int q = 0; q < quads.num_quads(); ++q) {
    bad[q] = repeats_a_corner(quads, q);
    for (int k = 0; k < 4 && !bad[q]; ++k) {
      const EdgeUses& u = edges.at(edge_key(quads.Q(q, k), quads.Q(q, (k + 1) % 4)));
      bad[q] = u.non_manifold() || u.inconsistent();
    }
  }
  return bad;
}

std::vector<Vec3> sample_surface(const std::vector<Vec3>& V, const std::vector<std::array<int, 3>>& T, int count,
                                 std::mt19937& rng) {
  std::vector<Vec3> samples(V.begin(), V.end());
  std::vector<double> cdf(T.size());
  double total = 0;
  for (size_t t = 0; t < T.size(); ++t) {
    total += 0.5 * (V[T[t][1]] - V[T[t][0]]).cross(V[T[t][2]] - V[T[t][0]]).norm();
    cdf[t] = total;
  }
  if (T.empty() || !(total > 0)) return samples;
  std::uniform_real_distribution<double> uniform(0, 1);
  for (int i = 0; i < count; ++i) {
    const size_t t =
        std::min(T.size() - 1, size_t(std::lower_bound(cdf.begin(), cdf.end(), uniform(rng) * total) - cdf.begin()));
    double r1 = uniform(rng), r2 = uniform(rng);
    if (r1 + r2 > 1) r1 = 1 - r1, r2 = 1 - r2;
    samples.push_back(V[T[t][0]] + r1 * (V[T[t][1]] - V[T[t][0]]) + r2 * (V[T[t][2]] - V[T[t][0]]));
  }
  return samples;
}

// Samples per thread below which max_distance starts no more threads.
constexpr double kMinSamplesPerThread = 2000;

// The largest distance from the samples to the target, the samples shared out among threads in
// ranges (a maximum is the same in any order). Only the calling thread checks for a cancel.
double max_distance(const std::vector<Vec3>& samples, const TriangleBvh& target, Progress& progress) {
  const int chunks = threads_for(double(samples.size()), kMinSamplesPerThread);
  std::vector<double> worst(chunks, 0.0);
  run_chunks(chunks, [&](int t) {
    const size_t begin = samples.size() * t / chunks, end = samples.size() * (t + 1) / chunks;
    for (size_t i = begin; i < end; ++i) {
      if (t == 0 && ((i - begin) & 1023) == 0) progress.check_cancel();
      worst[t] = std::max(worst[t], target.closest_point(samples[i]).squared_distance);
    }
  });
  return std::sqrt(*std::max_element(worst.begin(), worst.end()));
}

Vec3 quad_reference_normal(const Vec3 p[4], const TriMesh& reference, const TriangleBvh& reference_bvh,
                           OnCrease on_crease) {
  // Interior points of the bilinear quad (unlike corners on a sharp edge) have an unambiguous
  // closest triangle when the quad lies on the surface.
  // Where coincident sheets face opposite ways, the one facing with the quad counts.
  const Vec3 normal = (p[2] - p[0]).cross(p[3] - p[1]);
  const double tolerance = kCoincidentSheets * std::max((p[2] - p[0]).norm(), (p[3] - p[1]).norm());
  Vec3 sum = Vec3::Zero();
  const double at[5][2] = {{0.5, 0.5}, {0.25, 0.25}, {0.75, 0.25}, {0.75, 0.75}, {0.25, 0.75}};
  for (const auto& st : at) {
    const Vec3 x = (1 - st[0]) * (1 - st[1]) * p[0] + st[0] * (1 - st[1]) * p[1] + st[0] * st[1] * p[2] +
                   (1 - st[0]) * st[1] * p[3];
    const TriangleBvh::Hit hit = reference_bvh.closest_point_facing(x, normal, tolerance, on_crease);
    if (hit.triangle >= 0) sum += reference.face_normal_unnormalized(hit.triangle).normalized();
  }
  return sum;
}

bool quad_is_flipped(const Vec3 p[4], const TriMesh& reference, const TriangleBvh& reference_bvh, OnCrease on_crease) {
  const Vec3 normal = (p[2] - p[0]).cross(p[3] - p[1]);
  return !(normal.dot(quad_reference_normal(p, reference, reference_bvh, on_crease)) > 0);
}

bool quad_is_flipped(const QuadMesh& quads, int q, const TriMesh& reference, const TriangleBvh& reference_bvh,
                     OnCrease on_crease) {
  Vec3 p[4];
  for (int k = 0; k < 4; ++k) p[k] = quads.V.row(quads.Q(q, k)).transpose();
  return quad_is_flipped(p, reference, reference_bvh, on_crease);
}

bool quad_has_collapsed_edge(const Vec3 p[4]) {
  double length[4], sum = 0;
  for (int k = 0; k < 4; ++k) sum += length[k] = (p[(k + 1) % 4] - p[k]).norm();
  return *std::min_element(length, length + 4) <= kCollapsedEdgeShare * sum / 4;
}

bool quad_has_collapsed_edge(const QuadMesh& quads, int q) {
  Vec3 p[4];
  for (int k = 0; k < 4; ++k) p[k] = quads.V.row(quads.Q(q, k)).transpose();
  return quad_has_collapsed_edge(p);
}

int quads_with_a_collapsed_edge(const QuadMesh& quads) {
  int count = 0;
  for (int q = 0; q < quads.num_quads(); ++q) count += quad_has_collapsed_edge(quads, q);
  return count;
}

namespace {

// The reference surface per part, each with its own BVH, for judging a quad against its own part.
class PartSurfaces {
 public:
  PartSurfaces(const TriMesh& reference, const std::vector<int>& face_part) {
    std::vector<std::vector<int>> faces;
    for (int f = 0; f < reference.num_faces(); ++f) {
      const int part = face_part[f];
      if (part < 0) continue;
      if (part >= static_cast<int>(faces.size())) faces.resize(part + 1);
      faces[part].push_back(f);
    }
    for (const std::vector<int>& part_faces : faces) {
      meshes_.push_back(part_mesh(reference, part_faces));
      bvhs_.push_back(std::make_unique<TriangleBvh>(meshes_.back()));
    }
  }
  // Null for a part without reference faces.
  const TriMesh* mesh(int part) const { return has(part) ? &meshes_[part] : nullptr; }
  const TriangleBvh* bvh(int part) const { return has(part) ? bvhs_[part].get() : nullptr; }

 private:
  bool has(int part) const {
    return part >= 0 && part < static_cast<int>(meshes_.size()) && meshes_[part].num_faces() > 0;
  }
  // The faces as a mesh of their own: positions and triangles only (face normals need no more).
  static TriMesh part_mesh(const TriMesh& reference, const std::vector<int>& faces) {
    TriMesh m;
    std::vector<int> local(reference.num_vertices(), -1);
    int n = 0;
    m.F.resize(static_cast<int>(faces.size()), 3);
    for (size_t i = 0; i < faces.size(); ++i)
      for (int k = 0; k < 3; ++k) {
        int& v = local[reference.F(faces[i], k)];
        if (v < 0) v = n++;
        m.F(static_cast<int>(i), k) = v;
      }
    m.V.resize(n, 3);
    for (int v = 0; v < reference.num_vertices(); ++v)
      if (local[v] >= 0) m.V.row(local[v]) = reference.V.row(v);
    return m;
  }
  std::deque<TriMesh> meshes_;
  std::vector<std::unique_ptr<TriangleBvh>> bvhs_;
};

}  // namespace

QuadMetrics compute_quad_metrics(const QuadMesh& quads, const TriMesh& reference, const QuadMetricsOptions& options,
                                 Progress& progress) {
  QuadMetrics m;
  m.topology = quad_topology(quads);
  m.irregular_vertices = m.topology.irregular_interior + m.topology.irregular_boundary;
  const int nq = quads.num_quads();
  const TriangleBvh reference_bvh(reference);
  const bool by_part = !options.reference_component.empty() && !quads.component.empty();
  std::optional<PartSurfaces> parts;
  if (by_part) parts.emplace(reference, options.reference_component);

  std::vector<double> deviations;
  deviations.reserve(4 * static_cast<size_t>(nq));
  for (int q = 0; q < nq; ++q) {
    if ((q & 1023) == 0) progress.check_cancel();
    Vec3 p[4];
    for (int k = 0; k < 4; ++k) p[k] = quads.V.row(quads.Q(q, k)).transpose();
    const Vec3 normal = (p[2] - p[0]).cross(p[3] - p[1]);
    const double normal_length = normal.norm();
    for (int k = 0; k < 4; ++k) {
      const Vec3 e1 = p[(k + 1) % 4] - p[k], e2 = p[(k + 3) % 4] - p[k];
      const double l = e1.norm() * e2.norm();
      const double sj = l > 0 && normal_length > 0 ? e1.cross(e2).dot(normal) / (l * normal_length) : -1;
      m.min_scaled_jacobian = std::min(m.min_scaled_jacobian, sj);
      const double angle = l > 0 ? std::acos(std::clamp(e1.dot(e2) / l, -1.0, 1.0)) * 180 / M_PI : 0;
      deviations.push_back(std::abs(angle - 90));
    }
    const TriMesh* own = by_part ? parts->mesh(quads.component[q]) : nullptr;
    const bool flipped = own ? quad_is_flipped(p, *own, *parts->bvh(quads.component[q]), OnCrease::FacingSide)
                             : quad_is_flipped(p, reference, reference_bvh, OnCrease::FacingSide);
    if (flipped) m.flipped_quad_ids.push_back(q);
    if (quad_has_collapsed_edge(p)) m.collapsed_edge_quad_ids.push_back(q);
  }
  if (!deviations.empty()) {
    double sum = 0;
    for (double d : deviations) sum += d;
    m.mean_angle_deviation = sum / deviations.size();
    const size_t k = std::min(deviations.size() - 1, static_cast<size_t>(0.95 * deviations.size()));
    std::nth_element(deviations.begin(), deviations.begin() + k, deviations.end());
    m.p95_angle_deviation = deviations[k];
  }
  if (nq == 0) m.min_scaled_jacobian = 0;

  if (options.hausdorff && nq > 0 && reference.num_faces() > 0) {
    const double diagonal = reference.bounding_box_diagonal();
    const double scale = diagonal > 0 ? 1 / diagonal : 1;
    const std::array<double, 2> d =
        hausdorff_distances(quads, reference, reference_bvh, options.hausdorff_samples, options.seed, progress);
    m.hausdorff_quads_to_mesh = scale * d[0];
    m.hausdorff_mesh_to_quads = scale * d[1];
    m.hausdorff = std::max(m.hausdorff_quads_to_mesh, m.hausdorff_mesh_to_quads);
  }
  return m;
}

std::array<double, 2> hausdorff_distances(const QuadMesh& quads, const TriMesh& reference,
                                          const TriangleBvh& reference_bvh, int samples, uint32_t seed,
                                          Progress& progress) {
  const int nq = quads.num_quads();
  if (nq == 0 || reference.num_faces() == 0) return {0.0, 0.0};
  std::mt19937 rng(seed);
  std::vector<Vec3> qv(quads.V.rows());
  for (int v = 0; v < quads.V.rows(); ++v) qv[v] = quads.V.row(v).transpose();
  std::vector<std::array<int, 3>> qt;
  qt.reserve(2 * static_cast<size_t>(nq));
  for (int q = 0; q < nq; ++q) {
    qt.push_back({quads.Q(q, 0), quads.Q(q, 1), quads.Q(q, 2)});
    qt.push_back({quads.Q(q, 0), quads.Q(q, 2), quads.Q(q, 3)});
  }
  std::vector<Vec3> rv(reference.num_vertices());
  for (int v = 0; v < reference.num_vertices(); ++v) rv[v] = reference.position(v);
  std::vector<std::array<int, 3>> rt(reference.num_faces());
  for (int f = 0; f < reference.num_faces(); ++f) rt[f] = {reference.F(f, 0), reference.F(f, 1), reference.F(f, 2)};
  const TriangleBvh quad_bvh(quads.V, qt);
  const double quads_to_mesh = max_distance(sample_surface(qv, qt, samples, rng), reference_bvh, progress);
  return {quads_to_mesh, max_distance(sample_surface(rv, rt, samples, rng), quad_bvh, progress)};
}

void to_json(Json& j, const QuadMetrics& m) {
  j["faces"] = m.topology.faces;
  j["vertices"] = m.topology.vertices;
  j["irregular_vertices"] = m.irregular_vertices;
  j["irregular_interior"] = m.topology.irregular_interior;
  j["irregular_boundary"] = m.topology.irregular_boundary;
  j["euler_characteristic"] = m.topology.euler_characteristic;
  j["boundary_edges"] = m.topology.boundary_edges;
  j["non_manifold_edges"] = m.topology.non_manifold_edges;
  j["inconsistent_edges"] = m.topology.inconsistent_edges;
  j["min_scaled_jacobian"] = m.min_scaled_jacobian;
  j["mean_angle_deviation_deg"] = m.mean_angle_deviation;
  j["p95_angle_deviation_deg"] = m.p95_angle_deviation;
  j["flipped_quads"] = m.flipped_quads();
  j["flipped_quad_ids"] = m.flipped_quad_ids;
  j["collapsed_edge_quads"] = m.collapsed_edge_quads();
  j["collapsed_edge_quad_ids"] = m.collapsed_edge_quad_ids;
  j["hausdorff"] = m.hausdorff;
  j["hausdorff_quads_to_mesh"] = m.hausdorff_quads_to_mesh;
  j["hausdorff_mesh_to_quads"] = m.hausdorff_mesh_to_quads;
}

}  // namespace qgp

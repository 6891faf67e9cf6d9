#include "quad_extraction/untangle_quads.h"

#include <algorithm>

#include "core/error.h"
#include "core/timer.h"
#include "quad_extraction/quad_metrics.h"
#include "quad_extraction/surface_projection.h"

namespace qgp {

namespace {

// Quad vertices that must stay: on a feature or boundary edge or at a feature vertex of the surface.
std::vector<char> pinned_to_features(const QuadMesh& quads, const TriMesh& surface, const std::vector<char>& feature_edges) {
  auto is_feature = [&](int e) { return surface.is_boundary_edge(e) || (!feature_edges.empty() && feature_edges[e]); };
  std::vector<char> feature_vertex(surface.num_vertices(), 0);
  for (int e = 0; e < surface.num_edges(); ++e)
    if (is_feature(e)) {
      const int h = surface.edge_halfedge[e];
      feature_vertex[surface.from(h)] = feature_vertex[surface.to(h)] = 1;
    }
  std::vector<char> pinned(quads.num_vertices(), 0);
  for (int v = 0; v < quads.num_vertices(); ++v) {
    const int f = quads.vertex_face[v];
    if (f < 0 || f >= surface.num_faces()) {
      pinned[v] = 1;
      continue;
    }
    const Vec3 p = quads.V.row(v).transpose();
    for (int k = 0; k < 3 && !pinned[v]; ++k) {
      const Vec3 a = surface.position(surface.F(f, k)), b = surface.position(surface.F(f, (k + 1) % 3));
      const double tolerance = 1e-6 * (b - a).norm();
      if (is_feature(surface.edge_of[3 * f + k]) && point_segment_distance(p, a, b) <= tolerance) pinned[v] = 1;
      if (feature_vertex[surface.F(f, k)] && (p - a).norm() <= tolerance) pinned[v] = 1;
    }
  }
  return pinned;
}

}  // namespace

UntangleStats untangle_flipped_quads(QuadMesh& quads, const TriMesh& surface, const std::vector<char>& feature_edges,
                                     Progress& progress, int max_rings) {
  Timer timer;
  UntangleStats stats;
  const int nv = quads.num_vertices(), nq = quads.num_quads();
  if (static_cast<int>(quads.vertex_face.size()) != nv)
    throw Error(ErrorCode::Internal, "untangle: the quads have no surface triangle per vertex");
  if (!feature_edges.empty() && static_cast<int>(feature_edges.size()) != surface.num_edges())
    throw Error(ErrorCode::Internal, "untangle: the feature edges do not match the surface");
  const TriangleBvh bvh(surface);
  auto corners = [&](int q, Vec3 p[4]) {
    for (int k = 0; k < 4; ++k) p[k] = quads.V.row(quads.Q(q, k)).transpose();
  };
  auto is_flipped = [&](int q) {
    Vec3 p[4];
    corners(q, p);
    return quad_is_flipped(p, surface, bvh);
  };
  std::vector<char> flipped(nq, 0);
  for (int q = 0; q < nq; ++q) {
    if ((q & 1023) == 0) progress.check_cancel();
    flipped[q] = is_flipped(q);
    stats.flipped_before += flipped[q];
  }
  stats.flipped_after = stats.flipped_before;
  if (stats.flipped_before == 0) {
    stats.seconds = timer.seconds();
    return stats;
  }

  // Vertex -> quads and edge neighbours.
  std::vector<std::vector<int>> vertex_quads(nv), neighbours(nv);
  for (int q = 0; q < nq; ++q)
    for (int k = 0; k < 4; ++k) {
      const int v = quads.Q(q, k);
      vertex_quads[v].push_back(q);
      for (int w : {quads.Q(q, (k + 1) % 4), quads.Q(q, (k + 3) % 4)})
        if (std::find(neighbours[v].begin(), neighbours[v].end(), w) == neighbours[v].end()) neighbours[v].push_back(w);
    }
  std::vector<char> fixed = pinned_to_features(quads, surface, feature_edges);
  const QuadTopology topology = quad_topology(quads);
  for (int v = 0; v < nv; ++v) fixed[v] = fixed[v] || topology.on_boundary[v] || vertex_quads[v].empty();

  std::vector<char> moved(nv, 0);
  for (int rings = 0; rings <= max_rings && stats.flipped_after > 0;) {
    progress.check_cancel();
    ++stats.rounds;
    // The vertices of the flipped quads and `rings` rings around them; the free ones move.
    std::vector<char> in_region(nv, 0);
    std::vector<int> frontier;
    for (int q = 0; q < nq; ++q)
      if (flipped[q])
        for (int k = 0; k < 4; ++k)
          if (!in_region[quads.Q(q, k)]) in_region[quads.Q(q, k)] = 1, frontier.push_back(quads.Q(q, k));
    for (int r = 0; r < rings; ++r) {
      std::vector<int> next;
      for (int v : frontier)
        for (int w : neighbours[v])
          if (!in_region[w]) in_region[w] = 1, next.push_back(w);
      frontier.swap(next);
    }
    std::vector<int> movable, affected;
    std::vector<char> is_affected(nq, 0);
    for (int v = 0; v < nv; ++v)
      if (in_region[v] && !fixed[v]) {
        movable.push_back(v);
        for (int q : vertex_quads[v])
          if (!is_affected[q]) is_affected[q] = 1, affected.push_back(q);
      }
    int before = 0;
    for (int q : affected) before += flipped[q];
    if (movable.empty() || before == 0) {
      ++rings;
      continue;
    }
    std::vector<Vec3> old_position(movable.size());
    std::vector<int> old_face(movable.size());
    for (size_t i = 0; i < movable.size(); ++i) {
      old_position[i] = quads.V.row(movable[i]).transpose();
      old_face[i] = quads.vertex_face[movable[i]];
    }
    // A few Jacobi steps of the umbrella average, each projected onto the surface.
    std::vector<Vec3> target(movable.size());
    for (int step = 0; step < 5; ++step) {
      for (size_t i = 0; i < movable.size(); ++i) {
        Vec3 sum = Vec3::Zero();
        for (int w : neighbours[movable[i]]) sum += quads.V.row(w).transpose();
        target[i] = sum / static_cast<double>(neighbours[movable[i]].size());
      }
      for (size_t i = 0; i < movable.size(); ++i) {
        const TriangleBvh::Hit hit = bvh.closest_point(target[i]);
        if (hit.triangle < 0) continue;
        quads.V.row(movable[i]) = hit.point.transpose();
        quads.vertex_face[movable[i]] = hit.triangle;
      }
    }
    std::vector<char> now(affected.size());
    int after = 0;
    for (size_t i = 0; i < affected.size(); ++i) after += now[i] = is_flipped(affected[i]);
    if (after < before) {
      for (size_t i = 0; i < affected.size(); ++i) flipped[affected[i]] = now[i];
      for (int v : movable) moved[v] = 1;
      stats.flipped_after -= before - after;
      ++stats.accepted_rounds;
    } else {
      for (size_t i = 0; i < movable.size(); ++i) {
        quads.V.row(movable[i]) = old_position[i].transpose();
        quads.vertex_face[movable[i]] = old_face[i];
      }
      ++rings;
    }
  }
  stats.moved_vertices = static_cast<int>(std::count(moved.begin(), moved.end(), 1));
  stats.seconds = timer.seconds();
  return stats;
}

}  // namespace qgp

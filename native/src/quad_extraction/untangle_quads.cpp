#include "quad_extraction/untangle_quads.h"

#include <algorithm>
#include <limits>

#include "core/error.h"
#include "core/timer.h"
#include "quad_extraction/quad_metrics.h"
#include "quad_extraction/surface_projection.h"

namespace qgp {

namespace {

// Largest distance, in mean edge lengths of the moved vertices, from a moved vertex's old position
// (on the surface) to the quads after the move.
constexpr double kMaxSurfaceGap = 0.5;

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
  // Each cluster of flipped quads (sharing vertices) is repaired on its own, so that a move that
  // helps one place is not refused because of another.
  std::vector<int> cluster_of(nq, -1);
  auto clusters = [&] {
    std::fill(cluster_of.begin(), cluster_of.end(), -1);
    std::vector<std::vector<int>> out;
    for (int seed = 0; seed < nq; ++seed) {
      if (!flipped[seed] || cluster_of[seed] >= 0) continue;
      out.emplace_back();
      std::vector<int> stack = {seed};
      cluster_of[seed] = static_cast<int>(out.size()) - 1;
      while (!stack.empty()) {
        const int q = stack.back();
        stack.pop_back();
        out.back().push_back(q);
        for (int k = 0; k < 4; ++k)
          for (int r : vertex_quads[quads.Q(q, k)])
            if (flipped[r] && cluster_of[r] < 0) cluster_of[r] = cluster_of[seed], stack.push_back(r);
      }
    }
    return out;
  };
  // Distance from x to the quads (two triangles each, split at corner 0).
  auto distance_to_quads = [&](const Vec3& x, const std::vector<int>& list) {
    double best = std::numeric_limits<double>::infinity();
    for (int q : list) {
      Vec3 p[4];
      corners(q, p);
      best = std::min({best, (closest_point_on_triangle(x, p[0], p[1], p[2]) - x).norm(),
                       (closest_point_on_triangle(x, p[0], p[2], p[3]) - x).norm()});
    }
    return best;
  };
  std::vector<char> in_region(nv, 0), is_affected(nq, 0);
  for (int rings = 0; rings <= max_rings && stats.flipped_after > 0; ++rings) {
    progress.check_cancel();
    ++stats.rounds;
    for (const std::vector<int>& cluster : clusters()) {
      // The cluster's vertices and `rings` rings around them; the free ones move.
      std::vector<int> region;
      for (int q : cluster)
        for (int k = 0; k < 4; ++k)
          if (!in_region[quads.Q(q, k)]) in_region[quads.Q(q, k)] = 1, region.push_back(quads.Q(q, k));
      for (int r = 0, begin = 0; r < rings; ++r) {
        const int end = static_cast<int>(region.size());
        for (int i = begin; i < end; ++i)
          for (int w : neighbours[region[i]])
            if (!in_region[w]) in_region[w] = 1, region.push_back(w);
        begin = end;
      }
      std::vector<int> movable, affected;
      for (int v : region)
        if (!fixed[v]) {
          movable.push_back(v);
          for (int q : vertex_quads[v])
            if (!is_affected[q]) is_affected[q] = 1, affected.push_back(q);
        }
      for (int v : region) in_region[v] = 0;
      for (int q : affected) is_affected[q] = 0;
      int before = 0;
      for (int q : affected) before += flipped[q];
      if (movable.empty() || before == 0) continue;
      std::vector<Vec3> old_position(movable.size());
      std::vector<int> old_face(movable.size());
      double edge_sum = 0;
      int edge_count = 0;
      for (size_t i = 0; i < movable.size(); ++i) {
        old_position[i] = quads.V.row(movable[i]).transpose();
        old_face[i] = quads.vertex_face[movable[i]];
        for (int w : neighbours[movable[i]]) edge_sum += (quads.V.row(w).transpose() - old_position[i]).norm(), ++edge_count;
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
      // The quads must still pass close to where the moved vertices were (on the surface): a move
      // that unfolds by cutting off a tip or a ridge is refused.
      const double tolerance = kMaxSurfaceGap * edge_sum / std::max(1, edge_count);
      bool faithful = true;
      for (size_t i = 0; i < movable.size() && faithful; ++i)
        faithful = distance_to_quads(old_position[i], affected) <= tolerance;
      std::vector<char> now(affected.size());
      int after = before;
      if (faithful) {
        after = 0;
        for (size_t i = 0; i < affected.size(); ++i) after += now[i] = is_flipped(affected[i]);
      }
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
      }
    }
  }
  stats.moved_vertices = static_cast<int>(std::count(moved.begin(), moved.end(), 1));
  stats.seconds = timer.seconds();
  return stats;
}

}  // namespace qgp

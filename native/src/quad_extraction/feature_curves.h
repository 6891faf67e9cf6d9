// The feature and boundary curves of a surface, for quad vertices that lie on them (the untangle
// slides them along; the collapse keeps them in place).
#pragma once
#include <algorithm>
#include <cmath>
#include <vector>

#include "core/mesh.h"
#include "quad_extraction/surface_projection.h"

namespace qgp {

// The feature and boundary edges of a surface as curves that quad vertices on them slide along.
// Quad vertices at curve corners (surface vertices with other than two feature or boundary edges,
// or where the curve turns by more than a degree) never move, and none slides past a corner, so the
// quad edges along a curve keep its shape.
class FeatureCurves {
 public:
  FeatureCurves(const TriMesh& surface, const std::vector<char>& feature_edges)
      : surface_(surface), feature_edges_(feature_edges), edges_at_(surface.num_vertices()) {
    for (int e = 0; e < surface.num_edges(); ++e)
      if (is_curve(e)) {
        const int h = surface.edge_halfedge[e];
        edges_at_[surface.from(h)].push_back(e);
        edges_at_[surface.to(h)].push_back(e);
      }
    corner_.assign(surface.num_vertices(), 0);
    for (int u = 0; u < surface.num_vertices(); ++u) {
      if (edges_at_[u].empty()) continue;
      if (edges_at_[u].size() != 2) {
        corner_[u] = 1;
        continue;
      }
      Vec3 d[2];
      for (int i = 0; i < 2; ++i) {
        const int h = surface.edge_halfedge[edges_at_[u][i]];
        d[i] = (surface.position(surface.from(h) == u ? surface.to(h) : surface.from(h)) - surface.position(u))
                   .normalized();
      }
      corner_[u] = !(d[0].dot(d[1]) < -std::cos(M_PI / 180));
    }
  }

  // Where a quad vertex at p in surface triangle f sits.
  struct Place {
    enum Kind { kFree, kOnCurve, kCorner } kind = kFree;
    int edge = -1;  // kOnCurve: the surface edge ...
    double s = 0;   // ... and the parameter along it, from(edge_halfedge) = 0 to to(edge_halfedge) = 1
  };
  Place locate(const Vec3& p, int f) const {
    Place place;
    if (f < 0 || f >= surface_.num_faces()) {
      place.kind = Place::kCorner;
      return place;
    }
    for (int k = 0; k < 3; ++k) {
      const int u = surface_.F(f, k);
      const Vec3 a = surface_.position(u), b = surface_.position(surface_.F(f, (k + 1) % 3));
      const double tolerance = 1e-6 * (b - a).norm();
      if (edges_at_[u].empty() || (p - a).norm() > tolerance) continue;
      if (corner_[u]) {
        place.kind = Place::kCorner;
        return place;
      }
      place = {Place::kOnCurve, edges_at_[u][0],
               surface_.from(surface_.edge_halfedge[edges_at_[u][0]]) == u ? 0.0 : 1.0};
    }
    if (place.kind != Place::kFree) return place;
    for (int k = 0; k < 3; ++k) {
      const int e = surface_.edge_of[3 * f + k];
      const Vec3 a = surface_.position(surface_.F(f, k)), b = surface_.position(surface_.F(f, (k + 1) % 3));
      if (!is_curve(e) || point_segment_distance(p, a, b) > 1e-6 * (b - a).norm()) continue;
      const int h = surface_.edge_halfedge[e];
      const Vec3 from = surface_.position(surface_.from(h)), along = surface_.edge_vector(h);
      place = {Place::kOnCurve, e, std::clamp((p - from).dot(along) / along.squaredNorm(), 0.0, 1.0)};
    }
    return place;
  }

  Vec3 point(const Place& place) const {
    const int h = surface_.edge_halfedge[place.edge];
    return surface_.position(surface_.from(h)) + place.s * surface_.edge_vector(h);
  }
  // Unit direction of increasing s.
  Vec3 direction(const Place& place) const {
    return surface_.edge_vector(surface_.edge_halfedge[place.edge]).normalized();
  }
  int face(const Place& place) const { return TriMesh::face(surface_.edge_halfedge[place.edge]); }

  // The place `distance` away along the curve (towards increasing s if positive), stopping at corners.
  Place walk(Place place, double distance) const {
    int dir = distance >= 0 ? 1 : -1;
    double left = std::abs(distance);
    for (int guard = 0; guard < 100000; ++guard) {
      const int h = surface_.edge_halfedge[place.edge];
      const double length = surface_.edge_vector(h).norm();
      const double room = (dir > 0 ? 1 - place.s : place.s) * length;
      if (left <= room) {
        if (length > 0) place.s = std::clamp(place.s + dir * left / length, 0.0, 1.0);
        return place;
      }
      left -= room;
      const int u = dir > 0 ? surface_.to(h) : surface_.from(h);
      place.s = dir > 0 ? 1 : 0;
      if (corner_[u]) return place;
      place.edge = edges_at_[u][0] == place.edge ? edges_at_[u][1] : edges_at_[u][0];
      const bool forward = surface_.from(surface_.edge_halfedge[place.edge]) == u;
      dir = forward ? 1 : -1;
      place.s = forward ? 0 : 1;
    }
    return place;
  }

 private:
  bool is_curve(int e) const { return surface_.is_boundary_edge(e) || (!feature_edges_.empty() && feature_edges_[e]); }

  const TriMesh& surface_;
  const std::vector<char>& feature_edges_;
  std::vector<std::vector<int>> edges_at_;  // per surface vertex: its feature and boundary edges
  std::vector<char> corner_;                // per surface vertex
};

}  // namespace qgp

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
// or where the curve turns by more than a degree) never move, and none slides onto or past a
// corner, so the quad edges along a curve keep its shape (the untangle frees one of two quad
// vertices that share a corner: untangle_quads.cpp).
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
    const int u = curve_vertex_at(p, f);
    if (u >= 0 && corner_[u]) place.kind = Place::kCorner;
    if (u >= 0 && !corner_[u]) place = start_of(edges_at_[u][0], u);
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

  // Where a quad vertex at the corner at p (in surface triangle f) can leave it: the start of each
  // curve edge there. None when p is not at a corner.
  std::vector<Place> corner_exits(const Vec3& p, int f) const {
    std::vector<Place> exits;
    const int u = f >= 0 && f < surface_.num_faces() ? curve_vertex_at(p, f) : -1;
    if (u >= 0 && corner_[u])
      for (int e : edges_at_[u]) exits.push_back(start_of(e, u));
    return exits;
  }
  // Unit direction from the curve vertex at a place's end of its edge (s = 0 or 1) into the edge.
  Vec3 direction_from_end(const Place& place) const { return place.s == 0 ? direction(place) : -direction(place); }

  // The place is at a corner (a curve's end, or where it turns).
  bool at_corner(const Place& place) const {
    const int h = surface_.edge_halfedge[place.edge];
    return (place.s == 0 && corner_[surface_.from(h)]) || (place.s == 1 && corner_[surface_.to(h)]);
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
  // The vertex of triangle f on a curve that p lies on (within 1e-6 of an edge of f at it), or -1.
  int curve_vertex_at(const Vec3& p, int f) const {
    int at = -1;
    for (int k = 0; k < 3; ++k) {
      const int u = surface_.F(f, k);
      const Vec3 a = surface_.position(u), b = surface_.position(surface_.F(f, (k + 1) % 3));
      if (edges_at_[u].empty() || (p - a).norm() > 1e-6 * (b - a).norm()) continue;
      if (corner_[u]) return u;
      at = u;
    }
    return at;
  }
  // The place on curve edge e at its vertex u.
  Place start_of(int e, int u) const {
    return {Place::kOnCurve, e, surface_.from(surface_.edge_halfedge[e]) == u ? 0.0 : 1.0};
  }

  const TriMesh& surface_;
  const std::vector<char>& feature_edges_;
  std::vector<std::vector<int>> edges_at_;  // per surface vertex: its feature and boundary edges
  std::vector<char> corner_;                // per surface vertex
};

}  // namespace qgp

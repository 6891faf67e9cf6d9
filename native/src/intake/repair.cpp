#include "intake/repair.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <string>
#include <tuple>
#include <unordered_map>
#include <unordered_set>

#include "core/error.h"

namespace qgp {
namespace {

uint64_t edge_key(int a, int b) {
  const uint64_t lo = static_cast<uint32_t>(std::min(a, b)), hi = static_cast<uint32_t>(std::max(a, b));
  return lo << 32 | hi;
}

// Union-find with path halving.
struct DisjointSets {
  std::vector<int> parent;
  explicit DisjointSets(int n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  int find(int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  void unite(int a, int b) { parent[find(a)] = find(b); }
};

// Triangles incident to each undirected edge, grouped by sorting (edge key, triangle).
struct EdgeFaces {
  std::vector<std::pair<uint64_t, int>> sorted;  // (key, 3*triangle + local edge)
  explicit EdgeFaces(const TriangleSoup& soup) {
    sorted.reserve(soup.triangles.size() * 3);
    for (int t = 0; t < static_cast<int>(soup.triangles.size()); ++t)
      for (int k = 0; k < 3; ++k)
        sorted.push_back({edge_key(soup.triangles[t][k], soup.triangles[t][(k + 1) % 3]), 3 * t + k});
    sort_by_edge_key(sorted, static_cast<int>(soup.positions.size()));
  }
  // Calls fn(first, last) for each run of halfedges sharing an undirected edge.
  template <class Fn>
  void for_each_edge(Fn fn) const {
    for (size_t i = 0; i < sorted.size();) {
      size_t j = i + 1;
      while (j < sorted.size() && sorted[j].first == sorted[i].first) ++j;
      fn(i, j);
      i = j;
    }
  }
};

double triangle_area(const TriangleSoup& soup, int t) {
  const auto& tri = soup.triangles[t];
  const Vec3 &a = soup.positions[tri[0]], &b = soup.positions[tri[1]], &c = soup.positions[tri[2]];
  return 0.5 * (b - a).cross(c - a).norm();
}

// Ear clipping of one polygon projected onto its Newell plane; falls back to a fan.
// Smallest corner angle of triangle (a, b, c).
double min_angle(const Vec3& a, const Vec3& b, const Vec3& c) {
  auto angle = [](const Vec3& p, const Vec3& q, const Vec3& r) {
    const Vec3 u = q - p, v = r - p;
    return std::atan2(u.cross(v).norm(), u.dot(v));
  };
  return std::min({angle(a, b, c), angle(b, c, a), angle(c, a, b)});
}

// Ear clipping of one polygon projected onto its Newell plane; falls back to a fan. Diagonals
// that are already edges of the mesh (`existing`) are avoided: they would be non-manifold.
void triangulate_polygon(const PolygonSoup& soup, int f, const std::unordered_set<uint64_t>& existing,
                         std::vector<std::array<int, 3>>& out) {
  const int n = soup.face_size(f);
  // From the polygon's lowest vertex: ties between diagonals then do not depend on where the
  // file's corner list starts.
  std::vector<int> corners(&soup.face_vertices[soup.face_start[f]], &soup.face_vertices[soup.face_start[f]] + n);
  std::rotate(corners.begin(), std::min_element(corners.begin(), corners.end()), corners.end());
  const int* idx = corners.data();
  Vec3 normal = Vec3::Zero();
  for (int i = 0; i < n; ++i) {
    const Vec3& p = soup.positions[idx[i]];
    const Vec3& q = soup.positions[idx[(i + 1) % n]];
    normal +=
        Vec3((p.y() - q.y()) * (p.z() + q.z()), (p.z() - q.z()) * (p.x() + q.x()), (p.x() - q.x()) * (p.y() + q.y()));
  }
  auto fan = [&] {
    for (int i = 1; i + 1 < n; ++i) out.push_back({idx[0], idx[i], idx[i + 1]});
  };
  if (n == 4) {  // the better-shaped diagonal that is not an existing edge
    const Vec3* p[4];
    for (int i = 0; i < 4; ++i) p[i] = &soup.positions[idx[i]];
    const double q02 = std::min(min_angle(*p[0], *p[1], *p[2]), min_angle(*p[0], *p[2], *p[3]));
    const double q13 = std::min(min_angle(*p[1], *p[2], *p[3]), min_angle(*p[1], *p[3], *p[0]));
    const bool ok02 = !existing.count(edge_key(idx[0], idx[2])), ok13 = !existing.count(edge_key(idx[1], idx[3]));
    if ((ok13 && !ok02) || (ok13 == ok02 && q13 > q02)) {
      out.push_back({idx[1], idx[2], idx[3]});
      out.push_back({idx[1], idx[3], idx[0]});
    } else {
      out.push_back({idx[0], idx[1], idx[2]});
      out.push_back({idx[0], idx[2], idx[3]});
    }
    return;
  }
  if (normal.norm() == 0) return fan();
  normal.normalize();
  const Vec3 ax = (std::abs(normal.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY()).cross(normal).normalized();
  const Vec3 ay = normal.cross(ax);
  std::vector<Vec2> p(n);
  for (int i = 0; i < n; ++i) p[i] = Vec2(soup.positions[idx[i]].dot(ax), soup.positions[idx[i]].dot(ay));
  auto cross = [](const Vec2& a, const Vec2& b, const Vec2& c) {
    return (b - a).x() * (c - a).y() - (b - a).y() * (c - a).x();
  };
  std::vector<int> ring(n);
  std::iota(ring.begin(), ring.end(), 0);
  std::vector<std::array<int, 3>> tris;
  while (ring.size() > 3) {
    const int m = static_cast<int>(ring.size());
    bool clipped = false;
    for (int i = 0; i < 2 * m && !clipped; ++i) {  // first pass: only ears with a new diagonal
      const int a = ring[(i + m - 1) % m], b = ring[i % m], c = ring[(i + 1) % m];
      if (i < m && m > 3 && existing.count(edge_key(idx[a], idx[c]))) continue;
      if (cross(p[a], p[b], p[c]) <= 0) continue;  // reflex or flat corner
      bool empty = true;
      for (int j : ring) {
        if (j == a || j == b || j == c) continue;
        if (cross(p[a], p[b], p[j]) >= 0 && cross(p[b], p[c], p[j]) >= 0 && cross(p[c], p[a], p[j]) >= 0) {
          empty = false;
          break;
        }
      }
      if (!empty) continue;
      tris.push_back({idx[a], idx[b], idx[c]});
      ring.erase(ring.begin() + i % m);
      clipped = true;
    }
    if (!clipped) return fan();  // self-intersecting or degenerate polygon
  }
  tris.push_back({idx[ring[0]], idx[ring[1]], idx[ring[2]]});
  out.insert(out.end(), tris.begin(), tris.end());
}

// Repair of degenerate (zero-area or flat) triangles by edge collapses and flips, pass by pass;
// each pass indexes the adjacency afresh and locks the one-rings it changes.
class ZeroAreaRepair {
 public:
  ZeroAreaRepair(TriangleSoup& soup, double zero_area, double flatness)
      : soup_(soup), zero_area_(zero_area), flatness_(flatness) {
    measure_parts();
  }

  // Number of degenerate triangles in the soup.
  int count_degenerate(RepairLocations* where = nullptr) const {
    int n = 0;
    for (int t = 0; t < static_cast<int>(soup_.triangles.size()); ++t)
      if (is_degenerate(t)) {
        ++n;
        if (where) where->add(soup_.input_vertex[soup_.triangles[t][0]]);
      }
    return n;
  }

  // One repair pass over the degenerate triangles. Returns false when nothing was (or is left to
  // be) changed.
  bool run_pass() {
    const int nt = static_cast<int>(soup_.triangles.size());
    std::vector<int> degenerate;
    for (int t = 0; t < nt; ++t)
      if (is_degenerate(t)) degenerate.push_back(t);
    if (degenerate.empty()) return false;
    index_adjacency();
    locked_.assign(soup_.positions.size(), 0);
    removed_.assign(nt, 0);
    replace_.resize(soup_.positions.size());
    std::iota(replace_.begin(), replace_.end(), 0);
    bool changed = false;
    for (int t : degenerate)
      if (repair_triangle(t)) changed = true;
    if (!changed) return false;
    std::vector<char> keep(nt);
    for (int t = 0; t < nt; ++t) keep[t] = !removed_[t];
    keep_triangles(soup_, keep);
    return true;
  }

 private:
  // Tiny area relative to the bounding box diagonal, or flat relative to the longest edge.
  bool is_degenerate(int t) const {
    const double area = triangle_area(soup_, t);
    double longest2 = 0;
    for (int k = 0; k < 3; ++k)
      longest2 = std::max(
          longest2,
          (soup_.positions[soup_.triangles[t][(k + 1) % 3]] - soup_.positions[soup_.triangles[t][k]]).squaredNorm());
    return area <= zero_area_ * part_diag2_[soup_.triangles[t][0]] || 2 * area <= flatness_ * longest2;
  }

  // Per vertex, the squared bounding-box diagonal of its edge-connected part: "tiny" is relative to
  // the part, so a part a millionth the size of the others keeps its triangles. Repairs only
  // collapse within a part, so a vertex stays in its part.
  void measure_parts() {
    int num_parts = 0;
    const std::vector<int> part = edge_connected_components(soup_, &num_parts);
    std::vector<Vec3> lo(num_parts, Vec3::Constant(INFINITY)), hi(num_parts, Vec3::Constant(-INFINITY));
    std::vector<int> part_of_vertex(soup_.positions.size(), -1);
    for (size_t t = 0; t < soup_.triangles.size(); ++t)
      for (int v : soup_.triangles[t]) {
        part_of_vertex[v] = part[t];
        lo[part[t]] = lo[part[t]].cwiseMin(soup_.positions[v]);
        hi[part[t]] = hi[part[t]].cwiseMax(soup_.positions[v]);
      }
    part_diag2_.assign(soup_.positions.size(), 0);
    for (size_t v = 0; v < soup_.positions.size(); ++v)
      if (part_of_vertex[v] >= 0) part_diag2_[v] = (hi[part_of_vertex[v]] - lo[part_of_vertex[v]]).squaredNorm();
  }

  // Adjacency for this pass: triangles per edge and per vertex.
  void index_adjacency() {
    const int nt = static_cast<int>(soup_.triangles.size());
    edge_tris_ = std::unordered_map<uint64_t, std::vector<int>>();
    vertex_tris_.assign(soup_.positions.size(), {});
    for (int t = 0; t < nt; ++t)
      for (int k = 0; k < 3; ++k) {
        edge_tris_[edge_key(soup_.triangles[t][k], soup_.triangles[t][(k + 1) % 3])].push_back(t);
        vertex_tris_[soup_.triangles[t][k]].push_back(t);
      }
  }

  bool is_boundary_edge(int a, int b) { return edge_tris_[edge_key(a, b)].size() == 1; }
  // Sorted distinct vertices sharing a triangle of this pass's adjacency with v.
  std::vector<int> neighbours(int v) const {
    std::vector<int> n;
    for (int t : vertex_tris_[v])
      for (int w : soup_.triangles[t])
        if (w != v) n.push_back(w);
    std::sort(n.begin(), n.end());
    n.erase(std::unique(n.begin(), n.end()), n.end());
    return n;
  }
  bool is_boundary_vertex(int v) {
    for (int w : neighbours(v))
      if (is_boundary_edge(v, w)) return true;
    return false;
  }
  // Locks v and its neighbours for the rest of the pass.
  void lock_ring(int v) {
    locked_[v] = 1;
    for (int w : neighbours(v)) locked_[w] = 1;
  }

  // Collapses or flips degenerate triangle t unless it is removed or locked: needles (a tiny
  // edge or area) collapse first, caps flip first. Returns whether it changed the soup.
  bool repair_triangle(int t) {
    if (removed_[t]) return false;
    const auto tri = soup_.triangles[t];
    if (locked_[tri[0]] || locked_[tri[1]] || locked_[tri[2]]) return false;
    double len[3];
    for (int k = 0; k < 3; ++k) len[k] = (soup_.positions[tri[(k + 1) % 3]] - soup_.positions[tri[k]]).norm();
    const int shortest = static_cast<int>(std::min_element(len, len + 3) - len);
    const int longest = static_cast<int>(std::max_element(len, len + 3) - len);
    const bool needle =
        len[shortest] <= 1e-3 * len[longest] || triangle_area(soup_, t) <= zero_area_ * part_diag2_[tri[0]];
    return needle ? (try_collapse(tri, shortest) || try_flip(t, tri, longest))
                  : (try_flip(t, tri, longest) || try_collapse(tri, shortest));
  }

  // Collapses the edge of tri starting at corner `shortest` if the link condition holds.
  bool try_collapse(const std::array<int, 3>& tri, int shortest) {
    int p = tri[shortest], q = tri[(shortest + 1) % 3];
    const auto& faces = edge_tris_[edge_key(p, q)];
    const bool edge_on_boundary = faces.size() == 1;
    const bool pb = is_boundary_vertex(p), qb = is_boundary_vertex(q);
    if (pb && qb && !edge_on_boundary) return false;
    if (qb && !pb) std::swap(p, q);  // keep the boundary vertex where it is
    // Link condition: common neighbours are exactly the apexes of the edge's faces.
    std::vector<int> np = neighbours(p), nq = neighbours(q), common;
    std::set_intersection(np.begin(), np.end(), nq.begin(), nq.end(), std::back_inserter(common));
    if (common.size() != faces.size()) return false;
    for (int f : faces) removed_[f] = 1;
    for (int f : vertex_tris_[q])
      for (int& w : soup_.triangles[f])
        if (w == q) w = p;
    replace_[q] = p;
    lock_ring(p);
    lock_ring(q);
    return true;
  }

  // Flips the edge of triangle t (vertices tri) starting at corner `longest` if the result is
  // a new edge between unlocked vertices.
  bool try_flip(int t, const std::array<int, 3>& tri, int longest) {
    const int a = tri[longest], b = tri[(longest + 1) % 3], c = tri[(longest + 2) % 3];
    const auto& faces = edge_tris_[edge_key(a, b)];
    if (faces.size() != 2) return false;
    const int other = faces[0] == t ? faces[1] : faces[0];
    if (removed_[other]) return false;
    int d = -1;
    for (int w : soup_.triangles[other])
      if (w != a && w != b) d = w;
    if (d < 0 || d == c || edge_tris_.count(edge_key(c, d))) return false;
    for (int w : soup_.triangles[other])
      if (locked_[w]) return false;
    soup_.triangles[t] = {a, d, c};
    soup_.triangles[other] = {d, b, c};
    edge_tris_[edge_key(c, d)] = {t, other};
    for (int w : {a, b, c, d}) lock_ring(w);
    return true;
  }

  TriangleSoup& soup_;
  double zero_area_, flatness_;
  std::vector<double> part_diag2_;  // per vertex: squared bounding-box diagonal of its part
  // State of one pass.
  std::unordered_map<uint64_t, std::vector<int>> edge_tris_;
  std::vector<std::vector<int>> vertex_tris_;
  std::vector<char> locked_, removed_;
  std::vector<int> replace_;
};

// Vertices of edges with exactly one triangle.
std::vector<char> boundary_vertices(const TriangleSoup& soup) {
  std::vector<char> on(soup.positions.size(), 0);
  EdgeFaces ef(soup);
  ef.for_each_edge([&](size_t i, size_t j) {
    if (j - i != 1) return;
    const uint64_t key = ef.sorted[i].first;
    on[key >> 32] = on[key & 0xffffffffu] = 1;
  });
  return on;
}

double bounding_box_diagonal(const std::vector<Vec3>& positions) {
  Vec3 lo = Vec3::Constant(INFINITY), hi = Vec3::Constant(-INFINITY);
  for (const Vec3& p : positions) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  return positions.empty() ? 0 : (hi - lo).norm();
}

// Unites the candidate points closer than eps (exact duplicates also when eps is 0), looking up
// neighbours in a hash grid of cells of size eps.
void unite_close_points(const std::vector<Vec3>& positions, const std::vector<int>& candidates, double eps,
                        DisjointSets& sets) {
  using Cell = std::array<int64_t, 3>;
  struct CellHash {
    size_t operator()(const Cell& c) const {
      // Unsigned arithmetic: a cell index far from the origin wraps instead of overflowing.
      return static_cast<size_t>(static_cast<uint64_t>(c[0]) * 73856093u ^ static_cast<uint64_t>(c[1]) * 19349663u ^
                                 static_cast<uint64_t>(c[2]) * 83492791u);
    }
  };
  const double cell_size = eps > 0 ? eps : 1;
  auto cell_of = [&](const Vec3& p) {
    Cell c;
    for (int d = 0; d < 3; ++d) {
      const double index = std::floor(p[d] / cell_size);
      c[d] = std::isnan(index) ? 0 : static_cast<int64_t>(std::clamp(index, -1e15, 1e15));
    }
    return c;
  };
  std::unordered_map<Cell, std::vector<int>, CellHash> grid;
  for (int v : candidates) grid[cell_of(positions[v])].push_back(v);
  for (int v : candidates) {
    const Cell c = cell_of(positions[v]);
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          const auto it = grid.find({c[0] + dx, c[1] + dy, c[2] + dz});
          if (it == grid.end()) continue;
          for (int w : it->second)
            if (w < v && (positions[w] - positions[v]).squaredNorm() <= eps * eps) sets.unite(w, v);
        }
  }
}

// Joins, in `corners`, the corners of the two triangles of halfedges h0 and h1 (the same edge)
// at both ends of the edge.
void unite_corners_across(const TriangleSoup& soup, int h0, int h1, DisjointSets& corners) {
  for (int end = 0; end < 2; ++end) {
    const int v = soup.triangles[h0 / 3][(h0 % 3 + end) % 3];
    int c0 = -1, c1 = -1;
    for (int k = 0; k < 3; ++k) {
      if (soup.triangles[h0 / 3][k] == v) c0 = 3 * (h0 / 3) + k;
      if (soup.triangles[h1 / 3][k] == v) c1 = 3 * (h1 / 3) + k;
    }
    if (c0 >= 0 && c1 >= 0) corners.unite(c0, c1);
  }
}

// Welding groups (lowest[root] = the group's vertex) that join no two boundary edges are cancelled
// (lowest[root] = -1): they would only pinch the surface at a point.
void keep_only_zipping_groups(const TriangleSoup& soup, const std::vector<int>& candidates, DisjointSets& sets,
                              std::vector<int>& lowest) {
  std::vector<std::pair<uint64_t, int>> welded_edges;  // (welded edge key, a root of it)
  EdgeFaces ef(soup);
  ef.for_each_edge([&](size_t i, size_t j) {
    if (j - i != 1) return;
    const uint64_t key = ef.sorted[i].first;
    const int ra = sets.find(static_cast<int>(key >> 32)), rb = sets.find(static_cast<int>(key & 0xffffffffu));
    if (ra != rb) welded_edges.push_back({edge_key(lowest[ra], lowest[rb]), ra});
  });
  std::sort(welded_edges.begin(), welded_edges.end());
  std::vector<char> zips(soup.positions.size(), 0);
  for (size_t k = 1; k < welded_edges.size(); ++k)
    if (welded_edges[k].first == welded_edges[k - 1].first) {
      const uint64_t key = welded_edges[k].first;
      zips[sets.find(static_cast<int>(key >> 32))] = zips[sets.find(static_cast<int>(key & 0xffffffffu))] = 1;
    }
  for (int v : candidates)
    if (!zips[sets.find(v)]) lowest[sets.find(v)] = -1;
}

// Gives every fan of triangles around a vertex its own vertex: corners are in one fan when their
// triangles share a manifold edge (two triangles) or a pair of halfedges in `paired`. Only the
// vertices flagged in *only (all when null) are split. Returns #vertices split.
int split_vertex_fans(TriangleSoup& soup, const std::vector<std::array<int, 2>>& paired, const std::vector<char>* only,
                      RepairLocations* where) {
  const int nt = static_cast<int>(soup.triangles.size());
  DisjointSets corners(3 * nt);
  EdgeFaces ef(soup);
  ef.for_each_edge([&](size_t i, size_t j) {
    if (j - i == 2) unite_corners_across(soup, ef.sorted[i].second, ef.sorted[i + 1].second, corners);
  });
  for (const auto& pair : paired) unite_corners_across(soup, pair[0], pair[1], corners);
  std::vector<int> fan_vertex(3 * nt, -1);  // per corner root: assigned vertex
  const size_t original_vertices = soup.positions.size();
  std::vector<char> vertex_used(original_vertices, 0), vertex_split(original_vertices, 0);
  for (int t = 0; t < nt; ++t)
    for (int k = 0; k < 3; ++k) {
      const int v = soup.triangles[t][k];
      if (only && !(*only)[v]) continue;
      int& assigned = fan_vertex[corners.find(3 * t + k)];
      if (assigned < 0) {
        if (!vertex_used[v]) {
          vertex_used[v] = 1;
          assigned = v;
        } else {  // a further fan around v: give it a copy of v
          if (!vertex_split[v] && where) where->add(soup.input_vertex[v]);
          vertex_split[v] = 1;
          assigned = static_cast<int>(soup.positions.size());
          soup.positions.push_back(soup.positions[v]);
          soup.input_vertex.push_back(soup.input_vertex[v]);
        }
      }
      soup.triangles[t][k] = assigned;
    }
  return static_cast<int>(std::count(vertex_split.begin(), vertex_split.end(), 1));
}

// Triangles at the same angle around an edge (faces of two solids touching along a plane): the one
// running from a to b, which ends a solid wedge, goes before the one that starts the next wedge.
void put_ending_faces_first_at_ties(const TriangleSoup& soup, const std::vector<std::pair<double, int>>& by_angle,
                                    int a, std::vector<int>& ring) {
  const double kSameAngle = 1e-9;  // radians
  auto runs_forward = [&](int h) { return soup.triangles[h / 3][h % 3] == a; };
  for (size_t i = 0; i < ring.size();) {
    size_t j = i + 1;
    while (j < ring.size() && by_angle[j].first - by_angle[j - 1].first <= kSameAngle) ++j;
    std::stable_partition(ring.begin() + i, ring.begin() + j, runs_forward);
    i = j;
  }
}

// Halfedges [i, j) of ef.sorted (edge a-b, a < b) in the order of their triangles' angle around
// the axis from a to b.
std::vector<int> halfedges_by_angle(const TriangleSoup& soup, const EdgeFaces& ef, size_t i, size_t j, int a, int b) {
  const Vec3 axis = (soup.positions[b] - soup.positions[a]).normalized();
  auto radial = [&](int h) {
    const int apex = soup.triangles[h / 3][(h % 3 + 2) % 3];
    const Vec3 r = soup.positions[apex] - soup.positions[a];
    return Vec3(r - axis * axis.dot(r));
  };
  const Vec3 e1 = radial(ef.sorted[i].second).normalized(), e2 = axis.cross(e1);
  std::vector<std::pair<double, int>> by_angle;
  for (size_t k = i; k < j; ++k) {
    const Vec3 r = radial(ef.sorted[k].second);
    by_angle.push_back({std::atan2(r.dot(e2), r.dot(e1)), ef.sorted[k].second});
  }
  std::sort(by_angle.begin(), by_angle.end());
  std::vector<int> ring;
  for (const auto& entry : by_angle) ring.push_back(entry.second);
  put_ending_faces_first_at_ties(soup, by_angle, a, ring);
  return ring;
}

// Pairs angular neighbours of `ring` (halfedges around an edge starting at vertex a) into sheets.
// A pair bounding a solid wedge (the first runs b to a, the next a to b: both normals point out
// of the wedge) scores 2, any other oppositely oriented pair 1; the best-scoring start wins. With
// an odd count one triangle stays alone.
std::vector<std::array<int, 2>> pair_into_sheets(const TriangleSoup& soup, const std::vector<int>& ring, int a) {
  const int n = static_cast<int>(ring.size());
  std::vector<char> forward(n);
  for (int i = 0; i < n; ++i) forward[i] = soup.triangles[ring[i] / 3][ring[i] % 3] == a;
  auto pair_score = [&](int i, int j) { return !forward[i] && forward[j] ? 2 : forward[i] != forward[j] ? 1 : 0; };
  int best_start = 0, best_score = -1;
  for (int s = 0; s < (n % 2 == 0 ? 2 : n); ++s) {
    int score = 0;
    for (int p = 0; p < n / 2; ++p) score += pair_score((s + 2 * p) % n, (s + 2 * p + 1) % n);
    if (score > best_score) best_score = score, best_start = s;
  }
  std::vector<std::array<int, 2>> pairs;
  for (int p = 0; p < n / 2; ++p) pairs.push_back({ring[(best_start + 2 * p) % n], ring[(best_start + 2 * p + 1) % n]});
  return pairs;
}

// Fallback after the sheet split: triangles beyond the first two still on one edge (their sheets
// meet again elsewhere around the edge's vertices) get their own copies of the edge's vertices.
void detach_remaining_nonmanifold_faces(TriangleSoup& soup) {
  EdgeFaces ef(soup);
  std::vector<char> endpoint(soup.positions.size(), 0);
  bool detached = false;
  ef.for_each_edge([&](size_t i, size_t j) {
    for (size_t k = i + 2; k < j; ++k) {
      const int h = ef.sorted[k].second;
      for (int end = 0; end < 2; ++end) {
        int& v = soup.triangles[h / 3][(h % 3 + end) % 3];
        endpoint.resize(soup.positions.size(), 0);  // v may be a copy made for another of its edges
        endpoint[v] = 1;
        soup.positions.push_back(soup.positions[v]);
        soup.input_vertex.push_back(soup.input_vertex[v]);
        v = static_cast<int>(soup.positions.size()) - 1;
      }
      detached = true;
    }
  });
  endpoint.resize(soup.positions.size(), 0);
  if (detached) split_vertex_fans(soup, {}, &endpoint, nullptr);
}

}  // namespace

void validate_soup(const PolygonSoup& soup) {
  if (soup.num_faces() <= 0) throw Error(ErrorCode::InvalidMesh, "the mesh has no faces");
  for (int v = 0; v < soup.num_vertices(); ++v)
    if (!soup.positions[v].allFinite())
      throw Error(ErrorCode::InvalidMesh,
                  "vertex " + std::to_string(v) + " has a non-finite coordinate (NaN or infinity)");
  const int nv = soup.num_vertices();
  for (int f = 0; f < soup.num_faces(); ++f) {
    const int n = soup.face_size(f);
    if (n < 3)
      throw Error(ErrorCode::InvalidMesh, "face " + std::to_string(f) + " has " + std::to_string(n) +
                                              " vertices (a face needs at least three)");
    const int* idx = &soup.face_vertices[soup.face_start[f]];
    for (int i = 0; i < n; ++i) {
      if (idx[i] < 0 || idx[i] >= nv)
        throw Error(ErrorCode::InvalidMesh, "face " + std::to_string(f) + " refers to vertex " +
                                                std::to_string(idx[i]) + ", but the mesh has " + std::to_string(nv) +
                                                " vertices");
      for (int j = 0; j < i; ++j)
        if (idx[i] == idx[j])
          throw Error(ErrorCode::InvalidMesh, "face " + std::to_string(f) + " repeats vertex " +
                                                  std::to_string(idx[i]) + " (a face needs distinct vertices)");
    }
  }
}

int triangulate_polygons(const PolygonSoup& soup, TriangleSoup& out, RepairLocations* where) {
  out.positions = soup.positions;
  out.input_vertex.resize(soup.positions.size());
  std::iota(out.input_vertex.begin(), out.input_vertex.end(), 0);
  out.triangles.clear();
  out.input_face.clear();
  out.triangles.reserve(soup.num_faces());
  std::unordered_set<uint64_t> existing;  // polygon sides, for diagonal choices
  for (int f = 0; f < soup.num_faces(); ++f) {
    const int n = soup.face_size(f);
    if (n == 3) continue;
    const int* idx = &soup.face_vertices[soup.face_start[f]];
    for (int i = 0; i < n; ++i) existing.insert(edge_key(idx[i], idx[(i + 1) % n]));
  }
  if (!existing.empty())  // triangles' sides count too
    for (int f = 0; f < soup.num_faces(); ++f) {
      if (soup.face_size(f) != 3) continue;
      const int* idx = &soup.face_vertices[soup.face_start[f]];
      for (int i = 0; i < 3; ++i) existing.insert(edge_key(idx[i], idx[(i + 1) % 3]));
    }
  int polygons = 0;
  for (int f = 0; f < soup.num_faces(); ++f) {
    const size_t before = out.triangles.size();
    if (soup.face_size(f) == 3) {
      const int* idx = &soup.face_vertices[soup.face_start[f]];
      out.triangles.push_back({idx[0], idx[1], idx[2]});
    } else {
      triangulate_polygon(soup, f, existing, out.triangles);
      ++polygons;
      if (where) where->add(soup.face_vertices[soup.face_start[f]]);
    }
    out.input_face.resize(out.triangles.size(), f);
    (void)before;
  }
  return polygons;
}

void keep_triangles(TriangleSoup& soup, const std::vector<char>& keep) {
  size_t w = 0;
  for (size_t t = 0; t < soup.triangles.size(); ++t) {
    if (!keep[t]) continue;
    soup.triangles[w] = soup.triangles[t];
    soup.input_face[w] = soup.input_face[t];
    ++w;
  }
  soup.triangles.resize(w);
  soup.input_face.resize(w);
  remove_unreferenced_vertices(soup);
}

int remove_unreferenced_vertices(TriangleSoup& soup, RepairLocations* where) {
  std::vector<int> remap(soup.positions.size(), -1);
  for (const auto& t : soup.triangles)
    for (int v : t) remap[v] = 0;
  int next = 0, removed = 0;
  for (size_t v = 0; v < remap.size(); ++v) {
    if (remap[v] < 0) {
      ++removed;
      if (where) where->add(soup.input_vertex[v]);
      continue;
    }
    remap[v] = next;
    soup.positions[next] = soup.positions[v];
    soup.input_vertex[next] = soup.input_vertex[v];
    ++next;
  }
  soup.positions.resize(next);
  soup.input_vertex.resize(next);
  for (auto& t : soup.triangles)
    for (int& v : t) v = remap[v];
  return removed;
}

void sort_triangles_canonically(TriangleSoup& soup) {
  const size_t n = soup.triangles.size();
  for (std::array<int, 3>& t : soup.triangles) std::rotate(t.begin(), std::min_element(t.begin(), t.end()), t.end());
  std::vector<int> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](int a, int b) {
    return std::tie(soup.triangles[a], soup.input_face[a]) < std::tie(soup.triangles[b], soup.input_face[b]);
  });
  std::vector<std::array<int, 3>> triangles(n);
  std::vector<int> input_face(n);
  for (size_t i = 0; i < n; ++i) {
    triangles[i] = soup.triangles[order[i]];
    input_face[i] = soup.input_face[order[i]];
  }
  soup.triangles = std::move(triangles);
  soup.input_face = std::move(input_face);
}

int remove_duplicate_faces(TriangleSoup& soup, RepairLocations* where) {
  std::vector<std::pair<std::array<int, 3>, int>> keyed(soup.triangles.size());
  for (size_t t = 0; t < soup.triangles.size(); ++t) {
    auto key = soup.triangles[t];
    std::sort(key.begin(), key.end());
    keyed[t] = {key, static_cast<int>(t)};
  }
  std::sort(keyed.begin(), keyed.end());
  std::vector<char> keep(soup.triangles.size(), 1);
  int removed = 0;
  for (size_t i = 1; i < keyed.size(); ++i)
    if (keyed[i].first == keyed[i - 1].first) {
      keep[keyed[i].second] = 0;
      ++removed;
      if (where) where->add(soup.input_vertex[keyed[i].first[0]]);
    }
  if (removed) keep_triangles(soup, keep);
  return removed;
}

std::vector<std::array<int, 2>> find_nonmanifold_edges(const TriangleSoup& soup) {
  std::vector<std::array<int, 2>> result;
  EdgeFaces ef(soup);
  ef.for_each_edge([&](size_t i, size_t j) {
    if (j - i <= 2) return;
    const uint64_t key = ef.sorted[i].first;
    result.push_back({static_cast<int>(key >> 32), static_cast<int>(key & 0xffffffffu)});
  });
  return result;
}

std::vector<int> edge_connected_components(const TriangleSoup& soup, int* num_components) {
  DisjointSets sets(static_cast<int>(soup.triangles.size()));
  EdgeFaces ef(soup);
  ef.for_each_edge([&](size_t i, size_t j) {
    for (size_t k = i + 1; k < j; ++k) sets.unite(ef.sorted[i].second / 3, ef.sorted[k].second / 3);
  });
  std::vector<int> id(soup.triangles.size(), -1), root_id(soup.triangles.size(), -1);
  int count = 0;
  for (size_t t = 0; t < soup.triangles.size(); ++t) {
    const int r = sets.find(static_cast<int>(t));
    if (root_id[r] < 0) root_id[r] = count++;
    id[t] = root_id[r];
  }
  if (num_components) *num_components = count;
  return id;
}

int orient_consistently(TriangleSoup& soup, std::vector<int>* non_orientable, RepairLocations* where) {
  const int nt = static_cast<int>(soup.triangles.size());
  // Adjacency over manifold edges: (neighbour, same_direction) per halfedge.
  std::vector<int> neighbour(3 * nt, -1);
  std::vector<char> same_direction(3 * nt, 0);
  EdgeFaces ef(soup);
  ef.for_each_edge([&](size_t i, size_t j) {
    if (j - i != 2) return;
    const int h0 = ef.sorted[i].second, h1 = ef.sorted[i + 1].second;
    const int from0 = soup.triangles[h0 / 3][h0 % 3], from1 = soup.triangles[h1 / 3][h1 % 3];
    neighbour[h0] = h1 / 3;
    neighbour[h1] = h0 / 3;
    same_direction[h0] = same_direction[h1] = (from0 == from1);
  });
  int num_components = 0;
  const std::vector<int> component = edge_connected_components(soup, &num_components);
  std::vector<signed char> flip(nt, -1);
  std::vector<char> bad_component(num_components, 0);
  std::vector<int> stack, members;
  int flipped_total = 0;
  for (int seed = 0; seed < nt; ++seed) {
    if (flip[seed] >= 0) continue;
    members.clear();
    flip[seed] = 0;
    stack.push_back(seed);
    while (!stack.empty()) {
      const int t = stack.back();
      stack.pop_back();
      members.push_back(t);
      for (int k = 0; k < 3; ++k) {
        const int n = neighbour[3 * t + k];
        if (n < 0) continue;
        const signed char want = static_cast<signed char>(flip[t] ^ same_direction[3 * t + k]);
        if (flip[n] < 0) {
          flip[n] = want;
          stack.push_back(n);
        } else if (flip[n] != want) {
          bad_component[component[t]] = 1;
        }
      }
    }
    int flips = 0;
    for (int t : members) flips += flip[t];
    const bool invert = 2 * flips > static_cast<int>(members.size());
    for (int t : members) {
      if (invert) flip[t] ^= 1;
      if (flip[t] && !bad_component[component[t]]) {
        std::swap(soup.triangles[t][1], soup.triangles[t][2]);
        ++flipped_total;
        if (where) where->add(soup.input_vertex[soup.triangles[t][0]]);
      }
    }
  }
  if (non_orientable) {
    non_orientable->clear();
    for (int c = 0; c < num_components; ++c)
      if (bad_component[c]) non_orientable->push_back(c);
  }
  return flipped_total;
}

int split_nonmanifold_vertices(TriangleSoup& soup, RepairLocations* where) {
  return split_vertex_fans(soup, {}, nullptr, where);
}

int weld_boundary_vertices(TriangleSoup& soup, double tolerance, std::vector<int>* input_weld_target,
                           RepairLocations* where) {
  if (!(tolerance > 0) || soup.positions.empty()) return 0;
  const std::vector<char> on_boundary = boundary_vertices(soup);
  std::vector<int> candidates;
  for (size_t v = 0; v < on_boundary.size(); ++v)
    if (on_boundary[v]) candidates.push_back(static_cast<int>(v));
  if (candidates.empty()) return 0;
  DisjointSets sets(static_cast<int>(soup.positions.size()));
  unite_close_points(soup.positions, candidates, tolerance * bounding_box_diagonal(soup.positions), sets);
  std::vector<int> lowest(soup.positions.size(), -1);  // per set root: its lowest vertex
  for (int v : candidates) {
    int& low = lowest[sets.find(v)];
    if (low < 0 || v < low) low = v;
  }
  keep_only_zipping_groups(soup, candidates, sets, lowest);
  int merged = 0;
  for (int v : candidates) {
    const int target = lowest[sets.find(v)];
    if (target < 0 || target == v) continue;
    ++merged;
    if (input_weld_target) (*input_weld_target)[soup.input_vertex[v]] = soup.input_vertex[target];
    if (where) where->add(soup.input_vertex[target]);
  }
  if (merged == 0) return 0;
  for (auto& t : soup.triangles)
    for (int& v : t)
      if (on_boundary[v] && lowest[sets.find(v)] >= 0) v = lowest[sets.find(v)];
  remove_unreferenced_vertices(soup);
  return merged;
}

int remove_collapsed_triangles(TriangleSoup& soup, RepairLocations* where) {
  std::vector<char> keep(soup.triangles.size(), 1);
  int removed = 0;
  for (size_t t = 0; t < soup.triangles.size(); ++t) {
    const auto& tri = soup.triangles[t];
    if (tri[0] != tri[1] && tri[1] != tri[2] && tri[2] != tri[0]) continue;
    keep[t] = 0;
    ++removed;
    if (where) where->add(soup.input_vertex[tri[0] == tri[2] ? tri[0] : tri[1]]);
  }
  if (removed) keep_triangles(soup, keep);
  return removed;
}

int cut_nonmanifold_edges(TriangleSoup& soup, RepairLocations* where) {
  std::vector<std::array<int, 2>> paired;
  std::vector<char> endpoint(soup.positions.size(), 0);
  int cut = 0;
  EdgeFaces ef(soup);
  ef.for_each_edge([&](size_t i, size_t j) {
    if (j - i <= 2) return;
    const uint64_t key = ef.sorted[i].first;
    const int a = static_cast<int>(key >> 32), b = static_cast<int>(key & 0xffffffffu);
    const std::vector<int> ring = halfedges_by_angle(soup, ef, i, j, a, b);
    for (const auto& pair : pair_into_sheets(soup, ring, a)) paired.push_back(pair);
    endpoint[a] = endpoint[b] = 1;
    ++cut;
    if (where) where->add(soup.input_vertex[a]);
  });
  if (cut == 0) return 0;
  split_vertex_fans(soup, paired, &endpoint, nullptr);
  detach_remaining_nonmanifold_faces(soup);
  return cut;
}

int repair_zero_area_faces(TriangleSoup& soup, double zero_area, double flatness, int* remaining,
                           RepairLocations* where) {
  ZeroAreaRepair repair(soup, zero_area, flatness);
  const int found = repair.count_degenerate(where);
  if (found == 0) {
    if (remaining) *remaining = 0;
    return 0;
  }
  for (int pass = 0; pass < 50; ++pass)
    if (!repair.run_pass()) break;
  if (remaining) *remaining = repair.count_degenerate();
  return found;
}

}  // namespace qgp

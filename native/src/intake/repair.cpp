#include "intake/repair.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <string>
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
    std::sort(sorted.begin(), sorted.end());
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
  const int* idx = &soup.face_vertices[soup.face_start[f]];
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
    Vec3 lo = Vec3::Constant(INFINITY), hi = Vec3::Constant(-INFINITY);
    for (const Vec3& p : soup.positions) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
    diag2_ = (hi - lo).squaredNorm();
  }

  // Number of degenerate triangles in the soup.
  int count_degenerate() const {
    int n = 0;
    for (int t = 0; t < static_cast<int>(soup_.triangles.size()); ++t) n += is_degenerate(t);
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
    return area <= zero_area_ * diag2_ || 2 * area <= flatness_ * longest2;
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
    const bool needle = len[shortest] <= 1e-3 * len[longest] || triangle_area(soup_, t) <= zero_area_ * diag2_;
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
  double diag2_ = 0;  // squared bounding box diagonal
  // State of one pass.
  std::unordered_map<uint64_t, std::vector<int>> edge_tris_;
  std::vector<std::vector<int>> vertex_tris_;
  std::vector<char> locked_, removed_;
  std::vector<int> replace_;
};

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

int triangulate_polygons(const PolygonSoup& soup, TriangleSoup& out) {
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

int remove_unreferenced_vertices(TriangleSoup& soup) {
  std::vector<int> remap(soup.positions.size(), -1);
  for (const auto& t : soup.triangles)
    for (int v : t) remap[v] = 0;
  int next = 0, removed = 0;
  for (size_t v = 0; v < remap.size(); ++v) {
    if (remap[v] < 0) {
      ++removed;
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

int remove_duplicate_faces(TriangleSoup& soup) {
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

int orient_consistently(TriangleSoup& soup, std::vector<int>* non_orientable) {
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

int split_nonmanifold_vertices(TriangleSoup& soup) {
  const int nt = static_cast<int>(soup.triangles.size());
  // Corners (3*t + k) around the same vertex are joined when their faces share an edge at it.
  DisjointSets corners(3 * nt);
  EdgeFaces ef(soup);
  ef.for_each_edge([&](size_t i, size_t j) {
    if (j - i != 2) return;
    const int h0 = ef.sorted[i].second, h1 = ef.sorted[i + 1].second;
    for (int end = 0; end < 2; ++end) {
      const int v = soup.triangles[h0 / 3][(h0 % 3 + end) % 3];
      int c0 = -1, c1 = -1;
      for (int k = 0; k < 3; ++k) {
        if (soup.triangles[h0 / 3][k] == v) c0 = 3 * (h0 / 3) + k;
        if (soup.triangles[h1 / 3][k] == v) c1 = 3 * (h1 / 3) + k;
      }
      corners.unite(c0, c1);
    }
  });
  std::vector<int> fan_vertex(3 * nt, -1);  // per corner root: assigned vertex
  std::vector<char> vertex_used(soup.positions.size(), 0);
  std::vector<char> vertex_split(soup.positions.size(), 0);
  for (int t = 0; t < nt; ++t)
    for (int k = 0; k < 3; ++k) {
      const int root = corners.find(3 * t + k);
      int& assigned = fan_vertex[root];
      const int v = soup.triangles[t][k];
      if (assigned < 0) {
        if (!vertex_used[v]) {
          vertex_used[v] = 1;
          assigned = v;
        } else {  // a further fan around v: give it a copy of v
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

int repair_zero_area_faces(TriangleSoup& soup, double zero_area, double flatness, int* remaining) {
  ZeroAreaRepair repair(soup, zero_area, flatness);
  const int found = repair.count_degenerate();
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

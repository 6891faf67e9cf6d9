#include "igm/cell_map.h"

#include <Eigen/SparseLU>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <queue>

#include "core/error.h"
#include "core/parametrization.h"
#include "core/timer.h"
#include "core/union_find.h"
#include "igm/untangle_map.h"

namespace qgp {
namespace {

constexpr double kOnSide = 1e-10;    // barycentric weight below which a trace point is on a side
constexpr double kSamePoint = 1e-9;  // parameter distance below which two points are one

[[noreturn]] void fail(const std::string& why) { throw Error(ErrorCode::StageFailed, "fallback cell map: " + why); }

// Points of the refined mesh: the working mesh's vertices first, then points on its edges and
// inside its faces, each made once.
class RefinedPoints {
 public:
  explicit RefinedPoints(const TriMesh& mesh) : mesh_(mesh), on_edge_(mesh.num_edges()), in_face_(mesh.num_faces()) {
    for (int v = 0; v < mesh.num_vertices(); ++v) position.push_back(mesh.position(v));
  }

  std::vector<Vec3> position;

  // The point of sp, snapped onto a vertex or an edge where its barycentric weights vanish.
  int of(const SurfacePoint& sp) {
    const int f = sp.face;
    Vec3 b = sp.barycentric.cwiseMax(0.0);
    if (!(b.sum() > 0)) fail("a trace point has no barycentric coordinates");
    b /= b.sum();
    int zeros = 0, zero = -1;
    for (int k = 0; k < 3; ++k)
      if (b[k] < kOnSide) b[k] = 0, ++zeros, zero = k;
    if (zeros >= 2) {
      int k = 0;
      b.maxCoeff(&k);
      return mesh_.F(f, k);
    }
    if (zeros == 1) {
      const int k = (zero + 1) % 3;  // halfedge 3f + k runs from corner k to corner k + 1
      return on_halfedge(3 * f + k, b[(k + 1) % 3] / (b[k] + b[(k + 1) % 3]));
    }
    for (const auto& [existing, id] : in_face_[f])
      if ((existing - b).cwiseAbs().maxCoeff() < kSamePoint) return id;
    const int id = add_inside(f, b);
    in_face_[f].push_back({b, id});
    return id;
  }

  // The point sp of face sp.face where a trace passes into face `other`: on their common edge or
  // vertex.
  int shared(const SurfacePoint& sp, int other) {
    const int f = sp.face;
    Vec3 b = sp.barycentric.cwiseMax(0.0);
    for (int k = 0; k < 3; ++k) {
      const int o = mesh_.opposite[3 * f + k];
      if (o < 0 || o / 3 != other) continue;
      const double s = b[k] + b[(k + 1) % 3];
      const double lambda = s > 0 ? b[(k + 1) % 3] / s : 0.5;
      if (lambda < kOnSide) return mesh_.F(f, k);
      if (lambda > 1 - kOnSide) return mesh_.F(f, (k + 1) % 3);
      return on_halfedge(3 * f + k, lambda);
    }
    int best = -1;
    for (int k = 0; k < 3; ++k)
      for (int j = 0; j < 3; ++j)
        if (mesh_.F(f, k) == mesh_.F(other, j) && (best < 0 || b[k] > b[best])) best = k;
    if (best < 0)
      fail("a trace jumps between faces " + std::to_string(f) + " and " + std::to_string(other) +
           ", which do not touch");
    return mesh_.F(f, best);
  }

  // Points on edge e as (parameter along halfedge h, point), sorted.
  std::vector<std::pair<double, int>> along(int h) const {
    const int e = mesh_.edge_of[h];
    std::vector<std::pair<double, int>> list;
    for (const auto& [lambda, id] : on_edge_[e])
      list.push_back({mesh_.edge_halfedge[e] == h ? lambda : 1 - lambda, id});
    std::sort(list.begin(), list.end());
    return list;
  }
  const std::vector<std::pair<Vec3, int>>& inside(int f) const { return in_face_[f]; }

  // A new point inside face f at barycentric b (not looked up later: region centres).
  int add_inside(int f, const Vec3& b) {
    return add(b[0] * mesh_.position(mesh_.F(f, 0)) + b[1] * mesh_.position(mesh_.F(f, 1)) +
               b[2] * mesh_.position(mesh_.F(f, 2)));
  }

 private:
  int add(const Vec3& p) {
    position.push_back(p);
    return static_cast<int>(position.size()) - 1;
  }
  int on_halfedge(int h, double lambda) {
    const int e = mesh_.edge_of[h];
    if (mesh_.edge_halfedge[e] != h) lambda = 1 - lambda;
    for (const auto& [existing, id] : on_edge_[e])
      if (std::abs(existing - lambda) < kSamePoint) return id;
    const int g = mesh_.edge_halfedge[e];
    const int id = add((1 - lambda) * mesh_.position(mesh_.from(g)) + lambda * mesh_.position(mesh_.to(g)));
    on_edge_[e].push_back({lambda, id});
    return id;
  }

  const TriMesh& mesh_;
  std::vector<std::vector<std::pair<double, int>>> on_edge_;  // #E: (lambda from edge_halfedge's origin, point)
  std::vector<std::vector<std::pair<Vec3, int>>> in_face_;    // #F: (barycentric, point)
};

// A piece of a trace inside one face, between two points, in the trace's direction.
struct Piece {
  int from = -1, to = -1, edge = -1;
};

// An undirected refined edge on a trace: its T-edge and the point the trace leaves it from.
struct ArcPiece {
  int edge = -1, from = -1;
};
using PointPair = std::pair<int, int>;
PointPair key(int a, int b) { return {std::min(a, b), std::max(a, b)}; }

struct Insertion {
  std::vector<int> node_point;                            // #nodes: the refined point of each node
  std::vector<std::vector<Piece>> pieces;                 // #F
  std::vector<std::vector<std::pair<int, double>>> arcs;  // per point: (T-edge, fraction from its `from`)
  std::map<PointPair, ArcPiece> arc_pieces;
};

// Every trace as points of the refined mesh, with fractions of its parametric length.
Insertion insert_traces(const TriMesh& mesh, const TMesh& tmesh, RefinedPoints& points, Progress& progress) {
  Insertion ins;
  ins.pieces.resize(mesh.num_faces());
  ins.node_point.assign(tmesh.nodes.size(), -1);
  for (int e = 0; e < static_cast<int>(tmesh.edges.size()); ++e) {
    if (e % 256 == 0) progress.check_cancel();
    const std::vector<SurfacePoint>& trace = tmesh.edges[e].trace;
    const int n = static_cast<int>(trace.size());
    if (n < 2) fail("T-edge " + std::to_string(e) + " has no trace");
    std::vector<int> id(n, -1);
    std::vector<double> length(n, 0.0);
    for (int i = 0; i < n; ++i) {
      if (i > 0 && trace[i].face != trace[i - 1].face) {
        id[i] = id[i - 1];
        length[i] = length[i - 1];
        continue;
      }
      id[i] = i + 1 < n && trace[i + 1].face != trace[i].face ? points.shared(trace[i], trace[i + 1].face)
                                                              : points.of(trace[i]);
      if (i > 0) length[i] = length[i - 1] + (trace[i].uv - trace[i - 1].uv).cwiseAbs().sum();
    }
    // The ends are the nodes: one point for every edge meeting there.
    ins.node_point[tmesh.edges[e].from] = id[0];
    ins.node_point[tmesh.edges[e].to] = id[n - 1];
    const double total = length[n - 1];
    for (int i = 0; i < n; ++i) {
      const double t = i == n - 1 ? 1.0 : total > 0 ? length[i] / total : 0.0;
      if (ins.arcs.size() <= size_t(id[i])) ins.arcs.resize(id[i] + 1);
      auto& list = ins.arcs[id[i]];
      if (list.empty() || list.back().first != e || list.back().second != t) list.push_back({e, t});
      if (i > 0 && trace[i].face == trace[i - 1].face && id[i] != id[i - 1])
        ins.pieces[trace[i].face].push_back({id[i - 1], id[i], e});
    }
  }
  return ins;
}

// Face f of the working mesh as a planar graph: its points in the reference triangle (0,0), (1,0),
// (0,1) (orientation kept), and the edges between them (its sides' steps and the trace pieces).
struct FaceGraph {
  std::vector<int> gid;                    // the refined point of each local point
  std::vector<Vec2> xy;                    // its position in the reference triangle
  std::vector<int> side_mask;              // bit k: on side k
  std::vector<int> cycle;                  // corner 0, side 0, corner 1, side 1, corner 2, side 2
  std::vector<std::vector<int>> adjacent;  // sorted counter-clockwise once connected

  int size() const { return static_cast<int>(gid.size()); }
  void connect(int a, int b) {
    if (a == b || std::find(adjacent[a].begin(), adjacent[a].end(), b) != adjacent[a].end()) return;
    adjacent[a].push_back(b), adjacent[b].push_back(a);
  }
};

// The points of face f: the boundary cycle (its corners and the points on its sides), then the
// points inside it.
FaceGraph face_points(const TriMesh& mesh, int f, const RefinedPoints& points) {
  // Local points in the reference triangle (0,0), (1,0), (0,1) (orientation kept), and the
  // boundary cycle corner 0, side 0, corner 1, side 1, corner 2, side 2.
  FaceGraph g;
  const Vec2 corner[3] = {{0, 0}, {1, 0}, {0, 1}};
  for (int k = 0; k < 3; ++k) {
    g.cycle.push_back(g.size());
    g.gid.push_back(mesh.F(f, k)), g.xy.push_back(corner[k]), g.side_mask.push_back(1 << k | 1 << (k + 2) % 3);
    for (const auto& [mu, id] : points.along(3 * f + k)) {
      g.cycle.push_back(g.size());
      g.gid.push_back(id), g.xy.push_back((1 - mu) * corner[k] + mu * corner[(k + 1) % 3]),
          g.side_mask.push_back(1 << k);
    }
  }
  for (const auto& [b, id] : points.inside(f))
    g.gid.push_back(id), g.xy.push_back({b[1], b[2]}), g.side_mask.push_back(0);
  return g;
}

// Connects the boundary cycle and the trace pieces of face f, and records each refined edge on a
// trace in ins.arc_pieces (a piece along a side: every boundary step it covers).
void connect_pieces(int f, Insertion& ins, FaceGraph& g) {
  auto local = [&](int id) {
    for (size_t i = 0; i < g.gid.size(); ++i)
      if (g.gid[i] == id) return static_cast<int>(i);
    fail("a trace point of face " + std::to_string(f) + " is not in it");
  };
  auto mark_arc = [&](int a, int b, int edge, int from) {
    auto [it, added] = ins.arc_pieces.emplace(key(a, b), ArcPiece{edge, from});
    if (!added && it->second.edge != edge)
      fail("T-edges " + std::to_string(edge) + " and " + std::to_string(it->second.edge) + " overlap in face " +
           std::to_string(f));
  };
  const std::vector<int>& cycle = g.cycle;
  g.adjacent.assign(g.size(), {});
  for (size_t i = 0; i < cycle.size(); ++i) g.connect(cycle[i], cycle[(i + 1) % cycle.size()]);
  for (const Piece& p : ins.pieces[f]) {
    const int a = local(p.from), b = local(p.to);
    const int common = g.side_mask[a] & g.side_mask[b];
    if (!common) {
      g.connect(a, b);
      mark_arc(p.from, p.to, p.edge, p.from);
      continue;
    }
    // Along a side: every boundary step between a and b is on the trace.
    int s = 0;
    while (!(common >> s & 1)) ++s;
    auto position = [&](int l) {
      const int at = static_cast<int>(std::find(cycle.begin(), cycle.end(), l) - cycle.begin());
      return at == 0 && s == 2 ? static_cast<int>(cycle.size()) : at;  // corner 0 ends side 2
    };
    const int pa = position(a), pb = position(b);
    for (int i = std::min(pa, pb); i < std::max(pa, pb); ++i) {
      const int u = g.gid[cycle[i % cycle.size()]], v = g.gid[cycle[(i + 1) % cycle.size()]];
      mark_arc(u, v, p.edge, pa < pb ? u : v);
    }
  }
  for (int a = 0; a < g.size(); ++a)
    std::sort(g.adjacent[a].begin(), g.adjacent[a].end(), [&](int p, int q) {
      const Vec2 dp = g.xy[p] - g.xy[a], dq = g.xy[q] - g.xy[a];
      return std::atan2(dp.y(), dp.x()) < std::atan2(dq.y(), dq.x());
    });
}

// The face of the planar graph that starts with a -> b: turn to the next edge clockwise at every
// point; its directed edges are marked used.
std::vector<int> trace_polygon(int f, const FaceGraph& g, int a, int b, std::map<PointPair, bool>& used) {
  std::vector<int> polygon;
  int u = a, v = b;
  while (!used[{u, v}]) {
    used[{u, v}] = true;
    polygon.push_back(u);
    const std::vector<int>& around = g.adjacent[v];
    const int at = static_cast<int>(std::find(around.begin(), around.end(), u) - around.begin());
    const int w = around[(at + around.size() - 1) % around.size()];
    u = v, v = w;
    if (polygon.size() > static_cast<size_t>(4 * g.size())) fail("face " + std::to_string(f) + " has an open region");
  }
  return polygon;
}

// The signed area of a polygon of local points (reference triangle units).
double polygon_area(const FaceGraph& g, const std::vector<int>& polygon) {
  double area = 0;
  for (size_t i = 0; i < polygon.size(); ++i) {
    const Vec2& p = g.xy[polygon[i]];
    const Vec2& q = g.xy[polygon[(i + 1) % polygon.size()]];
    area += 0.5 * (p.x() * q.y() - p.y() * q.x());
  }
  return area;
}

// Appends a convex region of face f as triangles: itself, or a fan around a new point at its
// centroid.
void triangulate_region(int f, const FaceGraph& g, const std::vector<int>& polygon, RefinedPoints& points,
                        std::vector<std::array<int, 3>>& triangles, std::vector<int>& source_face) {
  const std::vector<int>& gid = g.gid;
  if (polygon.size() == 3) {
    triangles.push_back({gid[polygon[0]], gid[polygon[1]], gid[polygon[2]]});
    source_face.push_back(f);
    return;
  }
  Vec2 centre = Vec2::Zero();
  for (int l : polygon) centre += g.xy[l];
  centre /= static_cast<double>(polygon.size());
  for (size_t i = 0; i < polygon.size(); ++i) {
    const Vec2 p = g.xy[polygon[i]] - centre, q = g.xy[polygon[(i + 1) % polygon.size()]] - centre;
    if (!(p.x() * q.y() - p.y() * q.x() > 0))
      fail("traces cross or double back inside face " + std::to_string(f) + " (a region is not convex)");
  }
  const int c = points.add_inside(f, Vec3(1 - centre.x() - centre.y(), centre.x(), centre.y()));
  for (size_t i = 0; i < polygon.size(); ++i) {
    triangles.push_back({gid[polygon[i]], gid[polygon[(i + 1) % polygon.size()]], c});
    source_face.push_back(f);
  }
}

// Face f of the working mesh cut by its pieces into convex regions, each split into triangles
// around its centroid; appends them (refined point ids) to `triangles`.
void split_face(const TriMesh& mesh, int f, RefinedPoints& points, Insertion& ins,
                std::vector<std::array<int, 3>>& triangles, std::vector<int>& source_face) {
  FaceGraph g = face_points(mesh, f, points);
  if (g.gid.size() == 3 && ins.pieces[f].empty()) {
    triangles.push_back({mesh.F(f, 0), mesh.F(f, 1), mesh.F(f, 2)});
    source_face.push_back(f);
    return;
  }
  connect_pieces(f, ins, g);
  // Faces of the planar graph: turn to the next edge clockwise at every point.
  std::map<PointPair, bool> used;
  double area_sum = 0;
  for (int a = 0; a < g.size(); ++a)
    for (int b : g.adjacent[a]) {
      if (used[{a, b}]) continue;
      const std::vector<int> polygon = trace_polygon(f, g, a, b, used);
      const double area = polygon_area(g, polygon);
      if (area <= 0) continue;  // the outside of the triangle
      area_sum += area;
      triangulate_region(f, g, polygon, points, triangles, source_face);
    }
  if (std::abs(area_sum - 0.5) > 1e-9) fail("traces cross inside face " + std::to_string(f));
}

// Where each side of a cell runs in its rectangle [0,w] x [0,h], and its T-edges along it.
struct CellFrame {
  struct Along {
    int edge, side;
    int64_t offset;
    bool forward;  // the T-edge runs counter-clockwise around the cell
  };
  std::vector<Along> edges;
  int64_t width = 0, height = 0;
  int rotation = 0;        // into the glued uv layout
  Vec2 translation{0, 0};  // integer

  const Along* find(int edge) const {
    for (const Along& a : edges)
      if (a.edge == edge) return &a;
    return nullptr;
  }
  // The point at fraction t of T-edge a in the cell's rectangle.
  Vec2 local(const Along& a, double t, const std::vector<int64_t>& x) const {
    static const int kDir[4][2] = {{1, 0}, {0, 1}, {-1, 0}, {0, -1}};
    const double start[4][2] = {{0, 0}, {double(width), 0}, {double(width), double(height)}, {0, double(height)}};
    const double along = double(a.offset) + (a.forward ? t : 1 - t) * double(x[a.edge]);
    return {start[a.side][0] + kDir[a.side][0] * along, start[a.side][1] + kDir[a.side][1] * along};
  }
  Vec2 global(const Vec2& p) const { return rotate_quarter(p, rotation) + translation; }
};

std::vector<CellFrame> cell_frames(const TMesh& tmesh, const std::vector<int64_t>& x) {
  std::vector<CellFrame> frames(tmesh.cells.size());
  for (size_t c = 0; c < tmesh.cells.size(); ++c) {
    const TMeshCell& cell = tmesh.cells[c];
    if (!cell.four_sided) fail("cell " + std::to_string(c) + " is not four-sided");
    int64_t length[4] = {0, 0, 0, 0};
    for (int s = 0; s < 4; ++s)
      for (int e : cell.sides[s]) {
        const auto& cells = tmesh.edges[e].cells;
        if (cells[0] == cells[1])
          fail("cell " + std::to_string(c) + " borders itself along T-edge " + std::to_string(e));
        frames[c].edges.push_back({e, s, length[s], cells[0] == static_cast<int>(c)});
        length[s] += x[e];
      }
    if (length[0] != length[2] || length[1] != length[3])
      fail("cell " + std::to_string(c) + " is not a rectangle (the quantization breaks its equations)");
    frames[c].width = length[0], frames[c].height = length[1];
  }
  return frames;
}

// Glues the cells' rectangles along a spanning tree of the cell graph: neighbours share their
// T-edge; the remaining T-edges are seams (quarter turn plus integer translation).
void glue_cells(const TMesh& tmesh, const std::vector<int64_t>& x, std::vector<CellFrame>& frames) {
  std::vector<std::vector<int>> edges_of(frames.size());
  for (int e = 0; e < static_cast<int>(tmesh.edges.size()); ++e)
    for (int c : tmesh.edges[e].cells)
      if (c >= 0) edges_of[c].push_back(e);
  std::vector<char> placed(frames.size(), 0);
  for (size_t root = 0; root < frames.size(); ++root) {
    if (placed[root]) continue;
    placed[root] = 1;
    std::queue<int> queue;
    queue.push(static_cast<int>(root));
    while (!queue.empty()) {
      const int a = queue.front();
      queue.pop();
      for (int e : edges_of[a]) {
        const auto& cells = tmesh.edges[e].cells;
        const int b = cells[0] == a ? cells[1] : cells[0];
        if (b < 0 || placed[b]) continue;
        const CellFrame::Along* in_a = frames[a].find(e);
        const CellFrame::Along* in_b = frames[b].find(e);
        if (!in_a || !in_b) fail("T-edge " + std::to_string(e) + " is on no side of its cell");
        CellFrame& fb = frames[b];
        fb.rotation = ((frames[a].rotation + in_a->side + 2 - in_b->side) % 4 + 4) % 4;
        const Vec2 target = frames[a].global(frames[a].local(*in_a, 0, x));
        const Vec2 pb = fb.local(*in_b, 0, x);
        const Vec2 rotated = rotate_quarter(pb, fb.rotation);
        fb.translation = Vec2(std::round(target.x() - rotated.x()), std::round(target.y() - rotated.y()));
        placed[b] = 1;
        queue.push(b);
      }
    }
  }
}

// Weights of the outgoing halfedges of inner vertex v: mean-value weights (positive), or uniform
// ones where asked or where the geometry is degenerate.
std::vector<std::pair<int, double>> tutte_weights(const TriMesh& mesh, int v, bool uniform) {
  const std::vector<int> out = outgoing_halfedges(mesh, v);
  const size_t n = out.size();
  std::vector<std::pair<int, double>> weights;
  for (int h : out) weights.push_back({h, uniform ? 1.0 : 0.0});
  if (uniform) return weights;
  const Vec3 p = mesh.position(v);
  for (size_t i = 0; i < n; ++i) {  // the angle at v between out[i] and the next one counter-clockwise
    const Vec3 a = mesh.position(mesh.to(out[i])) - p, b = mesh.position(mesh.to(out[(i + 1) % n])) - p;
    const double la = a.norm(), lb = b.norm(), denominator = la * lb + a.dot(b);
    const double tan_half = a.cross(b).norm() / denominator;
    if (!(la > 0 && lb > 0 && denominator > 0 && std::isfinite(tan_half))) return tutte_weights(mesh, v, true);
    weights[i].second += tan_half / la;
    weights[(i + 1) % n].second += tan_half / lb;
  }
  double largest = 0;
  for (const auto& [h, w] : weights) largest = std::max(largest, w);
  if (!(largest > 0) || !std::isfinite(largest)) return tutte_weights(mesh, v, true);
  for (auto& [h, w] : weights) w = std::max(w, 1e-8 * largest);  // keep every edge's weight positive
  return weights;
}

// Where zero-length T-edges collapse trace points onto one point, or inner vertices hang on one
// side only, parts of the Tutte embedding are degenerate (segments): exactly so, but rounding
// scatters them by 1e-16 and flips some triangles. Such inner vertices are put exactly where they
// belong: onto the side's coordinate when every neighbour is on it (within 1e-9), or onto the
// collapsed point when all their boundary neighbours sit there and their star is a segment.
void snap_degenerate_stars(const TriMesh& mesh, const std::vector<int>& inner, const std::vector<Vec2>& boundary_uv,
                           std::vector<Vec2>& at) {
  constexpr double kTolerance = 1e-9;
  for (int sweep = 0, changed = 1; changed && sweep < 64; ++sweep) {
    changed = 0;
    for (int v = 0; v < mesh.num_vertices(); ++v) {
      if (inner[v] < 0) continue;
      std::vector<Vec2> ring, boundary;
      for (int h : outgoing_halfedges(mesh, v)) {
        const bool on_boundary = inner[mesh.to(h)] < 0;
        ring.push_back(on_boundary ? boundary_uv[TriMesh::next(h)] : at[inner[mesh.to(h)]]);
        if (on_boundary) boundary.push_back(ring.back());
      }
      if (boundary.empty()) continue;
      Vec2& p = at[inner[v]];
      const Vec2 before = p;
      for (int a = 0; a < 2; ++a) {  // every neighbour on the coordinate line of a boundary one
        const double line = boundary[0][a];
        bool on_line = true;
        for (const Vec2& q : ring) on_line = on_line && std::abs(q[a] - line) <= kTolerance * (1 + std::abs(line));
        if (on_line) p[a] = line;
      }
      const Vec2 c = boundary[0];
      bool one_point = true, segment = true;
      for (const Vec2& q : boundary) one_point = one_point && q == c;
      for (const Vec2& q : ring) {
        const Vec2 d = q - c, e = p - c;
        segment = segment && std::abs(d.x() * e.y() - d.y() * e.x()) <= kTolerance * d.norm() * e.norm();
      }
      if (one_point && segment) p = c;
      changed |= p != before;
    }
  }
}

// The map made exact on the grid of 2^-bits: every vertex is rounded once, in the chart of one of
// its corners, and carried into its other corners' charts by the transitions (quarter turn plus
// integer translation, read off the doubles), so transitions hold exactly.
ExactParametrization exact_map(const TriMesh& mesh, const std::vector<Vec2>& corner_uv, int bits) {
  ExactParametrization p;
  p.fraction_bits = bits;
  const int nh = mesh.num_halfedges();
  p.uv.assign(nh, IVec2{0, 0});
  p.rotation.assign(nh, 0);
  p.translation.assign(nh, IVec2{0, 0});
  p.is_cut.assign(mesh.num_edges(), 0);
  const double one = std::ldexp(1.0, bits);
  for (int h = 0; h < nh; ++h) {  // the transition from face(h)'s chart to the opposite face's
    const int o = mesh.opposite[h];
    if (o < 0) continue;
    const Vec2 a = corner_uv[h], b = corner_uv[TriMesh::next(h)];
    const Vec2 a2 = corner_uv[TriMesh::next(o)], b2 = corner_uv[o];
    double best = std::numeric_limits<double>::infinity();
    for (int r = 0; r < 4; ++r) {
      const Vec2 t = a2 - rotate_quarter(a, r);
      const double err = (rotate_quarter(b, r) + t - b2).cwiseAbs().maxCoeff();
      if (err < best) {
        best = err;
        p.rotation[h] = static_cast<int8_t>(r);
        p.translation[h] = {std::llround(t.x()) * p.one(), std::llround(t.y()) * p.one()};
      }
    }
    if (best > 1e-6) fail("a seam does not match a quarter turn and a translation");
    if (p.rotation[h] != 0 || p.translation[h] != IVec2{0, 0}) p.is_cut[mesh.edge_of[h]] = 1;
  }
  std::vector<char> done(nh, 0);
  for (int c0 = 0; c0 < nh; ++c0) {
    if (done[c0]) continue;
    p.uv[c0] = {std::llround(corner_uv[c0].x() * one), std::llround(corner_uv[c0].y() * one)};
    done[c0] = 1;
    std::vector<int> stack{c0};
    while (!stack.empty()) {  // the other corners of the vertex, across its edges
      const int c = stack.back();
      stack.pop_back();
      const int f = c / 3, k = c % 3;
      const int out = c, in = 3 * f + (k + 2) % 3;
      for (const int h : {out, in}) {
        const int o = mesh.opposite[h];
        if (o < 0) continue;
        const int next = h == out ? 3 * (o / 3) + (o % 3 + 1) % 3 : o;
        if (done[next]) continue;
        p.uv[next] = p.transfer(h, p.uv[c]);
        done[next] = 1;
        stack.push_back(next);
      }
    }
  }
  return p;
}

// The checks of map_cells_to_rectangles's arguments (Error(InvalidArgument) naming the mismatch).
void check_cell_map_inputs(const TriMesh& mesh, const TMesh& tmesh, const std::vector<int64_t>& x) {
  if (x.size() != tmesh.edges.size())
    throw Error(ErrorCode::InvalidArgument, "fallback cell map: " + std::to_string(x.size()) + " lengths for " +
                                                std::to_string(tmesh.edges.size()) + " T-edges");
  const int num_nodes = static_cast<int>(tmesh.nodes.size()), num_cells = static_cast<int>(tmesh.cells.size());
  auto invalid = [](const std::string& what) { throw Error(ErrorCode::InvalidArgument, "fallback cell map: " + what); };
  for (size_t e = 0; e < tmesh.edges.size(); ++e) {
    const TMeshEdge& edge = tmesh.edges[e];
    if (edge.from < 0 || edge.from >= num_nodes || edge.to < 0 || edge.to >= num_nodes)
      invalid("T-edge " + std::to_string(e) + " has no valid end nodes");
    for (int c : edge.cells)
      if (c < -1 || c >= num_cells) invalid("T-edge " + std::to_string(e) + " borders a cell that does not exist");
    for (const SurfacePoint& sp : edge.trace)
      if (sp.face < 0 || sp.face >= mesh.num_faces() || !sp.barycentric.allFinite() || !sp.uv.allFinite())
        invalid("the trace of T-edge " + std::to_string(e) + " leaves the mesh");
  }
  for (const TMeshCell& cell : tmesh.cells)
    for (const auto& side : cell.sides)
      for (int e : side)
        if (e < 0 || e >= static_cast<int>(tmesh.edges.size()))
          invalid("a cell side names a T-edge that does not exist");
  for (int64_t length : x)
    if (length < 0) invalid("a T-edge length is negative");
}

// The state of one cell map (paper §7.1.1), built in its phases: the traces inserted into the
// mesh, the cells found, every cell Tutte-mapped onto its rectangle, the rectangles glued, the map
// made exact and its degenerate triangles opened.
class CellMapper {
 public:
  CellMapper(const TriMesh& mesh, const TMesh& tmesh, const std::vector<int64_t>& x, Progress& progress,
             const CellMapOptions& options)
      : mesh_(mesh), tmesh_(tmesh), x_(x), progress_(progress), options_(options), points_(mesh) {}

  // All the phases; the map without its time.
  CellMap run();

 private:
  void insert_traces_into_mesh();
  void find_cells();
  double closest_fraction(int v, int w, int edge) const;
  Vec2 wedge_position(int h) const;
  void place_trace_points();
  std::vector<Vec2> solve_tutte(const std::vector<char>& uniform) const;
  int mark_uniform_around_flips(std::vector<char>& uniform) const;
  void embed_inner_points();
  void glue_rectangles();
  std::vector<int> refined_cone_turns() const;
  void open_degenerate_triangles(const std::vector<int>& cone_turns);
  void count_triangles();
  void count_wound_vertices(const std::vector<int>& cone_turns);

  const TriMesh& mesh_;
  const TMesh& tmesh_;
  const std::vector<int64_t>& x_;
  Progress& progress_;
  const CellMapOptions& options_;
  std::vector<CellFrame> frames_;  // #cells
  RefinedPoints points_;
  Insertion ins_;
  CellMap map_;
  std::vector<Vec2> local_uv_;  // 3#F of the refined mesh: corners in their cell's rectangle
  std::vector<int> inner_;      // #V of the refined mesh: row in the Tutte system, or -1 (on a trace)
  int num_inner_ = 0;
};

CellMap CellMapper::run() {
  frames_ = cell_frames(tmesh_, x_);
  insert_traces_into_mesh();
  find_cells();
  place_trace_points();
  embed_inner_points();
  glue_rectangles();
  // 5. Exact, and degenerate triangles opened where single moves can.
  map_.param = exact_map(map_.mesh, map_.corner_uv, options_.fraction_bits);
  const std::vector<int> cone_turns = refined_cone_turns();
  open_degenerate_triangles(cone_turns);
  count_triangles();
  count_wound_vertices(cone_turns);
  map_.stats.vertices = map_.mesh.num_vertices();
  map_.stats.faces = map_.mesh.num_faces();
  map_.stats.inner_vertices = num_inner_;
  return std::move(map_);
}

// 1. Insert the traces: split every face they touch; the refined mesh with its connectivity.
void CellMapper::insert_traces_into_mesh() {
  ins_ = insert_traces(mesh_, tmesh_, points_, progress_);
  std::vector<std::array<int, 3>> triangles;
  for (int f = 0; f < mesh_.num_faces(); ++f) {
    if (f % 1024 == 0) progress_.check_cancel();
    split_face(mesh_, f, points_, ins_, triangles, map_.source_face);
  }
  TriMesh& refined = map_.mesh;
  refined.V.resize(static_cast<int>(points_.position.size()), 3);
  for (size_t v = 0; v < points_.position.size(); ++v)
    refined.V.row(static_cast<int>(v)) = points_.position[v].transpose();
  refined.F.resize(static_cast<int>(triangles.size()), 3);
  for (size_t t = 0; t < triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) refined.F(static_cast<int>(t), k) = triangles[t][k];
  try {
    build_connectivity(refined);
  } catch (const Error& e) {
    fail(std::string("the mesh with the traces inserted is not a manifold: ") + e.what());
  }
  ins_.arcs.resize(points_.position.size());
}

// 2. Cells: the regions the traces bound, named by the T-edges on their boundary (face_cell).
void CellMapper::find_cells() {
  const TriMesh& refined = map_.mesh;
  const int nf = refined.num_faces();
  UnionFind<int> regions(nf);
  for (int h = 0; h < refined.num_halfedges(); ++h) {
    const int o = refined.opposite[h];
    if (o >= 0 && !ins_.arc_pieces.count(key(refined.from(h), refined.to(h)))) regions.unite(h / 3, o / 3);
  }
  std::vector<int> region_cell(nf, -1);
  for (int h = 0; h < refined.num_halfedges(); ++h) {
    const auto it = ins_.arc_pieces.find(key(refined.from(h), refined.to(h)));
    if (it == ins_.arc_pieces.end()) continue;
    const auto& cells = tmesh_.edges[it->second.edge].cells;
    const int cell = refined.from(h) == it->second.from ? cells[0] : cells[1];  // the face of h is on its left
    int& assigned = region_cell[regions.find(h / 3)];
    if (assigned >= 0 && assigned != cell)
      fail("the traces do not separate cells " + std::to_string(assigned) + " and " + std::to_string(cell));
    assigned = cell;
  }
  std::vector<int> cell_region(tmesh_.cells.size(), -1);
  map_.face_cell.resize(nf);
  for (int t = 0; t < nf; ++t) {
    const int r = regions.find(t), cell = region_cell[r];
    if (cell < 0) fail("a region of the surface touches no trace");
    if (cell_region[cell] >= 0 && cell_region[cell] != r)
      fail("cell " + std::to_string(cell) + " falls apart into two regions");
    cell_region[cell] = r;
    map_.face_cell[t] = cell;
  }
  for (size_t c = 0; c < tmesh_.cells.size(); ++c)
    if (cell_region[c] < 0) fail("cell " + std::to_string(c) + " covers no part of the surface");
}

// v's fraction on `edge` nearest w's (-1 where either is not on it).
double CellMapper::closest_fraction(int v, int w, int edge) const {
  double best = -1, gap = 2;
  for (const auto& [ev, tv] : ins_.arcs[v])
    for (const auto& [ew, tw] : ins_.arcs[w])
      if (ev == edge && ew == edge && std::abs(tv - tw) < gap) best = tv, gap = std::abs(tv - tw);
  return best;
}

// The position of from(h) in the rectangle of the cell of face h / 3.
Vec2 CellMapper::wedge_position(int h) const {
  const TriMesh& refined = map_.mesh;
  const int v = refined.from(h), cell = map_.face_cell[h / 3];
  for (int g = h, step = 0; g >= 0 && step < 4096; g = refined.rotate_cw(g), ++step) {
    const auto it = ins_.arc_pieces.find(key(v, refined.to(g)));
    if (it == ins_.arc_pieces.end()) continue;
    const CellFrame::Along* along = frames_[cell].find(it->second.edge);
    const double t = closest_fraction(v, refined.to(g), it->second.edge);
    if (!along || t < 0) break;
    return frames_[cell].local(*along, t, x_);
  }
  fail("a trace point of cell " + std::to_string(cell) + " lies on none of its sides");
}

// 3. Trace points on their rectangles' boundaries, per wedge (a cell can touch a node twice);
//    the other points numbered as the Tutte embedding's unknowns.
void CellMapper::place_trace_points() {
  const TriMesh& refined = map_.mesh;
  const int nv = refined.num_vertices(), nf = refined.num_faces();
  local_uv_.resize(3 * static_cast<size_t>(nf));
  inner_.assign(nv, -1);
  std::vector<int> vertex_cell(nv, -1);
  for (int t = 0; t < nf; ++t)
    for (int k = 0; k < 3; ++k) {
      const int v = refined.F(t, k);
      if (!ins_.arcs[v].empty()) {
        local_uv_[3 * t + k] = wedge_position(3 * t + k);
        continue;
      }
      if (inner_[v] >= 0) continue;
      if (refined.opposite[refined.vertex_halfedge[v]] < 0) fail("a boundary vertex lies on no trace");
      inner_[v] = num_inner_++;
      vertex_cell[v] = map_.face_cell[t];
    }
}

// The Tutte embedding of the inner points (rows of inner_), uniform weights where asked.
std::vector<Vec2> CellMapper::solve_tutte(const std::vector<char>& uniform) const {
  const TriMesh& refined = map_.mesh;
  const int nv = refined.num_vertices();
  std::vector<Eigen::Triplet<double>> entries;
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(num_inner_, 2);
  for (int v = 0; v < nv; ++v) {
    if (inner_[v] < 0) continue;
    const int row = inner_[v];
    double total = 0;
    for (const auto& [h, w] : tutte_weights(refined, v, uniform[v])) {
      const int j = refined.to(h);
      total += w;
      if (inner_[j] >= 0)
        entries.emplace_back(row, inner_[j], -w);
      else
        rhs.row(row) += w * local_uv_[TriMesh::next(h)].transpose();
    }
    entries.emplace_back(row, row, total);
  }
  Eigen::SparseMatrix<double> A(num_inner_, num_inner_);
  A.setFromTriplets(entries.begin(), entries.end());
  Eigen::SparseLU<Eigen::SparseMatrix<double>> solver;
  solver.compute(A);
  if (solver.info() != Eigen::Success) fail("the Tutte system could not be factorized");
  const Eigen::MatrixXd solution = solver.solve(rhs);
  if (solver.info() != Eigen::Success || !solution.allFinite()) fail("the Tutte system could not be solved");
  std::vector<Vec2> at(num_inner_);
  for (int v = 0; v < nv; ++v)
    if (inner_[v] >= 0) at[inner_[v]] = solution.row(inner_[v]).transpose();
  return at;
}

// Marks for uniform weights the inner vertices of every flipped triangle and their inner
// neighbours; returns how many were newly marked.
int CellMapper::mark_uniform_around_flips(std::vector<char>& uniform) const {
  const TriMesh& refined = map_.mesh;
  int marked = 0;
  for (int t = 0; t < refined.num_faces(); ++t) {
    const Vec2 a = local_uv_[3 * t + 1] - local_uv_[3 * t], b = local_uv_[3 * t + 2] - local_uv_[3 * t];
    if (!(a.x() * b.y() - a.y() * b.x() < 0)) continue;
    for (int k = 0; k < 3; ++k)  // the flipped triangle's inner vertices and their inner neighbours
      if (inner_[refined.F(t, k)] >= 0)
        for (int h : outgoing_halfedges(refined, refined.F(t, k)))
          for (int v : {refined.from(h), refined.to(h)})
            if (inner_[v] >= 0 && !uniform[v]) uniform[v] = 1, ++marked;
  }
  return marked;
}

// Inner points by the Tutte embedding, into local_uv_.
void CellMapper::embed_inner_points() {
  const TriMesh& refined = map_.mesh;
  // Mean-value weights first; where rounding flips sliver triangles, uniform weights around them.
  std::vector<char> uniform(refined.num_vertices(), 0);
  for (int round = 0; num_inner_ > 0; ++round) {
    progress_.check_cancel();
    std::vector<Vec2> at = solve_tutte(uniform);
    snap_degenerate_stars(refined, inner_, local_uv_, at);
    for (int t = 0; t < refined.num_faces(); ++t)
      for (int k = 0; k < 3; ++k)
        if (inner_[refined.F(t, k)] >= 0) local_uv_[3 * t + k] = at[inner_[refined.F(t, k)]];
    const int marked = round < 4 ? mark_uniform_around_flips(uniform) : 0;
    if (marked == 0) break;
  }
}

// 4. Corners in the glued layout (exact_map gives each vertex one uv per chart).
void CellMapper::glue_rectangles() {
  glue_cells(tmesh_, x_, frames_);
  const int nf = map_.mesh.num_faces();
  map_.corner_uv.resize(3 * static_cast<size_t>(nf));
  for (int t = 0; t < nf; ++t)
    for (int k = 0; k < 3; ++k) map_.corner_uv[3 * t + k] = frames_[map_.face_cell[t]].global(local_uv_[3 * t + k]);
}

// The cone angles of the refined mesh's vertices (inserted points regular), or empty.
std::vector<int> CellMapper::refined_cone_turns() const {
  const TriMesh& refined = map_.mesh;
  std::vector<int> cone_turns;
  if (!options_.cone_turns.empty()) {
    if (static_cast<int>(options_.cone_turns.size()) != mesh_.num_vertices())
      throw Error(ErrorCode::InvalidArgument, "fallback cell map: the cone angles do not match the mesh");
    cone_turns = options_.cone_turns;
    for (int v = mesh_.num_vertices(); v < refined.num_vertices(); ++v)
      cone_turns.push_back(refined.opposite[refined.vertex_halfedge[v]] < 0 ? 2 : 4);
  }
  return cone_turns;
}

// Degenerate triangles opened (and rounding flips unfolded) where single moves can.
void CellMapper::open_degenerate_triangles(const std::vector<int>& cone_turns) {
  const TriMesh& refined = map_.mesh;
  // Rounding can flip a sliver: the same moves unfold it (also when no opening was asked for).
  int rounding_flips = 0;
  for (int t = 0; t < refined.num_faces(); ++t)
    rounding_flips += orient2d_exact(map_.param.uv[3 * t], map_.param.uv[3 * t + 1], map_.param.uv[3 * t + 2]) < 0;
  if (!(options_.open_degenerate || rounding_flips > 0)) return;
  std::vector<char> pinned(refined.num_vertices(), 0);
  for (size_t n = 0; n < tmesh_.nodes.size(); ++n)
    if (tmesh_.nodes[n].kind != TMeshNode::Kind::TJunction && tmesh_.nodes[n].kind != TMeshNode::Kind::Crossing)
      pinned[ins_.node_point[n]] = 1;
  std::vector<IsolineConstraint> isolines;
  for (int h = 0; h < refined.num_halfedges(); ++h) {
    const int o = refined.opposite[h];
    if (o >= 0 && o < h) continue;
    const auto it = ins_.arc_pieces.find(key(refined.from(h), refined.to(h)));
    if (it == ins_.arc_pieces.end() || !tmesh_.edges[it->second.edge].on_feature) continue;
    const IVec2 &a = map_.param.uv[h], &b = map_.param.uv[TriMesh::next(h)];
    if (a[0] == b[0])
      isolines.push_back({h, 0});
    else if (a[1] == b[1])
      isolines.push_back({h, 1});
  }
  MapUntangleOptions untangle;
  untangle.never_flip = true;
  untangle.cone_turns = cone_turns;
  const MapUntangleStats opened = untangle_map(refined, pinned, isolines, map_.param, progress_, untangle);
  map_.stats.degenerate_before_opening = opened.degenerate_before;
  map_.stats.flipped_before_opening = opened.flipped_before;
  map_.stats.opened_vertices = opened.moved_vertices;
}

// corner_uv from the exact map, and its flipped, degenerate and collapsed triangles counted.
void CellMapper::count_triangles() {
  for (int t = 0; t < map_.mesh.num_faces(); ++t) {
    for (int k = 0; k < 3; ++k)
      map_.corner_uv[3 * t + k] =
          Vec2(map_.param.to_double(map_.param.uv[3 * t + k][0]), map_.param.to_double(map_.param.uv[3 * t + k][1]));
    const int sign = orient2d_exact(map_.param.uv[3 * t], map_.param.uv[3 * t + 1], map_.param.uv[3 * t + 2]);
    map_.stats.flipped_triangles += sign < 0;
    map_.stats.degenerate_triangles += sign == 0;
    const CellFrame& frame = frames_[map_.face_cell[t]];
    map_.stats.collapsed_cell_triangles += sign == 0 && (frame.width == 0 || frame.height == 0);
  }
}

// Counts the rings wound other than their cone where every triangle is positive (cone angles given).
void CellMapper::count_wound_vertices(const std::vector<int>& cone_turns) {
  if (cone_turns.empty()) return;
  const TriMesh& refined = map_.mesh;
  const std::vector<int> turns = exact_angle_sums(refined, map_.param);
  std::vector<char> positive(refined.num_vertices(), 1);
  for (int t = 0; t < refined.num_faces(); ++t)
    if (orient2d_exact(map_.param.uv[3 * t], map_.param.uv[3 * t + 1], map_.param.uv[3 * t + 2]) <= 0)
      for (int k = 0; k < 3; ++k) positive[refined.F(t, k)] = 0;
  for (int v = 0; v < refined.num_vertices(); ++v)
    map_.stats.wound_vertices += positive[v] && turns[v] != cone_turns[v];
}

}  // namespace

CellMap map_cells_to_rectangles(const TriMesh& mesh, const TMesh& tmesh, const std::vector<int64_t>& x,
                                Progress& progress, const CellMapOptions& options) {
  Timer timer;
  check_cell_map_inputs(mesh, tmesh, x);
  CellMap map = CellMapper(mesh, tmesh, x, progress, options).run();
  map.stats.seconds = timer.seconds();
  return map;
}

}  // namespace qgp

// T-mesh construction in two steps:
//  1. MotorcycleTracer (detail/motorcycles.h) traces every separatrix exactly and records, per
//     separatrix, its pieces in the faces and the nodes along it (by travel time); nodes are
//     identified by canonical surface points, so every meeting of traces shares one node.
//  2. Assembler (below) cuts separatrices and feature/boundary curves at their nodes into
//     pieces, collects each node's incidences in its local frame, merges the straight degree-2
//     nodes of head-on meetings, orients the edges, and walks the faces of the embedded graph
//     into cells (corners = quarter-turn angles at nodes).
#include "tmesh/trace_tmesh.h"

#include <algorithm>
#include <climits>
#include <cmath>
#include <map>

#include "core/error.h"
#include "core/timer.h"
#include "tmesh/detail/motorcycles.h"

namespace qgp {

namespace {

using namespace tmesh_detail;

[[noreturn]] void fail(const std::string& message) { throw Error(ErrorCode::StageFailed, "T-mesh: " + message); }

// x - y, exact in 128 bits when it fits (the usual case), else in long double.
long double rational_difference(const Rational& x, const Rational& y) {
  i128 a, b, num, den;
  if (!__builtin_mul_overflow(x.num, y.den, &a) && !__builtin_mul_overflow(y.num, x.den, &b) &&
      !__builtin_sub_overflow(a, b, &num) && !__builtin_mul_overflow(x.den, y.den, &den)) {
    const Rational r = Rational(num, den).reduced();
    return static_cast<long double>(r.num) / static_cast<long double>(r.den);
  }
  return static_cast<long double>(x.num) / x.den - static_cast<long double>(y.num) / y.den;
}

// A T-mesh edge under construction: a path between two nodes.
struct Piece {
  int a = -1, b = -1;        // end nodes; points run from a to b
  int dir_a = 0, dir_b = 0;  // direction numbers at a (towards b) and at b (towards a)
  std::vector<SurfacePoint> points;
  double length = 0;
  int first_dir = 0, last_dir = 0;  // direction a -> b in the charts of points.front()/back()
  bool wall = false;
  bool left_ok[2] = {true, true};  // a cell lies left of a -> b [0] / b -> a [1]
  bool alive = true;

  void reverse() {
    std::swap(a, b);
    std::swap(dir_a, dir_b);
    std::reverse(points.begin(), points.end());
    const int f = first_dir;
    first_dir = (last_dir + 2) & 3;
    last_dir = (f + 2) & 3;
    std::swap(left_ok[0], left_ok[1]);
  }
};

struct Incidence {
  int piece, end;  // end 0: the piece's a, 1: its b
  int number;
};

class Assembler {
 public:
  explicit Assembler(const MotorcycleTracer& tracer)
      : tracer_(tracer), mesh_(tracer.mesh()), scale_(std::ldexp(1.0, -tracer.fraction_bits() - 1)) {}

  TMesh build() {
    trace_pieces();
    wall_pieces();
    incidences();
    merge_straight_nodes();
    return finish();
  }

 private:
  void trace_pieces() {
    const auto& segments = tracer_.segments();
    for (const Motorcycle& mo : tracer_.motorcycles()) {
      if (mo.junctions.size() < 2 || mo.segments.empty()) continue;
      for (auto it = mo.junctions.begin(), next = std::next(it); next != mo.junctions.end(); ++it, ++next) {
        const Rational& ta = it->first;
        const Rational& tb = next->first;
        Piece p;
        p.a = it->second;
        p.b = next->second;
        const Segment* first = nullptr;
        const Segment* last = nullptr;
        for (int id : mo.segments) {
          const Segment& s = segments[id];
          const Rational lo = compare(s.t0, ta) > 0 ? s.t0 : ta;
          const Rational hi = compare(s.t1, tb) < 0 ? s.t1 : tb;
          if (compare(lo, hi) >= 0) continue;
          if (!first) first = &s;
          last = &s;
          p.points.push_back(tracer_.segment_point(s, lo));
          p.points.push_back(tracer_.segment_point(s, hi));
        }
        if (!first) fail("internal: empty separatrix piece");
        p.first_dir = first->dir;
        p.last_dir = last->dir;
        p.dir_a = tracer_.node_direction(p.a, first->face, first->dir);
        p.dir_b = tracer_.node_direction(p.b, last->face, last->dir + 2);
        if (p.dir_a == INT_MIN || p.dir_b == INT_MIN) fail("internal: separatrix direction unknown at its node");
        p.length = static_cast<double>(rational_difference(tb, ta) * scale_);
        pieces_.push_back(std::move(p));
      }
    }
  }

  // Point at parameter lambda of edge e (from its first halfedge's origin), in that face.
  SurfacePoint edge_point(int e, const Rational& lambda) const {
    const int hc = mesh_.edge_halfedge[e];
    const double l = lambda.to_double();
    SurfacePoint sp;
    sp.face = hc / 3;
    sp.barycentric = Vec3::Zero();
    sp.barycentric[hc % 3] = 1 - l;
    sp.barycentric[(hc % 3 + 1) % 3] += l;
    const P2& p = tracer_.uv2()[hc];
    const P2& q = tracer_.uv2()[TriMesh::next(hc)];
    sp.uv = Vec2((p[0] + l * double(q[0] - p[0])) * scale_, (p[1] + l * double(q[1] - p[1])) * scale_);
    return sp;
  }

  // Frame number of the wall edge e leaving vertex node v.
  int wall_number_at_vertex(int v, int e) const {
    const VertexStar& s = tracer_.stars()[v];
    for (size_t i = 0; i < s.ring.size(); ++i)
      if (mesh_.edge_of[s.ring[i].h_out] == e) return s.wall_number[i];
    if (s.boundary && !s.ring.empty() && mesh_.edge_of[TriMesh::prev(s.ring.back().h_out)] == e)
      return s.end_wall_number;
    return INT_MIN;
  }

  // Wall edges with the nodes on them and around them, and which of their sub-intervals the
  // wall walks have covered.
  struct WallIndex {
    std::map<int, std::vector<std::pair<Rational, int>>> on_edge;  // wall edge -> (lambda, node)
    std::vector<int> vertex_node;                                  // mesh vertex -> node or -1
    std::vector<std::vector<int>> wall_edges_at;                   // mesh vertex -> wall edges
    std::vector<std::vector<char>> visited;                        // wall edge -> sub-intervals between its nodes
  };

  // One walk along a wall: the piece under construction and the current atom (sub-interval k of
  // wall edge e, run with increasing lambda or not).
  struct WallWalk {
    Piece p;
    long double total[2] = {0, 0};  // displacement so far, in the first atom's chart
    int rho = 0, prev_face = -1, prev_vertex = -1;
    bool first_atom = true;
    int e = -1, k = 0;
    bool increasing = true;
  };

  // Indexes the wall edges: nodes on them sorted by lambda, nodes at vertices, wall edges at
  // each vertex, and unvisited sub-intervals.
  WallIndex index_walls() const {
    const auto& nodes = tracer_.nodes();
    const auto& walls = tracer_.wall_edge();
    WallIndex w;
    auto& on_edge = w.on_edge;
    w.vertex_node.assign(mesh_.num_vertices(), -1);
    for (int n = 0; n < static_cast<int>(nodes.size()); ++n) {
      const PointKey& k = nodes[n].key;
      if (k.type == PointKey::Vertex) w.vertex_node[k.id] = n;
      if (k.type == PointKey::Edge && walls[k.id]) on_edge[k.id].push_back({k.a, n});
    }
    w.wall_edges_at.resize(mesh_.num_vertices());
    w.visited.resize(mesh_.num_edges());
    for (int e = 0; e < mesh_.num_edges(); ++e) {
      if (!walls[e]) continue;
      auto& list = on_edge[e];
      std::sort(list.begin(), list.end(), [](const auto& x, const auto& y) { return compare(x.first, y.first) < 0; });
      w.visited[e].assign(list.size() + 1, 0);
      const int h = mesh_.edge_halfedge[e];
      w.wall_edges_at[mesh_.from(h)].push_back(e);
      w.wall_edges_at[mesh_.to(h)].push_back(e);
    }
    return w;
  }

  void wall_pieces() {
    const auto& nodes = tracer_.nodes();
    const auto& walls = tracer_.wall_edge();
    WallIndex w = index_walls();
    for (int n = 0; n < static_cast<int>(nodes.size()); ++n) {
      const PointKey& key = nodes[n].key;
      if (key.type == PointKey::Vertex) {
        for (int e : w.wall_edges_at[key.id]) {
          const bool from_v = mesh_.from(mesh_.edge_halfedge[e]) == key.id;
          walk_wall(w, n, e, from_v ? 0 : static_cast<int>(w.on_edge[e].size()), from_v);
        }
      } else if (key.type == PointKey::Edge && walls[key.id]) {
        const auto& list = w.on_edge[key.id];
        int i = 0;
        while (list[i].second != n) ++i;
        walk_wall(w, n, key.id, i + 1, true);
        walk_wall(w, n, key.id, i, false);
      }
    }
    for (int e = 0; e < mesh_.num_edges(); ++e)
      for (char v : w.visited[e])
        if (!v) fail("internal: part of a feature/boundary curve has no node");
  }

  // Walk from node `start` along wall edge e, starting with sub-interval k, increasing lambda
  // or not, through straight wall vertices, to the next node; appends the wall piece.
  void walk_wall(WallIndex& w, int start, int e, int k, bool increasing) {
    if (w.visited[e][k]) return;
    const auto& nodes = tracer_.nodes();
    WallWalk walk;
    Piece& p = walk.p;
    p.wall = true;
    p.a = start;
    walk.e = e, walk.k = k, walk.increasing = increasing;
    for (int guard = 0;; ++guard) {
      if (guard > 4 * mesh_.num_edges() + 8) fail("internal: wall walk does not end");
      const int face = mesh_.edge_halfedge[walk.e] / 3;
      const int dir = add_wall_atom(w, walk, start);
      const int end_node = wall_atom_end(w, walk);
      if (end_node < 0) continue;
      p.b = end_node;
      const int de = nodes[end_node].key.type == PointKey::Vertex
                         ? wall_number_at_vertex(nodes[end_node].key.id, walk.e)
                         : tracer_.node_direction(end_node, face, dir + 2);
      p.dir_b = de;
      break;
    }
    if (p.dir_a == INT_MIN || p.dir_b == INT_MIN) fail("internal: wall direction unknown at its node");
    const int axis = p.first_dir & 1;
    p.length = static_cast<double>(std::fabs(walk.total[axis]) * scale_);
    pieces_.push_back(std::move(p));
  }

  // Adds the walk's current atom to its piece (points, directions, displacement) and marks it
  // visited. Returns the atom's direction (nearest cardinal, in its face's chart).
  int add_wall_atom(WallIndex& w, WallWalk& walk, int start) const {
    const auto& nodes = tracer_.nodes();
    const int e = walk.e, k = walk.k;
    const bool increasing = walk.increasing;
    Piece& p = walk.p;
    w.visited[e][k] = 1;
    const auto& list = w.on_edge[e];
    const int hc = mesh_.edge_halfedge[e];
    const int face = hc / 3;
    if (walk.prev_vertex >= 0) {  // change of chart around the shared vertex
      const VertexStar& s = tracer_.stars()[walk.prev_vertex];
      const int c1 = s.corner_of_face(walk.prev_face), c2 = s.corner_of_face(face);
      if (c1 < 0 || c2 < 0) fail("internal: wall chain leaves the vertex ring");
      walk.rho += s.ring[c2].acc - s.ring[c1].acc;
    }
    const Rational lam0 = k == 0 ? Rational(0) : list[k - 1].first;
    const Rational lam1 = k == static_cast<int>(list.size()) ? Rational(1) : list[k].first;
    const Rational& ls = increasing ? lam0 : lam1;
    const Rational& le = increasing ? lam1 : lam0;
    p.points.push_back(edge_point(e, ls));
    p.points.push_back(edge_point(e, le));
    const P2& P = tracer_.uv2()[hc];
    const P2& Q = tracer_.uv2()[TriMesh::next(hc)];
    const P2 ev = increasing ? sub(Q, P) : sub(P, Q);
    const int dir = nearest_cardinal(ev);
    if (walk.first_atom) {
      p.first_dir = dir;
      if (mesh_.opposite[hc] < 0) {
        p.left_ok[0] = increasing;
        p.left_ok[1] = !increasing;
      }
      const int ds = nodes[start].key.type == PointKey::Vertex ? wall_number_at_vertex(nodes[start].key.id, e)
                                                               : tracer_.node_direction(start, face, dir);
      p.dir_a = ds;
    }
    walk.first_atom = false;
    p.last_dir = dir;
    // Displacement of this atom, rotated back into the first atom's chart.
    const long double span = rational_difference(le, ls);
    const std::array<long double, 2> disp{span * static_cast<long double>(Q[0] - P[0]),
                                          span * static_cast<long double>(Q[1] - P[1])};
    const std::array<long double, 2> back = rotate_quarter(disp, -walk.rho);
    walk.total[0] += back[0];
    walk.total[1] += back[1];
    return dir;
  }

  // Where does the walk's current atom end? Returns the node there, or -1 after moving the walk
  // on through a straight wall vertex (no node) onto the next wall edge.
  int wall_atom_end(WallIndex& w, WallWalk& walk) const {
    const int e = walk.e, k = walk.k;
    const bool increasing = walk.increasing;
    const auto& list = w.on_edge[e];
    const int hc = mesh_.edge_halfedge[e];
    const bool at_interior_node = increasing ? k < static_cast<int>(list.size()) : k > 0;
    if (at_interior_node) return list[increasing ? k : k - 1].second;
    const int x = increasing ? mesh_.to(hc) : mesh_.from(hc);
    if (w.vertex_node[x] >= 0) return w.vertex_node[x];
    int e2 = -1;
    for (int cand : w.wall_edges_at[x])
      if (cand != e) e2 = cand;
    if (w.wall_edges_at[x].size() != 2 || e2 < 0)
      fail("internal: wall vertex " + std::to_string(x) + " is no node but not straight");
    walk.prev_vertex = x;
    walk.prev_face = hc / 3;
    walk.e = e2;
    const bool from_x = mesh_.from(mesh_.edge_halfedge[e2]) == x;
    walk.increasing = from_x;
    walk.k = from_x ? 0 : static_cast<int>(w.on_edge[e2].size());
    if (w.visited[walk.e][walk.k]) fail("internal: wall atom visited twice");
    return -1;
  }

  int node_period(int n) const {
    const PointKey& key = tracer_.nodes()[n].key;
    if (key.type != PointKey::Vertex) return 4;
    const VertexStar& s = tracer_.stars()[key.id];
    return s.sector_frame ? s.period : 4;
  }
  bool node_chart_frame(int n) const {
    const PointKey& key = tracer_.nodes()[n].key;
    return key.type != PointKey::Vertex || !tracer_.stars()[key.id].sector_frame;
  }
  bool node_is_corner(int n) const {
    const PointKey& key = tracer_.nodes()[n].key;
    return key.type == PointKey::Vertex && tracer_.stars()[key.id].corner;
  }

  void incidences() {
    incidences_.assign(tracer_.nodes().size(), {});
    for (int i = 0; i < static_cast<int>(pieces_.size()); ++i) {
      incidences_[pieces_[i].a].push_back({i, 0, pieces_[i].dir_a});
      incidences_[pieces_[i].b].push_back({i, 1, pieces_[i].dir_b});
    }
  }

  void merge_straight_nodes() {
    node_alive_.assign(tracer_.nodes().size(), 1);
    for (int n = 0; n < static_cast<int>(incidences_.size()); ++n) {
      auto& inc = incidences_[n];
      if (inc.size() != 2 || node_is_corner(n) || !node_chart_frame(n)) continue;
      if (((inc[0].number - inc[1].number) & 3) != 2) continue;
      if (inc[0].piece == inc[1].piece) continue;
      Piece& p1 = pieces_[inc[0].piece];
      Piece& p2 = pieces_[inc[1].piece];
      if (p1.wall || p2.wall) continue;
      if (p1.b != n) p1.reverse();
      if (p2.a != n) p2.reverse();
      Piece merged;
      merged.a = p1.a;
      merged.b = p2.b;
      merged.dir_a = p1.dir_a;
      merged.dir_b = p2.dir_b;
      merged.points = p1.points;
      merged.points.insert(merged.points.end(), p2.points.begin(), p2.points.end());
      merged.length = p1.length + p2.length;
      merged.first_dir = p1.first_dir;
      merged.last_dir = p2.last_dir;
      merged.left_ok[0] = p1.left_ok[0] && p2.left_ok[0];
      merged.left_ok[1] = p1.left_ok[1] && p2.left_ok[1];
      const int id = static_cast<int>(pieces_.size());
      const int old1 = inc[0].piece, old2 = inc[1].piece;
      pieces_[old1].alive = false;
      pieces_[old2].alive = false;
      // Re-point the far ends to the merged piece (a loop may touch one node twice).
      for (Incidence& x : incidences_[merged.a])
        if (x.piece == old1) x.piece = id, x.end = 0;
      for (Incidence& x : incidences_[merged.b])
        if (x.piece == old2) x.piece = id, x.end = 1;
      pieces_.push_back(std::move(merged));
      incidences_[n].clear();
      node_alive_[n] = 0;
      ++merged_nodes_;
    }
  }

  // Orientation: positive in the chart of the first point; a piece that starts negatively is
  // reversed unless its other end starts negatively too (it crosses a half-turn transition).
  static bool flipped(const Piece& p) { return p.first_dir >= 2 && p.last_dir >= 2; }

  TMesh finish() {
    TMesh tm;
    const auto& nodes = tracer_.nodes();
    std::vector<int> node_id(nodes.size(), -1), piece_id(pieces_.size(), -1);
    for (size_t n = 0; n < nodes.size(); ++n)
      if (node_alive_[n]) node_id[n] = static_cast<int>(tm.nodes.size()), tm.nodes.emplace_back();
    for (size_t i = 0; i < pieces_.size(); ++i) {
      Piece& p = pieces_[i];
      if (!p.alive) continue;
      const bool flip = flipped(p);
      piece_id[i] = static_cast<int>(tm.edges.size());
      TMeshEdge e;
      e.from = node_id[flip ? p.b : p.a];
      e.to = node_id[flip ? p.a : p.b];
      e.axis = p.first_dir & 1;
      if (flip) e.axis = ((p.last_dir + 2) & 3) & 1;
      e.length = p.length;
      e.on_feature = p.wall;
      e.trace = p.points;
      if (flip) std::reverse(e.trace.begin(), e.trace.end());
      tm.edges.push_back(std::move(e));
    }
    // Nodes: kind, index, incidences sorted counter-clockwise.
    const auto& stars = tracer_.stars();
    const auto& walls = tracer_.wall_edge();
    for (size_t n = 0; n < nodes.size(); ++n) {
      if (node_id[n] < 0) continue;
      TMeshNode& out = tm.nodes[node_id[n]];
      const PointKey& key = nodes[n].key;
      out.point = nodes[n].point;
      std::vector<Incidence> inc = incidences_[n];
      std::sort(inc.begin(), inc.end(), [](const Incidence& x, const Incidence& y) { return x.number < y.number; });
      for (size_t i = 1; i < inc.size(); ++i)
        if (inc[i].number == inc[i - 1].number)
          fail("two T-mesh edges leave node at surface point (face " + std::to_string(out.point.face) +
               ") in the same direction (degenerate configuration)");
      for (const Incidence& x : inc) {
        const bool flip = flipped(pieces_[x.piece]);
        TMeshIncidence ti;
        ti.edge = piece_id[x.piece];
        ti.direction = x.number;
        ti.outgoing = (x.end == 0) != flip;
        out.incidences.push_back(ti);
      }
      if (key.type == PointKey::Vertex) {
        const VertexStar& s = stars[key.id];
        out.mesh_vertex = key.id;
        out.on_feature = s.on_wall;
        if (s.corner) {
          out.index = s.seed ? 0 : s.index;
          out.kind = s.seed       ? TMeshNode::Kind::Seed
                     : !s.on_wall ? TMeshNode::Kind::Singularity
                     : s.boundary ? TMeshNode::Kind::BoundaryNode
                                  : TMeshNode::Kind::FeatureCorner;
          continue;
        }
      } else if (key.type == PointKey::Edge) {
        out.on_feature = walls[key.id] != 0;
      }
      out.kind = out.incidences.size() >= 4 ? TMeshNode::Kind::Crossing : TMeshNode::Kind::TJunction;
    }
    build_cells(tm, node_id);
    tm.stats.merged_nodes = merged_nodes_;
    return tm;
  }

  void build_cells(TMesh& tm, const std::vector<int>& node_id) {
    // Per node: sorted incidences and its period; halfedge = (edge, forward).
    const int ne = static_cast<int>(tm.edges.size());
    std::vector<int> period(tm.nodes.size(), 4);
    std::vector<char> chart_frame(tm.nodes.size(), 1);
    for (size_t n = 0; n < node_id.size(); ++n)
      if (node_id[n] >= 0)
        period[node_id[n]] = node_period(static_cast<int>(n)),
        chart_frame[node_id[n]] = node_chart_frame(static_cast<int>(n));
    std::vector<char> exists(2 * ne, 1), visited(2 * ne, 0);
    {
      int id = 0;
      for (const Piece& p : pieces_) {
        if (!p.alive) continue;
        const bool flip = flipped(p);
        exists[2 * id + 0] = flip ? p.left_ok[1] : p.left_ok[0];  // from -> to
        exists[2 * id + 1] = flip ? p.left_ok[0] : p.left_ok[1];  // to -> from
        ++id;
      }
    }
    auto find_incidence = [&](int node, int edge, bool outgoing) -> int {
      const auto& inc = tm.nodes[node].incidences;
      for (size_t i = 0; i < inc.size(); ++i)
        if (inc[i].edge == edge && inc[i].outgoing == outgoing) return static_cast<int>(i);
      return -1;
    };
    for (int start = 0; start < 2 * ne; ++start) {
      if (!exists[start] || visited[start]) continue;
      std::vector<int> loop;
      std::vector<int> angle;
      int h = start;
      bool ok = true;
      for (int guard = 0;; ++guard) {
        if (guard > 2 * ne + 2) fail("internal: cell boundary does not close");
        visited[h] = 1;
        loop.push_back(h);
        const TMeshEdge& e = tm.edges[h / 2];
        const bool forward = (h & 1) == 0;
        const int head = forward ? e.to : e.from;
        const auto& inc = tm.nodes[head].incidences;
        const int pos = find_incidence(head, h / 2, !forward);
        if (pos < 0) fail("internal: edge missing at its node");
        const int per = period[head];
        int next_pos = pos - 1;
        if (next_pos < 0) {
          if (per == 0) fail("internal: cell boundary leaves the surface at a boundary node");
          next_pos = static_cast<int>(inc.size()) - 1;
        }
        const TMeshIncidence& out = inc[next_pos];
        int a = inc[pos].direction - out.direction;
        if (per > 0) a = ((a % per) + per) % per;
        if (next_pos == pos) a = per > 0 ? per : 0;  // a dead end
        angle.push_back(a);
        if (a != 1 && a != 2) ok = false;
        const int next = 2 * out.edge + (out.outgoing ? 0 : 1);
        if (!exists[next]) fail("internal: cell boundary runs outside the surface");
        if (next == start) break;
        if (visited[next]) fail("internal: cell boundaries overlap");
        h = next;
      }
      const int cell = static_cast<int>(tm.cells.size());
      TMeshCell c;
      const int corners = static_cast<int>(std::count(angle.begin(), angle.end(), 1));
      const int n = static_cast<int>(loop.size());
      if (!ok || corners != 4) {
        c.four_sided = false;
        for (int x : loop) c.sides[0].push_back(x / 2);
      } else {
        int i0 = 0;
        while (angle[(i0 + n - 1) % n] != 1) ++i0;  // loop[i0] starts at a corner
        const int first = loop[i0];
        const TMeshEdge& fe = tm.edges[first / 2];
        const int tail = (first & 1) == 0 ? fe.from : fe.to;
        int shift = 0;
        if (chart_frame[tail]) {
          const int pos = find_incidence(tail, first / 2, (first & 1) == 0);
          shift = tm.nodes[tail].incidences[pos].direction & 1;
        }
        int side = 0;
        for (int k = 0; k < n; ++k) {
          const int i = (i0 + k) % n;
          c.sides[(side + shift) % 4].push_back(loop[i] / 2);
          if (angle[i] == 1) ++side;
        }
      }
      for (int x : loop) tm.edges[x / 2].cells[x & 1] = cell;
      tm.cells.push_back(std::move(c));
    }
  }

  const MotorcycleTracer& tracer_;
  const TriMesh& mesh_;
  double scale_;
  std::vector<Piece> pieces_;
  std::vector<std::vector<Incidence>> incidences_;
  std::vector<char> node_alive_;
  int merged_nodes_ = 0;
};

}  // namespace

TMesh trace_tmesh(const TriMesh& mesh, const ExactParametrization& param, const TraceOptions& options,
                  Progress& progress) {
  Timer timer;
  std::vector<char> walls(mesh.num_edges(), 0);
  if (!options.feature_edges.empty()) {
    if (static_cast<int>(options.feature_edges.size()) != mesh.num_edges())
      throw Error(ErrorCode::InvalidArgument, "trace_tmesh: feature_edges must have one flag per edge");
    for (int e = 0; e < mesh.num_edges(); ++e) walls[e] = options.feature_edges[e] != 0;
  }
  const long long max_steps = options.max_steps > 0 ? options.max_steps : 200LL * mesh.num_faces() + 1000000;
  MotorcycleTracer tracer(mesh, param, std::move(walls), max_steps, progress);
  tracer.run();
  progress.update(0.9);
  TMesh tm = Assembler(tracer).build();
  const TraceStats& s = tracer.stats();
  tm.stats.motorcycles = s.motorcycles;
  tm.stats.steps = s.steps;
  tm.stats.head_on = s.head_on;
  tm.stats.crossings = s.crossings;
  tm.stats.vertex_passes = s.vertex_passes;
  tm.stats.edge_runs = s.edge_runs;
  tm.stats.cut_crossings = s.cut_crossings;
  tm.stats.cut_vertex_passes = s.cut_vertex_passes;
  tm.stats.virtual_corners = s.virtual_corners;
  tm.stats.seeds = s.seeds;
  tm.stats.walls_not_isolines = s.walls_not_isolines;
  tm.stats.trace_seconds = timer.seconds();
  progress.update(1.0);
  return tm;
}

}  // namespace qgp

#include "tmesh/detail/motorcycles.h"

#include <algorithm>
#include <climits>
#include <cmath>

#include "core/error.h"

namespace qgp::tmesh_detail {

namespace {

// Magnitude limit of doubled coordinates (keeps every derived numerator within 128 bits).
constexpr int64_t kCoordinateLimit = int64_t(1) << 59;

bool key_less(const Rational& x, const Rational& y) {
  // Keys are reduced: order by (num, den) lexicographically, a consistent total order.
  if (x.num != y.num) return x.num < y.num;
  return x.den < y.den;
}

}  // namespace

bool operator<(const PointKey& x, const PointKey& y) {
  if (x.type != y.type) return x.type < y.type;
  if (x.id != y.id) return x.id < y.id;
  if (x.a.num != y.a.num || x.a.den != y.a.den) return key_less(x.a, y.a);
  return key_less(x.b, y.b);
}

MotorcycleTracer::MotorcycleTracer(const TriMesh& mesh, const ExactParametrization& param, std::vector<char> wall_edge,
                                   long long max_steps, Progress& progress)
    : mesh_(mesh), param_(param), wall_edge_(std::move(wall_edge)), max_steps_(max_steps), progress_(progress) {
  const int nf = mesh.num_faces(), nc = 3 * nf;
  if (static_cast<int>(param.uv.size()) != nc || static_cast<int>(param.rotation.size()) != nc ||
      static_cast<int>(param.translation.size()) != nc)
    throw Error(ErrorCode::InvalidArgument, "trace_tmesh: the parametrization does not match the mesh");
  if (static_cast<int>(wall_edge_.size()) != mesh.num_edges())
    throw Error(ErrorCode::InvalidArgument, "trace_tmesh: feature flags must have one entry per edge");
  fraction_bits_ = param.fraction_bits;
  uv2_.resize(nc);
  translation2_.resize(nc);
  for (int c = 0; c < nc; ++c)
    for (int a = 0; a < 2; ++a) {
      const int64_t x = param.uv[c][a], t = param.translation[c][a];
      const int64_t limit = kCoordinateLimit / 2;
      if (x >= limit || x <= -limit || t >= limit || t <= -limit)
        throw Error(ErrorCode::InvalidArgument,
                    "trace_tmesh: parameter coordinates exceed the exact range (use fewer fraction bits)");
      uv2_[c][a] = 2 * x;
      translation2_[c][a] = 2 * t;
    }
  face_ok_.assign(nf, 0);
  for (int f = 0; f < nf; ++f) face_ok_[f] = orient(uv2_[3 * f], uv2_[3 * f + 1], uv2_[3 * f + 2]) > 0;
  for (int e = 0; e < mesh.num_edges(); ++e) {
    if (mesh.is_boundary_edge(e)) wall_edge_[e] = 1;
    if (!wall_edge_[e]) continue;
    const int h = mesh.edge_halfedge[e];
    const P2& a = uv2_[h];
    const P2& b = uv2_[TriMesh::next(h)];
    stats_.walls_not_isolines += a[0] != b[0] && a[1] != b[1];
  }
  stars_.resize(mesh.num_vertices());
  for (int v = 0; v < mesh.num_vertices(); ++v) stars_[v] = analyse_vertex(mesh, uv2_, param.rotation, wall_edge_, v);
  face_records_.resize(nf);
}

void MotorcycleTracer::fail(const std::string& message) const {
  throw Error(ErrorCode::StageFailed, "T-mesh tracing: " + message);
}

P2 MotorcycleTracer::transfer(int h, const P2& p) const {
  const P2 r = rotate_quarter(p, param_.rotation[h]);
  const P2 q{r[0] + translation2_[h][0], r[1] + translation2_[h][1]};
  if (q[0] >= kCoordinateLimit || q[0] <= -kCoordinateLimit || q[1] >= kCoordinateLimit || q[1] <= -kCoordinateLimit)
    fail("a separatrix left the exact coordinate range (it is extremely long)");
  return q;
}

Rational MotorcycleTracer::crossing(const P2& p, const P2& q, int fixed, int64_t c) const {
  const int moving = 1 - fixed;
  const i128 den = i128(q[fixed]) - p[fixed];
  const i128 num = i128(p[moving]) * den + (i128(c) - p[fixed]) * (i128(q[moving]) - p[moving]);
  return Rational(num, den);
}

bool MotorcycleTracer::blocking(int v) const {
  const VertexStar& s = stars_[v];
  return s.corner || s.on_wall || !s.regular();
}

void MotorcycleTracer::prepare_walls_and_corners() {
  const int nv = mesh_.num_vertices();
  for (int v = 0; v < nv; ++v) {
    const VertexStar& s = stars_[v];
    if (s.ring.empty()) continue;
    if (!s.problem.empty() && (s.corner || s.on_wall))
      fail("vertex " + std::to_string(v) + (s.on_wall ? " (on a feature/boundary)" : " (singular)") + ": " + s.problem);
  }
  // Closed walls through straight vertices only get a virtual corner (paper §9.1).
  std::vector<std::vector<int>> wall_edges_at(nv);
  for (int e = 0; e < mesh_.num_edges(); ++e)
    if (wall_edge_[e]) {
      const int h = mesh_.edge_halfedge[e];
      wall_edges_at[mesh_.from(h)].push_back(e);
      wall_edges_at[mesh_.to(h)].push_back(e);
    }
  std::vector<char> seen(mesh_.num_edges(), 0);
  for (int e0 = 0; e0 < mesh_.num_edges(); ++e0) {
    if (!wall_edge_[e0] || seen[e0]) continue;
    bool has_corner = false;
    int lowest = INT_MAX;
    std::vector<int> stack{e0};
    seen[e0] = 1;
    while (!stack.empty()) {
      const int e = stack.back();
      stack.pop_back();
      const int h = mesh_.edge_halfedge[e];
      for (int x : {mesh_.from(h), mesh_.to(h)}) {
        if (stars_[x].corner) {
          has_corner = true;
          continue;
        }
        lowest = std::min(lowest, x);
        for (int e2 : wall_edges_at[x])
          if (!seen[e2]) seen[e2] = 1, stack.push_back(e2);
      }
    }
    if (!has_corner && lowest != INT_MAX) {
      make_virtual_corner(stars_[lowest]);
      ++stats_.virtual_corners;
    }
  }
  // A connected component without any corner (e.g. a torus without singularities) gets a seed.
  const int nf = mesh_.num_faces();
  std::vector<int> component(nf, -1);
  for (int f0 = 0; f0 < nf; ++f0) {
    if (component[f0] >= 0) continue;
    std::vector<int> stack{f0}, faces;
    component[f0] = f0;
    while (!stack.empty()) {
      const int f = stack.back();
      stack.pop_back();
      faces.push_back(f);
      for (int k = 0; k < 3; ++k) {
        const int o = mesh_.opposite[3 * f + k];
        if (o >= 0 && component[o / 3] < 0) component[o / 3] = f0, stack.push_back(o / 3);
      }
    }
    bool has_corner = false;
    int seed = -1;
    for (int f : faces)
      for (int k = 0; k < 3; ++k) {
        const int v = mesh_.F(f, k);
        if (stars_[v].corner) has_corner = true;
        if (stars_[v].regular() && stars_[v].positive && (seed < 0 || v < seed)) seed = v;
      }
    if (has_corner) continue;
    if (seed < 0) fail("a component has no singularity and no vertex with a regular one-ring to start from");
    make_seed(stars_[seed]);
    ++stats_.seeds;
  }
}

void MotorcycleTracer::start_motorcycles() {
  for (int v = 0; v < mesh_.num_vertices(); ++v) {
    const VertexStar& s = stars_[v];
    if (!s.corner || s.ring.empty()) continue;
    const int node = vertex_node(v);
    for (int idx : s.emissions) {
      const StarDirection& d = s.directions[idx];
      const int m = static_cast<int>(motos_.size());
      Motorcycle moto;
      moto.source_vertex = v;
      moto.source_number = d.number;
      motos_.push_back(moto);
      add_junction(m, Rational(0), node);
    }
  }
  stats_.motorcycles = static_cast<int>(motos_.size());
  for (int m = 0; m < static_cast<int>(motos_.size()); ++m) {
    const int v = motos_[m].source_vertex;
    const VertexStar& s = stars_[v];
    for (int idx : s.emissions)
      if (s.directions[idx].number == motos_[m].source_number) {
        const StarDirection& d = s.directions[idx];
        plan_in_corner(m, v, d.corner, d.dir, uv2_[s.ring[d.corner].h_out], Rational(0));
        break;
      }
  }
}

int MotorcycleTracer::new_segment(Segment s) {
  const int id = static_cast<int>(segments_.size());
  segments_.push_back(s);
  motos_[s.moto].segments.push_back(id);
  const FaceRecord rec{id, s.dir, s.origin};
  check_faces(id, rec, s.face);
  face_records_[s.face].push_back(rec);
  if (s.along_halfedge >= 0) {
    ++stats_.edge_runs;
    const int o = mesh_.opposite[s.along_halfedge];
    if (o >= 0) {
      const FaceRecord other{id, (s.dir + param_.rotation[s.along_halfedge]) & 3, transfer(s.along_halfedge, s.origin)};
      check_faces(id, other, o / 3);
      face_records_[o / 3].push_back(other);
    }
  }
  if (s.end_vertex >= 0 && !blocking(s.end_vertex)) {
    const VertexStar& star = stars_[s.end_vertex];
    const int ci = star.corner_of_face(s.face);
    if (ci < 0) fail("internal: segment face not around its end vertex");
    const Passage p{s.moto, s.t1, (s.dir - star.ring[ci].acc) & 3};
    check_vertex(s.end_vertex, p);
    passages_[s.end_vertex].push_back(p);
  }
  Event e;
  e.time = s.t1;
  e.kind = Exit;
  e.a = s.moto;
  e.segment = id;
  push(e);
  return id;
}

void MotorcycleTracer::plan_in_corner(int m, int v, int corner, int dir, const P2& origin, const Rational& t0) {
  const StarCorner& k = stars_[v].ring[corner];
  const int g = k.face, h = k.h_out;
  if (!face_ok_[g])
    fail("a separatrix entered face " + std::to_string(g) + ", which is flipped or degenerate in parameter space");
  Segment s;
  s.moto = m;
  s.t0 = t0;
  s.face = g;
  s.dir = dir & 3;
  s.origin = origin;
  s.start_vertex = v;
  const int fixed = fixed_axis_of(dir);
  const int64_t c = origin[fixed];
  if (exact_cardinal(k.e1) == s.dir) {
    s.along_halfedge = h;
    s.end_vertex = mesh_.to(h);
    s.t1 = s.time_at(Rational(uv2_[TriMesh::next(h)][axis_of(dir)]));
  } else {
    const P2& pa = uv2_[TriMesh::next(h)];
    const P2& pb = uv2_[TriMesh::prev(h)];
    if (sign(i128(pa[fixed]) - c) * sign(i128(pb[fixed]) - c) >= 0)
      fail("internal: separatrix does not cross the edge opposite its start in face " + std::to_string(g));
    s.end_halfedge = TriMesh::next(h);
    s.t1 = s.time_at(crossing(pa, pb, fixed, c));
  }
  if (compare(s.t1, t0) <= 0)
    fail("a separatrix does not advance in face " + std::to_string(g) + " (non-injective parametrization)");
  new_segment(s);
}

void MotorcycleTracer::plan_from_vertex(int m, int v, int face, int dir, const P2& origin, const Rational& t0) {
  const VertexStar& star = stars_[v];
  const int n = static_cast<int>(star.ring.size());
  const int ci = star.corner_of_face(face);
  if (ci < 0) fail("internal: arrival face not around vertex " + std::to_string(v));
  const int ref = (dir - star.ring[ci].acc) & 3;
  const StarDirection* out = nullptr;
  for (const StarDirection& d : star.directions)
    if (d.number == ref) out = &d;
  if (!out) fail("internal: no continuation through vertex " + std::to_string(v));
  // Transport the origin counter-clockwise around v (the composed transitions fix v).
  P2 o = origin;
  int d = dir & 3;
  bool cut = false;
  for (int j = ci; j != out->corner; j = (j + 1) % n) {
    const int h = TriMesh::prev(star.ring[j].h_out);
    o = transfer(h, o);
    d = (d + param_.rotation[h]) & 3;
    cut = cut || param_.is_cut[mesh_.edge_of[h]];
  }
  if (d != out->dir) fail("internal: inconsistent chart rotation around vertex " + std::to_string(v));
  ++stats_.vertex_passes;
  if (cut) ++stats_.cut_vertex_passes;
  plan_in_corner(m, v, out->corner, out->dir, o, t0);
}

void MotorcycleTracer::plan_from_edge(int m, const Segment& prev) {
  const int k = prev.end_halfedge;
  const int o = mesh_.opposite[k];
  if (o < 0) fail("internal: separatrix left the surface through a boundary edge");
  const int g = o / 3;
  if (!face_ok_[g])
    fail("a separatrix entered face " + std::to_string(g) + ", which is flipped or degenerate in parameter space");
  if (param_.is_cut[mesh_.edge_of[k]]) ++stats_.cut_crossings;
  Segment s;
  s.moto = m;
  s.t0 = prev.t1;
  s.face = g;
  s.dir = (prev.dir + param_.rotation[k]) & 3;
  s.origin = transfer(k, prev.origin);
  const int fixed = fixed_axis_of(s.dir), moving = axis_of(s.dir);
  const int64_t c = s.origin[fixed];
  const int i = o % 3;
  const P2& pi = uv2_[3 * g + i];
  const P2& pj = uv2_[3 * g + (i + 1) % 3];
  const P2& pk = uv2_[3 * g + (i + 2) % 3];
  const int si = sign(i128(pi[fixed]) - c), sj = sign(i128(pj[fixed]) - c), sk = sign(i128(pk[fixed]) - c);
  if (si * sj >= 0 || compare(s.time_at(crossing(pi, pj, fixed, c)), prev.t1) != 0)
    fail("internal: inconsistent transition across edge " + std::to_string(mesh_.edge_of[k]));
  if (sk == 0) {
    s.end_vertex = mesh_.F(g, (i + 2) % 3);
    s.t1 = s.time_at(Rational(pk[moving]));
  } else if (sk != si) {
    s.end_halfedge = 3 * g + (i + 2) % 3;
    s.t1 = s.time_at(crossing(pk, pi, fixed, c));
  } else {
    s.end_halfedge = 3 * g + (i + 1) % 3;
    s.t1 = s.time_at(crossing(pj, pk, fixed, c));
  }
  if (compare(s.t1, s.t0) <= 0)
    fail("a separatrix does not advance in face " + std::to_string(g) + " (non-injective parametrization)");
  new_segment(s);
}

void MotorcycleTracer::check_faces(int id, const FaceRecord& rec, int face) {
  const Segment& A = segments_[id];
  const P2* corners = &uv2_[3 * face];
  auto is_corner = [&](int fixed, int64_t c, int64_t s) {
    for (int k = 0; k < 3; ++k)
      if (corners[k][fixed] == c && corners[k][1 - fixed] == s) return true;
    return false;
  };
  for (const FaceRecord& q : face_records_[face]) {
    if (q.segment == id) continue;
    const Segment& B = segments_[q.segment];
    if (B.dead) continue;
    const int dA = rec.dir, dB = q.dir;
    const int64_t cA = rec.origin[fixed_axis_of(dA)], cB = q.origin[fixed_axis_of(dB)];
    Event e;
    e.point.face = face;
    e.point.fixed = fixed_axis_of(dA);
    e.point.c = cA;
    if (axis_of(dA) != axis_of(dB)) {
      // Perpendicular: they meet at the grid point (cA, cB).
      const Rational tA(i128(sense_of(dA)) * (i128(cB) - rec.origin[axis_of(dA)]));
      const Rational tB(i128(sense_of(dB)) * (i128(cA) - q.origin[axis_of(dB)]));
      if (compare(tA, A.t0) < 0 || compare(tA, A.t1) > 0 || compare(tB, B.t0) < 0 || compare(tB, B.t1) > 0) continue;
      if (A.moto == B.moto && compare(tA, tB) == 0) continue;
      if (is_corner(fixed_axis_of(dA), cA, cB)) continue;  // vertices: see check_vertex
      e.point.s = Rational(cB);
      const int order = compare(tA, tB);
      if (order < 0) {
        e.kind = Stop, e.time = tB, e.a = B.moto, e.ta = tB, e.b = A.moto, e.tb = tA;
      } else if (order > 0) {
        e.kind = Stop, e.time = tA, e.a = A.moto, e.ta = tA, e.b = B.moto, e.tb = tB;
      } else {
        e.kind = Cross, e.time = tA, e.a = A.moto, e.ta = tA, e.b = B.moto, e.tb = tB;
      }
      push(e);
    } else if (cA == cB && dA != dB) {
      // Same line, opposite directions: they meet half way, at the same time.
      const i128 sum = i128(rec.origin[axis_of(dA)]) + q.origin[axis_of(dB)];
      if (sum % 2 != 0) fail("internal: odd head-on midpoint");
      const int64_t mid = static_cast<int64_t>(sum / 2);
      const Rational tA(i128(sense_of(dA)) * (i128(mid) - rec.origin[axis_of(dA)]));
      const Rational tB(i128(sense_of(dB)) * (i128(mid) - q.origin[axis_of(dB)]));
      if (compare(tA, tB) != 0) fail("internal: head-on times differ");
      if (compare(tA, A.t0) < 0 || compare(tA, A.t1) > 0 || compare(tB, B.t0) < 0 || compare(tB, B.t1) > 0) continue;
      if (A.moto == B.moto) continue;
      if (is_corner(fixed_axis_of(dA), cA, mid)) continue;
      e.point.s = Rational(mid);
      e.kind = HeadOn, e.time = tA, e.a = A.moto, e.ta = tA, e.b = B.moto, e.tb = tB;
      push(e);
    }
  }
}

void MotorcycleTracer::check_vertex(int v, const Passage& p) {
  auto it = passages_.find(v);
  if (it == passages_.end()) return;
  for (const Passage& q : it->second) {
    const int order = compare(p.time, q.time);
    if (q.moto == p.moto && order == 0) continue;
    Event e;
    e.point.vertex = v;
    if (order > 0) {
      e.kind = Stop, e.time = p.time, e.a = p.moto, e.ta = p.time, e.b = q.moto, e.tb = q.time;
    } else if (order < 0) {
      e.kind = Stop, e.time = q.time, e.a = q.moto, e.ta = q.time, e.b = p.moto, e.tb = p.time;
    } else {
      const int diff = (p.ref_dir - q.ref_dir) & 3;
      if (diff == 0) continue;
      e.kind = diff == 2 ? HeadOn : Cross;
      e.time = p.time, e.a = p.moto, e.ta = p.time, e.b = q.moto, e.tb = q.time;
    }
    push(e);
  }
}

void MotorcycleTracer::push(Event e) {
  e.seq = seq_++;
  queue_.push(std::move(e));
}

bool MotorcycleTracer::add_junction(int m, const Rational& t, int node) {
  auto [it, inserted] = motos_[m].junctions.emplace(t, node);
  if (!inserted && it->second != node) fail("internal: two nodes at one point of a separatrix");
  return inserted;
}

void MotorcycleTracer::stop(int m, const Rational& t, int node) {
  Motorcycle& mo = motos_[m];
  mo.stopped = true;
  mo.stop_time = t;
  add_junction(m, t, node);
  while (!mo.segments.empty() && compare(segments_[mo.segments.back()].t0, t) >= 0 && mo.segments.size() > 1) {
    segments_[mo.segments.back()].dead = true;
    mo.segments.pop_back();
  }
  if (!mo.segments.empty()) {
    Segment& s = segments_[mo.segments.back()];
    if (compare(s.t1, t) > 0) {
      s.t1 = t;
      s.end_vertex = -1;
      s.end_halfedge = -1;
    }
  }
  ++finished_;
}

int MotorcycleTracer::node_for(const PointRef& p) {
  if (p.vertex >= 0) return vertex_node(p.vertex);
  return node_at(classify(p.face, p.fixed, p.c, p.s));
}

int MotorcycleTracer::vertex_node(int v) {
  PointKey key;
  key.type = PointKey::Vertex;
  key.id = v;
  return node_at(key);
}

int MotorcycleTracer::node_at(const PointKey& key) {
  auto it = node_index_.find(key);
  if (it != node_index_.end()) return it->second;
  NodeRecord rec;
  rec.key = key;
  const double scale = std::ldexp(1.0, -fraction_bits_ - 1);
  if (key.type == PointKey::Vertex) {
    const VertexStar& s = stars_[key.id];
    if (s.ring.empty()) fail("internal: node at an isolated vertex");
    const int h = s.ring[0].h_out;
    rec.frame_face = h / 3;
    rec.point.face = h / 3;
    rec.point.barycentric = Vec3::Zero();
    rec.point.barycentric[h % 3] = 1;
    rec.point.uv = Vec2(uv2_[h][0] * scale, uv2_[h][1] * scale);
  } else if (key.type == PointKey::Edge) {
    const int hc = mesh_.edge_halfedge[key.id];
    const double lambda = key.a.to_double();
    rec.frame_face = hc / 3;
    rec.point.face = hc / 3;
    rec.point.barycentric = Vec3::Zero();
    rec.point.barycentric[hc % 3] = 1 - lambda;
    rec.point.barycentric[(hc % 3 + 1) % 3] = lambda;
    const P2& p = uv2_[hc];
    const P2& q = uv2_[TriMesh::next(hc)];
    rec.point.uv = Vec2((p[0] + lambda * double(q[0] - p[0])) * scale, (p[1] + lambda * double(q[1] - p[1])) * scale);
  } else {
    rec.frame_face = key.id;
    rec.point = surface_point(key.id, key.a, key.b);
  }
  const int id = static_cast<int>(nodes_.size());
  nodes_.push_back(rec);
  node_index_.emplace(key, id);
  return id;
}

SurfacePoint MotorcycleTracer::surface_point(int face, const Rational& u, const Rational& v) const {
  SurfacePoint sp;
  sp.face = face;
  const double scale = std::ldexp(1.0, -fraction_bits_ - 1);
  sp.uv = Vec2(u.to_double() * scale, v.to_double() * scale);
  // Barycentric coordinates: differences to corner 0 formed exactly, ratios in long double
  // (accurate also in thin triangles).
  const P2* P = &uv2_[3 * face];
  const P2 a = sub(P[1], P[0]), b = sub(P[2], P[0]);
  const long double det = static_cast<long double>(cross(a, b));
  const long double px = static_cast<long double>(u.num - i128(P[0][0]) * u.den) / static_cast<long double>(u.den);
  const long double py = static_cast<long double>(v.num - i128(P[0][1]) * v.den) / static_cast<long double>(v.den);
  if (det != 0) {
    const long double l1 = (px * b[1] - py * b[0]) / det, l2 = (a[0] * py - a[1] * px) / det;
    sp.barycentric = Vec3(static_cast<double>(1 - l1 - l2), static_cast<double>(l1), static_cast<double>(l2));
  }
  return sp;
}

SurfacePoint MotorcycleTracer::segment_point(const Segment& s, const Rational& t) const {
  const Rational moving = s.coord_at(t);
  const Rational fixed(s.line());
  return fixed_axis_of(s.dir) == 0 ? surface_point(s.face, fixed, moving) : surface_point(s.face, moving, fixed);
}

PointKey MotorcycleTracer::classify(int face, int fixed, int64_t c, const Rational& s) const {
  const int moving = 1 - fixed;
  const P2* P = &uv2_[3 * face];
  PointKey key;
  for (int k = 0; k < 3; ++k)
    if (P[k][fixed] == c && compare(s, Rational(P[k][moving])) == 0) {
      key.type = PointKey::Vertex;
      key.id = mesh_.F(face, k);
      return key;
    }
  for (int k = 0; k < 3; ++k) {
    const P2& p = P[k];
    const P2& q = P[(k + 1) % 3];
    Rational lambda;
    bool on_edge = false;
    if (p[fixed] == c && q[fixed] == c) {
      const int lo = compare(s, Rational(std::min(p[moving], q[moving])));
      const int hi = compare(s, Rational(std::max(p[moving], q[moving])));
      if (lo > 0 && hi < 0) {
        on_edge = true;
        lambda = Rational(s.num - i128(p[moving]) * s.den, s.den * (i128(q[moving]) - p[moving]));
      }
    } else if (sign(i128(p[fixed]) - c) * sign(i128(q[fixed]) - c) < 0 && compare(crossing(p, q, fixed, c), s) == 0) {
      on_edge = true;
      lambda = Rational(i128(c) - p[fixed], i128(q[fixed]) - p[fixed]);
    }
    if (!on_edge) continue;
    const int h = 3 * face + k;
    const int e = mesh_.edge_of[h];
    if (mesh_.edge_halfedge[e] != h) lambda = Rational(lambda.den - lambda.num, lambda.den);
    key.type = PointKey::Edge;
    key.id = e;
    key.a = lambda.reduced();
    return key;
  }
  key.type = PointKey::Face;
  key.id = face;
  const Rational fc = Rational(c), ms = s.reduced();
  key.a = fixed == 0 ? fc : ms;
  key.b = fixed == 0 ? ms : fc;
  return key;
}

int MotorcycleTracer::node_direction(int node, int face, int dir) const {
  const NodeRecord& rec = nodes_[node];
  switch (rec.key.type) {
    case PointKey::Vertex: {
      const VertexStar& s = stars_[rec.key.id];
      return s.frame_number(s.corner_of_face(face), dir);
    }
    case PointKey::Edge: {
      const int hc = mesh_.edge_halfedge[rec.key.id];
      if (face == hc / 3) return dir & 3;
      const int o = mesh_.opposite[hc];
      if (o >= 0 && face == o / 3) return (dir + param_.rotation[o]) & 3;
      return INT_MIN;
    }
    default: return face == rec.key.id ? (dir & 3) : INT_MIN;
  }
}

void MotorcycleTracer::process(const Event& e) {
  switch (e.kind) {
    case Exit: {
      if (motos_[e.a].stopped) return;  // stopped at or before the end of this segment
      const Segment s = segments_[e.segment];
      if (s.dead) return;
      if (++stats_.steps > max_steps_)
        fail("separatrices did not terminate within " + std::to_string(max_steps_) + " face steps");
      if (s.end_vertex >= 0) {
        const int v = s.end_vertex;
        if (!blocking(v)) {
          plan_from_vertex(e.a, v, s.face, s.dir, s.origin, s.t1);
        } else {
          const VertexStar& star = stars_[v];
          if (!star.problem.empty()) fail("a separatrix reached vertex " + std::to_string(v) + ": " + star.problem);
          stop(e.a, s.t1, vertex_node(v));
        }
      } else if (s.end_halfedge >= 0) {
        if (wall_edge_[mesh_.edge_of[s.end_halfedge]]) {
          stop(e.a, s.t1, node_at(classify(s.face, fixed_axis_of(s.dir), s.line(), s.coord_at(s.t1))));
        } else {
          plan_from_edge(e.a, s);
        }
      }
      return;
    }
    case Stop: {
      if (!alive_at(e.a, e.ta) || !alive_at(e.b, e.tb)) return;
      const int node = node_for(e.point);
      add_junction(e.b, e.tb, node);
      if (motos_[e.a].stopped) {
        add_junction(e.a, e.ta, node);  // already stopped exactly here
        return;
      }
      stop(e.a, e.ta, node);
      return;
    }
    default: {  // HeadOn, Cross
      if (!alive_at(e.a, e.ta) || !alive_at(e.b, e.tb)) return;
      const int node = node_for(e.point);
      const bool fresh_a = add_junction(e.a, e.ta, node);  // both junctions, whatever the first gives
      const bool fresh = add_junction(e.b, e.tb, node) || fresh_a;
      if (e.kind == HeadOn) {
        if (!motos_[e.a].stopped || !motos_[e.b].stopped) ++stats_.head_on;
        if (!motos_[e.a].stopped) stop(e.a, e.ta, node);
        if (!motos_[e.b].stopped) stop(e.b, e.tb, node);
      } else if (fresh) {
        ++stats_.crossings;
      }
      return;
    }
  }
}

void MotorcycleTracer::run() {
  progress_.check_cancel();
  prepare_walls_and_corners();
  start_motorcycles();
  long long processed = 0;
  while (!queue_.empty()) {
    const Event e = queue_.top();
    queue_.pop();
    process(e);
    if ((++processed & 1023) == 0) {
      progress_.check_cancel();
      if ((processed & 16383) == 0 && !motos_.empty())
        progress_.update(0.9 * finished_ / static_cast<double>(motos_.size()));
    }
  }
  for (size_t m = 0; m < motos_.size(); ++m)
    if (!motos_[m].stopped) fail("internal: a separatrix never stopped");
}

}  // namespace qgp::tmesh_detail

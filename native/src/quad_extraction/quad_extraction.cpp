#include "quad_extraction/quad_extraction.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <sstream>
#include <unordered_map>

#include "core/error.h"
#include "core/timer.h"

namespace qgp {
namespace {

using i128 = __int128;

// Unit vectors of the four parameter directions: 0 = +u, 1 = +v, 2 = -u, 3 = -v.
const IVec2 kUnit[4] = {{1, 0}, {0, 1}, {-1, 0}, {0, -1}};

i128 cross(const IVec2& a, const IVec2& b) { return i128(a[0]) * b[1] - i128(a[1]) * b[0]; }
i128 dot(const IVec2& a, const IVec2& b) { return i128(a[0]) * b[0] + i128(a[1]) * b[1]; }
IVec2 sub(const IVec2& a, const IVec2& b) { return {a[0] - b[0], a[1] - b[1]}; }
IVec2 add_scaled(const IVec2& p, const IVec2& w, int64_t s) { return {p[0] + s * w[0], p[1] + s * w[1]}; }
int64_t floor_div(int64_t a, int64_t b) { return a / b - ((a % b != 0) && ((a < 0) != (b < 0))); }

// Coordinates beyond this magnitude are refused, so that every difference and 128-bit product
// below stays exact (orient2d_exact needs inputs below 2^61).
constexpr int64_t kMaxCoordinate = int64_t(1) << 58;

// Whether direction w leaves the apex of the wedge from a to b (counter-clockwise, opening angle
// in (0, pi]) into the wedge: a is included, b only if include_b.
bool in_wedge(const IVec2& a, const IVec2& b, const IVec2& w, bool include_b) {
  const i128 c_aw = cross(a, w), c_wb = cross(w, b);
  if (c_aw == 0 && dot(a, w) > 0) return true;
  if (c_wb == 0 && dot(w, b) > 0) return include_b;
  if (cross(a, b) > 0) return c_aw > 0 && c_wb > 0;
  return c_aw > 0;  // opening angle exactly pi (b opposite to a): the left half-plane of a
}

// A ray can be read in the chart of every face whose closed triangle contains its start: at most
// two (a ray along a mesh edge).
struct RayAlias {
  int face = -1;
  int8_t dir = 0;
};

// An outgoing integer isoline direction at a grid point: a half-edge of the quad mesh.
struct Ray {
  int face = -1;              // owning face: contains the half-open sector starting at the ray
  int8_t dir = 0;             // direction in the owning face's chart
  bool sector_inside = true;  // the sector from this ray to the next counter-clockwise one lies
                              // on the surface (false only for the last ray at a boundary point)
  IVec2 start{0, 0};          // the grid point in the owning face's chart
  std::array<RayAlias, 2> alias;
  int num_alias = 0;
  int dest_point = -1;  // traced: the grid point reached ...
  int dest_ray = -1;    // ... and its ray pointing back along the same segment (global index)
};

struct GridPoint {
  int face = -1;  // a face containing the point and its coordinates in that chart
  IVec2 uv{0, 0};
  int mesh_vertex = -1;  // set if the point is a mesh vertex
  bool boundary = false;
  int ray_begin = 0, ray_count = 0;  // its rays: rays[ray_begin .. ray_begin + ray_count)
};

// One face corner around a grid point: the wedge from a to b (edge vectors, counter-clockwise) in
// face's chart, with the point at `at`.
struct Corner {
  int face;
  IVec2 at, a, b;
};

struct PointKey {
  int64_t x, y;
  int entity;
  bool operator==(const PointKey& o) const { return x == o.x && y == o.y && entity == o.entity; }
};
struct PointKeyHash {
  size_t operator()(const PointKey& k) const {
    uint64_t h = static_cast<uint64_t>(k.x) * 0x9E3779B97F4A7C15ull;
    h ^= static_cast<uint64_t>(k.y) + 0x632BE59BD9B4E019ull + (h << 6) + (h >> 2);
    h ^= static_cast<uint64_t>(k.entity) * 0xC2B2AE3D27D4EB4Full + (h << 6) + (h >> 2);
    return static_cast<size_t>(h);
  }
};

class Extractor {
 public:
  Extractor(const TriMesh& mesh, const ExactParametrization& igm, const QuadExtractionOptions& options,
            Progress& progress)
      : mesh_(mesh), igm_(igm), options_(options), progress_(progress), one_(igm.one()) {}

  QuadExtraction run() {
    Timer timer;
    progress_.begin_stage("quad_extraction");
    validate_input();
    check_triangles();
    progress_.update(0.05);
    generate_points();
    progress_.update(0.25);
    step_budget_ = 64 * (int64_t(mesh_.num_faces()) + int64_t(rays_.size())) + 1000000;
    trace_all();
    progress_.update(0.75);
    check_consistency();
    assemble();
    progress_.update(1.0);
    result_.stats.seconds = timer.seconds();
    if (!options_.allow_defects && !first_defect_.empty()) throw_defects();
    return std::move(result_);
  }

 private:
  IVec2 corner(int f, int k) const { return igm_.uv[3 * f + k]; }

  void note_defect(const std::string& what) {
    if (first_defect_.empty()) first_defect_ = what;
  }

  [[noreturn]] void throw_defects() const {
    const auto& s = result_.stats;
    std::ostringstream msg;
    msg << "quad extraction: the integer-grid map is not valid (" << s.flipped_triangles << " flipped and "
        << s.degenerate_triangles << " degenerate triangles, " << s.failed_traces << " failed isoline traces, "
        << s.inconsistent_segments << " inconsistent segments, " << s.non_quad_faces
        << " non-quad faces); first: " << first_defect_;
    throw Error(ErrorCode::StageFailed, msg.str());
  }

  void validate_input() {
    const size_t nh = static_cast<size_t>(mesh_.num_halfedges());
    if (mesh_.opposite.size() != nh || mesh_.vertex_halfedge.size() != static_cast<size_t>(mesh_.num_vertices()))
      throw Error(ErrorCode::InvalidArgument,
                  "quad extraction: the mesh has no connectivity (call build_connectivity)");
    if (igm_.uv.size() != nh || igm_.rotation.size() != nh || igm_.translation.size() != nh)
      throw Error(ErrorCode::InvalidArgument, "quad extraction: the integer-grid map does not match the mesh (" +
                                                  std::to_string(igm_.uv.size()) + " corners for " +
                                                  std::to_string(mesh_.num_faces()) + " faces)");
    if (igm_.fraction_bits < 0 || igm_.fraction_bits > 56)
      throw Error(ErrorCode::InvalidArgument, "quad extraction: fraction_bits must be in [0, 56]");
    for (size_t c = 0; c < nh; ++c) {
      for (int a = 0; a < 2; ++a)
        if (std::llabs(igm_.uv[c][a]) >= kMaxCoordinate || std::llabs(igm_.translation[c][a]) >= kMaxCoordinate)
          throw Error(ErrorCode::InvalidArgument,
                      "quad extraction: coordinates of face " + std::to_string(c / 3) + " exceed 2^58 grid units");
      if (igm_.rotation[c] < 0 || igm_.rotation[c] > 3)
        throw Error(ErrorCode::InvalidArgument,
                    "quad extraction: rotation of halfedge " + std::to_string(c) + " is not in 0..3");
    }
    for (int h = 0; h < mesh_.num_halfedges(); ++h) {
      const int o = mesh_.opposite[h];
      if (o < 0) continue;
      if (igm_.translation[h][0] % one_ != 0 || igm_.translation[h][1] % one_ != 0)
        throw Error(ErrorCode::InvalidArgument, "quad extraction: the transition across halfedge " + std::to_string(h) +
                                                    " has a non-integer translation");
      // Both endpoints must map exactly onto the opposite face's corners.
      const IVec2 pf[2] = {corner(h / 3, h % 3), corner(h / 3, (h % 3 + 1) % 3)};
      const IVec2 pg[2] = {corner(o / 3, (o % 3 + 1) % 3), corner(o / 3, o % 3)};
      for (int i = 0; i < 2; ++i)
        if (igm_.transfer(h, pf[i]) != pg[i])
          throw Error(ErrorCode::InvalidArgument, "quad extraction: the transition across halfedge " +
                                                      std::to_string(h) + " does not map the edge onto its twin");
    }
  }

  // Signed doubled area of each face in grid units; flipped/degenerate faces are defects.
  void check_triangles() {
    auto& s = result_.stats;
    const i128 unit2 = 2 * i128(one_) * one_;
    i128 whole = 0, rest = 0;
    face_ok_.assign(mesh_.num_faces(), 1);
    for (int f = 0; f < mesh_.num_faces(); ++f) {
      const IVec2 p0 = corner(f, 0), p1 = corner(f, 1), p2 = corner(f, 2);
      const i128 area2 = cross(sub(p1, p0), sub(p2, p0));
      if (area2 < 0) ++s.flipped_triangles;
      if (area2 == 0) ++s.degenerate_triangles;
      if (area2 <= 0) {
        face_ok_[f] = 0;
        note_defect("face " + std::to_string(f) + (area2 < 0 ? " is flipped" : " is degenerate") +
                    " in the parametrization");
      }
      whole += area2 / unit2;
      rest += area2 % unit2;
    }
    whole += rest / unit2;
    s.area_is_integral = rest % unit2 == 0;
    s.expected_quads = static_cast<int64_t>(whole);
    if (whole > options_.max_quads)
      throw Error(ErrorCode::StageFailed, "quad extraction: the map's parametric area asks for " +
                                              std::to_string(s.expected_quads) + " quads, more than the limit of " +
                                              std::to_string(options_.max_quads));
    scan_budget_ = 8 * options_.max_quads + 64 * int64_t(mesh_.num_faces()) + 1000000;
    if (!options_.allow_defects && (s.flipped_triangles > 0 || s.degenerate_triangles > 0)) throw_defects();
  }

  // ------------------------------------------------------------------------------------------
  // Grid points and their rays.

  // Counts one step of scanning grid lines; throws once the budget is spent.
  void spend_scan() {
    if (--scan_budget_ < 0)
      throw Error(ErrorCode::StageFailed,
                  "quad extraction: scanning the grid lines exceeds the work budget (the map's triangles span "
                  "far more grid lines than max_quads allows)");
    if ((scan_budget_ & 65535) == 0) progress_.check_cancel();
  }

  bool is_grid(const IVec2& p) const { return p[0] % one_ == 0 && p[1] % one_ == 0; }

  int add_point(int face, const IVec2& uv, const std::vector<Corner>& corners, bool closed) {
    GridPoint p;
    p.face = face;
    p.uv = uv;
    p.boundary = !closed;
    p.ray_begin = static_cast<int>(rays_.size());
    // Directions inside each corner, counter-clockwise; they are consecutive modulo 4.
    std::vector<int> ray_corner;
    for (size_t ci = 0; ci < corners.size(); ++ci) {
      const Corner& c = corners[ci];
      const bool include_b = !closed && ci + 1 == corners.size();
      bool in[4];
      int count = 0;
      for (int d = 0; d < 4; ++d) count += in[d] = in_wedge(c.a, c.b, kUnit[d], include_b);
      if (count == 0 || count == 4) continue;
      int first = 0;
      while (!(in[first] && !in[(first + 3) % 4])) ++first;
      for (int k = 0; k < count; ++k) {
        Ray r;
        r.face = c.face;
        r.dir = static_cast<int8_t>((first + k) % 4);
        r.start = c.at;
        r.alias[0] = {c.face, r.dir};
        r.num_alias = 1;
        rays_.push_back(r);
        ray_corner.push_back(static_cast<int>(ci));
      }
    }
    p.ray_count = static_cast<int>(rays_.size()) - p.ray_begin;
    // A ray along the closing edge b of a corner is owned by the next corner (along its a).
    const int nc = static_cast<int>(corners.size());
    for (int ci = 0; ci < nc; ++ci) {
      if (!closed && ci + 1 == nc) break;
      const Corner& c = corners[ci];
      const int next = (ci + 1) % nc;
      for (int d = 0; d < 4; ++d) {
        if (!(cross(kUnit[d], c.b) == 0 && dot(kUnit[d], c.b) > 0)) continue;
        for (int r = p.ray_begin; r < p.ray_begin + p.ray_count; ++r) {
          Ray& ray = rays_[r];
          if (ray_corner[r - p.ray_begin] == next && ray.num_alias == 1 &&
              cross(corners[next].a, kUnit[ray.dir]) == 0 && dot(corners[next].a, kUnit[ray.dir]) > 0)
            ray.alias[ray.num_alias++] = {c.face, static_cast<int8_t>(d)};
        }
      }
    }
    if (!closed && p.ray_count > 0) rays_[p.ray_begin + p.ray_count - 1].sector_inside = false;
    points_.push_back(p);
    return static_cast<int>(points_.size()) - 1;
  }

  void generate_points() {
    auto& s = result_.stats;
    vertex_point_.assign(mesh_.num_vertices(), -1);
    // Mesh vertices on integer points.
    for (int v = 0; v < mesh_.num_vertices(); ++v) {
      if ((v & 4095) == 0) progress_.check_cancel();
      const std::vector<int> out = outgoing_halfedges(mesh_, v);
      if (out.empty()) continue;
      const int h0 = out.front();
      if (!is_grid(corner(h0 / 3, h0 % 3))) continue;
      std::vector<Corner> corners;
      for (int h : out) {
        const int f = h / 3, k = h % 3;
        if (!face_ok_[f]) continue;
        const IVec2 at = corner(f, k);
        corners.push_back({f, at, sub(corner(f, (k + 1) % 3), at), sub(corner(f, (k + 2) % 3), at)});
      }
      const bool closed = !is_boundary_vertex(mesh_, v);
      const int id = add_point(h0 / 3, corner(h0 / 3, h0 % 3), corners, closed);
      points_[id].mesh_vertex = v;
      vertex_point_[v] = id;
      ++s.grid_points_on_vertices;
    }
    // Lattice points strictly inside edges, in the chart of the edge's first halfedge.
    for (int e = 0; e < mesh_.num_edges(); ++e) {
      if ((e & 4095) == 0) progress_.check_cancel();
      const int h = mesh_.edge_halfedge[e];
      const int f = h / 3, o = mesh_.opposite[h];
      if (!face_ok_[f] || (o >= 0 && !face_ok_[o / 3])) continue;
      const IVec2 A = corner(f, h % 3), B = corner(f, (h % 3 + 1) % 3);
      const IVec2 d = sub(B, A);
      const int m = std::llabs(d[0]) >= std::llabs(d[1]) ? 0 : 1, n = 1 - m;
      if (d[m] == 0) continue;
      const int64_t lo = std::min(A[m], B[m]), hi = std::max(A[m], B[m]);
      for (int64_t x = (floor_div(lo, one_) + 1) * one_; x < hi; x += one_) {
        spend_scan();
        const i128 num = i128(x - A[m]) * d[n];
        if (num % d[m] != 0) continue;
        const int64_t y = A[n] + static_cast<int64_t>(num / d[m]);
        if (y % one_ != 0) continue;
        IVec2 p;
        p[m] = x, p[n] = y;
        std::vector<Corner> corners{{f, p, d, IVec2{-d[0], -d[1]}}};
        if (o >= 0) {
          // The edge seen from the other face runs the other way, in the rotated frame.
          const IVec2 rd = rotate_quarter(d, igm_.rotation[h]);
          const IVec2 dg{-rd[0], -rd[1]};
          corners.push_back({o / 3, igm_.transfer(h, p), dg, IVec2{-dg[0], -dg[1]}});
        }
        const int id = add_point(f, p, corners, o >= 0);
        edge_point_.emplace(PointKey{p[0], p[1], e}, id);
        ++s.grid_points_on_edges;
      }
    }
    // Lattice points strictly inside faces, column by column.
    for (int f = 0; f < mesh_.num_faces(); ++f) {
      if ((f & 1023) == 0) progress_.check_cancel();
      if (!face_ok_[f]) continue;
      const IVec2 P[3] = {corner(f, 0), corner(f, 1), corner(f, 2)};
      const int64_t xlo = std::min({P[0][0], P[1][0], P[2][0]}), xhi = std::max({P[0][0], P[1][0], P[2][0]});
      for (int64_t x = (floor_div(xlo, one_) + 1) * one_; x < xhi; x += one_) {
        // Range of the column inside the triangle (approximate; membership is decided exactly).
        double ymin = 1e300, ymax = -1e300;
        for (int k = 0; k < 3; ++k) {
          const IVec2& p = P[k];
          const IVec2& q = P[(k + 1) % 3];
          if ((p[0] <= x && x <= q[0]) || (q[0] <= x && x <= p[0])) {
            double y = double(p[1]);
            if (p[0] != q[0]) y += double(x - p[0]) / double(q[0] - p[0]) * double(q[1] - p[1]);
            ymin = std::min(ymin, y), ymax = std::max(ymax, y);
            if (p[0] == q[0]) ymin = std::min(ymin, double(q[1])), ymax = std::max(ymax, double(q[1]));
          }
        }
        if (ymin > ymax) continue;
        const int64_t ylo = (static_cast<int64_t>(std::floor(ymin / double(one_))) - 1) * one_;
        const int64_t yhi = (static_cast<int64_t>(std::ceil(ymax / double(one_))) + 1) * one_;
        spend_scan();
        for (int64_t y = ylo; y <= yhi; y += one_) {
          spend_scan();
          const IVec2 q{x, y};
          if (orient2d_exact(P[0], P[1], q) <= 0 || orient2d_exact(P[1], P[2], q) <= 0 ||
              orient2d_exact(P[2], P[0], q) <= 0)
            continue;
          // Four rays, counter-clockwise.
          GridPoint p;
          p.face = f;
          p.uv = q;
          p.ray_begin = static_cast<int>(rays_.size());
          p.ray_count = 4;
          for (int d = 0; d < 4; ++d) {
            Ray r;
            r.face = f;
            r.dir = static_cast<int8_t>(d);
            r.start = q;
            r.alias[0] = {f, r.dir};
            r.num_alias = 1;
            rays_.push_back(r);
          }
          points_.push_back(p);
          face_point_.emplace(PointKey{x, y, f}, static_cast<int>(points_.size()) - 1);
          ++s.grid_points_in_faces;
        }
      }
    }
  }

  // ------------------------------------------------------------------------------------------
  // Tracing.

  struct Arrival {
    int face = -1;
    IVec2 at{0, 0};
    int dir = 0;
  };

  bool closed_contains(int f, const IVec2& q) const {
    const IVec2 P0 = corner(f, 0), P1 = corner(f, 1), P2 = corner(f, 2);
    return orient2d_exact(P0, P1, q) >= 0 && orient2d_exact(P1, P2, q) >= 0 && orient2d_exact(P2, P0, q) >= 0;
  }

  bool spend_step() {
    ++result_.stats.triangle_steps;
    if ((result_.stats.triangle_steps & 65535) == 0) progress_.check_cancel();
    if (result_.stats.triangle_steps > step_budget_) budget_exhausted_ = true;
    return !budget_exhausted_;
  }

  // Follows the isoline from `start` (in face f's chart, direction dir, its first part inside the
  // closed face f) to the first integer point along it. Returns false (with a reason) if the
  // isoline leaves the surface or tracing goes astray.
  bool trace(int f, IVec2 s, int dir, Arrival& out, std::string& why) {
    const int max_steps = 2 * mesh_.num_faces() + 16;
    for (int step = 0; step < max_steps; ++step) {
      if (!spend_step()) {
        why = "tracing exceeded its step budget";
        return false;
      }
      if (std::llabs(s[0]) >= 2 * kMaxCoordinate || std::llabs(s[1]) >= 2 * kMaxCoordinate) {
        why = "the isoline drifted out of range";
        return false;
      }
      const IVec2 w = kUnit[dir];
      const IVec2 target = add_scaled(s, w, one_);
      if (closed_contains(f, target)) {
        out = {f, target, dir};
        return true;
      }
      const IVec2 P[3] = {corner(f, 0), corner(f, 1), corner(f, 2)};
      const IVec2 ahead = add_scaled(s, w, 1);
      int side[3];
      for (int k = 0; k < 3; ++k) side[k] = orient2d_exact(s, ahead, P[k]);
      int exit_edge = -1;
      for (int k = 0; k < 3; ++k)
        if (side[k] < 0 && side[(k + 1) % 3] > 0) exit_edge = k;
      if (exit_edge >= 0) {
        const int h = 3 * f + exit_edge, o = mesh_.opposite[h];
        if (o < 0) {
          why = "the isoline leaves the surface through boundary edge " + std::to_string(mesh_.edge_of[h]);
          return false;
        }
        s = igm_.transfer(h, s);
        dir = (dir + igm_.rotation[h]) % 4;
        f = o / 3;
        if (!face_ok_[f]) {
          why = "the isoline enters invalid face " + std::to_string(f);
          return false;
        }
        continue;
      }
      // The isoline leaves through a vertex: the one on the line farthest ahead.
      int best = -1;
      i128 best_t = 0;
      for (int k = 0; k < 3; ++k) {
        if (side[k] != 0) continue;
        const i128 t = dot(sub(P[k], s), w);
        if (best < 0 || t > best_t) best = k, best_t = t;
      }
      if (best < 0 || best_t <= 0) {
        why = "the isoline misses face " + std::to_string(f);
        return false;
      }
      if (!pass_vertex(3 * f + best, f, s, dir, why)) return false;
    }
    why = "the isoline did not reach an integer point";
    return false;
  }

  // The isoline (start s, direction dir in face f's chart) passes through the vertex at the start
  // of halfedge hv (in f). Moves f, s, dir to the face around the vertex that it continues into.
  bool pass_vertex(int hv, int& f, IVec2& s, int& dir, std::string& why) {
    const int v = mesh_.from(hv);
    // Walk counter-clockwise, then (at a boundary) clockwise, carrying the chart along.
    for (int sense = 0; sense < 2; ++sense) {
      int h = hv, cf = f, cdir = dir;
      IVec2 cs = s;
      for (int guard = 0; guard <= mesh_.num_halfedges(); ++guard) {
        int cross_h, next_h;
        if (sense == 0) {
          cross_h = TriMesh::prev(h);
          next_h = mesh_.opposite[cross_h];
        } else {
          cross_h = h;
          next_h = mesh_.opposite[h] < 0 ? -1 : TriMesh::next(mesh_.opposite[h]);
        }
        if (next_h < 0 || next_h == hv) break;
        if (!spend_step()) {
          why = "tracing exceeded its step budget";
          return false;
        }
        cs = igm_.transfer(cross_h, cs);
        cdir = (cdir + igm_.rotation[cross_h]) % 4;
        h = next_h;
        cf = h / 3;
        if (!face_ok_[cf]) continue;
        const int k = h % 3;
        const IVec2 at = corner(cf, k);
        const IVec2 a = sub(corner(cf, (k + 1) % 3), at), b = sub(corner(cf, (k + 2) % 3), at);
        const bool last = mesh_.opposite[TriMesh::prev(h)] < 0;
        if (in_wedge(a, b, kUnit[cdir], last)) {
          f = cf, s = cs, dir = cdir;
          return true;
        }
      }
      if (!is_boundary_vertex(mesh_, v)) break;
    }
    why = "the isoline leaves the surface at vertex " + std::to_string(v);
    return false;
  }

  // The grid point at q (closed face g's chart), or -1.
  int locate(int g, const IVec2& q) const {
    const IVec2 P[3] = {corner(g, 0), corner(g, 1), corner(g, 2)};
    int o[3], zeros = 0;
    for (int k = 0; k < 3; ++k) zeros += (o[k] = orient2d_exact(P[k], P[(k + 1) % 3], q)) == 0;
    if (zeros == 0) {
      auto it = face_point_.find(PointKey{q[0], q[1], g});
      return it == face_point_.end() ? -1 : it->second;
    }
    if (zeros == 1) {
      const int k = o[0] == 0 ? 0 : o[1] == 0 ? 1 : 2;
      const int h = 3 * g + k, e = mesh_.edge_of[h];
      const IVec2 key = mesh_.edge_halfedge[e] == h ? q : igm_.transfer(h, q);
      auto it = edge_point_.find(PointKey{key[0], key[1], e});
      return it == edge_point_.end() ? -1 : it->second;
    }
    if (zeros == 2)
      for (int j = 0; j < 3; ++j)
        if (o[(j + 2) % 3] == 0 && o[j] == 0) return vertex_point_[mesh_.F(g, j)];
    return -1;
  }

  void trace_all() {
    auto& s = result_.stats;
    const size_t n = rays_.size();
    for (size_t r = 0; r < n; ++r) {
      if ((r & 4095) == 0) progress_.update(0.25 + 0.5 * double(r) / double(std::max<size_t>(n, 1)));
      Ray& ray = rays_[r];
      ++s.traced_segments;
      Arrival arrival;
      std::string why;
      bool ok = trace(ray.face, ray.start, ray.dir, arrival, why);
      if (ok) {
        const int q = locate(arrival.face, arrival.at);
        if (q < 0) {
          ok = false;
          why = "the isoline meets an integer point in face " + std::to_string(arrival.face) +
                " that is not a grid point (non-integer vertex?)";
        } else {
          const int back = (arrival.dir + 2) % 4;
          const GridPoint& p = points_[q];
          for (int i = p.ray_begin; i < p.ray_begin + p.ray_count && ray.dest_ray < 0; ++i)
            for (int a = 0; a < rays_[i].num_alias; ++a)
              if (rays_[i].alias[a].face == arrival.face && rays_[i].alias[a].dir == back) {
                ray.dest_point = q;
                ray.dest_ray = i;
              }
          if (ray.dest_ray < 0) {
            ok = false;
            why = "the isoline arrives at a grid point from a direction it does not have";
          }
        }
      }
      if (!ok) {
        ++s.failed_traces;
        ray.dest_point = ray.dest_ray = -1;
        note_defect("isoline from face " + std::to_string(ray.face) + " direction " + std::to_string(ray.dir) + ": " +
                    why);
        if (budget_exhausted_) {
          // The map is wild: give up on the remaining isolines.
          if (!options_.allow_defects) throw_defects();
          break;
        }
      }
    }
  }

  void check_consistency() {
    for (Ray& ray : rays_) {
      if (ray.dest_ray < 0) continue;
      const Ray& back = rays_[ray.dest_ray];
      if (back.dest_ray < 0 || &rays_[back.dest_ray] != &ray) {
        ++result_.stats.inconsistent_segments;
        note_defect("the isoline segments from face " + std::to_string(ray.face) + " and back do not match");
      }
    }
  }

  // ------------------------------------------------------------------------------------------
  // Faces.

  Vec3 point_position(const GridPoint& p) const {
    if (p.mesh_vertex >= 0) return mesh_.position(p.mesh_vertex);
    const IVec2 P[3] = {corner(p.face, 0), corner(p.face, 1), corner(p.face, 2)};
    const long double total = static_cast<long double>(cross(sub(P[1], P[0]), sub(P[2], P[0])));
    Vec3 pos = Vec3::Zero();
    for (int k = 0; k < 3; ++k) {
      const long double w = static_cast<long double>(cross(sub(P[(k + 1) % 3], p.uv), sub(P[(k + 2) % 3], p.uv)));
      pos += static_cast<double>(w / total) * mesh_.position(mesh_.F(p.face, k));
    }
    return pos;
  }

  void assemble() {
    auto& s = result_.stats;
    QuadMesh& qm = result_.quads;
    const int np = static_cast<int>(points_.size());
    qm.V.resize(np, 3);
    qm.vertex_face.resize(np);
    qm.vertex_singular.resize(np);
    std::vector<int> ray_owner(rays_.size());
    for (int i = 0; i < np; ++i) {
      const GridPoint& p = points_[i];
      qm.V.row(i) = point_position(p).transpose();
      qm.vertex_face[i] = p.face;
      qm.vertex_singular[i] = p.ray_count != (p.boundary ? 3 : 4);
      s.singular_vertices += qm.vertex_singular[i];
      for (int r = p.ray_begin; r < p.ray_begin + p.ray_count; ++r) ray_owner[r] = i;
    }
    std::vector<std::array<int, 4>> quads;
    std::vector<char> visited(rays_.size(), 0);
    for (size_t r0 = 0; r0 < rays_.size(); ++r0) {
      if (!rays_[r0].sector_inside) ++s.boundary_edges;
      if (visited[r0] || !rays_[r0].sector_inside || rays_[r0].dest_ray < 0) continue;
      if ((r0 & 4095) == 0) progress_.check_cancel();
      std::vector<int> corners;
      int r = static_cast<int>(r0);
      bool closed = false, broken = false;
      for (int guard = 0; guard < 64; ++guard) {
        visited[r] = 1;
        corners.push_back(ray_owner[r]);
        const Ray& ray = rays_[r];
        if (ray.dest_ray < 0) {
          broken = true;
          break;
        }
        const GridPoint& q = points_[ray.dest_point];
        const int idx = ray.dest_ray - q.ray_begin;
        r = q.ray_begin + (idx + q.ray_count - 1) % q.ray_count;
        if (!rays_[r].sector_inside) {
          broken = true;
          break;
        }
        if (r == static_cast<int>(r0)) {
          closed = true;
          break;
        }
        if (visited[r]) {
          broken = true;
          break;
        }
      }
      if (closed && corners.size() == 4) {
        quads.push_back({corners[0], corners[1], corners[2], corners[3]});
      } else {
        ++s.non_quad_faces;
        note_defect(std::string(broken || !closed ? "an open face walk"
                                                  : "a face with " + std::to_string(corners.size()) + " sides") +
                    " at the grid point in face " + std::to_string(points_[ray_owner[r0]].face));
      }
    }
    qm.Q.resize(static_cast<int>(quads.size()), 4);
    for (size_t i = 0; i < quads.size(); ++i)
      for (int k = 0; k < 4; ++k) qm.Q(static_cast<int>(i), k) = quads[i][k];
  }

  const TriMesh& mesh_;
  const ExactParametrization& igm_;
  const QuadExtractionOptions& options_;
  Progress& progress_;
  const int64_t one_;
  QuadExtraction result_;
  std::string first_defect_;
  std::vector<char> face_ok_;  // #F: positive parametric area
  std::vector<GridPoint> points_;
  std::vector<Ray> rays_;
  std::vector<int> vertex_point_;                               // #V: grid point on the vertex or -1
  std::unordered_map<PointKey, int, PointKeyHash> edge_point_;  // (coords in edge_halfedge's chart, edge)
  std::unordered_map<PointKey, int, PointKeyHash> face_point_;  // (coords, face)
  int64_t step_budget_ = 0;
  int64_t scan_budget_ = 0;
  bool budget_exhausted_ = false;
};

}  // namespace

QuadExtraction extract_quads(const TriMesh& mesh, const ExactParametrization& igm, const QuadExtractionOptions& options,
                             Progress& progress) {
  Extractor extractor(mesh, igm, options, progress);
  return extractor.run();
}

void append_quad_mesh(QuadMesh& into, const QuadMesh& part, int component) {
  const int nv = into.num_vertices(), nq = into.num_quads();
  const bool had_vertex_data =
      into.vertex_face.size() == static_cast<size_t>(nv) && into.vertex_singular.size() == static_cast<size_t>(nv);
  into.V.conservativeResize(nv + part.num_vertices(), 3);
  into.V.bottomRows(part.num_vertices()) = part.V;
  into.Q.conservativeResize(nq + part.num_quads(), 4);
  into.Q.bottomRows(part.num_quads()) = part.Q.array() + nv;
  into.component.resize(nq, -1);
  into.component.insert(into.component.end(), part.num_quads(), component);
  if (had_vertex_data && part.vertex_face.size() == static_cast<size_t>(part.num_vertices()) &&
      part.vertex_singular.size() == static_cast<size_t>(part.num_vertices())) {
    into.vertex_face.insert(into.vertex_face.end(), part.vertex_face.begin(), part.vertex_face.end());
    into.vertex_singular.insert(into.vertex_singular.end(), part.vertex_singular.begin(), part.vertex_singular.end());
  } else {
    into.vertex_face.clear(), into.vertex_singular.clear();
  }
}

void to_json(Json& j, const QuadExtractionStats& s) {
  j["grid_points"] = {
      {"vertices", s.grid_points_on_vertices}, {"edges", s.grid_points_on_edges}, {"faces", s.grid_points_in_faces}};
  j["traced_segments"] = s.traced_segments;
  j["triangle_steps"] = s.triangle_steps;
  j["expected_quads"] = s.expected_quads;
  j["area_is_integral"] = s.area_is_integral;
  j["singular_vertices"] = s.singular_vertices;
  j["boundary_edges"] = s.boundary_edges;
  j["defects"] = {{"flipped_triangles", s.flipped_triangles},
                  {"degenerate_triangles", s.degenerate_triangles},
                  {"failed_traces", s.failed_traces},
                  {"inconsistent_segments", s.inconsistent_segments},
                  {"non_quad_faces", s.non_quad_faces}};
  j["seconds"] = s.seconds;
}

}  // namespace qgp

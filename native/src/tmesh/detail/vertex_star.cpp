#include "tmesh/detail/vertex_star.h"

namespace qgp::tmesh_detail {

namespace {

// Signed number of cardinal directions swept by a corner from e1 to e2 (winding count).
int signed_corner_count(const StarCorner& c) {
  int count = 0;
  if (c.orient > 0) {
    for (int d = 0; d < 4; ++d) count += cardinal_in_corner(d, c.e1, c.e2);
  } else if (c.orient < 0) {
    for (int d = 0; d < 4; ++d) count -= cardinal_in_corner(d, c.e2, c.e1);
  } else if (dot(c.e1, c.e2) < 0) {
    // Degenerate corner of angle pi: counted as +pi (the surface's orientation).
    for (int d = 0; d < 4; ++d) {
      const i128 cr = cross(c.e1, cardinal(d));
      count += cr > 0 || (cr == 0 && dot(c.e1, cardinal(d)) > 0);
    }
  }
  return count;
}

// Cardinal directions of a positive corner in [e1, e2), counter-clockwise.
void corner_directions(const StarCorner& c, int corner, std::vector<StarDirection>& out) {
  const int first = cardinal_at_or_after(c.e1);
  const int along = exact_cardinal(c.e1);
  for (int k = 0; k < 3; ++k) {
    const int d = (first + k) & 3;
    if (!cardinal_in_corner(d, c.e1, c.e2)) break;
    StarDirection s;
    s.corner = corner;
    s.dir = d;
    s.along_edge = d == along;
    out.push_back(s);
  }
}

// Walks the one-ring of the vertex from h0 counter-clockwise and fills star.ring, positive,
// on_wall and holonomy (and problem for zero-length parametric edges).
void walk_ring(const TriMesh& mesh, const std::vector<P2>& uv2, const std::vector<int8_t>& rotation,
               const std::vector<char>& wall_edge, int h0, VertexStar& star) {
  int h = h0, acc = 0;
  const int limit = mesh.num_halfedges();
  for (int guard = 0; guard <= limit; ++guard) {
    StarCorner c;
    c.face = h / 3;
    c.h_out = h;
    c.acc = acc & 3;
    const P2 pv = uv2[h];
    c.e1 = sub(uv2[TriMesh::next(h)], pv);
    c.e2 = sub(uv2[TriMesh::prev(h)], pv);
    c.orient = sign(cross(c.e1, c.e2));
    c.rot_to_next = rotation[TriMesh::prev(h)] & 3;
    if (c.orient <= 0) star.positive = false;
    if ((c.e1[0] == 0 && c.e1[1] == 0) || (c.e2[0] == 0 && c.e2[1] == 0))
      star.problem = "zero-length edge in parameter space";
    if (wall_edge[mesh.edge_of[h]]) star.on_wall = true;
    star.ring.push_back(c);
    const int hn = mesh.rotate_ccw(h);
    if (hn < 0) break;
    acc += c.rot_to_next;
    if (hn == h0) {
      star.holonomy = acc & 3;
      break;
    }
    h = hn;
  }
}

// Vertex off every wall: angle sum, index, directions and their frame numbers (sets problem
// when the ring cannot be used).
void analyse_interior_star(VertexStar& star) {
  const int n = static_cast<int>(star.ring.size());
  int count = 0;
  for (const StarCorner& c : star.ring) count += signed_corner_count(c);
  star.quarter_turns = count;
  star.index = 4 - count;
  if (count <= 0) {
    star.problem = "non-positive parametric angle sum";
    return;
  }
  // Going around, the angle sum plus the transition rotations closes up: count + holonomy = 0 mod 4.
  if (((count + star.holonomy) & 3) != 0) {
    star.problem = "parametric angle sum disagrees with the transition rotations";
    return;
  }
  if (!star.positive) {
    star.problem = "flipped or degenerate triangle in the one-ring";
    star.corner = count != 4;
    return;
  }
  for (int i = 0; i < n; ++i) corner_directions(star.ring[i], i, star.directions);
  const bool regular = count == 4 && star.holonomy == 0;
  star.sector_frame = !regular;
  star.period = regular ? 4 : count;
  star.corner = !regular;
  for (size_t i = 0; i < star.directions.size(); ++i) {
    StarDirection& s = star.directions[i];
    s.number = regular ? (s.dir - star.ring[s.corner].acc) & 3 : static_cast<int>(i);
    if (!regular) star.emissions.push_back(static_cast<int>(i));
  }
}

// One sector of a wall vertex, corners [first, end) (indices modulo the ring size): appends its
// directions numbered from `base`, its emissions and its first wall. Returns the sector's angle
// in quarter turns q; q <= 0 (zero angle) leaves the directions unnumbered.
int number_wall_sector(VertexStar& star, int first, int end, int base) {
  const int n = static_cast<int>(star.ring.size());
  const size_t list_begin = star.directions.size();
  for (int i = first; i < end; ++i) corner_directions(star.ring[i % n], i % n, star.directions);
  const int L = static_cast<int>(star.directions.size() - list_begin);
  const StarCorner& c_first = star.ring[first];
  const StarCorner& c_last = star.ring[(end - 1) % n];
  // Lifted index k = k-th cardinal at or after wall W1; round each wall to its nearest.
  const int r1 = nearest_cardinal(c_first.e1) == cardinal_at_or_after(c_first.e1) ? 0 : -1;
  const bool w2_exact = exact_cardinal(c_last.e2) >= 0;
  const int before_w2 = w2_exact ? L : L - 1;
  const int r2 = nearest_cardinal(c_last.e2) == cardinal_at_or_before(c_last.e2) ? before_w2 : before_w2 + 1;
  const int q = r2 - r1;
  if (q <= 0) return q;
  for (int k = 0; k < L; ++k) {
    StarDirection& d = star.directions[list_begin + k];
    d.number = base + (k - r1);
    if (k > r1 && k < r2) star.emissions.push_back(static_cast<int>(list_begin + k));
  }
  star.wall_number[first] = base;
  star.wall_dir[first] = nearest_cardinal(c_first.e1);
  return q;
}

// A wall vertex whose sectors add up to a regular frame: renumbers directions and walls in
// chart directions of ring[0]'s face.
void use_chart_frame(VertexStar& star) {
  const int n = static_cast<int>(star.ring.size());
  for (StarDirection& d : star.directions) d.number = (d.dir - star.ring[d.corner].acc) & 3;
  for (int i = 0; i < n; ++i)
    if (star.wall_number[i] != INT_MIN) star.wall_number[i] = (star.wall_dir[i] - star.ring[i].acc) & 3;
  if (star.boundary) {
    const StarCorner& last = star.ring[n - 1];
    // The last boundary edge, seen from the last face: nearest cardinal, into ring[0]'s chart.
    star.end_wall_number = (nearest_cardinal(last.e2) - last.acc) & 3;
  }
}

// Wall vertex: sectors between consecutive walls (feature or boundary edges). Numbers the
// directions sector by sector and classifies the vertex (sets problem when it cannot be used).
void analyse_wall_star(const TriMesh& mesh, const std::vector<char>& wall_edge, VertexStar& star) {
  const int n = static_cast<int>(star.ring.size());
  if (!star.positive) {
    star.problem = "flipped or degenerate triangle in the one-ring of a feature/boundary vertex";
    star.corner = true;
    return;
  }
  std::vector<int> wall_starts;
  for (int i = 0; i < n; ++i)
    if (wall_edge[mesh.edge_of[star.ring[i].h_out]] || (star.boundary && i == 0)) wall_starts.push_back(i);
  const int num_sectors = static_cast<int>(wall_starts.size());
  std::vector<int> sector_q;
  int base = 0;
  for (int s = 0; s < num_sectors; ++s) {
    const int first = wall_starts[s];
    const int end = s + 1 < num_sectors ? wall_starts[s + 1] : (star.boundary ? n : wall_starts[0] + n);
    const int q = number_wall_sector(star, first, end, base);
    if (q <= 0) {
      star.problem = "feature/boundary edges meet at a zero parametric angle";
      star.corner = true;
      return;
    }
    sector_q.push_back(q);
    base += q;
    if (star.boundary && s + 1 == num_sectors) star.end_wall_number = base;
  }
  star.quarter_turns = base;
  star.index = (star.boundary ? 2 : 4) - base;
  const bool regular_frame = star.boundary ? base == 2 : (base == 4 && star.holonomy == 0);
  star.straight_wall = star.boundary ? (num_sectors == 1 && base == 2)
                                     : (num_sectors == 2 && sector_q[0] == 2 && sector_q[1] == 2 && star.holonomy == 0);
  star.corner = !star.straight_wall;
  star.sector_frame = !regular_frame;
  star.period = regular_frame ? 4 : (star.boundary ? 0 : base);
  if (regular_frame) use_chart_frame(star);
}

}  // namespace

int VertexStar::frame_number(int corner, int dir) const {
  if (corner < 0 || corner >= static_cast<int>(ring.size())) return INT_MIN;
  dir &= 3;
  if (!sector_frame) return (dir - ring[corner].acc) & 3;
  for (const StarDirection& s : directions)
    if (s.corner == corner && s.dir == dir) return s.number;
  // A direction along e2 belongs to the next corner (as its e1).
  const StarCorner& c = ring[corner];
  if (exact_cardinal(c.e2) == dir) {
    const int next = corner + 1 < static_cast<int>(ring.size()) ? corner + 1 : (boundary ? -1 : 0);
    if (next >= 0) {
      const int d2 = (dir + c.rot_to_next) & 3;
      for (const StarDirection& s : directions)
        if (s.corner == next && s.dir == d2) return s.number;
    }
  }
  return INT_MIN;
}

VertexStar analyse_vertex(const TriMesh& mesh, const std::vector<P2>& uv2, const std::vector<int8_t>& rotation,
                          const std::vector<char>& wall_edge, int v) {
  VertexStar star;
  const int h0 = mesh.vertex_halfedge[v];
  if (h0 < 0) {
    star.problem = "isolated vertex";
    return star;
  }
  star.boundary = mesh.opposite[h0] < 0;
  walk_ring(mesh, uv2, rotation, wall_edge, h0, star);
  if (star.boundary) star.on_wall = true;
  const int n = static_cast<int>(star.ring.size());
  star.wall_number.assign(n, INT_MIN);
  star.wall_dir.assign(n, -1);
  if (!star.on_wall)
    analyse_interior_star(star);
  else
    analyse_wall_star(mesh, wall_edge, star);
  return star;
}

void make_virtual_corner(VertexStar& star) {
  star.corner = true;
  star.virtual_corner = true;
}

void make_seed(VertexStar& star) {
  star.corner = true;
  star.seed = true;
  star.emissions.clear();
  for (size_t i = 0; i < star.directions.size(); ++i) star.emissions.push_back(static_cast<int>(i));
}

}  // namespace qgp::tmesh_detail

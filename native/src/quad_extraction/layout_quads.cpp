#include "quad_extraction/layout_quads.h"

#include <algorithm>
#include <array>
#include <limits>
#include <numeric>
#include <string>

#include "core/error.h"
#include "core/timer.h"
#include "core/union_find.h"
#include "quad_extraction/surface_projection.h"

namespace qgp {
namespace {

// A grid point before merging: where it is and whether it may move.
struct GridPoint {
  Vec3 position = Vec3::Zero();
  bool singular = false;
  bool pinned = false;        // on a node at one of the caller's pinned vertices
  SurfacePoint point;         // where it lies in the map (face -1: unknown, found by projection)
  Vec2 along = Vec2::Zero();  // unit direction of its T-edge (from -> to) in point.face's chart
};

// Unit axis direction closest to d (zero for a zero vector).
Vec2 axis_direction(const Vec2& d) {
  if (d.x() == 0 && d.y() == 0) return Vec2::Zero();
  return std::abs(d.x()) >= std::abs(d.y()) ? Vec2(d.x() > 0 ? 1 : -1, 0) : Vec2(0, d.y() > 0 ? 1 : -1);
}

// Walks from `start` by `delta` (in start.face's chart) straight through the map, crossing edges
// with their transitions. false if the walk leaves the surface or meets a degenerate triangle.
bool walk(const TriMesh& mesh, const ExactParametrization& param, const SurfacePoint& start, const Vec2& delta,
          SurfacePoint& end) {
  int f = start.face, entered = -1;
  Vec2 p = start.uv, q = start.uv + delta;
  auto cross = [](const Vec2& a, const Vec2& b) { return a.x() * b.y() - a.y() * b.x(); };
  for (int step = 0; step < 100000; ++step) {
    Vec2 c[3];
    for (int k = 0; k < 3; ++k)
      c[k] = Vec2(param.to_double(param.uv[3 * f + k][0]), param.to_double(param.uv[3 * f + k][1]));
    const double area = cross(c[1] - c[0], c[2] - c[0]);
    if (!(area > 0)) return false;
    auto barycentric = [&](const Vec2& x) {
      return Vec3(cross(c[1] - x, c[2] - x) / area, cross(c[2] - x, c[0] - x) / area, cross(c[0] - x, c[1] - x) / area);
    };
    const Vec3 lq = barycentric(q);
    int exit = -1;
    double first = std::numeric_limits<double>::infinity();
    if (lq.minCoeff() < 0) {
      const Vec3 lp = barycentric(p);
      for (int i = 0; i < 3; ++i) {
        const int h = 3 * f + (i + 1) % 3;  // the edge opposite corner i
        if (!(lq[i] < 0) || h == entered) continue;
        const double t = lp[i] <= 0 ? 0.0 : lp[i] / (lp[i] - lq[i]);
        if (t < first || (t == first && lq[i] < lq[exit])) first = t, exit = i;
      }
    }
    if (exit < 0) {  // inside (up to rounding)
      Vec3 b = lq.cwiseMax(0.0);
      b /= b.sum();
      end.face = f;
      end.barycentric = b;
      end.uv = b[0] * c[0] + b[1] * c[1] + b[2] * c[2];
      return true;
    }
    const int h = 3 * f + (exit + 1) % 3, o = mesh.opposite[h];
    if (o < 0) return false;
    auto transfer = [&](const Vec2& x) {
      const Vec2 r = rotate_quarter(x, param.rotation[h]);
      return Vec2(r.x() + param.to_double(param.translation[h][0]), r.y() + param.to_double(param.translation[h][1]));
    };
    p = transfer(p + first * (q - p));
    q = transfer(q);
    f = o / 3;
    entered = o;
  }
  return false;
}

// The x + 1 points of edge e (from -> to) at equal parametric spacing along its trace.
void place_edge_points(const TriMesh& mesh, const TMesh& tm, int e, int64_t x, std::vector<GridPoint>& out) {
  const TMeshEdge& edge = tm.edges[e];
  const std::vector<SurfacePoint>& trace = edge.trace;
  const Vec3 a = tm.nodes[edge.from].point.position(mesh), b = tm.nodes[edge.to].point.position(mesh);
  out.assign(x + 1, GridPoint{});
  // Cumulative parametric length over the straight pieces (pairs in the same face).
  std::vector<double> cumulative(trace.size(), 0.0);
  for (size_t i = 1; i < trace.size(); ++i)
    cumulative[i] =
        cumulative[i - 1] + (trace[i].face == trace[i - 1].face ? (trace[i].uv - trace[i - 1].uv).norm() : 0.0);
  const double total = trace.empty() ? 0.0 : cumulative.back();
  size_t piece = 1;
  for (int64_t k = 0; k <= x; ++k) {
    GridPoint& p = out[k];
    if (x == 0 || !(total > 0) || trace.size() < 2) {
      const double t = x == 0 ? 0.0 : static_cast<double>(k) / static_cast<double>(x);
      p.position = (1 - t) * a + t * b;  // point.face stays -1: found by projection
      continue;
    }
    const double target = total * static_cast<double>(k) / static_cast<double>(x);
    while (piece + 1 < trace.size() && (cumulative[piece] < target || trace[piece].face != trace[piece - 1].face))
      ++piece;
    const SurfacePoint& s = trace[piece - 1];
    const SurfacePoint& t = trace[piece];
    const double length = cumulative[piece] - cumulative[piece - 1];
    const double w = length > 0 ? std::clamp((target - cumulative[piece - 1]) / length, 0.0, 1.0) : 0.0;
    p.position = (1 - w) * s.position(mesh) + w * t.position(mesh);
    p.point.face = t.face;
    p.point.barycentric = (1 - w) * s.barycentric + w * t.barycentric;
    p.point.uv = (1 - w) * s.uv + w * t.uv;
    p.along = axis_direction(t.uv - s.uv);
  }
}

// The cell's boundary counter-clockwise (sides 0..3 in order) with each edge's direction in it.
struct OrientedSide {
  std::vector<int> edges;
  std::vector<char> forward;  // the loop runs from -> to
};

std::array<OrientedSide, 4> orient_cell(const TMesh& tm, int c) {
  const TMeshCell& cell = tm.cells[c];
  std::vector<std::pair<int, int>> loop;  // (side, index in side)
  for (int s = 0; s < 4; ++s)
    for (size_t i = 0; i < cell.sides[s].size(); ++i) loop.push_back({s, static_cast<int>(i)});
  const int n = static_cast<int>(loop.size());
  std::vector<int> dir(n, -1);  // 1 forward, 0 backward, -1 unknown
  auto edge_at = [&](int i) { return cell.sides[loop[i].first][loop[i].second]; };
  int known = -1;
  for (int i = 0; i < n; ++i) {
    const TMeshEdge& e = tm.edges[edge_at(i)];
    if (e.cells[0] == c && e.cells[1] != c) dir[i] = 1;
    if (e.cells[1] == c && e.cells[0] != c) dir[i] = 0;
    if (dir[i] >= 0 && known < 0) known = i;
  }
  if (known < 0) known = 0, dir[0] = 1;
  // Edges with this cell on both sides: follow the loop from a known one.
  std::vector<char> seen_forward(tm.edges.size(), 0);
  for (int step = 1; step < n; ++step) {
    const int i = (known + step) % n, prev = (known + step - 1) % n;
    if (dir[i] >= 0) continue;
    const TMeshEdge& p = tm.edges[edge_at(prev)];
    const int head = dir[prev] ? p.to : p.from;
    const TMeshEdge& e = tm.edges[edge_at(i)];
    if (e.from == head && e.to == head)
      dir[i] = seen_forward[edge_at(i)] ? 0 : 1;  // a loop edge
    else
      dir[i] = e.from == head ? 1 : 0;
    if (dir[i]) seen_forward[edge_at(i)] = 1;
  }
  std::array<OrientedSide, 4> sides;
  for (int i = 0; i < n; ++i) {
    sides[loop[i].first].edges.push_back(edge_at(i));
    sides[loop[i].first].forward.push_back(static_cast<char>(dir[i]));
  }
  return sides;
}

// A point of a side, in the side's direction: its id, where it lies in the map, the side's
// direction there, and its parametric distance from the side's first corner.
struct SidePoint {
  int64_t id;
  const GridPoint* at;
  Vec2 along;
  double distance;
};

// One cell as a w x h grid: the points of its four sides, their parametric lengths, and the id of
// its first inner point.
struct CellGrid {
  std::array<std::vector<SidePoint>, 4> side;
  std::array<double, 4> length{0, 0, 0, 0};
  int64_t w = 0, h = 0;
  int64_t inner_first = 0;

  // Grid point (i, j): side 0 runs along i at j = 0, side 1 up at i = w, side 2 back at j = h,
  // side 3 down at i = 0.
  const SidePoint& boundary(int64_t i, int64_t j) const {
    if (j == 0) return side[0][i];
    if (i == w) return side[1][j];
    if (j == h) return side[2][w - i];
    return side[3][h - j];
  }
  // The id of grid point (i, j): its side point's, or one of the cell's inner points.
  int64_t id(int64_t i, int64_t j) const {
    return (i == 0 || j == 0 || i == w || j == h) ? boundary(i, j).id : inner_first + (j - 1) * (w - 1) + (i - 1);
  }
};

// The state of one layout extraction: the grid points (nodes, edges' inner points, cells' inner
// points), their identifications by collapses, and the quads.
class LayoutQuadExtractor {
 public:
  LayoutQuadExtractor(const TriMesh& mesh, const ExactParametrization& seamless, const TMesh& tm,
                      const std::vector<int64_t>& x, Progress& progress, bool with_positions,
                      const std::vector<char>& pinned_vertices)
      : mesh_(mesh),
        seamless_(seamless),
        tm_(tm),
        x_(x),
        progress_(progress),
        with_positions_(with_positions),
        pinned_vertices_(pinned_vertices),
        ne_(static_cast<int>(tm.edges.size())) {}

  // All the phases; the layout without its time.
  LayoutQuads run();

 private:
  void number_grid_points();
  int64_t edge_point(int e, int64_t k) const;
  void place_node_and_edge_points();
  CellGrid cell_sides(int c);
  void make_cell_quads(int c);
  void glue_collapsed_cell(const CellGrid& g);
  void place_inner_points(const CellGrid& g);
  void merge_points();
  void build_quad_mesh();
  void project_onto_surface();

  static constexpr int64_t kMaxQuads = 50000000;

  const TriMesh& mesh_;
  const ExactParametrization& seamless_;
  const TMesh& tm_;
  const std::vector<int64_t>& x_;
  Progress& progress_;
  const bool with_positions_;
  const std::vector<char>& pinned_vertices_;
  const int ne_;
  LayoutQuads result_;
  std::vector<int64_t> edge_first_;              // #edges: the id of each edge's first inner point
  int64_t count_ = 0;                            // nodes and edges' inner points
  std::vector<GridPoint> points_;                // by id
  std::vector<std::vector<GridPoint>> on_edge_;  // the x + 1 points of each edge, from -> to
  UnionFind<int64_t> uf_;                        // points identified by collapses
  std::vector<std::array<int64_t, 4>> quads_;    // point ids
  std::vector<int> vertex_of_;                   // by id: the merged point
  std::vector<GridPoint> merged_;
};

LayoutQuads LayoutQuadExtractor::run() {
  number_grid_points();
  place_node_and_edge_points();
  // Cells: side point lists, collapses, inner points, quads.
  uf_.grow(count_);
  for (int e = 0; e < ne_; ++e)
    if (x_[e] == 0) uf_.unite(tm_.edges[e].from, tm_.edges[e].to);
  for (int c = 0; c < static_cast<int>(tm_.cells.size()); ++c) make_cell_quads(c);
  progress_.update(0.4);
  merge_points();
  build_quad_mesh();
  project_onto_surface();
  return std::move(result_);
}

// Grid point ids: nodes, then the inner points of every edge, then the cells' inner points.
void LayoutQuadExtractor::number_grid_points() {
  edge_first_.resize(ne_);
  count_ = static_cast<int64_t>(tm_.nodes.size());
  for (int e = 0; e < ne_; ++e) {
    if (x_[e] < 0)
      throw Error(ErrorCode::InvalidArgument, "layout quads: negative length of T-edge " + std::to_string(e));
    edge_first_[e] = count_;
    count_ += std::max<int64_t>(0, x_[e] - 1);
    result_.stats.zero_edges += x_[e] == 0;
  }
}

// The id of point k of edge e (from -> to).
int64_t LayoutQuadExtractor::edge_point(int e, int64_t k) const {
  if (k == 0) return tm_.edges[e].from;
  if (k == x_[e]) return tm_.edges[e].to;
  return edge_first_[e] + k - 1;
}

// The nodes' points and the points along every edge (zero where positions are not asked for).
void LayoutQuadExtractor::place_node_and_edge_points() {
  points_.resize(count_);
  for (size_t n = 0; n < tm_.nodes.size(); ++n) {
    const TMeshNode& node = tm_.nodes[n];
    points_[n].position = node.point.position(mesh_);
    points_[n].singular = node.singular();
    points_[n].pinned = node.mesh_vertex >= 0 && node.mesh_vertex < static_cast<int>(pinned_vertices_.size()) &&
                        pinned_vertices_[node.mesh_vertex];
    points_[n].point = node.point;
  }
  on_edge_.resize(ne_);
  for (int e = 0; e < ne_; ++e) {
    if (!with_positions_) {
      on_edge_[e].assign(x_[e] + 1, GridPoint{});
      continue;
    }
    place_edge_points(mesh_, tm_, e, x_[e], on_edge_[e]);
    for (int64_t k = 1; k < x_[e]; ++k) points_[edge_point(e, k)] = on_edge_[e][k];
    if (e % 256 == 0) progress_.check_cancel();
  }
}

// Cell c's side point lists and lengths; throws where the cell is no rectangle of the grid.
CellGrid LayoutQuadExtractor::cell_sides(int c) {
  if (!tm_.cells[c].four_sided)
    throw Error(ErrorCode::InvalidArgument, "layout quads: T-mesh cell " + std::to_string(c) + " is not four-sided");
  const std::array<OrientedSide, 4> sides = orient_cell(tm_, c);
  CellGrid g;
  for (int s = 0; s < 4; ++s) {
    for (size_t i = 0; i < sides[s].edges.size(); ++i) {
      const int e = sides[s].edges[i];
      const bool forward = sides[s].forward[i];
      for (int64_t k = (i == 0 ? 0 : 1); k <= x_[e]; ++k) {
        const int64_t kk = forward ? k : x_[e] - k;
        const GridPoint& p = on_edge_[e][kk];
        const double fraction = x_[e] > 0 ? static_cast<double>(k) / static_cast<double>(x_[e]) : 0.0;
        g.side[s].push_back(
            {edge_point(e, kk), &p, forward ? p.along : Vec2(-p.along), g.length[s] + fraction * tm_.edges[e].length});
      }
      g.length[s] += tm_.edges[e].length;
    }
    if (g.side[s].empty())
      throw Error(ErrorCode::InvalidArgument, "layout quads: cell " + std::to_string(c) + " has an empty side");
  }
  g.w = static_cast<int64_t>(g.side[0].size()) - 1, g.h = static_cast<int64_t>(g.side[1].size()) - 1;
  if (static_cast<int64_t>(g.side[2].size()) - 1 != g.w || static_cast<int64_t>(g.side[3].size()) - 1 != g.h)
    throw Error(ErrorCode::InvalidArgument, "layout quads: opposite sides of cell " + std::to_string(c) +
                                                " have different integer lengths (Ax != 0)");
  for (int s = 0; s < 4; ++s)
    if (uf_.find(g.side[s].back().id) != uf_.find(g.side[(s + 1) % 4].front().id))
      throw Error(ErrorCode::InvalidArgument, "layout quads: the sides of cell " + std::to_string(c) + " do not meet");
  return g;
}

// Cell c as a grid of quads, or glued shut where it has zero width or height.
void LayoutQuadExtractor::make_cell_quads(int c) {
  CellGrid g = cell_sides(c);
  const int64_t w = g.w, h = g.h;
  if (w == 0 || h == 0) {
    glue_collapsed_cell(g);
    return;
  }
  result_.stats.quads += w * h;
  if (result_.stats.quads > kMaxQuads)
    throw Error(ErrorCode::InvalidArgument, "layout quads: more than " + std::to_string(kMaxQuads) + " quads");
  g.inner_first = static_cast<int64_t>(points_.size());
  points_.resize(points_.size() + (w - 1) * (h - 1));
  uf_.grow(static_cast<int64_t>(points_.size()));
  if (with_positions_) place_inner_points(g);
  for (int64_t j = 0; j < h; ++j)
    for (int64_t i = 0; i < w; ++i) {
      quads_.push_back({g.id(i, j), g.id(i + 1, j), g.id(i + 1, j + 1), g.id(i, j + 1)});
      result_.quad_cell.push_back(c);
    }
  if (c % 64 == 0) progress_.check_cancel();
}

// A cell of zero width or height: its opposite sides' points identified.
void LayoutQuadExtractor::glue_collapsed_cell(const CellGrid& g) {
  const int64_t w = g.w, h = g.h;
  ++result_.stats.collapsed_cells;
  if (w == 0)  // glue (w, j) to (0, j)
    for (int64_t j = 0; j <= h; ++j) uf_.unite(g.side[1][j].id, g.side[3][h - j].id);
  if (h == 0)  // glue (i, 0) to (i, h)
    for (int64_t i = 0; i <= w; ++i) uf_.unite(g.side[0][i].id, g.side[2][w - i].id);
}

// The inner points of a cell, walked to in the map (or by the Coons patch of its sides).
void LayoutQuadExtractor::place_inner_points(const CellGrid& g) {
  const int64_t w = g.w, h = g.h;
  const auto& side = g.side;
  const auto& length = g.length;
  // Inner points: the cell is the rectangle [0, W] x [0, H] of the map. Sides in normalized
  // parametric position: bottom b(i), top t(i) (from the left), left l(j), right r(j) (from the
  // bottom). (i, j) -> v = ((1 - s) l(j) + s r(j)) H with s = i / w, u = (b(i) + (t(i) - b(i)) v / H) W:
  // monotone in j for each column and in i for each height, so grid lines never cross. The point
  // is found by walking there from the bottom point (i, 0).
  const double W = 0.5 * (length[0] + length[2]), H = 0.5 * (length[1] + length[3]);
  auto normalized = [](double d, double total) { return total > 0 ? d / total : 0.0; };
  auto pos = [&](int64_t i, int64_t j) { return points_[g.boundary(i, j).id].position; };
  for (int64_t j = 1; j < h; ++j)
    for (int64_t i = 1; i < w; ++i) {
      const double s = static_cast<double>(i) / w, t = static_cast<double>(j) / h;
      GridPoint& p = points_[g.id(i, j)];
      const SidePoint& bottom = side[0][i];
      const double bi = normalized(bottom.distance, length[0]);
      const double ti = 1 - normalized(side[2][w - i].distance, length[2]);
      const double lj = 1 - normalized(side[3][h - j].distance, length[3]);
      const double rj = normalized(side[1][j].distance, length[1]);
      const double v = ((1 - s) * lj + s * rj) * H;
      const double du = (ti - bi) * W * (H > 0 ? v / H : 0.0);
      const Vec2 up(-bottom.along.y(), bottom.along.x());
      SurfacePoint found;
      if (bottom.at->point.face >= 0 && bottom.along != Vec2::Zero() &&
          walk(mesh_, seamless_, bottom.at->point, v * up + du * bottom.along, found)) {
        p.point = found;
        p.position = found.position(mesh_);
        continue;
      }
      // No usable start: the Coons patch of the sides, projected onto the surface later.
      ++result_.stats.walk_failures;
      p.position =
          (1 - t) * pos(i, 0) + t * pos(i, h) + (1 - s) * pos(0, j) + s * pos(w, j) -
          ((1 - s) * (1 - t) * pos(0, 0) + s * (1 - t) * pos(w, 0) + (1 - s) * t * pos(0, h) + s * t * pos(w, h));
    }
}

// Merge identified points (singular if any member is): at a pinned member if there is one (the
// first), else at the average of their positions.
void LayoutQuadExtractor::merge_points() {
  const int64_t total = static_cast<int64_t>(points_.size());
  vertex_of_.assign(total, -1);
  std::vector<int> members;
  for (int64_t p = 0; p < total; ++p) {
    const int64_t r = uf_.find(p);
    if (vertex_of_[r] < 0) {
      vertex_of_[r] = static_cast<int>(merged_.size());
      merged_.push_back(points_[p]);
      merged_.back().position = Vec3::Zero();
      merged_.back().singular = false;
      merged_.back().pinned = false;
      members.push_back(0);
    }
    const int v = vertex_of_[p] = vertex_of_[r];
    GridPoint& m = merged_[v];
    m.singular = m.singular || points_[p].singular;
    ++members[v];
    if (m.pinned) continue;
    m.position += points_[p].position;
    if (!points_[p].pinned) continue;
    m.pinned = true;
    m.position = points_[p].position;
    m.point = points_[p].point;
  }
  result_.stats.merged_points = static_cast<int>(total - static_cast<int64_t>(merged_.size()));
  for (size_t v = 0; v < merged_.size(); ++v) {
    if (merged_[v].pinned) continue;
    merged_[v].position /= members[v];
    if (members[v] > 1) merged_[v].point.face = -1;  // an average: project it
  }
}

// The quad mesh of the merged points the quads use.
void LayoutQuadExtractor::build_quad_mesh() {
  // Unused points (e.g. the nodes of a component without cells) are dropped.
  std::vector<int> used(merged_.size(), -1);
  int nv = 0;
  for (const auto& q : quads_)
    for (int64_t p : q)
      if (used[vertex_of_[p]] < 0) used[vertex_of_[p]] = nv++;
  QuadMesh& out = result_.quads;
  out.V.resize(nv, 3);
  out.Q.resize(static_cast<int>(quads_.size()), 4);
  out.vertex_face.assign(nv, -1);
  out.vertex_singular.assign(nv, 0);
  for (size_t v = 0; v < merged_.size(); ++v) {
    if (used[v] < 0) continue;
    out.V.row(used[v]) = merged_[v].position.transpose();
    out.vertex_face[used[v]] = merged_[v].point.face;
    out.vertex_singular[used[v]] = merged_[v].singular;
  }
  for (size_t q = 0; q < quads_.size(); ++q)
    for (int k = 0; k < 4; ++k) out.Q(static_cast<int>(q), k) = used[vertex_of_[quads_[q][k]]];
}

// Points placed by the Coons fallback or averaged by a collapse: onto the surface.
void LayoutQuadExtractor::project_onto_surface() {
  if (!with_positions_) return;
  QuadMesh& out = result_.quads;
  const TriangleBvh bvh(mesh_);
  for (int v = 0; v < out.V.rows(); ++v) {
    if (out.vertex_face[v] >= 0) continue;
    const TriangleBvh::Hit hit = bvh.closest_point(out.V.row(v).transpose());
    if (hit.triangle < 0) continue;
    out.V.row(v) = hit.point.transpose();
    out.vertex_face[v] = hit.triangle;
  }
}

}  // namespace

LayoutQuads extract_layout_quads(const TriMesh& mesh, const ExactParametrization& seamless, const TMesh& tm,
                                 const std::vector<int64_t>& x, Progress& progress, bool with_positions,
                                 const std::vector<char>& pinned_vertices) {
  Timer timer;
  if (static_cast<int>(x.size()) != static_cast<int>(tm.edges.size()))
    throw Error(ErrorCode::InvalidArgument, "layout quads: x must have one length per T-edge");
  LayoutQuads result = LayoutQuadExtractor(mesh, seamless, tm, x, progress, with_positions, pinned_vertices).run();
  result.stats.seconds = timer.seconds();
  return result;
}

}  // namespace qgp

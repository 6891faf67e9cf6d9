#include "igm/integer_grid_map.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "core/error.h"
#include "core/sanitize_isolines.h"
#include "core/timer.h"
#include "igm/untangle_map.h"
#include "quantization/round_quantization.h"
#include "seamless_map/parametrization_problem.h"

namespace qgp {
namespace {

// A point of the plane as a linear expression over corner coordinates plus a constant.
struct PointExpr {
  std::array<std::vector<CornerTerm>, 2> terms;  // u, v
  std::array<double, 2> constant{0, 0};
};

PointExpr surface_point_expr(const SurfacePoint& p) {
  PointExpr e;
  for (int k = 0; k < 3; ++k) {
    const double b = p.barycentric[k];
    if (b == 0) continue;
    for (int a = 0; a < 2; ++a) e.terms[a].push_back({3 * p.face + k, a, b});
  }
  return e;
}

// Rotation by r quarter turns: (u,v) -> (-v,u) per turn.
void rotate(PointExpr& e, int r) {
  for (int i = 0; i < ((r % 4) + 4) % 4; ++i) {
    std::swap(e.terms[0], e.terms[1]);
    std::swap(e.constant[0], e.constant[1]);
    for (CornerTerm& t : e.terms[0]) t.coeff = -t.coeff;
    e.constant[0] = -e.constant[0];
  }
}

// Maps a point expression of face(h)'s chart to the opposite face's chart with the new map's
// transition: p_g = R^r p_f + t_h, t_h = c_g(w) - R^r c_f(w) for the shared vertex w = from(h).
void transfer(const TriMesh& mesh, const std::vector<int8_t>& rotation, int h, PointExpr& e) {
  const int o = mesh.opposite[h];
  const int r = rotation[h];
  rotate(e, r);
  PointExpr cf;
  for (int a = 0; a < 2; ++a) cf.terms[a].push_back({h, a, 1.0});  // corner h is from(h) in face(h)
  rotate(cf, r);
  const int cg = 3 * (o / 3) + (o % 3 + 1) % 3;  // corner of to(o) = from(h) in face(o)
  for (int a = 0; a < 2; ++a) {
    e.terms[a].push_back({cg, a, 1.0});
    for (CornerTerm t : cf.terms[a]) {
      t.coeff = -t.coeff;
      e.terms[a].push_back(t);
    }
  }
}

// Halfedge of face f whose opposite lies in face g, preferring one whose edge holds the point.
int shared_halfedge(const TriMesh& mesh, int f, int g, const Vec3& barycentric) {
  int found = -1;
  for (int k = 0; k < 3; ++k) {
    const int h = 3 * f + k;
    const int o = mesh.opposite[h];
    if (o < 0 || o / 3 != g) continue;
    if (barycentric[(k + 2) % 3] == 0) return h;  // the point lies on this edge
    if (found < 0) found = h;
  }
  return found;
}

// Halfedges crossed to carry point p (in face p.face) into face g: the shared edge, or for a point
// on a mesh vertex the walk around the vertex (either way round; the vertex is regular where a
// trace passes through it). Empty if none is found.
std::vector<int> crossed_halfedges(const TriMesh& mesh, const SurfacePoint& p, int g) {
  const int f = p.face;
  const int h = shared_halfedge(mesh, f, g, p.barycentric);
  if (h >= 0) return {h};
  int k = -1;
  for (int i = 0; i < 3; ++i)
    if (p.barycentric[i] == 1) k = i;
  if (k < 0) return {};
  const int v = mesh.F(f, k);
  for (int dir = 0; dir < 2; ++dir) {
    std::vector<int> path;
    int cur = f, came = -1;
    for (int step = 0; step < 1024; ++step) {
      if (cur == g) return path;
      int i = 0;
      while (mesh.F(cur, i) != v) ++i;
      const int h1 = 3 * cur + i, h2 = 3 * cur + (i + 2) % 3;  // from v / to v
      const int next = came < 0 ? (dir == 0 ? h1 : h2) : (came == h1 ? h2 : h1);
      if (mesh.opposite[next] < 0) break;
      path.push_back(next);
      came = mesh.opposite[next];
      cur = came / 3;
      if (cur == f) break;
    }
  }
  return {};
}

// Exact affine transfer of a double point across halfedge h with the sanitized map's transition.
Vec2 transfer_point(const ExactParametrization& ex, int h, const Vec2& p) {
  const Vec2 r = rotate_quarter(p, ex.rotation[h]);
  return r + Vec2(ex.to_double(ex.translation[h][0]), ex.to_double(ex.translation[h][1]));
}

std::vector<CornerTerm> merge_terms(std::vector<CornerTerm> terms) {
  std::sort(terms.begin(), terms.end(), [](const CornerTerm& a, const CornerTerm& b) {
    return a.corner != b.corner ? a.corner < b.corner : a.axis < b.axis;
  });
  std::vector<CornerTerm> out;
  for (const CornerTerm& t : terms) {
    if (!out.empty() && out.back().corner == t.corner && out.back().axis == t.axis)
      out.back().coeff += t.coeff;
    else
      out.push_back(t);
  }
  out.erase(std::remove_if(out.begin(), out.end(), [](const CornerTerm& t) { return t.coeff == 0; }), out.end());
  return out;
}

// Unit direction of a T-edge (from -> to) in the chart of its trace's last face: read off the
// sanitized map where the edge has a length, else its axis in the first chart carried along.
Vec2 edge_direction(const TriMesh& mesh, const ExactParametrization& ex, const TMeshEdge& edge) {
  Vec2 moved = edge.trace.front().uv;
  int rotation = 0;
  for (size_t i = 1; i < edge.trace.size(); ++i) {
    if (edge.trace[i - 1].face == edge.trace[i].face) continue;
    const std::vector<int> crossed = crossed_halfedges(mesh, edge.trace[i - 1], edge.trace[i].face);
    if (crossed.empty())
      throw Error(ErrorCode::InvalidArgument, "integer-grid map: T-edge trace jumps between faces that do not touch");
    for (int h : crossed) {
      moved = transfer_point(ex, h, moved);
      rotation += ex.rotation[h];
    }
  }
  const Vec2 d = edge.trace.back().uv - moved;
  Vec2 dir = Vec2::Zero();
  if (d.norm() > 0) {
    const int a = std::abs(d.x()) >= std::abs(d.y()) ? 0 : 1;
    dir[a] = d[a] > 0 ? 1 : -1;
  } else {
    dir[edge.axis] = 1;
    dir = rotate_quarter(dir, rotation);
  }
  return dir;
}

// Walks a path of T-edges carrying the start node's position (as an expression of the new map)
// and the required offset (numeric) through the charts: at the end,  p_end = moved + offset.
class PathWalker {
 public:
  PathWalker(const TriMesh& mesh, const std::vector<int8_t>& rotation, const TMesh& tmesh,
             const std::vector<Vec2>& direction, const std::vector<double>& lengths)
      : mesh_(mesh), rotation_(rotation), tmesh_(tmesh), direction_(direction), lengths_(lengths) {}

  // Starts at the end of edge e that it would leave through (forward: from, backward: to).
  void start(int e, bool forward) {
    const TMeshEdge& edge = tmesh_.edges[e];
    at_ = forward ? edge.trace.front() : edge.trace.back();
    moved_ = surface_point_expr(at_);
    offset_ = Vec2::Zero();
  }
  // Traverses edge e (forward: from -> to). The walker must stand on the edge's start node.
  void traverse(int e, bool forward) {
    const TMeshEdge& edge = tmesh_.edges[e];
    const int n = static_cast<int>(edge.trace.size());
    if (forward) {
      enter(edge.trace.front());
      for (int i = 1; i < n; ++i) step(edge.trace[i - 1], edge.trace[i]);
      at_ = edge.trace.back();
      offset_ += lengths_[e] * direction_[e];
    } else {
      enter(edge.trace.back());
      offset_ -= lengths_[e] * direction_[e];
      for (int i = n - 2; i >= 0; --i) step(edge.trace[i + 1], edge.trace[i]);
      at_ = edge.trace.front();
    }
  }
  // Rows  p_end - moved = offset  (both axes) for the node the walker stands on.
  std::array<IgmRow, 2> rows() const {
    const PointExpr end = surface_point_expr(at_);
    std::array<IgmRow, 2> out;
    for (int a = 0; a < 2; ++a) {
      std::vector<CornerTerm> t = end.terms[a];
      for (CornerTerm m : moved_.terms[a]) {
        m.coeff = -m.coeff;
        t.push_back(m);
      }
      out[a].terms = merge_terms(std::move(t));
      out[a].rhs = offset_[a] + moved_.constant[a] - end.constant[a];
    }
    return out;
  }

 private:
  void cross(int h) {
    transfer(mesh_, rotation_, h, moved_);
    offset_ = rotate_quarter(offset_, rotation_[h]);
  }
  // Same surface point: from a (in a.face) into b.face.
  void step(const SurfacePoint& a, const SurfacePoint& b) {
    if (a.face == b.face) return;
    const std::vector<int> crossed = crossed_halfedges(mesh_, a, b.face);
    if (crossed.empty())
      throw Error(ErrorCode::InvalidArgument, "integer-grid map: T-edge trace jumps between faces that do not touch");
    for (int h : crossed) cross(h);
  }
  // Moves from the current face into p.face at the node (p given in its own face).
  void enter(const SurfacePoint& p) {
    if (p.face == at_.face) return;
    const std::vector<int> back = crossed_halfedges(mesh_, p, at_.face);
    if (back.empty())
      throw Error(ErrorCode::InvalidArgument, "integer-grid map: consecutive T-edges do not meet at a common node");
    for (auto it = back.rbegin(); it != back.rend(); ++it) cross(mesh_.opposite[*it]);
  }

  const TriMesh& mesh_;
  const std::vector<int8_t>& rotation_;
  const TMesh& tmesh_;
  const std::vector<Vec2>& direction_;
  const std::vector<double>& lengths_;
  SurfacePoint at_;
  PointExpr moved_;
  Vec2 offset_ = Vec2::Zero();
};

// Paper §7: paths in T between nodes whose position matters (singularities, feature/boundary
// corners, seeds), over a BFS spanning tree; every edge outside the tree closes a loop. A path
// never passes through a vertex with holonomy (the chart change there would be ambiguous): such
// nodes end paths and start new ones. Returns the rows over the new map's corners.
std::vector<IgmRow> path_rows(const TriMesh& mesh, const ExactParametrization& ex, const TMesh& tmesh,
                              const std::vector<double>& lengths, int root, Progress& progress) {
  const int nn = static_cast<int>(tmesh.nodes.size()), ne = static_cast<int>(tmesh.edges.size());
  std::vector<int> holonomy(mesh.num_vertices(), 0);
  for (int h = 0; h < mesh.num_halfedges(); ++h)
    if (mesh.opposite[h] >= 0) holonomy[mesh.to(h)] += ex.rotation[h];
  std::vector<char> terminal(nn, 0), important(nn, 0);
  for (int n = 0; n < nn; ++n) {
    const TMeshNode& node = tmesh.nodes[n];
    const int v = node.mesh_vertex;
    terminal[n] = n == root || (v >= 0 && holonomy[v] % 4 != 0 && !is_boundary_vertex(mesh, v));
    important[n] = terminal[n] || node.singular() || node.kind == TMeshNode::Kind::FeatureCorner ||
                   node.kind == TMeshNode::Kind::BoundaryNode || node.kind == TMeshNode::Kind::Seed;
  }
  std::vector<Vec2> direction(ne);
  for (int e = 0; e < ne; ++e) {
    if (tmesh.edges[e].trace.empty())
      throw Error(ErrorCode::InvalidArgument, "integer-grid map: T-edge without a trace");
    direction[e] = edge_direction(mesh, ex, tmesh.edges[e]);
  }
  // BFS tree: parent edge of each node.
  std::vector<std::vector<int>> incident(nn);
  for (int e = 0; e < ne; ++e) {
    incident[tmesh.edges[e].from].push_back(e);
    incident[tmesh.edges[e].to].push_back(e);
  }
  std::vector<int> parent(nn, -1), order;
  std::vector<char> reached(nn, 0), tree_edge(ne, 0);
  reached[root] = 1;
  order.push_back(root);
  for (size_t i = 0; i < order.size(); ++i) {
    const int n = order[i];
    for (int e : incident[n]) {
      const int m = tmesh.edges[e].from == n ? tmesh.edges[e].to : tmesh.edges[e].from;
      if (reached[m]) continue;
      reached[m] = 1;
      parent[m] = e;
      tree_edge[e] = 1;
      order.push_back(m);
    }
  }
  for (int n = 0; n < nn; ++n)
    if (!reached[n]) throw Error(ErrorCode::StageFailed, "integer-grid map: the T-mesh is not connected");
  auto other = [&](int e, int n) { return tmesh.edges[e].from == n ? tmesh.edges[e].to : tmesh.edges[e].from; };
  // Tree path from the nearest terminal ancestor down to n: (edge, forward) pairs.
  auto tree_path = [&](int n) {
    std::vector<std::pair<int, bool>> path;
    while (!terminal[n]) {
      const int e = parent[n];
      path.push_back({e, tmesh.edges[e].to == n});
      n = other(e, n);
    }
    std::reverse(path.begin(), path.end());
    return path;
  };
  PathWalker walker(mesh, ex.rotation, tmesh, direction, lengths);
  std::vector<IgmRow> rows;
  auto emit = [&](const std::vector<std::pair<int, bool>>& path, int id) {
    if (path.empty()) return;
    walker.start(path[0].first, path[0].second);
    for (const auto& [e, forward] : path) walker.traverse(e, forward);
    for (IgmRow& r : walker.rows()) {
      r.edge = id;
      rows.push_back(std::move(r));
    }
  };
  for (int n = 0; n < nn; ++n) {
    if (n == root || !important[n]) continue;
    // From the terminal ancestor down to n (a terminal n is reached through its parent edge).
    std::vector<std::pair<int, bool>> path;
    if (terminal[n]) {
      const int e = parent[n];
      path = tree_path(other(e, n));
      path.push_back({e, tmesh.edges[e].to == n});
    } else {
      path = tree_path(n);
    }
    emit(path, parent[n]);
    if (n % 64 == 0) progress.check_cancel();
  }
  for (int e = 0; e < ne; ++e) {
    if (tree_edge[e]) continue;
    // Loop: terminal ancestor of `from` -> from -> e -> to -> back up to to's terminal ancestor.
    std::vector<std::pair<int, bool>> path = tree_path(tmesh.edges[e].from);
    path.push_back({e, true});
    std::vector<std::pair<int, bool>> back = tree_path(tmesh.edges[e].to);
    for (auto it = back.rbegin(); it != back.rend(); ++it) path.push_back({it->first, !it->second});
    emit(path, e);
    if (e % 64 == 0) progress.check_cancel();
  }
  return rows;
}

double distance_to_integer(double v) { return std::abs(v - std::round(v)); }

// Exact signed doubled area of face f.
__int128 doubled_area(const ExactParametrization& p, int f) {
  const IVec2 a = p.uv[3 * f], b = p.uv[3 * f + 1], c = p.uv[3 * f + 2];
  return static_cast<__int128>(b[0] - a[0]) * (c[1] - a[1]) - static_cast<__int128>(b[1] - a[1]) * (c[0] - a[0]);
}

}  // namespace

std::vector<IgmRow> integer_grid_rows(const TriMesh& mesh, const ExactParametrization& sanitized, const TMesh& tmesh,
                                      const std::vector<double>& lengths, int root) {
  if (lengths.size() != tmesh.edges.size() || root < 0 || root >= static_cast<int>(tmesh.nodes.size()))
    throw Error(ErrorCode::InvalidArgument, "integer-grid map: one length per T-edge and a valid root expected");
  Progress progress;
  return path_rows(mesh, sanitized, tmesh, lengths, root, progress);
}

void count_exact_irregular(const ExactParametrization& param, int* flipped, int* degenerate) {
  *flipped = *degenerate = 0;
  const int nf = static_cast<int>(param.uv.size() / 3);
  for (int f = 0; f < nf; ++f) {
    const int s = orient2d_exact(param.uv[3 * f], param.uv[3 * f + 1], param.uv[3 * f + 2]);
    *flipped += s < 0;
    *degenerate += s == 0;
  }
}

int count_exact_winding_defects(const TriMesh& mesh, const ExactParametrization& param,
                                const std::vector<int>& cone_turns) {
  const std::vector<int> turns = exact_angle_sums(mesh, param);
  int defects = 0;
  for (int v = 0; v < mesh.num_vertices(); ++v) defects += turns[v] != cone_turns[v];
  return defects;
}

int64_t exact_parametric_area(const ExactParametrization& param, bool* integral) {
  __int128 sum = 0;
  const int nf = static_cast<int>(param.uv.size() / 3);
  for (int f = 0; f < nf; ++f) sum += doubled_area(param, f);
  const __int128 unit = static_cast<__int128>(param.one()) * param.one() * 2;
  if (integral) *integral = sum % unit == 0;
  return static_cast<int64_t>(sum / unit);
}

namespace {

// Refuses inputs that do not belong together (Error(InvalidArgument) naming what is wrong).
bool check_inputs(const TriMesh& mesh, const CrossField& field, const CutGraph& cut, const SeamlessMap& seamless,
                  const ExactParametrization& sanitized, const TMesh& tmesh, const QuantizationResult& quantization,
                  const IgmOptions& options) {
  const int nf = mesh.num_faces(), nc = 3 * nf, ne = mesh.num_edges();
  if (seamless.param.uv.rows() != nc || static_cast<int>(sanitized.uv.size()) != nc ||
      static_cast<int>(sanitized.rotation.size()) != nc || static_cast<int>(cut.rotation.size()) != nc ||
      static_cast<int>(cut.frame_u.size()) != nf || static_cast<int>(field.feature_edge.size()) != ne)
    throw Error(ErrorCode::InvalidArgument, "integer-grid map: the maps, field or cut graph do not match the mesh");
  if (quantization.x.size() != tmesh.edges.size())
    throw Error(ErrorCode::InvalidArgument, "integer-grid map: the quantization does not match the T-mesh (" +
                                                std::to_string(quantization.x.size()) + " lengths, " +
                                                std::to_string(tmesh.edges.size()) + " edges)");
  if (!quantization.valid)
    throw Error(ErrorCode::InvalidArgument,
                "integer-grid map: the quantization is invalid: " + quantization.invalid_reason);
  if (!(quantization.scale > 0) || !(options.edge_length > 0))
    throw Error(ErrorCode::InvalidArgument, "integer-grid map: scale and edge length must be positive");
  if (tmesh.nodes.empty()) throw Error(ErrorCode::InvalidArgument, "integer-grid map: empty T-mesh");
  const int num_nodes = static_cast<int>(tmesh.nodes.size());
  for (const TMeshNode& n : tmesh.nodes)
    if (n.point.face < 0 || n.point.face >= nf || n.mesh_vertex >= mesh.num_vertices())
      throw Error(ErrorCode::InvalidArgument, "integer-grid map: a T-mesh node lies outside the mesh");
  for (size_t e = 0; e < tmesh.edges.size(); ++e) {
    const TMeshEdge& edge = tmesh.edges[e];
    bool ok = edge.from >= 0 && edge.from < num_nodes && edge.to >= 0 && edge.to < num_nodes && !edge.trace.empty() &&
              quantization.x[e] >= 0;
    for (const SurfacePoint& p : edge.trace) ok = ok && p.face >= 0 && p.face < nf;
    if (!ok) throw Error(ErrorCode::InvalidArgument, "integer-grid map: malformed T-edge " + std::to_string(e));
  }
  if (static_cast<int>(seamless.param.is_cut.size()) != ne)
    throw Error(ErrorCode::InvalidArgument, "integer-grid map: the seamless map's cut flags do not match the mesh");
  for (int h = 0; h < nc; ++h)
    if (sanitized.rotation[h] != seamless.param.rotation[h])
      throw Error(ErrorCode::InvalidArgument,
                  "integer-grid map: the sanitized and the seamless map have different transitions");
  return true;
}

// The node whose position is fixed (at its rounded position): the first singular node on a mesh
// vertex, else the first node.
int root_node(const TMesh& tmesh) {
  for (size_t n = 0; n < tmesh.nodes.size(); ++n)
    if (tmesh.nodes[n].singular() && tmesh.nodes[n].mesh_vertex >= 0) return static_cast<int>(n);
  return 0;
}

}  // namespace

const char* igm_attempt_name(IgmAttempt attempt) {
  switch (attempt) {
    case IgmAttempt::Default: return "default";
    case IgmAttempt::RelinearizedPenalty: return "relinearized penalty";
    case IgmAttempt::AllFaces: return "all faces";
  }
  return "?";
}

IntegerGridMapSolver::IntegerGridMapSolver(const TriMesh& mesh, const CrossField& field, const CutGraph& cut,
                                           const SeamlessMap& seamless, const ExactParametrization& sanitized,
                                           const TMesh& tmesh, const QuantizationResult& quantization,
                                           const IgmOptions& options, Progress& progress)
    : mesh_(mesh),
      field_(field),
      tmesh_(tmesh),
      options_(options),
      progress_(progress),
      inputs_checked_(check_inputs(mesh, field, cut, seamless, sanitized, tmesh, quantization, options)),
      problem_(mesh, seamless.param.rotation, seamless.param.is_cut, cut.frame_u,
               options.edge_length / quantization.scale, seamless.face_size),
      scale_(quantization.scale),
      cones_(cone_quarter_turns(mesh, field)) {
  add_seamless_isolines(seamless, cut);
  build_path_rows(sanitized, quantization);
  problem_.set_pin_translation(false);
  seamless_pose_ = seamless.param;
  seamless_pose_.uv *= scale_;
  solve_options_.penalty_weight = options.penalty_weight;
  solve_options_.max_repair_rounds = options.max_repair_rounds;
  solve_options_.count_stagnation_rounds = options.count_stagnation_rounds;
  solve_options_.halving_rounds = options.halving_rounds;
  solve_options_.relinearization_rounds = options.relinearization_rounds;
  solve_options_.skip_repair_if_forced = options.skip_repair_if_forced;
}

IntegerGridMapSolver::~IntegerGridMapSolver() = default;

void IntegerGridMapSolver::add_seamless_isolines(const SeamlessMap& seamless, const CutGraph& cut) {
  // The seamless map's isolines (it may have left a few more feature edges free).
  std::vector<char> left_free(mesh_.num_edges(), 0);
  for (int e : seamless.stats.dropped_isoline_edges)
    if (e >= 0 && e < mesh_.num_edges()) left_free[e] = 1;
  for (const Isoline& line : select_isolines(mesh_, field_, cut).isolines)
    if (!left_free[mesh_.edge_of[line.halfedge]]) problem_.add_isoline(line.halfedge, line.axis);
}

void IntegerGridMapSolver::build_path_rows(const ExactParametrization& sanitized,
                                           const QuantizationResult& quantization) {
  root_ = root_node(tmesh_);
  std::vector<double> lengths(quantization.x.begin(), quantization.x.end());
  rows_ = path_rows(mesh_, sanitized, tmesh_, lengths, root_, progress_);
  for (const IgmRow& r : rows_)
    if (r.terms.empty() && std::abs(r.rhs) > 0)
      throw Error(ErrorCode::StageFailed,
                  "integer-grid map: a loop of the T-mesh without transition has a non-zero length");
}

void IntegerGridMapSolver::add_path_constraints() {
  problem_.clear_linear_constraints();
  int count = 0;
  for (const IgmRow& r : rows_)
    if (!r.terms.empty()) problem_.add_linear_constraint(r.terms, r.rhs), ++count;
  const SurfacePoint& root_point = tmesh_.nodes[root_].point;
  const PointExpr e = surface_point_expr(root_point);
  for (int a = 0; a < 2; ++a)
    problem_.add_linear_constraint(e.terms[a], std::round(scale_ * root_point.uv[a])), ++count;
  stats_.constraints = count;
}

ParametrizationSolution IntegerGridMapSolver::penalty_phase(bool with_regularity, double begin, double end) {
  add_path_constraints();
  pose_ = seamless_pose_;
  ParametrizationSolution solution;
  const int rounds = std::max(1, options_.max_penalty_rounds);
  for (int round = 0; round < rounds; ++round) {
    solve_options_.linear_constraints = ConstraintMode::Penalty;
    solve_options_.regularity = with_regularity ? RegularityMode::Repair : RegularityMode::Off;
    solve_options_.reference = &pose_;
    solve_options_.progress_begin = begin + (end - begin) * 0.7 * round / rounds;
    solve_options_.progress_end = begin + (end - begin) * 0.7 * (round + 1) / rounds;
    solution = problem_.solve(solve_options_, progress_);
    ++stats_.penalty_iterations;
    count_solves(solution);
    stats_.penalty_violation.push_back(solution.stats.constraint_violation);
    if (with_regularity) pose_ = solution.param;  // the next round is linearized around it
    // Without regularity the next round would give the same result.
    if (solution.stats.constraint_violation <= options_.penalty_tolerance || !with_regularity) break;
  }
  return solution;
}

void IntegerGridMapSolver::impose_integers(const Parametrization& integers) {
  const int nc = mesh_.num_halfedges();
  snap_vertices_ = independent_vertices(mesh_, integers, tmesh_);
  isolines_ = isoline_constraints(mesh_, integers, field_.feature_edge, true);
  problem_.clear_linear_constraints();
  std::vector<char> wedge_done(problem_.num_wedges(), 0);
  for (int c = 0; c < nc; ++c) {
    const int w = problem_.wedge_of_corner()[c];
    if (!snap_vertices_[mesh_.F(c / 3, c % 3)] || wedge_done[w]) continue;
    wedge_done[w] = 1;
    for (int a = 0; a < 2; ++a) problem_.add_linear_constraint({{c, a, 1.0}}, std::round(integers.uv(c, a)));
  }
  for (int h = 0; h < nc; ++h) {
    const int o = mesh_.opposite[h];
    if (o < 0 || o < h || !integers.is_cut[mesh_.edge_of[h]]) continue;
    PointExpr t;  // t_h = c_g(w) - R^r c_f(w), w = from(h)
    transfer(mesh_, integers.rotation, h, t);
    const Vec2 value = integers.translation(mesh_, h);
    for (int a = 0; a < 2; ++a) problem_.add_linear_constraint(merge_terms(t.terms[a]), std::round(value[a]));
  }
  for (const IsolineConstraint& c : isolines_)
    problem_.add_linear_constraint({{c.halfedge, c.axis, 1.0}}, std::round(integers.uv(c.halfedge, c.axis)));
}

ParametrizationSolution IntegerGridMapSolver::hard_solve(bool after_relinearized_penalty, double begin, double end) {
  solve_options_.linear_constraints = ConstraintMode::Hard;
  solve_options_.regularity = RegularityMode::Repair;
  solve_options_.reference = after_relinearized_penalty ? &pose_ : &seamless_pose_;
  solve_options_.progress_begin = begin;
  solve_options_.progress_end = end;
  if (options_.finish_by_untangle_up_to_share > 0)
    solve_options_.caller_finishes = [this](const Parametrization& pose) { return untangles_to_regular(pose); };
  ParametrizationSolution solution = problem_.solve(solve_options_, progress_);
  solve_options_.caller_finishes = nullptr;
  count_solves(solution);
  stats_.flipped_initial = solution.stats.flipped_initial;
  stats_.forced_degenerate = solution.stats.forced_degenerate;
  stats_.faces = mesh_.num_faces();
  stats_.repair_bad_faces = solution.stats.bad_after_round;
  stats_.repair_seconds = solution.stats.seconds_of_round;
  stats_.repair_left_to_untangle = solution.stats.finished_by_caller;
  stats_.max_constraint_violation = row_violation(solution.param);
  return solution;
}

double IntegerGridMapSolver::row_violation(const Parametrization& map) const {
  double worst = 0;
  for (const IgmRow& r : rows_) {
    double value = -r.rhs;
    for (const CornerTerm& t : r.terms) value += t.coeff * map.uv(t.corner, t.axis);
    worst = std::max(worst, std::abs(value));
  }
  return worst;
}

ParametrizationSolution IntegerGridMapSolver::solve_global(bool relinearized_penalty, double begin, double end) {
  const ParametrizationSolution penalty = penalty_phase(relinearized_penalty, begin, end);
  impose_integers(penalty.param);
  // The hard solve is linearized around the penalty optimum where it is healthy and around the
  // seamless map elsewhere.
  const Parametrization penalty_optimum = penalty.param;
  ParametrizationSolution solution = hard_solve(relinearized_penalty, begin + (end - begin) * 0.7, end);
  pose_ = penalty_optimum;
  return solution;
}

ParametrizationSolution IntegerGridMapSolver::solve_all_faces(double begin, double end) {
  Parametrization seamless_pose = seamless_pose_;
  solve_options_.regularity = RegularityMode::AllFaces;
  solve_options_.reference = &seamless_pose;
  solve_options_.progress_begin = begin;
  solve_options_.progress_end = end;
  const ParametrizationSolution all = problem_.solve(solve_options_, progress_);
  count_solves(all);
  stats_.repair_bad_faces = all.stats.bad_after_round;
  stats_.repair_seconds = all.stats.seconds_of_round;
  return all;
}

void IntegerGridMapSolver::count_solves(const ParametrizationSolution& solution) {
  stats_.ipopt_solves += solution.stats.ipopt_solves;
  stats_.qp_by_ipopt += solution.stats.qp_by_ipopt;
  stats_.ipopt_iterations += solution.stats.ipopt_iterations;
}

void IntegerGridMapSolver::set_snapping(const std::vector<char>& snap_vertices,
                                        const std::vector<IsolineConstraint>& isolines) {
  sanitize_.fraction_bits = options_.fraction_bits;
  sanitize_.snap_bits = 0;
  sanitize_.snap_vertex = snap_vertices;
  sanitize_.snap_corner_axes.assign(mesh_.num_halfedges(), 0);
  for (const IsolineConstraint& c : isolines) {
    const int f = c.halfedge / 3, k = c.halfedge % 3;
    sanitize_.snap_corner_axes[3 * f + k] |= uint8_t(1 << c.axis);
    sanitize_.snap_corner_axes[3 * f + (k + 1) % 3] |= uint8_t(1 << c.axis);
  }
}

double IntegerGridMapSolver::integer_residual(const Parametrization& map) const {
  double worst = 0;
  for (int c = 0; c < mesh_.num_halfedges(); ++c) {
    const int v = mesh_.F(c / 3, c % 3);
    for (int a = 0; a < 2; ++a)
      if (snap_vertices_[v] || ((sanitize_.snap_corner_axes[c] >> a) & 1))
        worst = std::max(worst, distance_to_integer(map.uv(c, a)));
  }
  for (int h = 0; h < mesh_.num_halfedges(); ++h) {
    if (mesh_.opposite[h] < 0 || !map.is_cut[mesh_.edge_of[h]]) continue;
    const Vec2 t = map.translation(mesh_, h);
    worst = std::max({worst, distance_to_integer(t.x()), distance_to_integer(t.y())});
  }
  return worst;
}

IntegerGridMap IntegerGridMapSolver::round_exactly(const Parametrization& solved) {
  Timer sanitize_timer;
  IntegerGridMap result;
  result.continuous = solved;
  stats_.max_integer_residual = integer_residual(solved);
  SanitizeResult exact = sanitize_with_isolines(mesh_, solved, isolines_, sanitize_);
  stats_.unresolved_equations = exact.unresolved_equations;
  result.param = std::move(exact.param);
  result.snapped_vertices = snap_vertices_;
  result.isolines = isolines_;
  count_exact_irregular(result.param, &stats_.flipped_triangles, &stats_.degenerate_triangles);
  stats_.winding_defects = count_exact_winding_defects(mesh_, result.param, cones_);
  stats_.seconds_sanitize += sanitize_timer.seconds();
  return result;
}

bool IntegerGridMapSolver::untangles_to_regular(const Parametrization& pose) {
  Timer timer;
  set_snapping(snap_vertices_, isolines_);  // as solve() sets it after this hard solve
  ExactParametrization exact = sanitize_with_isolines(mesh_, pose, isolines_, sanitize_).param;
  int flipped = 0, degenerate = 0;
  count_exact_irregular(exact, &flipped, &degenerate);
  const int bad = flipped + degenerate;
  bool regular = bad <= options_.finish_by_untangle_up_to_share * mesh_.num_faces();
  if (regular && bad > 0) {
    const MapUntangleStats u = untangle_map(mesh_, snap_vertices_, isolines_, exact, progress_);
    regular = u.flipped_after + u.degenerate_after == 0 && u.moved_vertices <= options_.finish_by_untangle_moves * bad;
  }
  regular = regular && count_exact_winding_defects(mesh_, exact, cones_) == 0;
  stats_.seconds_untangle_trials += timer.seconds();
  return regular;
}

IntegerGridMap IntegerGridMapSolver::solve(IgmAttempt attempt, double progress_begin, double progress_end) {
  Timer timer;
  IntegerGridMap result;
  if (attempt == IgmAttempt::AllFaces) {
    if (!solved_once_)
      throw Error(ErrorCode::InvalidArgument, "integer-grid map: the all-faces attempt needs a global attempt first");
    result = round_exactly(solve_all_faces(progress_begin, progress_end).param);
  } else {
    const ParametrizationSolution solution =
        solve_global(attempt == IgmAttempt::RelinearizedPenalty, progress_begin, progress_end);
    // Exact rounding: singular/corner vertices snapped to integers (translations become
    // integral), feature and boundary edges exact isolines on integer values. The first attempt's
    // snapped sets are kept by later ones (they follow from the T-mesh and the transitions).
    if (!solved_once_) set_snapping(snap_vertices_, isolines_);
    progress_.update(progress_end + 0.02);
    result = round_exactly(solution.param);
    stats_.penalty_integer_residual = integer_residual(pose_);
    solved_once_ = true;
  }
  stats_.attempt = attempt;
  stats_.seconds_solve += timer.seconds();
  stats_.parametric_area = exact_parametric_area(result.param, &stats_.area_is_integral);
  result.stats = stats_;
  return result;
}

}  // namespace qgp

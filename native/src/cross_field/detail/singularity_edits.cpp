#include "cross_field/detail/singularity_edits.h"

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <queue>
#include <tuple>

namespace qgp::cross_field_detail {
namespace {

constexpr double kQuarter = M_PI / 2;

int mod4(int x) { return ((x % 4) + 4) % 4; }

// cancel_close_pairs smooths the field this many rings of vertices around the paths.
constexpr int kPairSmoothingRings = 4;
// ...and cancels pairs at most this many edges apart: farther pairs hold real curvature (a bump
// beside a saddle), and without them the seamless map may have to fold (dragon-genus1's
// 20 000-triangle working mesh at 500 quads: pairs up to 5 edges apart cancelled, 481 -> 175
// singularities, and the map kept 2-3 flipped triangles after 13-17 repair rounds).
constexpr int kMaxPairEdges = 2;
// Pairs whose path comes within this many rings of where a seamless map with them folded are kept
// (keep_near): twice the smoothing's reach, where the cancelled quarter turn bends the field.
constexpr int kKeepPairsRings = 2 * kPairSmoothingRings;

// True for a closed surface of genus 1 (a torus: no boundary, Euler characteristic 0).
bool is_closed_torus(const TriMesh& mesh, const CrossField& field) {
  if (field.euler_characteristic != 0) return false;
  for (int h = 0; h < mesh.num_halfedges(); ++h)
    if (mesh.opposite[h] < 0) return false;
  return true;
}

// Turns the matching of halfedge h (and its opposite) by s quarter turns; eps follows
// (eps = mismatch - matching * 90deg). Index of from(h) - s, of to(h) + s.
void turn_matching(const TriMesh& mesh, int h, int s, CrossField& field, std::vector<double>& eps) {
  const int o = mesh.opposite[h];
  eps[h] -= s * kQuarter;
  eps[o] += s * kQuarter;
  field.matching[h] = static_cast<int8_t>(mod4(field.matching[h] + s));
  field.matching[o] = static_cast<int8_t>(mod4(field.matching[o] - s));
  ++field.num_turned_matchings;
}

// Halfedges of a shortest path (in edge length) from vertex `from` to vertex `to` over ordinary
// (not feature) edges, in order; empty if there is none.
std::vector<int> shortest_ordinary_path(const TriMesh& mesh, const std::vector<char>& feature_edge, int from, int to) {
  const int nv = mesh.num_vertices();
  std::vector<double> distance(nv, std::numeric_limits<double>::infinity());
  std::vector<int> reached_by(nv, -1);
  using Entry = std::pair<double, int>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> queue;
  distance[from] = 0;
  queue.push({0.0, from});
  while (!queue.empty()) {
    const auto [d, v] = queue.top();
    queue.pop();
    if (d > distance[v]) continue;
    if (v == to) break;
    for (int h : outgoing_halfedges(mesh, v)) {
      if (feature_edge[mesh.edge_of[h]]) continue;
      const int w = mesh.to(h);
      const double dw = d + mesh.edge_vector(h).norm();
      if (dw < distance[w]) distance[w] = dw, reached_by[w] = h, queue.push({dw, w});
    }
  }
  if (reached_by[to] < 0) return {};
  std::vector<int> path;
  for (int v = to; v != from; v = mesh.from(reached_by[v])) path.push_back(reached_by[v]);
  std::reverse(path.begin(), path.end());
  return path;
}

// A torus field with exactly one singularity of index +1 and one of -1 has no seamless map without
// folds: no quad mesh of the torus has exactly one vertex of valence 3 and one of valence 5
// (Jucovic and Trenkler 1973), and it is the one cone configuration without any seamless
// parametrization (Campen, Shen, Zhou and Zorin 2019). The pair is cancelled: one quarter turn
// moved along the shortest ordinary path from the +1 to the -1 vertex. Returns true when it did.
bool cancel_obstructed_pair(const TriMesh& mesh, CrossField& field, std::vector<double>& eps) {
  if (field.num_singularities != 2) return false;
  int plus = -1, minus = -1;
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    if (field.vertex_index[v] == 1) plus = v;
    if (field.vertex_index[v] == -1) minus = v;
  }
  if (plus < 0 || minus < 0) return false;
  const std::vector<int> path = shortest_ordinary_path(mesh, field.feature_edge, plus, minus);
  if (path.empty()) return false;
  for (int h : path) turn_matching(mesh, h, 1, field, eps);
  ++field.num_cancelled_pairs;
  return true;
}

// Handle loops of a closed mesh by tree-cotree (Eppstein 2003): a breadth-first spanning tree of the
// vertices, one of the faces across the other edges, and the 2g edges left over. Left-over edge i
// closes primal loop i (through the vertex tree) and dual loop i (through the face tree); primal
// loop i crosses dual loop j once when i == j and never otherwise.
struct HandleLoops {
  std::vector<int> left_over;      // a halfedge of each left-over edge
  std::vector<int> vertex_parent;  // #V: halfedge from the parent to the vertex (-1 at the root)
  std::vector<int> face_parent;    // #F: halfedge of the parent face crossing into the face (-1)
  std::vector<int> face_order;     // faces in breadth-first order (parents first)
};

HandleLoops handle_loops(const TriMesh& mesh) {
  HandleLoops loops;
  const int nv = mesh.num_vertices(), nf = mesh.num_faces();
  std::vector<char> in_tree(mesh.num_edges(), 0), seen(nv, 0);
  loops.vertex_parent.assign(nv, -1);
  std::vector<int> queue{0};
  seen[0] = 1;
  for (size_t i = 0; i < queue.size(); ++i)
    for (int h : outgoing_halfedges(mesh, queue[i]))
      if (!seen[mesh.to(h)]) {
        seen[mesh.to(h)] = 1, loops.vertex_parent[mesh.to(h)] = h, in_tree[mesh.edge_of[h]] = 1;
        queue.push_back(mesh.to(h));
      }
  std::vector<char> reached(nf, 0), crossed(mesh.num_edges(), 0);
  loops.face_parent.assign(nf, -1);
  loops.face_order = {0};
  reached[0] = 1;
  for (size_t i = 0; i < loops.face_order.size(); ++i)
    for (int k = 0; k < 3; ++k) {
      const int h = 3 * loops.face_order[i] + k, o = mesh.opposite[h];
      if (o < 0 || in_tree[mesh.edge_of[h]] || reached[o / 3]) continue;
      reached[o / 3] = 1, loops.face_parent[o / 3] = h, crossed[mesh.edge_of[h]] = 1;
      loops.face_order.push_back(o / 3);
    }
  for (int e = 0; e < mesh.num_edges(); ++e)
    if (!in_tree[e] && !crossed[e]) loops.left_over.push_back(mesh.edge_halfedge[e]);
  return loops;
}

// Quarter turns (mod 4) of the field's matchings around each dual handle loop.
std::vector<int> handle_holonomies(const TriMesh& mesh, const CrossField& field, const HandleLoops& loops) {
  std::vector<int> turns_from_root(mesh.num_faces(), 0);
  for (int f : loops.face_order)
    if (loops.face_parent[f] >= 0)
      turns_from_root[f] = turns_from_root[loops.face_parent[f] / 3] + field.matching[loops.face_parent[f]];
  std::vector<int> holonomy;
  for (int h : loops.left_over)
    holonomy.push_back(mod4(turns_from_root[h / 3] + field.matching[h] - turns_from_root[mesh.opposite[h] / 3]));
  return holonomy;
}

// A torus field without singularities whose matchings turn around a handle loop has no seamless
// map without folds either: a flat torus without cones has no rotation around any loop. Each such
// loop is untwisted by turning the matchings along the primal loop that crosses it once (vertex
// indices unchanged). Only for fields without feature edges (their matchings are fixed by their
// isoline sectors). Returns the number of loops untwisted.
int untwist_handle_loops(const TriMesh& mesh, CrossField& field, std::vector<double>& eps) {
  if (std::any_of(field.feature_edge.begin(), field.feature_edge.end(), [](char c) { return c; })) return 0;
  const HandleLoops loops = handle_loops(mesh);
  const std::vector<int> holonomy = handle_holonomies(mesh, field, loops);
  int untwisted = 0;
  for (size_t i = 0; i < loops.left_over.size(); ++i) {
    if (holonomy[i] == 0) continue;
    const int s = holonomy[i] == 3 ? 1 : -holonomy[i];
    // The closed walk: the left-over edge, up the vertex tree to the root, down to its start.
    const int h = loops.left_over[i];
    turn_matching(mesh, h, s, field, eps);
    for (int v = mesh.to(h); loops.vertex_parent[v] >= 0; v = mesh.from(loops.vertex_parent[v]))
      turn_matching(mesh, mesh.opposite[loops.vertex_parent[v]], s, field, eps);
    for (int v = mesh.from(h); loops.vertex_parent[v] >= 0; v = mesh.from(loops.vertex_parent[v]))
      turn_matching(mesh, loops.vertex_parent[v], s, field, eps);
    ++untwisted;
  }
  return untwisted;
}

// The field angles theta of the faces flagged in `moving` (#F; empty: all) moved by the least change
// that minimizes the residual rotations' energy, sum over ordinary edges of w_e eps_e^2 (w_e as in
// the power field), with the matchings kept and the constrained faces fixed (face 0 when no face is
// fixed): the smoothest field with these matchings there. eps (3#F) is updated with theta.
void smooth_with_fixed_matchings(const TriMesh& mesh, const std::vector<double>& area, const CrossField& field,
                                 const std::vector<char>& moving, std::vector<double>& theta,
                                 std::vector<double>& eps) {
  const int nf = mesh.num_faces();
  std::vector<char> free(nf, 0);
  for (int f = 0; f < nf; ++f) free[f] = !field.constrained_face[f] && (moving.empty() || moving[f]);
  if (std::all_of(free.begin(), free.end(), [](char c) { return c; })) free[0] = 0;  // nothing holds the field
  std::vector<int> unknown(nf, -1);
  int n = 0;
  for (int f = 0; f < nf; ++f)
    if (free[f]) unknown[f] = n++;
  std::vector<Eigen::Triplet<double>> triplets;
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(n);
  for (int e = 0; e < mesh.num_edges(); ++e) {
    const int h = mesh.edge_halfedge[e], o = mesh.opposite[h];
    if (o < 0 || field.feature_edge[e]) continue;
    const int f = unknown[h / 3], g = unknown[o / 3];
    const double w = 3 * mesh.edge_vector(h).squaredNorm() / (2 * (area[h / 3] + area[o / 3]));
    // eps_h(theta + delta) = eps_h + delta_f - delta_g.
    if (f >= 0) triplets.emplace_back(f, f, w), rhs[f] -= w * eps[h];
    if (g >= 0) triplets.emplace_back(g, g, w), rhs[g] += w * eps[h];
    if (f >= 0 && g >= 0) triplets.emplace_back(f, g, -w), triplets.emplace_back(g, f, -w);
  }
  Eigen::SparseMatrix<double> L(n, n);
  L.setFromTriplets(triplets.begin(), triplets.end());
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(L);
  if (solver.info() != Eigen::Success) return;  // the field keeps its angles (its matchings hold)
  const Eigen::VectorXd delta = solver.solve(rhs);
  auto moved = [&](int f) { return unknown[f] >= 0 ? delta[unknown[f]] : 0.0; };
  for (int f = 0; f < nf; ++f) theta[f] += moved(f);
  for (int e = 0; e < mesh.num_edges(); ++e) {
    const int h = mesh.edge_halfedge[e], o = mesh.opposite[h];
    if (o < 0 || field.feature_edge[e]) continue;
    eps[h] += moved(h / 3) - moved(o / 3);
    eps[o] = -eps[h];
  }
}

// Vertices with a feature or boundary edge (#V flags): their indices also count isoline sectors.
std::vector<char> vertices_on_features(const TriMesh& mesh, const std::vector<char>& feature_edge) {
  std::vector<char> on(mesh.num_vertices(), 0);
  for (int h = 0; h < mesh.num_halfedges(); ++h)
    if (mesh.opposite[h] < 0 || feature_edge[mesh.edge_of[h]]) on[mesh.from(h)] = on[mesh.to(h)] = 1;
  return on;
}

// Rings of vertices from the nearest seed (#V; int max where none is reached).
std::vector<int> rings_from(const TriMesh& mesh, const std::vector<int>& seeds) {
  std::vector<int> rings(mesh.num_vertices(), std::numeric_limits<int>::max()), queue;
  for (int v : seeds)
    if (rings[v] != 0) rings[v] = 0, queue.push_back(v);
  for (size_t i = 0; i < queue.size(); ++i)
    for (int h : outgoing_halfedges(mesh, queue[i]))
      if (rings[mesh.to(h)] == std::numeric_limits<int>::max())
        rings[mesh.to(h)] = rings[queue[i]] + 1, queue.push_back(mesh.to(h));
  return rings;
}

// Per vertex, the number of edges to the nearest vertex of a constrained face (a face next to a
// feature or boundary edge); INT_MAX when there is none.
std::vector<int> rings_to_constraints(const TriMesh& mesh, const CrossField& field) {
  std::vector<int> corners;
  for (int f = 0; f < mesh.num_faces(); ++f)
    if (field.constrained_face[f])
      for (int k = 0; k < 3; ++k) corners.push_back(mesh.F(f, k));
  return rings_from(mesh, corners);
}

// A candidate pair: a path of ordinary halfedges from a +1 to a -1 vertex.
struct PairPath {
  double length = 0;
  std::vector<int> halfedges;
};

// From vertex `plus`, per -1 vertex off features, the shortest path of at most kMaxPairEdges
// ordinary edges no longer than max_length whose every vertex is `eligible` (all such paths are
// enumerated: there are few of at most two edges).
std::vector<PairPath> paths_to_minus(const TriMesh& mesh, const CrossField& field, const std::vector<char>& eligible,
                                     int plus, double max_length) {
  std::map<int, PairPath> shortest;  // by -1 vertex
  std::vector<int> walk;
  auto extend = [&](auto&& self, int v, double length) -> void {
    if (!walk.empty() && field.vertex_index[v] == -1) {
      auto it = shortest.find(v);
      if (it == shortest.end() || length < it->second.length) shortest[v] = {length, walk};
    }
    if (static_cast<int>(walk.size()) == kMaxPairEdges) return;
    for (int h : outgoing_halfedges(mesh, v)) {
      if (mesh.opposite[h] < 0 || field.feature_edge[mesh.edge_of[h]] || !eligible[mesh.to(h)]) continue;
      if (mesh.to(h) == plus) continue;
      const double next = length + mesh.edge_vector(h).norm();
      if (next > max_length) continue;
      walk.push_back(h);
      self(self, mesh.to(h), next);
      walk.pop_back();
    }
  };
  extend(extend, plus, 0.0);
  std::vector<PairPath> paths;
  for (auto& [minus, path] : shortest) paths.push_back(std::move(path));
  return paths;
}

// Faces within `rings` rings of vertices around the given halfedges' endpoints (#F flags).
std::vector<char> faces_near(const TriMesh& mesh, const std::vector<int>& halfedges, int rings) {
  std::vector<int> ends;
  for (int h : halfedges) ends.push_back(mesh.from(h)), ends.push_back(mesh.to(h));
  const std::vector<int> depth = rings_from(mesh, ends);
  std::vector<char> near(mesh.num_faces(), 0);
  for (int f = 0; f < mesh.num_faces(); ++f)
    for (int k = 0; k < 3; ++k) near[f] |= depth[mesh.F(f, k)] <= rings;
  return near;
}

// Every candidate pair within max_length, nearest first (then by vertex ids). Only where the
// smoothing moves no constrained face: next to features the field cannot turn, and the quarter turn
// squeezed between them folds the seamless map (wingnut at 40 degrees).
std::vector<PairPath> close_pair_candidates(const TriMesh& mesh, const CrossField& field, double max_length) {
  const std::vector<int> rings = rings_to_constraints(mesh, field);
  const std::vector<char> on_feature = vertices_on_features(mesh, field.feature_edge);
  std::vector<char> eligible(mesh.num_vertices(), 0);
  for (int v = 0; v < mesh.num_vertices(); ++v) eligible[v] = !on_feature[v] && rings[v] > kPairSmoothingRings;
  std::vector<PairPath> candidates;
  for (int v = 0; v < mesh.num_vertices(); ++v)
    if (field.vertex_index[v] == 1 && eligible[v])
      for (PairPath& p : paths_to_minus(mesh, field, eligible, v, max_length)) candidates.push_back(std::move(p));
  auto key = [&](const PairPath& p) {
    return std::make_tuple(p.length, mesh.from(p.halfedges.front()), mesh.to(p.halfedges.back()));
  };
  std::sort(candidates.begin(), candidates.end(),
            [&](const PairPath& a, const PairPath& b) { return key(a) < key(b); });
  return candidates;
}

// The candidates (in their order) that pair vertices not paired before.
std::vector<const PairPath*> choose_pairs(const TriMesh& mesh, const std::vector<PairPath>& candidates) {
  std::vector<char> paired(mesh.num_vertices(), 0);
  std::vector<const PairPath*> chosen;
  for (const PairPath& p : candidates) {
    const int plus = mesh.from(p.halfedges.front()), minus = mesh.to(p.halfedges.back());
    if (paired[plus] || paired[minus]) continue;
    paired[plus] = paired[minus] = 1;
    chosen.push_back(&p);
  }
  return chosen;
}

// Drops the candidates with a vertex within kKeepPairsRings rings of `keep_near`; returns how many
// of the pairs chosen from all candidates that drops.
int drop_pairs_near(const TriMesh& mesh, const std::vector<int>& keep_near, std::vector<PairPath>& candidates) {
  const std::vector<int> rings = rings_from(mesh, keep_near);
  auto near = [&](const PairPath* p) {
    return std::any_of(p->halfedges.begin(), p->halfedges.end(), [&](int h) {
      return rings[mesh.from(h)] <= kKeepPairsRings || rings[mesh.to(h)] <= kKeepPairsRings;
    });
  };
  const std::vector<const PairPath*> chosen = choose_pairs(mesh, candidates);
  const int kept = static_cast<int>(std::count_if(chosen.begin(), chosen.end(), near));
  candidates.erase(std::remove_if(candidates.begin(), candidates.end(), [&](const PairPath& p) { return near(&p); }),
                   candidates.end());
  return kept;
}

}  // namespace

int cancel_close_pairs(const TriMesh& mesh, const std::vector<double>& area, double max_length,
                       const std::vector<int>& keep_near, std::vector<double>& theta, std::vector<double>& eps,
                       CrossField& field) {
  if (!(max_length > 0)) return 0;
  std::vector<PairPath> candidates = close_pair_candidates(mesh, field, max_length);
  if (!keep_near.empty()) field.num_pairs_kept_near_folds = drop_pairs_near(mesh, keep_near, candidates);
  std::vector<int> moved_halfedges;
  const std::vector<const PairPath*> chosen = choose_pairs(mesh, candidates);
  for (const PairPath* p : chosen)
    for (int h : p->halfedges) turn_matching(mesh, h, 1, field, eps), moved_halfedges.push_back(h);
  if (chosen.empty()) return 0;
  smooth_with_fixed_matchings(mesh, area, field, faces_near(mesh, moved_halfedges, kPairSmoothingRings), theta, eps);
  return static_cast<int>(chosen.size());
}

bool make_torus_field_admissible(const TriMesh& mesh, const std::vector<double>& area, std::vector<double>& theta,
                                 std::vector<double>& eps, CrossField& field) {
  if (!is_closed_torus(mesh, field)) return false;
  const bool cancelled = cancel_obstructed_pair(mesh, field, eps);
  if (cancelled || field.num_singularities == 0) field.num_untwisted_loops = untwist_handle_loops(mesh, field, eps);
  if (!cancelled && field.num_untwisted_loops == 0) return false;
  smooth_with_fixed_matchings(mesh, area, field, {}, theta, eps);
  return true;
}

}  // namespace qgp::cross_field_detail

#include "cut_graph/cut_graph.h"

#include <algorithm>
#include <limits>
#include <numeric>
#include <queue>
#include <string>

#include "core/error.h"
#include "core/union_find.h"

namespace qgp {
namespace {

int mod4(int x) { return ((x % 4) + 4) % 4; }

// Vertex -> incident interior edges (compressed rows).
struct InteriorAdjacency {
  std::vector<int> offset;  // #V+1
  std::vector<int> edge;    // 2 #interior edges
  InteriorAdjacency(const TriMesh& mesh) : offset(mesh.num_vertices() + 1, 0) {
    for (int e = 0; e < mesh.num_edges(); ++e) {
      const int h = mesh.edge_halfedge[e];
      if (mesh.opposite[h] < 0) continue;
      ++offset[mesh.from(h) + 1], ++offset[mesh.to(h) + 1];
    }
    std::partial_sum(offset.begin(), offset.end(), offset.begin());
    edge.resize(offset.back());
    std::vector<int> fill(offset.begin(), offset.end() - 1);
    for (int e = 0; e < mesh.num_edges(); ++e) {
      const int h = mesh.edge_halfedge[e];
      if (mesh.opposite[h] < 0) continue;
      edge[fill[mesh.from(h)]++] = e;
      edge[fill[mesh.to(h)]++] = e;
    }
  }
};

int other_end(const TriMesh& mesh, int e, int v) {
  const int h = mesh.edge_halfedge[e];
  return mesh.from(h) == v ? mesh.to(h) : mesh.from(h);
}

double edge_length(const TriMesh& mesh, int e) { return mesh.edge_vector(mesh.edge_halfedge[e]).norm(); }

void check_field(const TriMesh& mesh, const CrossField& field) {
  const size_t nf = mesh.num_faces(), nh = mesh.num_halfedges(), nv = mesh.num_vertices();
  if (field.direction.size() != nf || field.matching.size() != nh || field.vertex_index.size() != nv ||
      field.edge_sector.size() != nh)
    throw Error(ErrorCode::InvalidArgument, "cut graph: the cross field does not belong to this mesh");
}

// Multi-source shortest-path forest of the primal tree T: distance to, region of (terminal id) and
// parent edge towards the nearest terminal of every vertex.
struct PrimalForest {
  std::vector<double> dist;
  std::vector<int> region, parent_edge;
};

// Terminals: every boundary loop (all its vertices) and every interior singularity. Fills
// terminal[v] (terminal id or -1) and returns the number of terminals.
int find_terminals(const TriMesh& mesh, const std::vector<char>& singular_vertex, std::vector<int>& terminal) {
  const int nv = mesh.num_vertices(), nh = mesh.num_halfedges();
  terminal.assign(nv, -1);
  int num_terminals = 0;
  {
    std::vector<char> seen(nh, 0);
    for (int h = 0; h < nh; ++h) {
      if (mesh.opposite[h] >= 0 || seen[h]) continue;
      for (int c = h; c >= 0 && !seen[c]; c = mesh.vertex_halfedge[mesh.to(c)]) {
        seen[c] = 1;
        terminal[mesh.from(c)] = num_terminals;
      }
      ++num_terminals;
    }
  }
  for (int v = 0; v < nv; ++v)
    if (terminal[v] < 0 && singular_vertex[v]) terminal[v] = num_terminals++;
  if (num_terminals == 0) terminal[0] = num_terminals++;  // e.g. a torus without singularities
  return num_terminals;
}

// Primal tree T: shortest-path forest grown from all terminals at once (multi-source Dijkstra over
// interior edges) ...
PrimalForest grow_shortest_path_forest(const TriMesh& mesh, const InteriorAdjacency& adjacency,
                                       const std::vector<int>& terminal, Progress& progress) {
  const int nv = mesh.num_vertices();
  PrimalForest forest;
  std::vector<double>& dist = forest.dist;
  std::vector<int>& region = forest.region;
  std::vector<int>& parent_edge = forest.parent_edge;
  dist.assign(nv, std::numeric_limits<double>::infinity());
  region.assign(nv, -1), parent_edge.assign(nv, -1);
  using Entry = std::pair<double, int>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> queue;
  for (int v = 0; v < nv; ++v)
    if (terminal[v] >= 0) {
      dist[v] = 0, region[v] = terminal[v];
      queue.push({0.0, v});
    }
  int settled = 0;
  while (!queue.empty()) {
    const auto [d, v] = queue.top();
    queue.pop();
    if (d > dist[v]) continue;
    if (++settled % 65536 == 0) progress.check_cancel();
    for (int i = adjacency.offset[v]; i < adjacency.offset[v + 1]; ++i) {
      const int e = adjacency.edge[i], w = other_end(mesh, e, v);
      const double dw = d + edge_length(mesh, e);
      if (dw < dist[w]) {
        dist[w] = dw, region[w] = region[v], parent_edge[w] = e;
        queue.push({dw, w});
      }
    }
  }
  return forest;
}

// Edges of the primal tree T (#E flags): the forest's parent edges ... Throws if a vertex was not
// reached.
std::vector<char> primal_tree_edges(const TriMesh& mesh, const PrimalForest& forest, int num_terminals) {
  const int nv = mesh.num_vertices(), ne = mesh.num_edges();
  const std::vector<double>& dist = forest.dist;
  const std::vector<int>& region = forest.region;
  std::vector<char> in_tree(ne, 0);
  for (int v = 0; v < nv; ++v) {
    if (region[v] < 0)
      throw Error(ErrorCode::StageFailed, "cut graph: vertex " + std::to_string(v) +
                                              " is not connected to the rest of the component by interior edges");
    if (forest.parent_edge[v] >= 0) in_tree[forest.parent_edge[v]] = 1;
  }
  // ... whose regions are joined by a minimum spanning tree of the region-crossing edges.
  std::vector<std::pair<double, int>> candidates;
  for (int e = 0; e < ne; ++e) {
    const int h = mesh.edge_halfedge[e];
    if (mesh.opposite[h] < 0) continue;
    const int a = mesh.from(h), b = mesh.to(h);
    if (region[a] != region[b]) candidates.push_back({dist[a] + edge_length(mesh, e) + dist[b], e});
  }
  std::sort(candidates.begin(), candidates.end());
  UnionFind<int> regions(num_terminals);
  for (const auto& [cost, e] : candidates) {
    const int h = mesh.edge_halfedge[e];
    if (regions.unite(region[mesh.from(h)], region[mesh.to(h)])) in_tree[e] = 1;
  }
  return in_tree;
}

// Dual tree T* over the other interior edges: maximum spanning tree by the length of the loop
// each edge would close, so that the left-over (handle loop) edges close short loops. Returns the
// #E flags of the edges T* crosses; throws if the faces are not connected.
std::vector<char> dual_tree_edges(const TriMesh& mesh, const std::vector<double>& dist,
                                  const std::vector<char>& in_tree) {
  const int ne = mesh.num_edges(), nf = mesh.num_faces();
  std::vector<std::pair<double, int>> dual_edges;
  for (int e = 0; e < ne; ++e) {
    const int h = mesh.edge_halfedge[e];
    if (mesh.opposite[h] < 0 || in_tree[e]) continue;
    dual_edges.push_back({dist[mesh.from(h)] + edge_length(mesh, e) + dist[mesh.to(h)], e});
  }
  std::sort(dual_edges.begin(), dual_edges.end(), std::greater<>());
  UnionFind<int> faces(nf);
  std::vector<char> in_dual_tree(ne, 0);
  int dual_tree_edges = 0;
  for (const auto& [weight, e] : dual_edges) {
    const int h = mesh.edge_halfedge[e];
    if (faces.unite(h / 3, mesh.opposite[h] / 3)) in_dual_tree[e] = 1, ++dual_tree_edges;
  }
  if (dual_tree_edges != nf - 1)
    throw Error(ErrorCode::StageFailed,
                "cut graph: the faces are not connected across interior edges "
                "(internal error: " +
                    std::to_string(dual_tree_edges) + " dual tree edges for " + std::to_string(nf) + " faces)");
  return in_dual_tree;
}

// Cut candidates: interior edges off the dual tree. Prune dangling branches at regular
// interior vertices. Fills cut.is_cut and cut.num_cut_edges (needs cut.singular_vertex).
void choose_cut_edges(const TriMesh& mesh, const InteriorAdjacency& adjacency, const std::vector<char>& in_dual_tree,
                      CutGraph& cut) {
  const int nv = mesh.num_vertices(), ne = mesh.num_edges();
  cut.is_cut.assign(ne, 0);
  std::vector<int> degree(nv, 0);
  for (int e = 0; e < ne; ++e) {
    const int h = mesh.edge_halfedge[e];
    if (mesh.opposite[h] < 0 || in_dual_tree[e]) continue;
    cut.is_cut[e] = 1;
    ++degree[mesh.from(h)], ++degree[mesh.to(h)];
  }
  auto prunable = [&](int v) { return degree[v] == 1 && !cut.singular_vertex[v] && !is_boundary_vertex(mesh, v); };
  std::vector<int> leaves;
  for (int v = 0; v < nv; ++v)
    if (prunable(v)) leaves.push_back(v);
  while (!leaves.empty()) {
    const int v = leaves.back();
    leaves.pop_back();
    if (!prunable(v)) continue;
    for (int i = adjacency.offset[v]; i < adjacency.offset[v + 1]; ++i) {
      const int e = adjacency.edge[i];
      if (!cut.is_cut[e]) continue;
      cut.is_cut[e] = 0;
      const int w = other_end(mesh, e, v);
      --degree[v], --degree[w];
      if (prunable(w)) leaves.push_back(w);
      break;
    }
  }
  for (int e = 0; e < ne; ++e) cut.num_cut_edges += cut.is_cut[e];
}

// Comb: turn each face's frame so that the matching vanishes across every dual tree edge. Fills
// cut.frame_turns, rotation, frame_u and edge_sector (needs cut.is_cut).
void comb_field(const TriMesh& mesh, const CrossField& field, const std::vector<char>& in_dual_tree, CutGraph& cut) {
  const int nf = mesh.num_faces(), nh = mesh.num_halfedges();
  cut.frame_turns.assign(nf, 0);
  std::vector<char> visited(nf, 0);
  std::vector<int> stack{0};
  visited[0] = 1;
  while (!stack.empty()) {
    const int f = stack.back();
    stack.pop_back();
    for (int k = 0; k < 3; ++k) {
      const int h = 3 * f + k, o = mesh.opposite[h];
      if (o < 0 || !in_dual_tree[mesh.edge_of[h]] || visited[o / 3]) continue;
      visited[o / 3] = 1;
      cut.frame_turns[o / 3] = static_cast<int8_t>(mod4(cut.frame_turns[f] + field.matching[h]));
      stack.push_back(o / 3);
    }
  }
  cut.rotation.assign(nh, 0);
  for (int h = 0; h < nh; ++h) {
    const int o = mesh.opposite[h];
    if (o < 0) continue;
    cut.rotation[h] = static_cast<int8_t>(mod4(field.matching[h] + cut.frame_turns[h / 3] - cut.frame_turns[o / 3]));
    if (cut.rotation[h] != 0 && !cut.is_cut[mesh.edge_of[h]])
      throw Error(ErrorCode::StageFailed, "cut graph: combing left a rotation on non-cut edge " +
                                              std::to_string(mesh.edge_of[h]) + " (internal error)");
  }
  cut.frame_u.resize(nf);
  for (int f = 0; f < nf; ++f) cut.frame_u[f] = rotate_in_face(mesh, f, field.direction[f], cut.frame_turns[f]);
  cut.edge_sector.assign(nh, -1);
  for (int h = 0; h < nh; ++h)
    if (field.edge_sector[h] >= 0)
      cut.edge_sector[h] = static_cast<int8_t>(mod4(field.edge_sector[h] - cut.frame_turns[h / 3]));
}

}  // namespace

CutGraph compute_cut_graph(const TriMesh& mesh, const CrossField& field, Progress& progress) {
  check_field(mesh, field);
  const int nv = mesh.num_vertices();
  CutGraph cut;
  cut.singular_vertex.assign(nv, 0);
  for (int v = 0; v < nv; ++v) cut.singular_vertex[v] = field.vertex_index[v] != 0;

  std::vector<int> terminal;
  const int num_terminals = find_terminals(mesh, cut.singular_vertex, terminal);
  const InteriorAdjacency adjacency(mesh);
  const PrimalForest forest = grow_shortest_path_forest(mesh, adjacency, terminal, progress);
  const std::vector<char> in_tree = primal_tree_edges(mesh, forest, num_terminals);
  progress.update(0.3);

  const std::vector<char> in_dual_tree = dual_tree_edges(mesh, forest.dist, in_tree);
  progress.update(0.5);

  choose_cut_edges(mesh, adjacency, in_dual_tree, cut);
  progress.update(0.7);

  comb_field(mesh, field, in_dual_tree, cut);
  progress.update(1.0);
  return cut;
}

}  // namespace qgp

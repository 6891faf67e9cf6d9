// The quantizer's view of a TMesh: every edge's two occurrences in cell sides ("slots"), the node
// sequence along each cell side, and the directed graph D of paper §6.2 (Figure 6).
//
// Conventions (validated by the constructor): sides 0,1,2,3 of a cell follow each other
// counter-clockwise and each side lists its edges counter-clockwise; an edge's left cell
// (TMeshEdge::cells[0]) traverses it along its direction, the right cell against it.
//
// Graph D: D-node 2e+d for T-edge e; d = 0 crosses e from its left cell into its right cell,
// d = 1 from right to left. A strip entering cell c through side s leaves it through any edge of
// the opposite side. To keep the arc count linear, the arcs of one cell and direction pass
// through a hub node 2E + 4c + s ("entering c through side s") of weight 0. Simple circuits of D
// through hubs at most once are exactly D's elementary circuits whose minimum is sought.
#pragma once
#include <array>
#include <cstdint>
#include <vector>

#include "tmesh/tmesh.h"

namespace qgp {

struct EdgeSlot {
  int cell = -1;        // -1: no cell on this side (boundary)
  int side = -1;        // 0..3
  int occurrence = -1;  // global occurrence index (see CellSystem::occ_*)
};

class CellSystem {
 public:
  // Validates the T-mesh topology; throws Error(InvalidArgument) naming the first problem.
  explicit CellSystem(const TMesh& tmesh);

  const TMesh& tmesh() const { return *tmesh_; }
  int num_edges() const { return num_edges_; }
  int num_cells() const { return num_cells_; }
  int num_nodes() const { return num_nodes_; }

  // slot[e][j]: j = 0 the occurrence in the left cell (traversed along e), j = 1 in the right.
  std::vector<std::array<EdgeSlot, 2>> slot;

  // Occurrences of side (c,s) are [side_begin(c,s), side_end(c,s)); occ_edge/occ_slot give the
  // edge and which of its slots the occurrence is; occ_start_node is the node where the
  // occurrence starts going counter-clockwise (the end is the next occurrence's start).
  std::vector<int> side_offset;                                       // 4#C + 1
  std::vector<int> occ_edge, occ_slot, occ_start_node, occ_end_node;  // #occurrences
  int side_begin(int c, int s) const { return side_offset[4 * c + s]; }
  int side_end(int c, int s) const { return side_offset[4 * c + s + 1]; }

  // Positions of each node on cell sides: (side id 4c+s, k) with the node at the start of the
  // k-th occurrence of the side (k = length: at its end). CSR over nodes.
  std::vector<int> node_pos_offset;          // #N + 1
  std::vector<std::array<int, 2>> node_pos;  // (side id, k)
  // Edges incident to each node (each loop once). CSR over nodes.
  std::vector<int> node_edge_offset, node_edge;

  // Sums of x over a side, and the offset of occurrence k from the side's start.
  int64_t side_sum(const std::vector<int64_t>& x, int side_id) const;
  int64_t side_prefix(const std::vector<int64_t>& x, int side_id, int k) const;

  // Graph D.
  int num_dnodes() const { return 2 * num_edges_; }
  int num_graph_nodes() const { return 2 * num_edges_ + 4 * num_cells_; }
  bool is_hub(int n) const { return n >= 2 * num_edges_; }
  // The hub a D-node leads into, or -1 (a sink: it leaves through the boundary).
  int dnode_successor_hub(int dnode) const {
    const EdgeSlot& in = slot[dnode / 2][1 - dnode % 2];
    return in.cell < 0 ? -1 : 2 * num_edges_ + 4 * in.cell + in.side;
  }
  // The hub a D-node comes from, or -1 (a source: it enters from the boundary).
  int dnode_predecessor_hub(int dnode) const {
    const EdgeSlot& out = slot[dnode / 2][dnode % 2];
    return out.cell < 0 ? -1 : 2 * num_edges_ + 4 * out.cell + (out.side + 2) % 4;
  }
  // Hub h = 2E + 4c + s: successors leave c through side (s+2)%4, predecessors enter through s.
  template <class F>
  void for_each_hub_successor(int hub, F&& f) const {
    const int id = hub - 2 * num_edges_, c = id / 4, s = (id % 4 + 2) % 4;
    for (int o = side_begin(c, s); o < side_end(c, s); ++o) f(2 * occ_edge[o] + occ_slot[o]);
  }
  template <class F>
  void for_each_hub_predecessor(int hub, F&& f) const {
    const int id = hub - 2 * num_edges_, c = id / 4, s = id % 4;
    for (int o = side_begin(c, s); o < side_end(c, s); ++o) f(2 * occ_edge[o] + 1 - occ_slot[o]);
  }

 private:
  const TMesh* tmesh_;
  int num_edges_ = 0, num_cells_ = 0, num_nodes_ = 0;
};

}  // namespace qgp

// Generating vectors of Ax = 0 (paper §6.2, §9.2): a minimum-weight elementary circuit of the
// directed graph D through a given T-edge, or on meshes with boundary a minimum-weight path from a
// D-node without incoming arcs to one without outgoing arcs through it. Found by a bidirectional
// Dijkstra-type search (one front along, one against the arcs) that stops as soon as no
// undiscovered circuit or path can be lighter than the best one found.
#pragma once
#include <cstdint>
#include <vector>

#include "quantization/cell_system.h"

namespace qgp {

class GeneratingVectorSearch {
 public:
  explicit GeneratingVectorSearch(const CellSystem& system);

  // weight: #edges, the weight of both D-nodes of each T-edge (> 0; +infinity: excluded).
  // On success fills `dnodes` with the D-nodes of the circuit (starting with D-node 2*edge) or of
  // the path (from its source to its sink), in arc order, without hubs; each D-node occurs once,
  // so each edge at most twice. Returns false if D has no circuit or path through the edge.
  // If `explored` is given, the edges of every D-node the search labelled are appended to it
  // (the region the result depends on).
  bool find(int edge, const std::vector<double>& weight, std::vector<int>& dnodes, std::vector<int>* explored);

  int64_t labelled_nodes() const { return labelled_; }  // total over all searches (statistics)

 private:
  struct HeapItem {
    double dist;
    int node;
    bool operator<(const HeapItem& o) const { return dist > o.dist || (dist == o.dist && node > o.node); }
  };
  // Search state of one graph node (D-nodes then hubs), valid where *label == stamp_.
  struct NodeState {
    double fdist, bdist;
    int fparent, bparent;
    uint32_t flabel, blabel, fsettled, bsettled;
  };
  void next_stamp();

  const CellSystem& system_;
  int num_dnodes_ = 0;
  std::vector<int> next_hub_, prev_hub_;  // #D-nodes: hub entered / left, -1 at the boundary
  std::vector<int> exit_dnode_, enter_dnode_;  // per side occurrence: D-node leaving / entering
  std::vector<NodeState> state_;
  std::vector<uint32_t> edge_seen_;
  std::vector<HeapItem> fheap_, bheap_;
  uint32_t stamp_ = 0;
  int64_t labelled_ = 0;
};

}  // namespace qgp

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

  // Phases of find(); they share the state of the search in progress (the members at the end).
  // Resets both fronts and the best circuit/path, and labels s = 2*edge as settled by both.
  void begin_search(int edge, const std::vector<double>& weight, std::vector<int>* explored);
  // Settles s forward and labels the hub it comes from backward (or makes s a sink/source).
  void start_fronts();
  // Settles the nearer front's next node until no unfound circuit or path can beat the best.
  void grow_fronts();
  void settle_next_forward();   // pops the forward heap and settles its D-node (if not stale)
  void settle_next_backward();  // pops the backward heap and settles its hub (if not stale)
  // Forward step: labels D-node b from its settled hub h (arc h -> b).
  void forward_label(int h, int b);
  // Forward step: D-node a is settled; settles its hub and labels the D-nodes leaving it.
  void forward_settle(int a);
  // Backward step: hub h is settled; settles D-node a (arc a -> h) and labels a's hub.
  void backward_settle_dnode(int a, int h);
  // Backward step: settles the D-nodes entering the settled hub h.
  void backward_settle_hub(int h);
  // Counts a newly labelled node; appends its edge to *explored_ once if it is a D-node.
  void touch(int n);
  // Keeps the circuit closed by the arc a -> b if its cost beats the best one so far.
  void offer_circuit(double cost, int a, int b);
  // Writes the best circuit or path into dnodes (loop-erased); false if there is none.
  bool trace_result(std::vector<int>& dnodes) const;
  void trace_path(std::vector<int>& dnodes) const;         // source -> ... -> s -> ... -> sink
  void trace_circuit(std::vector<int>& dnodes) const;      // s -> ... -> a -> b -> ... -> s
  void push_dnode(int n, std::vector<int>& dnodes) const;  // appends n unless it is a hub

  const CellSystem& system_;
  int num_dnodes_ = 0;
  std::vector<int> next_hub_, prev_hub_;       // #D-nodes: hub entered / left, -1 at the boundary
  std::vector<int> exit_dnode_, enter_dnode_;  // per side occurrence: D-node leaving / entering
  std::vector<NodeState> state_;
  std::vector<uint32_t> edge_seen_;
  std::vector<HeapItem> fheap_, bheap_;
  uint32_t stamp_ = 0;
  int64_t labelled_ = 0;

  // The search in progress: s_ = 2*edge, the weights, the explored-edge output; the best circuit
  // (closed by the arc cycle_a_ -> cycle_b_, a forward-, b backward-labelled) and the best path
  // (source_ -> ... -> sink_, sink_cost_ + source_cost_) found so far.
  int s_ = -1;
  const double* weight_ = nullptr;
  std::vector<int>* explored_ = nullptr;
  double best_cycle_ = 0, sink_cost_ = 0, source_cost_ = 0;
  int cycle_a_ = -1, cycle_b_ = -1, sink_ = -1, source_ = -1;
};

}  // namespace qgp

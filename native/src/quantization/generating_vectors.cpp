#include "quantization/generating_vectors.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace qgp {

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();

// Removes closed sub-walks so that every D-node occurs once (loop erasure). The minimum walk is
// elementary already; this only matters when rounding made a detour cost nothing. A sub-walk that
// contains s becomes the result itself (a circuit through s).
void make_elementary(std::vector<int>& walk, int s, bool is_path) {
  std::vector<int> sorted(walk);
  std::sort(sorted.begin(), sorted.end());
  if (std::adjacent_find(sorted.begin(), sorted.end()) == sorted.end()) return;
  if (is_path) {
    const size_t at = std::find(walk.begin(), walk.end(), s) - walk.begin();
    for (size_t i = 0; i < at; ++i) {
      const auto later = std::find(walk.begin() + at + 1, walk.end(), walk[i]);
      if (later == walk.end()) continue;
      // walk[i..later) is closed and passes through s: use it as a circuit.
      std::vector<int> loop(walk.begin() + i, later);
      std::rotate(loop.begin(), std::find(loop.begin(), loop.end(), s), loop.end());
      walk.swap(loop);
      is_path = false;
      break;
    }
  }
  std::vector<int> out;
  for (int n : walk) {
    const auto it = std::find(out.begin(), out.end(), n);
    if (it != out.end())
      out.erase(it + 1, out.end());
    else
      out.push_back(n);
  }
  walk.swap(out);
}

}  // namespace

GeneratingVectorSearch::GeneratingVectorSearch(const CellSystem& system) : system_(system) {
  num_dnodes_ = system.num_dnodes();
  next_hub_.resize(num_dnodes_);
  prev_hub_.resize(num_dnodes_);
  for (int n = 0; n < num_dnodes_; ++n) {
    next_hub_[n] = system.dnode_successor_hub(n);
    prev_hub_[n] = system.dnode_predecessor_hub(n);
  }
  const int occurrences = static_cast<int>(system.occ_edge.size());
  exit_dnode_.resize(occurrences);
  enter_dnode_.resize(occurrences);
  for (int o = 0; o < occurrences; ++o) {
    exit_dnode_[o] = 2 * system.occ_edge[o] + system.occ_slot[o];
    enter_dnode_[o] = 2 * system.occ_edge[o] + 1 - system.occ_slot[o];
  }
  state_.assign(system.num_graph_nodes(), NodeState{kInf, kInf, -1, -1, 0, 0, 0, 0});
  edge_seen_.assign(system.num_edges(), 0);
}

void GeneratingVectorSearch::next_stamp() {
  if (++stamp_ == 0) {  // wrapped around: clear once every 2^32 searches
    for (NodeState& n : state_) n.flabel = n.blabel = n.fsettled = n.bsettled = 0;
    std::fill(edge_seen_.begin(), edge_seen_.end(), 0);
    stamp_ = 1;
  }
}

// Arc a -> b costs the weight of b (hubs weigh 0), so a circuit through s costs the sum of its
// node weights: f(u) counts the nodes after s up to u, g(u) those after u up to s (s included).
bool GeneratingVectorSearch::find(int edge, const std::vector<double>& weight, std::vector<int>& dnodes,
                                  std::vector<int>* explored) {
  dnodes.clear();
  if (!(weight[edge] < kInf)) return false;
  next_stamp();
  begin_search(edge, weight, explored);
  start_fronts();
  grow_fronts();
  return trace_result(dnodes);
}

void GeneratingVectorSearch::begin_search(int edge, const std::vector<double>& weight, std::vector<int>* explored) {
  s_ = 2 * edge;
  weight_ = weight.data();
  explored_ = explored;
  fheap_.clear();
  bheap_.clear();
  best_cycle_ = kInf;
  cycle_a_ = cycle_b_ = -1;
  sink_cost_ = source_cost_ = kInf;
  sink_ = source_ = -1;
  const uint32_t st = stamp_;
  state_[s_] = NodeState{0, 0, -1, -1, st, st, st, st};
  touch(s_);
}

void GeneratingVectorSearch::touch(int n) {
  ++labelled_;
  if (explored_ && n < num_dnodes_ && edge_seen_[n / 2] != stamp_) {
    edge_seen_[n / 2] = stamp_;
    explored_->push_back(n / 2);
  }
}

void GeneratingVectorSearch::offer_circuit(double cost, int a, int b) {
  if (cost < best_cycle_) best_cycle_ = cost, cycle_a_ = a, cycle_b_ = b;
}

// Forward search: the heap holds D-nodes. Settling a D-node settles its hub at once (the arc
// costs 0, so the hub is at the current minimum distance) and labels the D-nodes leaving it.
void GeneratingVectorSearch::forward_label(int h, int b) {  // arc hub h -> D-node b, h settled
  const uint32_t st = stamp_;
  const double wb = weight_[b / 2];
  if (!(wb < kInf)) return;
  NodeState& nb = state_[b];
  const double nd = state_[h].fdist + wb;
  if (nb.blabel == st) offer_circuit(nd + nb.bdist, h, b);
  if (b == s_ || nb.fsettled == st) return;
  if (nb.flabel == st) {
    if (nb.fdist <= nd) return;
  } else if (nb.blabel != st) {
    touch(b);
  }
  nb.fdist = nd, nb.flabel = st, nb.fparent = h;
  fheap_.push_back({nd, b});
  std::push_heap(fheap_.begin(), fheap_.end());
  if (next_hub_[b] < 0 && nd < sink_cost_) sink_cost_ = nd, sink_ = b;
}

void GeneratingVectorSearch::forward_settle(int a) {  // D-node a settled
  const uint32_t st = stamp_;
  const int h = next_hub_[a];
  if (h < 0) return;
  NodeState& nh = state_[h];
  const double d = state_[a].fdist;
  if (nh.blabel == st) offer_circuit(d + nh.bdist, a, h);
  if (nh.fsettled == st) return;
  if (nh.flabel != st && nh.blabel != st) touch(h);
  nh.fdist = d, nh.flabel = nh.fsettled = st, nh.fparent = a;
  const int id = h - num_dnodes_, c = id / 4, side = (id % 4 + 2) % 4;
  for (int o = system_.side_begin(c, side); o < system_.side_end(c, side); ++o) forward_label(h, exit_dnode_[o]);
}

// Backward search: the heap holds hubs. Settling a hub settles the D-nodes entering it at once
// (arcs into hubs cost 0) and labels the hubs they come from.
void GeneratingVectorSearch::backward_settle_dnode(int a, int h) {  // arc D-node a -> hub h, h settled backward
  const uint32_t st = stamp_;
  const double wa = weight_[a / 2];
  if (!(wa < kInf)) return;
  NodeState& na = state_[a];
  const double d = state_[h].bdist;
  if (na.flabel == st) offer_circuit(na.fdist + d, a, h);
  if (a == s_ || na.bsettled == st) return;
  if (na.flabel != st && na.blabel != st) touch(a);
  na.bdist = d, na.blabel = na.bsettled = st, na.bparent = h;
  const int p = prev_hub_[a];
  if (p < 0) {
    if (d + wa < source_cost_) source_cost_ = d + wa, source_ = a;
    return;
  }
  NodeState& np = state_[p];
  const double nd = d + wa;  // arc p -> a costs the weight of a
  if (np.flabel == st) offer_circuit(np.fdist + nd, p, a);
  if (np.bsettled == st) return;
  if (np.blabel == st) {
    if (np.bdist <= nd) return;
  } else if (np.flabel != st) {
    touch(p);
  }
  np.bdist = nd, np.blabel = st, np.bparent = a;
  bheap_.push_back({nd, p});
  std::push_heap(bheap_.begin(), bheap_.end());
}

void GeneratingVectorSearch::backward_settle_hub(int h) {
  const int id = h - num_dnodes_, c = id / 4, side = id % 4;
  for (int o = system_.side_begin(c, side); o < system_.side_end(c, side); ++o)
    backward_settle_dnode(enter_dnode_[o], h);
}

void GeneratingVectorSearch::start_fronts() {
  const uint32_t st = stamp_;
  // s itself may be a sink or a source (an edge on the boundary).
  if (next_hub_[s_] < 0) sink_cost_ = 0, sink_ = s_;
  forward_settle(s_);
  const double ws = weight_[s_ / 2];
  if (const int p = prev_hub_[s_]; p < 0) {
    source_cost_ = ws, source_ = s_;
  } else {
    NodeState& np = state_[p];
    np.bdist = ws, np.blabel = st, np.bparent = s_;
    if (np.flabel == st) offer_circuit(np.fdist + np.bdist, p, s_);
    if (np.flabel != st) touch(p);
    bheap_.push_back({np.bdist, p});
  }
}

void GeneratingVectorSearch::grow_fronts() {
  for (;;) {
    const double top_f = fheap_.empty() ? kInf : fheap_.front().dist;
    const double top_b = bheap_.empty() ? kInf : bheap_.front().dist;
    const double best = std::min(best_cycle_, sink_cost_ + source_cost_);
    const double bound = std::min(top_f + top_b, std::min(sink_cost_, top_f) + std::min(source_cost_, top_b));
    if (bound >= best) break;
    if (top_f <= top_b)
      settle_next_forward();
    else
      settle_next_backward();
  }
}

void GeneratingVectorSearch::settle_next_forward() {
  std::pop_heap(fheap_.begin(), fheap_.end());
  const HeapItem item = fheap_.back();
  fheap_.pop_back();
  NodeState& n = state_[item.node];
  if (n.fsettled == stamp_ || item.dist > n.fdist) return;
  n.fsettled = stamp_;
  forward_settle(item.node);
}

void GeneratingVectorSearch::settle_next_backward() {
  std::pop_heap(bheap_.begin(), bheap_.end());
  const HeapItem item = bheap_.back();
  bheap_.pop_back();
  NodeState& n = state_[item.node];
  if (n.bsettled == stamp_ || item.dist > n.bdist) return;
  n.bsettled = stamp_;
  backward_settle_hub(item.node);
}

bool GeneratingVectorSearch::trace_result(std::vector<int>& dnodes) const {
  const double best = std::min(best_cycle_, sink_cost_ + source_cost_);
  if (!(best < kInf)) return false;
  const bool is_path = sink_cost_ + source_cost_ < best_cycle_;
  if (is_path)
    trace_path(dnodes);
  else
    trace_circuit(dnodes);
  make_elementary(dnodes, s_, is_path);
  return true;
}

void GeneratingVectorSearch::trace_path(std::vector<int>& dnodes) const {
  // source -> ... -> s -> ... -> sink
  for (int n = source_;; n = state_[n].bparent) {
    push_dnode(n, dnodes);
    if (n == s_) break;
  }
  std::vector<int> chain;
  for (int n = sink_; n != s_; n = state_[n].fparent) chain.push_back(n);
  for (auto it = chain.rbegin(); it != chain.rend(); ++it) push_dnode(*it, dnodes);
}

void GeneratingVectorSearch::trace_circuit(std::vector<int>& dnodes) const {
  // s -> ... -> a -> b -> ... -> s
  std::vector<int> chain;
  for (int n = cycle_a_;; n = state_[n].fparent) {
    chain.push_back(n);
    if (n == s_) break;
  }
  for (auto it = chain.rbegin(); it != chain.rend(); ++it) push_dnode(*it, dnodes);
  for (int n = cycle_b_; n != s_; n = state_[n].bparent) push_dnode(n, dnodes);
}

void GeneratingVectorSearch::push_dnode(int n, std::vector<int>& dnodes) const {
  if (!system_.is_hub(n)) dnodes.push_back(n);
}

}  // namespace qgp

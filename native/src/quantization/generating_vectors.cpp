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
    if (it != out.end()) out.erase(it + 1, out.end());
    else out.push_back(n);
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
  const CellSystem& sys = system_;
  const int s = 2 * edge, D = num_dnodes_;
  if (!(weight[edge] < kInf)) return false;
  next_stamp();
  const uint32_t st = stamp_;
  NodeState* state = state_.data();
  auto touch = [&](int n) {
    ++labelled_;
    if (explored && n < D && edge_seen_[n / 2] != st) {
      edge_seen_[n / 2] = st;
      explored->push_back(n / 2);
    }
  };
  fheap_.clear();
  bheap_.clear();

  double best_cycle = kInf;
  int cycle_a = -1, cycle_b = -1;  // the closing arc a -> b (a forward-, b backward-labelled)
  double sink_cost = kInf, source_cost = kInf;
  int sink = -1, source = -1;

  state[s] = NodeState{0, 0, -1, -1, st, st, st, st};
  touch(s);

  // Forward search: the heap holds D-nodes. Settling a D-node settles its hub at once (the arc
  // costs 0, so the hub is at the current minimum distance) and labels the D-nodes leaving it.
  auto forward_label = [&](int h, int b) {  // arc hub h -> D-node b, h settled
    const double wb = weight[b / 2];
    if (!(wb < kInf)) return;
    NodeState& nb = state[b];
    const double nd = state[h].fdist + wb;
    if (nb.blabel == st && nd + nb.bdist < best_cycle) best_cycle = nd + nb.bdist, cycle_a = h, cycle_b = b;
    if (b == s || nb.fsettled == st) return;
    if (nb.flabel == st) {
      if (nb.fdist <= nd) return;
    } else if (nb.blabel != st) {
      touch(b);
    }
    nb.fdist = nd, nb.flabel = st, nb.fparent = h;
    fheap_.push_back({nd, b});
    std::push_heap(fheap_.begin(), fheap_.end());
    if (next_hub_[b] < 0 && nd < sink_cost) sink_cost = nd, sink = b;
  };
  auto forward_settle = [&](int a) {  // D-node a settled
    const int h = next_hub_[a];
    if (h < 0) return;
    NodeState& nh = state[h];
    const double d = state[a].fdist;
    if (nh.blabel == st && d + nh.bdist < best_cycle) best_cycle = d + nh.bdist, cycle_a = a, cycle_b = h;
    if (nh.fsettled == st) return;
    if (nh.flabel != st && nh.blabel != st) touch(h);
    nh.fdist = d, nh.flabel = nh.fsettled = st, nh.fparent = a;
    const int id = h - D, c = id / 4, side = (id % 4 + 2) % 4;
    for (int o = sys.side_begin(c, side); o < sys.side_end(c, side); ++o) forward_label(h, exit_dnode_[o]);
  };
  // Backward search: the heap holds hubs. Settling a hub settles the D-nodes entering it at once
  // (arcs into hubs cost 0) and labels the hubs they come from.
  auto backward_settle_dnode = [&](int a, int h) {  // arc D-node a -> hub h, h settled backward
    const double wa = weight[a / 2];
    if (!(wa < kInf)) return;
    NodeState& na = state[a];
    const double d = state[h].bdist;
    if (na.flabel == st && na.fdist + d < best_cycle) best_cycle = na.fdist + d, cycle_a = a, cycle_b = h;
    if (a == s || na.bsettled == st) return;
    if (na.flabel != st && na.blabel != st) touch(a);
    na.bdist = d, na.blabel = na.bsettled = st, na.bparent = h;
    const int p = prev_hub_[a];
    if (p < 0) {
      if (d + wa < source_cost) source_cost = d + wa, source = a;
      return;
    }
    NodeState& np = state[p];
    const double nd = d + wa;  // arc p -> a costs the weight of a
    if (np.flabel == st && np.fdist + nd < best_cycle) best_cycle = np.fdist + nd, cycle_a = p, cycle_b = a;
    if (np.bsettled == st) return;
    if (np.blabel == st) {
      if (np.bdist <= nd) return;
    } else if (np.flabel != st) {
      touch(p);
    }
    np.bdist = nd, np.blabel = st, np.bparent = a;
    bheap_.push_back({nd, p});
    std::push_heap(bheap_.begin(), bheap_.end());
  };
  auto backward_settle_hub = [&](int h) {
    const int id = h - D, c = id / 4, side = id % 4;
    for (int o = sys.side_begin(c, side); o < sys.side_end(c, side); ++o) backward_settle_dnode(enter_dnode_[o], h);
  };

  // s itself may be a sink or a source (an edge on the boundary).
  if (next_hub_[s] < 0) sink_cost = 0, sink = s;
  forward_settle(s);
  if (const int p = prev_hub_[s]; p < 0) {
    source_cost = weight[edge], source = s;
  } else {
    NodeState& np = state[p];
    np.bdist = weight[edge], np.blabel = st, np.bparent = s;
    if (np.flabel == st && np.fdist + np.bdist < best_cycle) best_cycle = np.fdist + np.bdist, cycle_a = p, cycle_b = s;
    if (np.flabel != st) touch(p);
    bheap_.push_back({np.bdist, p});
  }

  for (;;) {
    const double top_f = fheap_.empty() ? kInf : fheap_.front().dist;
    const double top_b = bheap_.empty() ? kInf : bheap_.front().dist;
    const double best = std::min(best_cycle, sink_cost + source_cost);
    const double bound = std::min(top_f + top_b, std::min(sink_cost, top_f) + std::min(source_cost, top_b));
    if (bound >= best) break;
    if (top_f <= top_b) {
      std::pop_heap(fheap_.begin(), fheap_.end());
      const HeapItem item = fheap_.back();
      fheap_.pop_back();
      NodeState& n = state[item.node];
      if (n.fsettled == st || item.dist > n.fdist) continue;
      n.fsettled = st;
      forward_settle(item.node);
    } else {
      std::pop_heap(bheap_.begin(), bheap_.end());
      const HeapItem item = bheap_.back();
      bheap_.pop_back();
      NodeState& n = state[item.node];
      if (n.bsettled == st || item.dist > n.bdist) continue;
      n.bsettled = st;
      backward_settle_hub(item.node);
    }
  }

  const double best = std::min(best_cycle, sink_cost + source_cost);
  if (!(best < kInf)) return false;
  std::vector<int> chain;
  auto push_dnode = [&](int n) {
    if (!sys.is_hub(n)) dnodes.push_back(n);
  };
  const bool is_path = sink_cost + source_cost < best_cycle;
  if (is_path) {
    // source -> ... -> s -> ... -> sink
    for (int n = source;; n = state[n].bparent) {
      push_dnode(n);
      if (n == s) break;
    }
    for (int n = sink; n != s; n = state[n].fparent) chain.push_back(n);
    for (auto it = chain.rbegin(); it != chain.rend(); ++it) push_dnode(*it);
  } else {
    // s -> ... -> a -> b -> ... -> s
    for (int n = cycle_a;; n = state[n].fparent) {
      chain.push_back(n);
      if (n == s) break;
    }
    for (auto it = chain.rbegin(); it != chain.rend(); ++it) push_dnode(*it);
    for (int n = cycle_b; n != s; n = state[n].bparent) push_dnode(n);
  }
  make_elementary(dnodes, s, is_path);
  return true;
}

}  // namespace qgp

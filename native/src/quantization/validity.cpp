#include "quantization/validity.h"

#include <algorithm>
#include <string>

#include "core/error.h"

namespace qgp {

ValidityChecker::ValidityChecker(const CellSystem& system) : sys_(system) {
  const TMesh& tm = system.tmesh();
  const int N = system.num_nodes();
  is_singular_.assign(N, 0);
  is_feature_point_.assign(N, 0);
  for (int n = 0; n < N; ++n) {
    const TMeshNode& node = tm.nodes[n];
    // Singularities, feature corners (curve turns, ends, branches, virtual corners) and boundary
    // corners / virtual boundary nodes: every node whose integer position the map must keep.
    is_singular_[n] =
        node.singular() || node.kind == TMeshNode::Kind::FeatureCorner || node.kind == TMeshNode::Kind::BoundaryNode;
    is_feature_point_[n] = node.on_feature;
    if (is_singular_[n]) sources_.push_back(n);
  }
  for (const TMeshEdge& e : tm.edges)
    if (e.on_feature) is_feature_point_[e.from] = is_feature_point_[e.to] = 1;
  // Then the other feature points, whose searches find two curves collapsing onto each other.
  for (int n = 0; n < N; ++n)
    if (is_feature_point_[n] && !is_singular_[n]) sources_.push_back(n);
  node_stamp_.assign(N, 0);
  trivial_stamp_.assign(N, 0);
  node_trail_.assign(N, -1);
  cell_seen_.assign(system.num_cells(), 0);
  readers_.assign(system.num_cells(), {});
  generation_.assign(sources_.size(), 0);
  affected_seen_.assign(sources_.size(), 0);
}

ValidityChecker::Point ValidityChecker::point_on_side(const std::vector<int64_t>& x, int side_id,
                                                      int64_t offset) const {
  int64_t p = 0;
  const int b = sys_.side_offset[side_id], end = sys_.side_offset[side_id + 1];
  for (int o = b; o < end; ++o) {
    if (offset == p) return {sys_.occ_start_node[o], -1, 0};
    const int e = sys_.occ_edge[o];
    const int64_t len = x[e];
    if (offset < p + len) {
      const int64_t q = offset - p;
      return {-1, e, sys_.occ_slot[o] == 0 ? q : len - q};
    }
    p += len;
  }
  return {sys_.occ_end_node[end - 1], -1, 0};  // offset == side length
}

int ValidityChecker::mark(const Point& p, int index) {
  if (p.node >= 0) {
    if (node_stamp_[p.node] == stamp_) return node_trail_[p.node];
    node_stamp_[p.node] = stamp_;
    node_trail_[p.node] = index;
    return -1;
  }
  const auto [it, inserted] = interior_trail_.emplace(std::make_pair(p.edge, p.t), index);
  return inserted ? -1 : it->second;
}

void ValidityChecker::add_witness(int index, std::vector<int>& witness) const {
  for (; index >= 0; index = trail_[index].parent) {
    const TrailItem& item = trail_[index];
    if (item.via_edge >= 0) witness.push_back(item.via_edge);
    if (item.via_cell >= 0)
      for (int o = sys_.side_begin(item.via_cell, 0); o < sys_.side_end(item.via_cell, 3); ++o)
        witness.push_back(sys_.occ_edge[o]);
    if (item.point.edge >= 0) witness.push_back(item.point.edge);
  }
}

void ValidityChecker::read_cell(int c) {
  if (reads_ && c >= 0 && cell_seen_[c] != read_stamp_) {
    cell_seen_[c] = read_stamp_;
    reads_->push_back(c);
  }
}

void ValidityChecker::read_edge(int e) {
  if (!reads_) return;
  read_cell(sys_.slot[e][0].cell);
  read_cell(sys_.slot[e][1].cell);
}

void ValidityChecker::begin_check() {
  if (++stamp_ == 0) {
    std::fill(node_stamp_.begin(), node_stamp_.end(), 0);
    stamp_ = 1;
  }
  interior_trail_.clear();
  trail_.clear();
}

bool ValidityChecker::search(int i, const std::vector<int64_t>& x, QuantizationValidity& result,
                             std::vector<int>* witness, std::vector<int>* cells) {
  ++searched_;
  begin_search(i, x, result, cells);
  if (node_stamp_[i] == stamp_) return reached_before(witness);
  collect_trivial_nodes();
  stack_.clear();
  visit({i, -1, 0}, -1, -1, -1);
  explore();
  reads_ = nullptr;
  if (violation_ < 0) return true;
  if (witness) add_violation_witness(*witness);
  return false;
}

void ValidityChecker::begin_search(int i, const std::vector<int64_t>& x, QuantizationValidity& result,
                                   std::vector<int>* cells) {
  source_ = i;
  x_ = &x;
  result_ = &result;
  // A feature source's zero-distance set may share points with others' (along its own curve):
  // it is explored on its own. Singular sources come first in every check, sharing marks.
  feature_source_ = !is_singular_[i];
  if (feature_source_) begin_check();
  reads_ = cells;
  if (cells && ++read_stamp_ == 0) {
    std::fill(cell_seen_.begin(), cell_seen_.end(), 0);
    read_stamp_ = 1;
  }
  violation_ = violation2_ = -1;
}

bool ValidityChecker::reached_before(std::vector<int>* witness) {
  // Reached from another singularity already (not expected).
  const int i = source_;
  violation_ = node_trail_[i];
  result_->valid = false;
  result_->node = trail_[violation_].owner, result_->other_node = i;
  if (witness) add_witness(violation_, *witness);
  reads_ = nullptr;
  return false;
}

void ValidityChecker::collect_trivial_nodes() {
  // The zero-length continuation of i's own feature curves may collapse onto i.
  const TMesh& tm = sys_.tmesh();
  const std::vector<int64_t>& x = *x_;
  const int i = source_;
  if (++trivial_id_ == 0) {
    std::fill(trivial_stamp_.begin(), trivial_stamp_.end(), 0);
    trivial_id_ = 1;
  }
  trivial_nodes_.assign(1, i);
  trivial_stamp_[i] = trivial_id_;
  for (size_t q = 0; q < trivial_nodes_.size(); ++q) {
    const int n = trivial_nodes_[q];
    for (int k = sys_.node_edge_offset[n]; k < sys_.node_edge_offset[n + 1]; ++k) {
      const int e = sys_.node_edge[k];
      if (!tm.edges[e].on_feature) continue;
      read_edge(e);
      if (x[e] != 0) continue;
      for (int m : {tm.edges[e].from, tm.edges[e].to})
        if (trivial_stamp_[m] != trivial_id_) trivial_stamp_[m] = trivial_id_, trivial_nodes_.push_back(m);
    }
  }
}

void ValidityChecker::visit(const Point& p, int parent, int via_edge, int via_cell) {
  const int i = source_;
  const int index = static_cast<int>(trail_.size());
  const int before = mark(p, index);
  if (before >= 0) {
    if (trail_[before].owner != i) {  // the zero-distance sets of two singularities meet
      trail_.push_back({p, i, parent, via_edge, via_cell});
      result_->valid = false;
      result_->node = i, result_->other_node = trail_[before].owner;
      violation_ = index, violation2_ = before;
    }
    return;
  }
  trail_.push_back({p, i, parent, via_edge, via_cell});
  if (new_point_violates(p))
    violation_ = index;
  else
    stack_.push_back(index);
}

bool ValidityChecker::new_point_violates(const Point& p) {
  const TMesh& tm = sys_.tmesh();
  const int i = source_;
  QuantizationValidity& result = *result_;
  if (p.node >= 0) {
    // (A feature point at zero distance from a singular node is that node's violation.)
    if (p.node != i && is_singular_[p.node] && !feature_source_) {
      result.valid = false;
      result.node = i, result.other_node = p.node;
      return true;
    }
    if (is_feature_point_[p.node] && trivial_stamp_[p.node] != trivial_id_) {
      result.valid = false;
      result.node = i;
      for (int k = sys_.node_edge_offset[p.node]; k < sys_.node_edge_offset[p.node + 1]; ++k)
        if (tm.edges[sys_.node_edge[k]].on_feature) result.feature_edge = sys_.node_edge[k];
      return true;
    }
  } else if (tm.edges[p.edge].on_feature) {
    result.valid = false;
    result.node = i, result.feature_edge = p.edge;
    return true;
  }
  return false;
}

void ValidityChecker::cross(int sid, int64_t offset, int parent) {
  const std::vector<int64_t>& x = *x_;
  const int c = sid / 4, s = sid % 4;
  read_cell(c);
  if (sys_.side_sum(x, 4 * c + (s + 1) % 4) != 0) return;
  const int64_t length = sys_.side_sum(x, sid);
  visit(point_on_side(x, 4 * c + (s + 2) % 4, length - offset), parent, -1, c);
}

void ValidityChecker::explore() {
  while (!stack_.empty() && violation_ < 0) {
    const int index = stack_.back();
    stack_.pop_back();
    const Point p = trail_[index].point;
    if (p.node >= 0)
      explore_node(index, p.node);
    else
      explore_edge_point(index, p);
  }
}

void ValidityChecker::explore_node(int index, int n) {
  const TMesh& tm = sys_.tmesh();
  const std::vector<int64_t>& x = *x_;
  for (int k = sys_.node_edge_offset[n]; k < sys_.node_edge_offset[n + 1] && violation_ < 0; ++k) {
    const int e = sys_.node_edge[k];
    read_edge(e);
    if (x[e] != 0) continue;
    const int other = tm.edges[e].from == n ? tm.edges[e].to : tm.edges[e].from;
    visit({other, -1, 0}, index, e, -1);
  }
  for (int k = sys_.node_pos_offset[n]; k < sys_.node_pos_offset[n + 1] && violation_ < 0; ++k) {
    const auto [sid, pos] = sys_.node_pos[k];
    cross(sid, sys_.side_prefix(x, sid, pos), index);
  }
}

void ValidityChecker::explore_edge_point(int index, const Point& p) {
  const std::vector<int64_t>& x = *x_;
  read_edge(p.edge);
  for (int j = 0; j < 2 && violation_ < 0; ++j) {
    const EdgeSlot& sl = sys_.slot[p.edge][j];
    if (sl.cell < 0) continue;
    const int sid = 4 * sl.cell + sl.side;
    const int64_t inside = j == 0 ? p.t : x[p.edge] - p.t;
    cross(sid, sys_.side_prefix(x, sid, sl.occurrence - sys_.side_offset[sid]) + inside, index);
  }
}

void ValidityChecker::add_violation_witness(std::vector<int>& witness) const {
  const TMesh& tm = sys_.tmesh();
  add_witness(violation_, witness);
  if (violation2_ >= 0) add_witness(violation2_, witness);
  for (int n : trivial_nodes_)
    for (int k = sys_.node_edge_offset[n]; k < sys_.node_edge_offset[n + 1]; ++k)
      if (tm.edges[sys_.node_edge[k]].on_feature) witness.push_back(sys_.node_edge[k]);
}

void ValidityChecker::describe(QuantizationValidity& result) const {
  if (result.valid) return;
  if (result.other_node >= 0)
    result.reason = "singular nodes " + std::to_string(result.node) + " and " + std::to_string(result.other_node) +
                    " collapse (zero parametric distance)";
  else
    result.reason = std::string(is_singular_[result.node] ? "singular" : "feature") + " node " +
                    std::to_string(result.node) + " collapses onto feature/boundary edge " +
                    std::to_string(result.feature_edge);
}

QuantizationValidity ValidityChecker::check(const std::vector<int64_t>& x, std::vector<int>* witness) {
  begin_check();
  QuantizationValidity result;
  for (int i : sources_)
    if (!search(i, x, result, witness, nullptr)) break;
  describe(result);
  return result;
}

void ValidityChecker::remember(int si, const std::vector<int>& cells) {
  ++generation_[si];
  for (int c : cells) readers_[c].push_back({si, generation_[si]});
}

QuantizationValidity ValidityChecker::commit_full(const std::vector<int64_t>& x) {
  begin_check();
  for (auto& list : readers_) list.clear();
  QuantizationValidity result;
  std::vector<int> cells;
  committed_ = true;
  for (size_t si = 0; si < sources_.size(); ++si) {
    cells.clear();
    if (!search(sources_[si], x, result, nullptr, &cells)) {
      committed_ = false;
      break;
    }
    remember(static_cast<int>(si), cells);
  }
  describe(result);
  return result;
}

QuantizationValidity ValidityChecker::check_changed(const std::vector<int64_t>& x, const std::vector<int>& changed,
                                                    std::vector<int>* witness, bool commit) {
  if (!committed_) throw Error(ErrorCode::Internal, "validity: incremental test without committed lengths");
  // Singular nodes whose committed search read a cell of a changed edge.
  if (++affected_stamp_ == 0) {
    std::fill(affected_seen_.begin(), affected_seen_.end(), 0);
    affected_stamp_ = 1;
  }
  affected_.clear();
  for (int e : changed)
    for (int j = 0; j < 2; ++j) {
      const int c = sys_.slot[e][j].cell;
      if (c < 0) continue;
      auto& list = readers_[c];
      size_t kept = 0;
      for (const auto& [si, gen] : list) {
        if (generation_[si] != gen) continue;  // stale: that node was searched again since
        list[kept++] = {si, gen};
        if (affected_seen_[si] != affected_stamp_) affected_seen_[si] = affected_stamp_, affected_.push_back(si);
      }
      list.resize(kept);
    }
  std::sort(affected_.begin(), affected_.end());  // deterministic order
  begin_check();
  QuantizationValidity result;
  if (pending_cells_.size() < affected_.size()) pending_cells_.resize(affected_.size());
  for (size_t k = 0; k < affected_.size(); ++k) {
    pending_cells_[k].clear();
    if (!search(sources_[affected_[k]], x, result, witness, commit ? &pending_cells_[k] : nullptr)) break;
  }
  if (result.valid && commit)
    for (size_t k = 0; k < affected_.size(); ++k) remember(affected_[k], pending_cells_[k]);
  describe(result);
  return result;
}

}  // namespace qgp

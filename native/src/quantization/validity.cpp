#include "quantization/validity.h"

#include <algorithm>
#include <string>

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
    is_singular_[n] = node.singular() || node.kind == TMeshNode::Kind::FeatureCorner ||
                      node.kind == TMeshNode::Kind::BoundaryNode;
    is_feature_point_[n] = node.on_feature;
    if (is_singular_[n]) singular_nodes_.push_back(n);
  }
  for (const TMeshEdge& e : tm.edges)
    if (e.on_feature) is_feature_point_[e.from] = is_feature_point_[e.to] = 1;
  node_stamp_.assign(N, 0);
  trivial_stamp_.assign(N, 0);
  node_trail_.assign(N, -1);
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

QuantizationValidity ValidityChecker::check(const std::vector<int64_t>& x, std::vector<int>* witness) {
  const TMesh& tm = sys_.tmesh();
  if (++stamp_ == 0) {
    std::fill(node_stamp_.begin(), node_stamp_.end(), 0);
    stamp_ = 1;
  }
  interior_trail_.clear();
  trail_.clear();
  QuantizationValidity result;
  int violation = -1, violation2 = -1;  // trail indices whose chains explain the violation

  for (int i : singular_nodes_) {
    if (node_stamp_[i] == stamp_) {  // reached from another singularity already (not expected)
      result.valid = false;
      violation = node_trail_[i];
      result.node = trail_[violation].owner, result.other_node = i;
      if (witness) add_witness(violation, *witness);
      break;
    }
    // The zero-length continuation of i's own feature curves may collapse onto i.
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
        if (!tm.edges[e].on_feature || x[e] != 0) continue;
        for (int m : {tm.edges[e].from, tm.edges[e].to})
          if (trivial_stamp_[m] != trivial_id_) trivial_stamp_[m] = trivial_id_, trivial_nodes_.push_back(m);
      }
    }

    stack_.clear();
    auto visit = [&](const Point& p, int parent, int via_edge, int via_cell) {
      const int index = static_cast<int>(trail_.size());
      const int before = mark(p, index);
      if (before >= 0) {
        if (trail_[before].owner != i) {  // the zero-distance sets of two singularities meet
          trail_.push_back({p, i, parent, via_edge, via_cell});
          result.valid = false;
          result.node = i, result.other_node = trail_[before].owner;
          violation = index, violation2 = before;
        }
        return;
      }
      trail_.push_back({p, i, parent, via_edge, via_cell});
      if (p.node >= 0) {
        if (p.node != i && is_singular_[p.node]) {
          result.valid = false;
          result.node = i, result.other_node = p.node;
          violation = index;
          return;
        }
        if (is_feature_point_[p.node] && trivial_stamp_[p.node] != trivial_id_) {
          result.valid = false;
          result.node = i;
          for (int k = sys_.node_edge_offset[p.node]; k < sys_.node_edge_offset[p.node + 1]; ++k)
            if (tm.edges[sys_.node_edge[k]].on_feature) result.feature_edge = sys_.node_edge[k];
          violation = index;
          return;
        }
      } else if (tm.edges[p.edge].on_feature) {
        result.valid = false;
        result.node = i, result.feature_edge = p.edge;
        violation = index;
        return;
      }
      stack_.push_back(index);
    };
    // Crossing a cell from side `sid` at `offset` when its perpendicular extent is zero.
    auto cross = [&](int sid, int64_t offset, int parent) {
      const int c = sid / 4, s = sid % 4;
      if (sys_.side_sum(x, 4 * c + (s + 1) % 4) != 0) return;
      const int64_t length = sys_.side_sum(x, sid);
      visit(point_on_side(x, 4 * c + (s + 2) % 4, length - offset), parent, -1, c);
    };

    visit({i, -1, 0}, -1, -1, -1);
    while (!stack_.empty() && violation < 0) {
      const int index = stack_.back();
      stack_.pop_back();
      const Point p = trail_[index].point;
      if (p.node >= 0) {
        const int n = p.node;
        for (int k = sys_.node_edge_offset[n]; k < sys_.node_edge_offset[n + 1] && violation < 0; ++k) {
          const int e = sys_.node_edge[k];
          if (x[e] != 0) continue;
          const int other = tm.edges[e].from == n ? tm.edges[e].to : tm.edges[e].from;
          visit({other, -1, 0}, index, e, -1);
        }
        for (int k = sys_.node_pos_offset[n]; k < sys_.node_pos_offset[n + 1] && violation < 0; ++k) {
          const auto [sid, pos] = sys_.node_pos[k];
          cross(sid, sys_.side_prefix(x, sid, pos), index);
        }
      } else {
        for (int j = 0; j < 2 && violation < 0; ++j) {
          const EdgeSlot& sl = sys_.slot[p.edge][j];
          if (sl.cell < 0) continue;
          const int sid = 4 * sl.cell + sl.side;
          const int64_t inside = j == 0 ? p.t : x[p.edge] - p.t;
          cross(sid, sys_.side_prefix(x, sid, sl.occurrence - sys_.side_offset[sid]) + inside, index);
        }
      }
    }
    if (violation >= 0) {
      if (witness) {
        add_witness(violation, *witness);
        if (violation2 >= 0) add_witness(violation2, *witness);
        for (int n : trivial_nodes_)
          for (int k = sys_.node_edge_offset[n]; k < sys_.node_edge_offset[n + 1]; ++k)
            if (tm.edges[sys_.node_edge[k]].on_feature) witness->push_back(sys_.node_edge[k]);
      }
      break;
    }
  }

  if (!result.valid) {
    if (result.other_node >= 0)
      result.reason = "singular nodes " + std::to_string(result.node) + " and " + std::to_string(result.other_node) +
                      " collapse (zero parametric distance)";
    else
      result.reason = "singular node " + std::to_string(result.node) + " collapses onto feature/boundary edge " +
                      std::to_string(result.feature_edge);
  }
  return result;
}

}  // namespace qgp

#include "quantization/cell_system.h"

#include <cmath>
#include <string>

#include "core/error.h"

namespace qgp {

namespace {

[[noreturn]] void invalid(const std::string& what) {
  throw Error(ErrorCode::InvalidArgument, "T-mesh: " + what);
}

}  // namespace

CellSystem::CellSystem(const TMesh& tmesh) : tmesh_(&tmesh) {
  num_nodes_ = static_cast<int>(tmesh.nodes.size());
  num_edges_ = static_cast<int>(tmesh.edges.size());
  num_cells_ = static_cast<int>(tmesh.cells.size());
  const int E = num_edges_, C = num_cells_, N = num_nodes_;

  for (int e = 0; e < E; ++e) {
    const TMeshEdge& edge = tmesh.edges[e];
    if (edge.from < 0 || edge.from >= N || edge.to < 0 || edge.to >= N)
      invalid("edge " + std::to_string(e) + " has an endpoint out of range");
    if (!std::isfinite(edge.length) || edge.length < 0)
      invalid("edge " + std::to_string(e) + " has a negative or non-finite length");
    for (int c : edge.cells)
      if (c < -1 || c >= C) invalid("edge " + std::to_string(e) + " names a cell out of range");
    if (edge.cells[0] < 0 && edge.cells[1] < 0) invalid("edge " + std::to_string(e) + " has no cell");
  }

  // Occurrences, side by side.
  side_offset.assign(4 * C + 1, 0);
  for (int c = 0; c < C; ++c)
    for (int s = 0; s < 4; ++s) {
      const auto& side = tmesh.cells[c].sides[s];
      if (side.empty())
        invalid("cell " + std::to_string(c) + " is not four-sided (side " + std::to_string(s) + " is empty)");
      side_offset[4 * c + s + 1] = side_offset[4 * c + s] + static_cast<int>(side.size());
    }
  const int O = side_offset[4 * C];
  occ_edge.resize(O);
  occ_slot.assign(O, -1);
  std::vector<int> occ_cell(O), occ_side(O);
  std::vector<std::array<int, 2>> edge_occ(E, {-1, -1});
  std::vector<int> edge_occ_count(E, 0);
  for (int c = 0; c < C; ++c)
    for (int s = 0; s < 4; ++s)
      for (int k = 0; k < static_cast<int>(tmesh.cells[c].sides[s].size()); ++k) {
        const int o = side_offset[4 * c + s] + k, e = tmesh.cells[c].sides[s][k];
        if (e < 0 || e >= E) invalid("cell " + std::to_string(c) + " names an edge out of range");
        occ_edge[o] = e;
        occ_cell[o] = c;
        occ_side[o] = s;
        if (edge_occ_count[e] >= 2) invalid("edge " + std::to_string(e) + " lies on more than two cell sides");
        edge_occ[e][edge_occ_count[e]++] = o;
      }

  // Slots: the occurrence in the left cell is slot 0. An edge with the same cell on both sides is
  // resolved below from the cell's boundary chain.
  slot.assign(E, {});
  std::vector<char> ambiguous(E, 0);
  for (int e = 0; e < E; ++e) {
    const auto& cells = tmesh.edges[e].cells;
    const int expected = (cells[0] >= 0) + (cells[1] >= 0);
    if (edge_occ_count[e] != expected)
      invalid("edge " + std::to_string(e) + " lies on " + std::to_string(edge_occ_count[e]) +
              " cell sides but names " + std::to_string(expected) + " cells");
    if (cells[0] == cells[1]) {
      ambiguous[e] = 1;
      occ_slot[edge_occ[e][0]] = 0;
      occ_slot[edge_occ[e][1]] = 1;
      continue;
    }
    for (int i = 0; i < expected; ++i) {
      const int o = edge_occ[e][i];
      if (occ_cell[o] == cells[0]) occ_slot[o] = 0;
      else if (occ_cell[o] == cells[1]) occ_slot[o] = 1;
      else invalid("edge " + std::to_string(e) + " lies on a side of cell " + std::to_string(occ_cell[o]) +
                   " which is not one of its cells");
    }
  }

  occ_start_node.resize(O);
  occ_end_node.resize(O);
  auto set_ends = [&](int o) {
    const TMeshEdge& edge = tmesh.edges[occ_edge[o]];
    occ_start_node[o] = occ_slot[o] == 0 ? edge.from : edge.to;
    occ_end_node[o] = occ_slot[o] == 0 ? edge.to : edge.from;
  };
  for (int o = 0; o < O; ++o) set_ends(o);

  // Each cell's boundary must be a closed chain. For edges with the cell on both sides try both
  // slot assignments (few per cell; a consistent one exists for a well-formed T-mesh).
  for (int c = 0; c < C; ++c) {
    const int b = side_offset[4 * c], end = side_offset[4 * c + 4];
    auto chain_ok = [&]() {
      for (int o = b; o < end; ++o) {
        const int next = o + 1 < end ? o + 1 : b;
        if (occ_end_node[o] != occ_start_node[next]) return false;
      }
      return true;
    };
    std::vector<int> flips;  // first occurrence of each ambiguous edge in this cell
    for (int o = b; o < end; ++o)
      if (ambiguous[occ_edge[o]] && edge_occ[occ_edge[o]][0] == o) flips.push_back(o);
    if (flips.size() > 12) invalid("cell " + std::to_string(c) + " has too many edges on two of its sides");
    bool ok = false;
    for (uint32_t mask = 0; mask < (1u << flips.size()) && !ok; ++mask) {
      for (size_t i = 0; i < flips.size(); ++i) {
        const int e = occ_edge[flips[i]];
        const int first = (mask >> i) & 1;
        occ_slot[edge_occ[e][0]] = first;
        occ_slot[edge_occ[e][1]] = 1 - first;
        set_ends(edge_occ[e][0]);
        set_ends(edge_occ[e][1]);
      }
      ok = chain_ok();
    }
    if (!ok) {
      for (int o = b; o < end; ++o) {
        const int next = o + 1 < end ? o + 1 : b;
        if (occ_end_node[o] != occ_start_node[next])
          invalid("cell " + std::to_string(c) + ": its sides are not a closed counter-clockwise chain (edge " +
                  std::to_string(occ_edge[o]) + " ends at node " + std::to_string(occ_end_node[o]) + ", edge " +
                  std::to_string(occ_edge[next]) + " starts at node " + std::to_string(occ_start_node[next]) + ")");
      }
    }
  }
  for (int o = 0; o < O; ++o) {
    EdgeSlot& sl = slot[occ_edge[o]][occ_slot[o]];
    sl.cell = occ_cell[o];
    sl.side = occ_side[o];
    sl.occurrence = o;
  }

  // Node positions on sides.
  node_pos_offset.assign(N + 1, 0);
  auto for_each_position = [&](auto&& f) {
    for (int sid = 0; sid < 4 * C; ++sid) {
      const int b = side_offset[sid], len = side_offset[sid + 1] - b;
      for (int k = 0; k < len; ++k) f(occ_start_node[b + k], sid, k);
      f(occ_end_node[b + len - 1], sid, len);
    }
  };
  for_each_position([&](int n, int, int) { ++node_pos_offset[n + 1]; });
  for (int n = 0; n < N; ++n) node_pos_offset[n + 1] += node_pos_offset[n];
  node_pos.resize(node_pos_offset[N]);
  {
    std::vector<int> fill(node_pos_offset.begin(), node_pos_offset.end() - 1);
    for_each_position([&](int n, int sid, int k) { node_pos[fill[n]++] = {sid, k}; });
  }

  node_edge_offset.assign(N + 1, 0);
  for (const TMeshEdge& edge : tmesh.edges) {
    ++node_edge_offset[edge.from + 1];
    if (edge.to != edge.from) ++node_edge_offset[edge.to + 1];
  }
  for (int n = 0; n < N; ++n) node_edge_offset[n + 1] += node_edge_offset[n];
  node_edge.resize(node_edge_offset[N]);
  {
    std::vector<int> fill(node_edge_offset.begin(), node_edge_offset.end() - 1);
    for (int e = 0; e < E; ++e) {
      node_edge[fill[tmesh.edges[e].from]++] = e;
      if (tmesh.edges[e].to != tmesh.edges[e].from) node_edge[fill[tmesh.edges[e].to]++] = e;
    }
  }
}

int64_t CellSystem::side_sum(const std::vector<int64_t>& x, int side_id) const {
  int64_t sum = 0;
  for (int o = side_offset[side_id]; o < side_offset[side_id + 1]; ++o) sum += x[occ_edge[o]];
  return sum;
}

int64_t CellSystem::side_prefix(const std::vector<int64_t>& x, int side_id, int k) const {
  int64_t sum = 0;
  for (int o = side_offset[side_id]; o < side_offset[side_id] + k; ++o) sum += x[occ_edge[o]];
  return sum;
}

}  // namespace qgp

#include "quantization/cell_system.h"

#include <cmath>
#include <string>

#include "core/error.h"

namespace qgp {

namespace {

[[noreturn]] void invalid(const std::string& what) { throw Error(ErrorCode::InvalidArgument, "T-mesh: " + what); }

// Fills the tables of a CellSystem from its T-mesh, one phase per method, validating the topology
// on the way (the phases must run in the constructor's order). Holds the scratch data they share.
class CellSystemBuilder {
 public:
  CellSystemBuilder(CellSystem& sys, const TMesh& tmesh) : sys_(sys), tmesh_(tmesh) {}

  // Checks each edge's endpoints, length and cells.
  void validate_edges() const;
  // side_offset; checks that no side is empty.
  void count_side_occurrences();
  // occ_edge and each occurrence's cell/side; each edge's occurrences.
  void collect_occurrences();
  // occ_slot by the edges' left/right cells (provisional for edges with one cell on both sides).
  void assign_slots();
  // occ_start_node / occ_end_node from the slots.
  void set_occurrence_ends();
  // Resolves the ambiguous slots so that each cell's boundary is a closed chain.
  void close_cell_chains();
  // slot[e][j] from the occurrences.
  void fill_slots();
  // node_pos_offset / node_pos (CSR of node positions on cell sides).
  void index_node_positions();
  // node_edge_offset / node_edge (CSR of the edges at each node).
  void index_node_edges();

 private:
  void set_ends(int o);  // occurrence o's start and end node from its slot
  // Whether occurrences [b, end) (one cell's sides) form a closed chain.
  bool chain_ok(int b, int end) const;
  // Tries the slot assignments of the cell's ambiguous edges until its chain closes; throws if none does.
  void close_chain(int c);
  // Throws naming the first break in cell c's chain (occurrences [b, end)).
  void report_broken_chain(int c, int b, int end) const;
  // Calls f(node, side id, k) for every node position on every side.
  template <class F>
  void for_each_position(F&& f) const;

  CellSystem& sys_;
  const TMesh& tmesh_;
  std::vector<int> occ_cell_, occ_side_;      // #occurrences
  std::vector<std::array<int, 2>> edge_occ_;  // #edges: its occurrences
  std::vector<int> edge_occ_count_;           // #edges
  std::vector<char> ambiguous_;               // #edges: the same cell on both sides
};

void CellSystemBuilder::validate_edges() const {
  const int E = sys_.num_edges(), C = sys_.num_cells(), N = sys_.num_nodes();
  for (int e = 0; e < E; ++e) {
    const TMeshEdge& edge = tmesh_.edges[e];
    if (edge.from < 0 || edge.from >= N || edge.to < 0 || edge.to >= N)
      invalid("edge " + std::to_string(e) + " has an endpoint out of range");
    if (!std::isfinite(edge.length) || edge.length < 0)
      invalid("edge " + std::to_string(e) + " has a negative or non-finite length");
    for (int c : edge.cells)
      if (c < -1 || c >= C) invalid("edge " + std::to_string(e) + " names a cell out of range");
    if (edge.cells[0] < 0 && edge.cells[1] < 0) invalid("edge " + std::to_string(e) + " has no cell");
  }
}

void CellSystemBuilder::count_side_occurrences() {
  // Occurrences, side by side.
  const int C = sys_.num_cells();
  std::vector<int>& side_offset = sys_.side_offset;
  side_offset.assign(4 * C + 1, 0);
  for (int c = 0; c < C; ++c)
    for (int s = 0; s < 4; ++s) {
      const auto& side = tmesh_.cells[c].sides[s];
      if (side.empty())
        invalid("cell " + std::to_string(c) + " is not four-sided (side " + std::to_string(s) + " is empty)");
      side_offset[4 * c + s + 1] = side_offset[4 * c + s] + static_cast<int>(side.size());
    }
}

void CellSystemBuilder::collect_occurrences() {
  const int E = sys_.num_edges(), C = sys_.num_cells();
  const int O = sys_.side_offset[4 * C];
  sys_.occ_edge.resize(O);
  sys_.occ_slot.assign(O, -1);
  occ_cell_.resize(O);
  occ_side_.resize(O);
  edge_occ_.assign(E, {-1, -1});
  edge_occ_count_.assign(E, 0);
  for (int c = 0; c < C; ++c)
    for (int s = 0; s < 4; ++s)
      for (int k = 0; k < static_cast<int>(tmesh_.cells[c].sides[s].size()); ++k) {
        const int o = sys_.side_offset[4 * c + s] + k, e = tmesh_.cells[c].sides[s][k];
        if (e < 0 || e >= E) invalid("cell " + std::to_string(c) + " names an edge out of range");
        sys_.occ_edge[o] = e;
        occ_cell_[o] = c;
        occ_side_[o] = s;
        if (edge_occ_count_[e] >= 2) invalid("edge " + std::to_string(e) + " lies on more than two cell sides");
        edge_occ_[e][edge_occ_count_[e]++] = o;
      }
}

void CellSystemBuilder::assign_slots() {
  // Slots: the occurrence in the left cell is slot 0. An edge with the same cell on both sides is
  // resolved below from the cell's boundary chain.
  const int E = sys_.num_edges();
  sys_.slot.assign(E, {});
  ambiguous_.assign(E, 0);
  for (int e = 0; e < E; ++e) {
    const auto& cells = tmesh_.edges[e].cells;
    const int expected = (cells[0] >= 0) + (cells[1] >= 0);
    if (edge_occ_count_[e] != expected)
      invalid("edge " + std::to_string(e) + " lies on " + std::to_string(edge_occ_count_[e]) +
              " cell sides but names " + std::to_string(expected) + " cells");
    if (cells[0] == cells[1]) {
      ambiguous_[e] = 1;
      sys_.occ_slot[edge_occ_[e][0]] = 0;
      sys_.occ_slot[edge_occ_[e][1]] = 1;
      continue;
    }
    for (int i = 0; i < expected; ++i) {
      const int o = edge_occ_[e][i];
      if (occ_cell_[o] == cells[0])
        sys_.occ_slot[o] = 0;
      else if (occ_cell_[o] == cells[1])
        sys_.occ_slot[o] = 1;
      else
        invalid("edge " + std::to_string(e) + " lies on a side of cell " + std::to_string(occ_cell_[o]) +
                " which is not one of its cells");
    }
  }
}

void CellSystemBuilder::set_ends(int o) {
  const TMeshEdge& edge = tmesh_.edges[sys_.occ_edge[o]];
  sys_.occ_start_node[o] = sys_.occ_slot[o] == 0 ? edge.from : edge.to;
  sys_.occ_end_node[o] = sys_.occ_slot[o] == 0 ? edge.to : edge.from;
}

void CellSystemBuilder::set_occurrence_ends() {
  const int O = static_cast<int>(sys_.occ_edge.size());
  sys_.occ_start_node.resize(O);
  sys_.occ_end_node.resize(O);
  for (int o = 0; o < O; ++o) set_ends(o);
}

bool CellSystemBuilder::chain_ok(int b, int end) const {
  for (int o = b; o < end; ++o) {
    const int next = o + 1 < end ? o + 1 : b;
    if (sys_.occ_end_node[o] != sys_.occ_start_node[next]) return false;
  }
  return true;
}

void CellSystemBuilder::close_cell_chains() {
  // Each cell's boundary must be a closed chain. For edges with the cell on both sides try both
  // slot assignments (few per cell; a consistent one exists for a well-formed T-mesh).
  for (int c = 0; c < sys_.num_cells(); ++c) close_chain(c);
}

void CellSystemBuilder::close_chain(int c) {
  const int b = sys_.side_offset[4 * c], end = sys_.side_offset[4 * c + 4];
  std::vector<int> flips;  // first occurrence of each ambiguous edge in this cell
  for (int o = b; o < end; ++o)
    if (ambiguous_[sys_.occ_edge[o]] && edge_occ_[sys_.occ_edge[o]][0] == o) flips.push_back(o);
  if (flips.size() > 12) invalid("cell " + std::to_string(c) + " has too many edges on two of its sides");
  bool ok = false;
  for (uint32_t mask = 0; mask < (1u << flips.size()) && !ok; ++mask) {
    for (size_t i = 0; i < flips.size(); ++i) {
      const int e = sys_.occ_edge[flips[i]];
      const int first = (mask >> i) & 1;
      sys_.occ_slot[edge_occ_[e][0]] = first;
      sys_.occ_slot[edge_occ_[e][1]] = 1 - first;
      set_ends(edge_occ_[e][0]);
      set_ends(edge_occ_[e][1]);
    }
    ok = chain_ok(b, end);
  }
  if (!ok) report_broken_chain(c, b, end);
}

void CellSystemBuilder::report_broken_chain(int c, int b, int end) const {
  for (int o = b; o < end; ++o) {
    const int next = o + 1 < end ? o + 1 : b;
    if (sys_.occ_end_node[o] != sys_.occ_start_node[next])
      invalid("cell " + std::to_string(c) + ": its sides are not a closed counter-clockwise chain (edge " +
              std::to_string(sys_.occ_edge[o]) + " ends at node " + std::to_string(sys_.occ_end_node[o]) + ", edge " +
              std::to_string(sys_.occ_edge[next]) + " starts at node " + std::to_string(sys_.occ_start_node[next]) +
              ")");
  }
}

void CellSystemBuilder::fill_slots() {
  for (int o = 0; o < static_cast<int>(sys_.occ_edge.size()); ++o) {
    EdgeSlot& sl = sys_.slot[sys_.occ_edge[o]][sys_.occ_slot[o]];
    sl.cell = occ_cell_[o];
    sl.side = occ_side_[o];
    sl.occurrence = o;
  }
}

template <class F>
void CellSystemBuilder::for_each_position(F&& f) const {
  for (int sid = 0; sid < 4 * sys_.num_cells(); ++sid) {
    const int b = sys_.side_offset[sid], len = sys_.side_offset[sid + 1] - b;
    for (int k = 0; k < len; ++k) f(sys_.occ_start_node[b + k], sid, k);
    f(sys_.occ_end_node[b + len - 1], sid, len);
  }
}

void CellSystemBuilder::index_node_positions() {
  // Node positions on sides.
  const int N = sys_.num_nodes();
  std::vector<int>& offset = sys_.node_pos_offset;
  offset.assign(N + 1, 0);
  for_each_position([&](int n, int, int) { ++offset[n + 1]; });
  for (int n = 0; n < N; ++n) offset[n + 1] += offset[n];
  sys_.node_pos.resize(offset[N]);
  std::vector<int> fill(offset.begin(), offset.end() - 1);
  for_each_position([&](int n, int sid, int k) { sys_.node_pos[fill[n]++] = {sid, k}; });
}

void CellSystemBuilder::index_node_edges() {
  const int E = sys_.num_edges(), N = sys_.num_nodes();
  std::vector<int>& offset = sys_.node_edge_offset;
  offset.assign(N + 1, 0);
  for (const TMeshEdge& edge : tmesh_.edges) {
    ++offset[edge.from + 1];
    if (edge.to != edge.from) ++offset[edge.to + 1];
  }
  for (int n = 0; n < N; ++n) offset[n + 1] += offset[n];
  sys_.node_edge.resize(offset[N]);
  std::vector<int> fill(offset.begin(), offset.end() - 1);
  for (int e = 0; e < E; ++e) {
    sys_.node_edge[fill[tmesh_.edges[e].from]++] = e;
    if (tmesh_.edges[e].to != tmesh_.edges[e].from) sys_.node_edge[fill[tmesh_.edges[e].to]++] = e;
  }
}

}  // namespace

CellSystem::CellSystem(const TMesh& tmesh) : tmesh_(&tmesh) {
  num_nodes_ = static_cast<int>(tmesh.nodes.size());
  num_edges_ = static_cast<int>(tmesh.edges.size());
  num_cells_ = static_cast<int>(tmesh.cells.size());
  CellSystemBuilder builder(*this, tmesh);
  builder.validate_edges();
  builder.count_side_occurrences();
  builder.collect_occurrences();
  builder.assign_slots();
  builder.set_occurrence_ends();
  builder.close_cell_chains();
  builder.fill_slots();
  builder.index_node_positions();
  builder.index_node_edges();
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

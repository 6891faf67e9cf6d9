// The validity test of paper §5.2 with the feature/boundary extension of §9.1.
//
// For integer lengths x (Ax = 0, x >= 0) the cells are rectangles of width x.side0 and height
// x.side1, glued along the T-edges; this defines a (degenerate where x = 0) flat metric. From each
// singular node i the search explores P0(i), the set of points at zero distance from i: it moves
// along zero-length edges and across cells whose extent perpendicular to a side is zero (a point at
// offset t on side s lands at the mirrored offset on side s+2). Points are nodes or integer offsets
// inside edges. The quantization is invalid if P0(i) contains another singular node or a point of a
// feature/boundary edge other than the zero-length continuation of i's own feature curves.
// "Singular" here means index != 0, a feature corner or a boundary corner/virtual boundary node
// (the corners and virtual singularities of §9.1, TMeshNode::Kind FeatureCorner/BoundaryNode).
// Beyond the paper, the search also starts from every other node on a feature or boundary curve:
// two curves (or two parts of one) at zero distance without a singular node between them would
// glue distinct creases together and leave quads of zero area.
//
// Incremental use (stage II): the search from i reads x only through the cells it looks at (edge
// lengths via the edges' cells, side sums of cells). The checker remembers these cells per
// singular node for the committed lengths; after a change of some edges only the singular nodes
// whose remembered cells contain a changed edge are searched again; the others' zero-distance
// sets are unchanged, so the answer equals that of the full test.
#pragma once
#include <cstdint>
#include <unordered_map>
#include <utility>
#include <vector>

#include "quantization/cell_system.h"
#include "quantization/quantization.h"

namespace qgp {

class ValidityChecker {
 public:
  explicit ValidityChecker(const CellSystem& system);

  // Full test. x: consistent lengths. If invalid and `witness` is given, appends the edges whose
  // lengths the found violation depends on (it persists while they keep their lengths).
  QuantizationValidity check(const std::vector<int64_t>& x, std::vector<int>* witness = nullptr);

  // Full test that also makes x the committed lengths of the incremental test.
  QuantizationValidity commit_full(const std::vector<int64_t>& x);
  // Test of x, which differs from the committed lengths only on `changed` edges. If valid and
  // `commit`, x becomes the committed lengths.
  QuantizationValidity check_changed(const std::vector<int64_t>& x, const std::vector<int>& changed,
                                     std::vector<int>* witness, bool commit);

  int64_t searched_singularities() const { return searched_; }  // statistics

 private:
  struct Point {
    int node = -1;  // >= 0: a node
    int edge = -1;  // otherwise a point inside this edge ...
    int64_t t = 0;  // ... at distance t from its `from` node (0 < t < x)
  };
  struct TrailItem {
    Point point;
    int owner = -1;   // the singular node whose search reached it
    int parent = -1;  // trail index
    int via_edge = -1, via_cell = -1;
  };
  void begin_check();
  // Explores P0(i); returns false and fills result/witness on a violation. If `cells` is given,
  // appends the cells whose lengths the search read.
  bool search(int i, const std::vector<int64_t>& x, QuantizationValidity& result, std::vector<int>* witness,
              std::vector<int>* cells);
  // Phases of search(); they share the state of the search in progress (source_ ... violation2_).
  // Sets up the search from i; a feature source gets a check of its own.
  void begin_search(int i, const std::vector<int64_t>& x, QuantizationValidity& result, std::vector<int>* cells);
  // The source was reached by an earlier source's search: records that violation, returns false.
  bool reached_before(std::vector<int>* witness);
  // trivial_nodes_: the source and the nodes joined to it by zero-length feature edges.
  void collect_trivial_nodes();
  // Adds a point reached from trail index `parent` to the trail and the stack, or records the
  // violation it reveals.
  void visit(const Point& p, int parent, int via_edge, int via_cell);
  // Whether the newly reached point p is a violation; if so fills *result_.
  bool new_point_violates(const Point& p);
  // Crossing a cell from side `sid` at `offset` when its perpendicular extent is zero.
  void cross(int sid, int64_t offset, int parent);
  // Pops and explores stacked points until none is left or a violation is found.
  void explore();
  // Moves from node n (trail index `index`) along zero-length edges and across zero-extent cells.
  void explore_node(int index, int n);
  // Moves from a point inside an edge across the zero-extent cells on either side.
  void explore_edge_point(int index, const Point& p);
  // Appends the edges the found violation depends on.
  void add_violation_witness(std::vector<int>& witness) const;
  Point point_on_side(const std::vector<int64_t>& x, int side_id, int64_t offset) const;
  // Trail index of the point if visited before in this check; else records `index` and returns -1.
  int mark(const Point& p, int index);
  void add_witness(int trail_index, std::vector<int>& witness) const;
  void read_edge(int e);
  void read_cell(int c);
  void remember(int singular_index, const std::vector<int>& cells);
  void describe(QuantizationValidity& result) const;

  const CellSystem& sys_;
  std::vector<char> is_singular_, is_feature_point_;
  std::vector<int> sources_;  // where searches start: the singular nodes, then other feature points
  std::vector<uint32_t> node_stamp_, trivial_stamp_;
  std::vector<int> node_trail_;
  struct KeyHash {
    size_t operator()(const std::pair<int, int64_t>& k) const {
      return std::hash<int64_t>()(k.second * 1000003 + k.first);
    }
  };
  std::unordered_map<std::pair<int, int64_t>, int, KeyHash> interior_trail_;  // (edge, t) -> trail
  std::vector<TrailItem> trail_;
  std::vector<int> stack_, trivial_nodes_;
  uint32_t stamp_ = 0, trivial_id_ = 0;
  int64_t searched_ = 0;

  // Cells read by the current search (deduplicated by cell_seen_).
  std::vector<int>* reads_ = nullptr;
  std::vector<uint32_t> cell_seen_;
  uint32_t read_stamp_ = 0;
  // Committed read sets: per cell the singular nodes (index, generation) whose search read it.
  std::vector<std::vector<std::pair<int, uint32_t>>> readers_;
  std::vector<uint32_t> generation_;  // per singular node
  bool committed_ = false;
  std::vector<int> affected_;
  std::vector<std::vector<int>> pending_cells_;  // per affected singular node, for commit
  std::vector<uint32_t> affected_seen_;
  uint32_t affected_stamp_ = 0;

  // The search in progress: its source node, the lengths and result it works on, and the trail
  // indices whose chains explain the violation found (-1: none).
  int source_ = -1;
  bool feature_source_ = false;  // the source is a feature point, not a singular node
  const std::vector<int64_t>* x_ = nullptr;
  QuantizationValidity* result_ = nullptr;
  int violation_ = -1, violation2_ = -1;
};

}  // namespace qgp

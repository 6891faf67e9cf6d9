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
    int node = -1;    // >= 0: a node
    int edge = -1;    // otherwise a point inside this edge ...
    int64_t t = 0;    // ... at distance t from its `from` node (0 < t < x)
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
};

}  // namespace qgp

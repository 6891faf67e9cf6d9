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

  // x: consistent lengths. If invalid and `witness` is given, appends the edges whose lengths the
  // found violation depends on (it persists while they and the cell sides it crosses keep theirs).
  QuantizationValidity check(const std::vector<int64_t>& x, std::vector<int>* witness = nullptr);

  const std::vector<int>& singular_nodes() const { return singular_nodes_; }

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
  Point point_on_side(const std::vector<int64_t>& x, int side_id, int64_t offset) const;
  // Trail index of the point if visited before in this check; else records `index` and returns -1.
  int mark(const Point& p, int index);
  void add_witness(int trail_index, std::vector<int>& witness) const;

  const CellSystem& sys_;
  std::vector<char> is_singular_, is_feature_point_;
  std::vector<int> singular_nodes_;
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
};

}  // namespace qgp

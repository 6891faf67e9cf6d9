// Disjoint sets over 0..n-1 (path halving), for merging identified elements.
#pragma once
#include <numeric>
#include <vector>

namespace qgp {

template <class Index = int>
class UnionFind {
 public:
  explicit UnionFind(Index n = 0) { grow(n); }
  Index size() const { return static_cast<Index>(parent_.size()); }
  // Adds singletons up to n elements.
  void grow(Index n) {
    const Index old = size();
    if (n <= old) return;
    parent_.resize(n);
    std::iota(parent_.begin() + old, parent_.end(), old);
  }
  Index find(Index x) {
    while (parent_[x] != x) x = parent_[x] = parent_[parent_[x]];
    return x;
  }
  // Merges the sets of a and b; false if they were one set already.
  bool unite(Index a, Index b) {
    a = find(a), b = find(b);
    if (a == b) return false;
    parent_[a] = b;
    return true;
  }

 private:
  std::vector<Index> parent_;
};

}  // namespace qgp

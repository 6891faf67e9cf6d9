// Closest points on a triangle surface (axis-aligned bounding-box tree) and the projection of quad
// vertices back onto the original surface when they come from a working mesh (decimated or remeshed).
#pragma once
#include <array>
#include <utility>
#include <vector>

#include "core/mesh.h"
#include "core/progress.h"
#include "core/quad_mesh.h"

namespace qgp {

class TriangleBvh {
 public:
  // V: #V x 3 positions; triangles: #T vertex triples. Both are copied.
  TriangleBvh(const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>& V,
              std::vector<std::array<int, 3>> triangles);
  explicit TriangleBvh(const TriMesh& mesh);

  struct Hit {
    int triangle = -1;  // index into the triangle list (the face index for a TriMesh)
    Vec3 point = Vec3::Zero();
    double squared_distance = 0;
  };
  // Closest point of the surface to p (triangle -1 if the surface is empty).
  Hit closest_point(const Vec3& p) const;
  // The closest point of the surface to p, except where its triangle faces against `normal` and
  // another sheet lies as close (at most `tolerance` farther), facing the opposite way (normals
  // more than acos(kOppositeSheets) apart) and so with `normal`: then that one's point (the nearest
  // such). Two solids in face contact (cycloidal's rings and pins, sharing vertices but not
  // triangles there) leave two coincident sheets facing opposite ways; a quad on them faces with
  // one of them. Across a crease (normals less far apart) the closest point stays, unless
  // `on_crease` is FacingSide and p is as close to a triangle on the crease's other side that faces
  // with `normal`: p's closest point then lies on the crease, whose normal is any of its sides'
  // (a quad just past a concave feature curve: wingnut with sharp edges at 2 000 quads), and the
  // point of the one facing most with `normal` counts.
  enum class OnCrease { KeepClosest, FacingSide };
  Hit closest_point_facing(const Vec3& p, const Vec3& normal, double tolerance,
                           OnCrease on_crease = OnCrease::KeepClosest) const;

  int num_triangles() const { return static_cast<int>(triangles_.size()); }

 private:
  struct Node {
    Eigen::AlignedBox3d box;
    int left = -1, right = -1;  // children, or -1 for a leaf
    int begin = 0, end = 0;     // leaf: order_[begin..end)
  };
  // A triangle's centroid and index, partitioned in place while building (contiguous, so the
  // partitions stay in cache).
  struct Item {
    Vec3 centroid;
    int triangle;
  };
  int build(int begin, int end, std::vector<Item>& items);
  // The closest hit and its leaf-ordered triangle (-1 for an empty surface).
  std::pair<Hit, int> closest_leaf(const Vec3& p) const;
  // Calls visit(i) for each leaf-ordered triangle i whose box lies within squared_radius of p.
  template <class Visit>
  void for_each_near(const Vec3& p, double squared_radius, Visit&& visit) const;
  Vec3 normal(int i) const;                     // of leaf-ordered triangle i, not normalized
  bool face_opposite_ways(int i, int j) const;  // leaf-ordered triangles, kOppositeSheets
  static constexpr double kOppositeSheets = 0.9;
  // Distances equal up to this share of the search's reach are one (a closest point on a shared
  // edge or vertex, found through either triangle, differs only by rounding).
  static constexpr double kTieShare = 1e-9;
  // Median splits: the depth is at most log2 of the triangle count (below 31).
  static constexpr int kMaxDepth = 32;

  std::vector<Vec3> vertices_;
  std::vector<std::array<int, 3>> triangles_;  // in the leaves' order once built...
  std::vector<int> order_;                     // ...triangles_[i] is the caller's triangle order_[i]
  std::vector<Node> nodes_;
};

// Closest point to p on triangle (a, b, c), exact up to rounding, degenerate triangles included.
Vec3 closest_point_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c);
// Distance from p to segment [a, b] (a point when a == b).
double point_segment_distance(const Vec3& p, const Vec3& a, const Vec3& b);

// Per face of a polygon mesh (V, faces of K corners), the triangle of `bvh` nearest the mean of
// its corners (-1 for an empty surface). K is 3 or 4.
template <int K>
std::vector<int> triangles_under_centres(const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>& V,
                                         const Eigen::Matrix<int, Eigen::Dynamic, K, Eigen::RowMajor>& faces,
                                         const TriangleBvh& bvh);

// Moves every quad vertex onto its closest point of `target` (the original, finer surface) and
// sets vertex_face to the target triangle.
void project_to_surface(QuadMesh& quads, const TriMesh& target, Progress& progress);

}  // namespace qgp

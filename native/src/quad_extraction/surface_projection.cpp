#include "quad_extraction/surface_projection.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <utility>

namespace qgp {

double point_segment_distance(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 d = b - a;
  const double len2 = d.squaredNorm();
  const double t = len2 > 0 ? std::clamp((p - a).dot(d) / len2, 0.0, 1.0) : 0.0;
  return (a + t * d - p).norm();
}

Vec3 closest_point_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  // Voronoi regions of the vertices, edges and face (as in Ericson, Real-Time Collision Detection).
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double denom = d1 - d3;
    return denom > 0 ? Vec3(a + (d1 / denom) * ab) : a;
  }
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double denom = d2 - d6;
    return denom > 0 ? Vec3(a + (d2 / denom) * ac) : a;
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const double denom = (d4 - d3) + (d5 - d6);
    return denom > 0 ? Vec3(b + ((d4 - d3) / denom) * (c - b)) : b;
  }
  const double sum = va + vb + vc;
  if (!(sum > 0)) {
    // Degenerate (collinear) triangle: the best of its three edges.
    auto on_segment = [&](const Vec3& s, const Vec3& t) {
      const Vec3 d = t - s;
      const double len2 = d.squaredNorm();
      const double u = len2 > 0 ? std::clamp((p - s).dot(d) / len2, 0.0, 1.0) : 0.0;
      return Vec3(s + u * d);
    };
    Vec3 best = on_segment(a, b);
    for (const Vec3& q : {on_segment(b, c), on_segment(c, a)})
      if ((q - p).squaredNorm() < (best - p).squaredNorm()) best = q;
    return best;
  }
  const double v = vb / sum, w = vc / sum;
  return a + ab * v + ac * w;
}

TriangleBvh::TriangleBvh(const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>& V,
                         std::vector<std::array<int, 3>> triangles)
    : triangles_(std::move(triangles)) {
  vertices_.resize(V.rows());
  for (int v = 0; v < V.rows(); ++v) vertices_[v] = V.row(v).transpose();
  std::vector<Item> items(triangles_.size());
  for (size_t t = 0; t < triangles_.size(); ++t)
    items[t] = {(vertices_[triangles_[t][0]] + vertices_[triangles_[t][1]] + vertices_[triangles_[t][2]]) / 3.0,
                static_cast<int>(t)};
  nodes_.reserve(triangles_.size() / 2 + 1);
  if (!triangles_.empty()) build(0, static_cast<int>(items.size()), items);
  order_.resize(items.size());
  for (size_t i = 0; i < items.size(); ++i) order_[i] = items[i].triangle;
  // The triangles in the leaves' order: a leaf's corners are read without going through order_.
  std::vector<std::array<int, 3>> in_leaf_order(triangles_.size());
  for (size_t i = 0; i < order_.size(); ++i) in_leaf_order[i] = triangles_[order_[i]];
  triangles_ = std::move(in_leaf_order);
}

static std::vector<std::array<int, 3>> triangles_of(const TriMesh& mesh) {
  std::vector<std::array<int, 3>> t(mesh.num_faces());
  for (int f = 0; f < mesh.num_faces(); ++f) t[f] = {mesh.F(f, 0), mesh.F(f, 1), mesh.F(f, 2)};
  return t;
}

TriangleBvh::TriangleBvh(const TriMesh& mesh) : TriangleBvh(mesh.V, triangles_of(mesh)) {}

// Leaves take the boxes of their triangles, inner nodes the union of their children's boxes.
int TriangleBvh::build(int begin, int end, std::vector<Item>& items) {
  const int id = static_cast<int>(nodes_.size());
  nodes_.push_back(Node{});
  if (end - begin <= 4) {
    Eigen::AlignedBox3d box;
    for (int i = begin; i < end; ++i)
      for (int k = 0; k < 3; ++k) box.extend(vertices_[triangles_[items[i].triangle][k]]);
    nodes_[id].box = box;
    nodes_[id].begin = begin, nodes_[id].end = end;
    return id;
  }
  Eigen::AlignedBox3d cbox;
  for (int i = begin; i < end; ++i) cbox.extend(items[i].centroid);
  int axis = 0;
  cbox.sizes().maxCoeff(&axis);
  const int mid = (begin + end) / 2;
  std::nth_element(items.begin() + begin, items.begin() + mid, items.begin() + end,
                   [&](const Item& x, const Item& y) { return x.centroid[axis] < y.centroid[axis]; });
  const int left = build(begin, mid, items);
  const int right = build(mid, end, items);
  nodes_[id].left = left, nodes_[id].right = right;
  nodes_[id].box = nodes_[left].box.merged(nodes_[right].box);
  return id;
}

TriangleBvh::Hit TriangleBvh::closest_point(const Vec3& p) const { return closest_leaf(p).first; }

std::pair<TriangleBvh::Hit, int> TriangleBvh::closest_leaf(const Vec3& p) const {
  Hit best;
  int leaf = -1;
  best.squared_distance = std::numeric_limits<double>::infinity();
  if (nodes_.empty()) return {best, leaf};
  // Depth-first, nearer child first, pruning boxes farther than the best hit. Each stacked node
  // keeps its box's distance, found when its parent was opened. The tree is balanced (median
  // splits), so the stack holds at most one node per level and the one being opened.
  struct Stacked {
    int node;
    double distance;
  };
  std::array<Stacked, kMaxDepth + 2> stack;
  int top = 0;
  stack[top++] = {0, nodes_[0].box.squaredExteriorDistance(p)};
  while (top > 0) {
    const Stacked next = stack[--top];
    if (next.distance >= best.squared_distance) continue;
    const Node& node = nodes_[next.node];
    if (node.left < 0) {
      for (int i = node.begin; i < node.end; ++i) {
        const auto& t = triangles_[i];
        const Vec3 q = closest_point_on_triangle(p, vertices_[t[0]], vertices_[t[1]], vertices_[t[2]]);
        const double d = (q - p).squaredNorm();
        if (d < best.squared_distance) best = Hit{order_[i], q, d}, leaf = i;
      }
      continue;
    }
    const Stacked left{node.left, nodes_[node.left].box.squaredExteriorDistance(p)};
    const Stacked right{node.right, nodes_[node.right].box.squaredExteriorDistance(p)};
    if (left.distance < right.distance) {
      stack[top++] = right, stack[top++] = left;
    } else {
      stack[top++] = left, stack[top++] = right;
    }
  }
  return {best, leaf};
}

template <class Visit>
void TriangleBvh::for_each_near(const Vec3& p, double squared_radius, Visit&& visit) const {
  if (nodes_.empty()) return;
  std::array<int, kMaxDepth + 2> stack;
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& node = nodes_[stack[--top]];
    if (node.box.squaredExteriorDistance(p) > squared_radius) continue;
    if (node.left < 0) {
      for (int i = node.begin; i < node.end; ++i) visit(i);
      continue;
    }
    stack[top++] = node.right, stack[top++] = node.left;
  }
}

Vec3 TriangleBvh::normal(int i) const {
  const auto& t = triangles_[i];
  return (vertices_[t[1]] - vertices_[t[0]]).cross(vertices_[t[2]] - vertices_[t[0]]);
}

bool TriangleBvh::face_opposite_ways(int i, int j) const {
  const Vec3 a = normal(i), b = normal(j);
  return a.dot(b) < -kOppositeSheets * a.norm() * b.norm();
}

TriangleBvh::Hit TriangleBvh::closest_point_facing(const Vec3& p, const Vec3& normal_wanted, double tolerance,
                                                   OnCrease on_crease) const {
  const std::pair<Hit, int> found = closest_leaf(p);
  const Hit& closest = found.first;
  const int first = found.second;  // a plain local: the lambda below captures it (C++17)
  if (first < 0) return closest;
  if (normal(first).dot(normal_wanted) > 0) return closest;
  const double distance = std::sqrt(closest.squared_distance);
  const double reach = distance + tolerance;
  const double tie = distance + kTieShare * reach;  // as close: the point on the crease they share
  Hit best, best_on_crease;
  best.squared_distance = reach * reach;
  double most_facing = 0;  // of the triangles on the crease: the one facing most with `normal_wanted`
  for_each_near(p, reach * reach, [&](int i) {
    const Vec3 n = normal(i);
    if (!(n.dot(normal_wanted) > 0)) return;
    const bool other_sheet = face_opposite_ways(i, first);
    if (!other_sheet && on_crease == OnCrease::KeepClosest) return;
    const auto& t = triangles_[i];
    const Vec3 q = closest_point_on_triangle(p, vertices_[t[0]], vertices_[t[1]], vertices_[t[2]]);
    const double d = (q - p).squaredNorm();
    if (on_crease == OnCrease::FacingSide && d <= tie * tie) {
      const double facing = n.normalized().dot(normal_wanted.normalized());
      if (facing > most_facing) most_facing = facing, best_on_crease = Hit{order_[i], q, d};
    }
    if (other_sheet && d <= best.squared_distance) best = Hit{order_[i], q, d};
  });
  if (best_on_crease.triangle >= 0) return best_on_crease;
  return best.triangle >= 0 ? best : closest;
}

template <int K>
std::vector<int> triangles_under_centres(const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>& V,
                                         const Eigen::Matrix<int, Eigen::Dynamic, K, Eigen::RowMajor>& faces,
                                         const TriangleBvh& bvh) {
  std::vector<int> triangles(faces.rows(), -1);
  for (int f = 0; f < faces.rows(); ++f) {
    Vec3 centre = Vec3::Zero();
    for (int k = 0; k < K; ++k) centre += V.row(faces(f, k)).transpose();
    triangles[f] = bvh.closest_point(centre / K).triangle;
  }
  return triangles;
}

template std::vector<int> triangles_under_centres<3>(const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>&,
                                                     const Eigen::Matrix<int, Eigen::Dynamic, 3, Eigen::RowMajor>&,
                                                     const TriangleBvh&);
template std::vector<int> triangles_under_centres<4>(const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>&,
                                                     const Eigen::Matrix<int, Eigen::Dynamic, 4, Eigen::RowMajor>&,
                                                     const TriangleBvh&);

void project_to_surface(QuadMesh& quads, const TriMesh& target, Progress& progress) {
  const TriangleBvh bvh(target);
  quads.vertex_face.assign(quads.V.rows(), -1);
  for (int v = 0; v < quads.V.rows(); ++v) {
    if ((v & 1023) == 0) progress.check_cancel();
    const TriangleBvh::Hit hit = bvh.closest_point(quads.V.row(v).transpose());
    if (hit.triangle < 0) continue;
    quads.V.row(v) = hit.point.transpose();
    quads.vertex_face[v] = hit.triangle;
  }
}

}  // namespace qgp

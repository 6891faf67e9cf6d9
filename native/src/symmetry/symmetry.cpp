#include "symmetry/symmetry.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <unordered_map>
#include <utility>

#include "core/error.h"

namespace qgp {

std::string SymmetryAxes::name() const {
  std::string s;
  for (int a = 0; a < 3; ++a)
    if (axis[a]) s += static_cast<char>('x' + a);
  return s;
}

SymmetryAxes parse_symmetry_axes(const std::string& text) {
  SymmetryAxes axes;
  for (char c : text) {
    const char lower = static_cast<char>(c >= 'A' && c <= 'Z' ? c - 'A' + 'a' : c);
    const int a = lower - 'x';
    if (a < 0 || a > 2 || axes.axis[a])
      throw Error(ErrorCode::InvalidArgument,
                  "symmetry '" + text + "': give each of the letters x, y and z at most once (for example xz)");
    axes.axis[a] = true;
  }
  return axes;
}

namespace {

// One plane's cut of a soup: what is on the positive side of `axis`, vertices renumbered compactly.
class PlaneCut {
 public:
  PlaneCut(const PolygonSoup& soup, int axis, double snap_tolerance) : in_(soup), axis_(axis) {
    side_.resize(soup.num_vertices());
    positions_ = soup.positions;
    for (int v = 0; v < soup.num_vertices(); ++v) {
      double& x = positions_[v][axis];
      if (x != 0 && std::abs(x) <= snap_tolerance) x = 0, ++snapped;
      side_[v] = x > 0 ? 1 : (x < 0 ? -1 : 0);
    }
    new_index_.assign(soup.num_vertices(), -1);
    for (int f = 0; f < soup.num_faces(); ++f) cut_face(f);
  }

  // Feature edge (a, b) of the soup cut to the positive side, in the output's numbering; false if
  // nothing of it is left.
  bool cut_feature(const std::array<int, 2>& e, std::array<int, 2>& out) const {
    const int sa = side_[e[0]], sb = side_[e[1]];
    if (std::max(sa, sb) <= 0 && std::min(sa, sb) < 0) return false;  // nothing of it on the positive side
    if (sa * sb < 0) {
      const auto found = cut_points_.find(ordered(e[0], e[1]));
      if (found == cut_points_.end()) return false;
      out = {new_index_[sa > 0 ? e[0] : e[1]], found->second};
    } else {
      out = {new_index_[e[0]], new_index_[e[1]]};
    }
    return out[0] >= 0 && out[1] >= 0;
  }

  PolygonSoup out;
  std::vector<int> face_from;    // per output face: the soup face it comes from
  std::vector<int> vertex_from;  // per output vertex: the soup vertex, -1 for a cut point
  // Per output vertex that is a cut point: the soup edge's ends (a, b) and where along it (from a).
  std::vector<std::pair<int, int>> cut_ends;
  std::vector<double> cut_t;
  int cut = 0, dropped = 0, snapped = 0;

 private:
  static std::pair<int, int> ordered(int a, int b) { return {std::min(a, b), std::max(a, b)}; }

  int keep_vertex(int v) {
    if (new_index_[v] < 0) {
      new_index_[v] = out.num_vertices();
      out.positions.push_back(positions_[v]);
      vertex_from.push_back(v);
      cut_ends.push_back({-1, -1});
      cut_t.push_back(0);
    }
    return new_index_[v];
  }

  // The point where edge (a, b) crosses the plane, computed from the ordered pair so that both faces
  // of the edge get the same bits, and exactly on the plane.
  int cut_point(int a, int b) {
    const std::pair<int, int> key = ordered(a, b);
    const auto found = cut_points_.find(key);
    if (found != cut_points_.end()) return found->second;
    const Vec3& p = positions_[key.first];
    const Vec3& q = positions_[key.second];
    const double t = p[axis_] / (p[axis_] - q[axis_]);
    Vec3 point = p + t * (q - p);
    point[axis_] = 0;
    const int index = out.num_vertices();
    out.positions.push_back(point);
    vertex_from.push_back(-1);
    cut_ends.push_back(key);
    cut_t.push_back(t);
    cut_points_.emplace(key, index);
    return index;
  }

  void cut_face(int f) {
    const int* corners = in_.face_vertices.data() + in_.face_start[f];
    const int n = in_.face_size(f);
    bool any_positive = false, any_negative = false;
    for (int k = 0; k < n; ++k) any_positive |= side_[corners[k]] > 0, any_negative |= side_[corners[k]] < 0;
    if (!any_positive) {
      ++dropped;
      return;
    }
    cut += any_negative;
    std::vector<int> polygon;
    for (int k = 0; k < n; ++k) {  // Sutherland-Hodgman against the half-space
      const int a = corners[k], b = corners[(k + 1) % n];
      if (side_[a] >= 0) polygon.push_back(keep_vertex(a));
      if (side_[a] * side_[b] < 0) polygon.push_back(cut_point(a, b));
    }
    out.add_face(polygon.data(), static_cast<int>(polygon.size()));
    face_from.push_back(f);
  }

  const PolygonSoup& in_;
  const int axis_;
  std::vector<Vec3> positions_;
  std::vector<int> side_, new_index_;
  std::map<std::pair<int, int>, int> cut_points_;
};

}  // namespace

HalfSoup cut_to_positive_half(const PolygonSoup& input, const std::vector<std::array<int, 2>>& feature_edges,
                              const SymmetryAxes& axes, double snap_tolerance,
                              const std::vector<double>& vertex_values) {
  HalfSoup half;
  half.soup = input;
  half.input_face.resize(input.num_faces());
  half.input_vertex.resize(input.num_vertices());
  for (int f = 0; f < input.num_faces(); ++f) half.input_face[f] = f;
  for (int v = 0; v < input.num_vertices(); ++v) half.input_vertex[v] = v;
  half.feature_edges = feature_edges;
  half.vertex_values = vertex_values;
  for (int a = 0; a < 3; ++a) {
    if (!axes.axis[a]) continue;
    PlaneCut step(half.soup, a, snap_tolerance);
    std::vector<std::array<int, 2>> features;
    for (const auto& e : half.feature_edges) {
      std::array<int, 2> kept{};
      if (step.cut_feature(e, kept)) features.push_back(kept);
    }
    std::vector<int> input_face, input_vertex;
    std::vector<double> values;
    if (!half.vertex_values.empty())
      for (int v = 0; v < step.out.num_vertices(); ++v) {
        const auto [a, b] = step.cut_ends[v];
        const double t = step.cut_t[v];
        values.push_back(step.vertex_from[v] >= 0 ? half.vertex_values[step.vertex_from[v]]
                                                  : (1 - t) * half.vertex_values[a] + t * half.vertex_values[b]);
      }
    for (int f : step.face_from) input_face.push_back(half.input_face[f]);
    for (int v : step.vertex_from) input_vertex.push_back(v < 0 ? -1 : half.input_vertex[v]);
    half.cut_faces += step.cut;
    half.dropped_faces += step.dropped;
    half.snapped_vertices += step.snapped;
    half.soup = std::move(step.out);
    half.input_face = std::move(input_face);
    half.input_vertex = std::move(input_vertex);
    half.vertex_values = std::move(values);
    half.feature_edges = std::move(features);
  }
  return half;
}

namespace {

uint64_t edge_key(int a, int b) {
  return (static_cast<uint64_t>(std::min(a, b)) << 32) | static_cast<uint32_t>(std::max(a, b));
}

// How many faces use each edge (by edge_key).
template <int K>
std::unordered_map<uint64_t, int> edge_uses(const Eigen::Matrix<int, Eigen::Dynamic, K, Eigen::RowMajor>& faces) {
  std::unordered_map<uint64_t, int> uses;
  for (int f = 0; f < faces.rows(); ++f)
    for (int k = 0; k < K; ++k) ++uses[edge_key(faces(f, k), faces(f, (k + 1) % K))];
  return uses;
}

template <int K>
std::vector<char> boundary_vertices(int num_vertices,
                                    const Eigen::Matrix<int, Eigen::Dynamic, K, Eigen::RowMajor>& faces) {
  std::unordered_map<uint64_t, int> uses = edge_uses<K>(faces);
  std::vector<char> boundary(num_vertices, 0);
  for (int f = 0; f < faces.rows(); ++f)
    for (int k = 0; k < K; ++k)
      if (uses[edge_key(faces(f, k), faces(f, (k + 1) % K))] == 1)
        boundary[faces(f, k)] = boundary[faces(f, (k + 1) % K)] = 1;
  return boundary;
}

// Faces and vertices compacted: faces with keep_face[f] == 0 dropped (with their face_origin entry),
// vertices no kept face uses dropped.
template <int K>
void compact(Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>& V,
             Eigen::Matrix<int, Eigen::Dynamic, K, Eigen::RowMajor>& faces, const std::vector<char>& keep_face,
             std::vector<int>& face_origin) {
  std::vector<int> new_vertex(V.rows(), -1);
  int nv = 0, nf = 0;
  for (int f = 0; f < faces.rows(); ++f) {
    if (!keep_face[f]) continue;
    for (int k = 0; k < K; ++k) {
      int& v = new_vertex[faces(f, k)];
      if (v < 0) v = nv++;
      faces(nf, k) = v;
    }
    face_origin[nf++] = face_origin[f];
  }
  faces.conservativeResize(nf, K);
  face_origin.resize(nf);
  Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> kept(nv, 3);
  for (int v = 0; v < static_cast<int>(new_vertex.size()); ++v)
    if (new_vertex[v] >= 0) kept.row(new_vertex[v]) = V.row(v);
  V = std::move(kept);
}

// A quad corner on a straight part of the half's boundary (a boundary singularity of the cross field
// there) becomes, mirrored, a vertex of two quads that share two edges. The two quads become one (the
// outer four corners, itself mirror-symmetric) and the vertex goes. Returns how many went.
int dissolve_doublets(Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>& V,
                      Eigen::Matrix<int, Eigen::Dynamic, 4, Eigen::RowMajor>& quads, const std::vector<char>& welded,
                      std::vector<int>& face_origin) {
  std::vector<std::vector<std::pair<int, int>>> corners(V.rows());  // welded vertex -> (quad, corner)
  for (int q = 0; q < quads.rows(); ++q)
    for (int k = 0; k < 4; ++k)
      if (welded[quads(q, k)]) corners[quads(q, k)].push_back({q, k});
  std::vector<char> keep(quads.rows(), 1);
  int dissolved = 0;
  for (const auto& around : corners) {
    if (around.size() != 2 || !keep[around[0].first] || !keep[around[1].first]) continue;
    const auto [a, i] = around[0];
    const auto [b, j] = around[1];
    const int next_a = quads(a, (i + 1) % 4), far_a = quads(a, (i + 2) % 4), prev_a = quads(a, (i + 3) % 4);
    const int far_b = quads(b, (j + 2) % 4);
    if (quads(b, (j + 1) % 4) != prev_a || quads(b, (j + 3) % 4) != next_a || far_a == far_b) continue;
    quads.row(a) << next_a, far_a, prev_a, far_b;
    keep[b] = 0;
    ++dissolved;
  }
  if (dissolved > 0) compact<4>(V, quads, keep, face_origin);
  return dissolved;
}

// The mirror image across one plane appended to the mesh, welded on the plane.
template <int K>
void mirror_across_plane(Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>& V,
                         Eigen::Matrix<int, Eigen::Dynamic, K, Eigen::RowMajor>& faces, int axis, double weld_tolerance,
                         std::vector<int>& face_origin, MirrorStats& stats) {
  const int nv = static_cast<int>(V.rows()), nf = static_cast<int>(faces.rows());
  const std::vector<char> boundary = boundary_vertices<K>(nv, faces);
  std::vector<int> image(nv);
  std::vector<char> welded(nv, 0);
  int copies = 0;
  for (int v = 0; v < nv; ++v) {
    welded[v] = boundary[v] && std::abs(V(v, axis)) <= weld_tolerance;
    if (welded[v]) V(v, axis) = 0;
    image[v] = welded[v] ? v : nv + copies++;
    stats.welded_vertices += welded[v];
  }
  V.conservativeResize(nv + copies, 3);
  for (int v = 0; v < nv; ++v) {
    if (welded[v]) continue;
    V.row(image[v]) = V.row(v);
    V(image[v], axis) = -V(v, axis);
  }
  welded.resize(nv + copies, 0);
  faces.conservativeResize(2 * nf, K);
  for (int f = 0; f < nf; ++f) {
    faces(nf + f, 0) = image[faces(f, 0)];
    for (int k = 1; k < K; ++k) faces(nf + f, k) = image[faces(f, K - k)];  // reversed: the mirror flips
    face_origin.push_back(face_origin[f]);
  }
  if constexpr (K == 4) stats.dissolved_doublets += dissolve_doublets(V, faces, welded, face_origin);
}

// Boundary edges of the symmetric mesh on one of the planes (both ends within tolerance of it): where
// the half's boundary left the plane, so the welding missed it.
template <int K>
int open_edges_on_planes(const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>& V,
                         const Eigen::Matrix<int, Eigen::Dynamic, K, Eigen::RowMajor>& faces, const SymmetryAxes& axes,
                         double tolerance) {
  int open = 0;
  for (const auto& [key, count] : edge_uses<K>(faces)) {
    if (count != 1) continue;
    const int a = static_cast<int>(key >> 32), b = static_cast<int>(key & 0xffffffffu);
    for (int axis = 0; axis < 3; ++axis)
      if (axes.axis[axis] && std::abs(V(a, axis)) <= tolerance && std::abs(V(b, axis)) <= tolerance) {
        ++open;
        break;
      }
  }
  return open;
}

}  // namespace

template <int K>
MirrorStats mirror_across_planes(Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>& V,
                                 Eigen::Matrix<int, Eigen::Dynamic, K, Eigen::RowMajor>& faces,
                                 const SymmetryAxes& axes, double weld_tolerance, std::vector<int>& face_origin) {
  MirrorStats stats;
  face_origin.resize(faces.rows());
  for (int f = 0; f < faces.rows(); ++f) face_origin[f] = f;
  for (int a = 2; a >= 0; --a)
    if (axes.axis[a]) mirror_across_plane<K>(V, faces, a, weld_tolerance, face_origin, stats);
  stats.open_edges_on_plane = open_edges_on_planes<K>(V, faces, axes, weld_tolerance);
  return stats;
}

template MirrorStats mirror_across_planes<3>(Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>&,
                                             Eigen::Matrix<int, Eigen::Dynamic, 3, Eigen::RowMajor>&,
                                             const SymmetryAxes&, double, std::vector<int>&);
template MirrorStats mirror_across_planes<4>(Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>&,
                                             Eigen::Matrix<int, Eigen::Dynamic, 4, Eigen::RowMajor>&,
                                             const SymmetryAxes&, double, std::vector<int>&);

}  // namespace qgp

#include "intake/isotropic_remesh.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <unordered_set>
#include <utility>

#include "core/error.h"
#include "quad_extraction/surface_projection.h"

namespace qgp {
namespace {

constexpr double kMaxFaceTurnDeg = 30;  // no operation turns a face further than this
constexpr double kChordShare = 0.05;    // of the target length: how far a line vertex collapsed away may be
                                        // from the line's new chord
constexpr double kCornerTurnDeg = 45;   // a line turning more than this at a vertex has a corner there
constexpr double kMinAreaShare = 1e-8;  // of the target length squared: faces below are degenerate
constexpr int kMaxPasses = 50;          // per operation and iteration (each pass shrinks the work)

uint64_t edge_key(int a, int b) {
  return static_cast<uint64_t>(std::min(a, b)) << 32 | static_cast<uint32_t>(std::max(a, b));
}

Vec3 triangle_normal(const Vec3& a, const Vec3& b, const Vec3& c) { return (b - a).cross(c - a); }

double distance_to_segment(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 ab = b - a;
  const double len2 = ab.squaredNorm();
  const double t = len2 > 0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
  return (p - (a + t * ab)).norm();
}

class Remesher {
 public:
  Remesher(const TriMesh& input, const std::vector<char>& features, const IsotropicRemeshOptions& options)
      : input_(input), bvh_(input), length_(options.edge_length) {
    for (int v = 0; v < input.num_vertices(); ++v) positions_.push_back(input.position(v));
    for (int f = 0; f < input.num_faces(); ++f) faces_.push_back({input.F(f, 0), input.F(f, 1), input.F(f, 2)});
    mark_lines(features, options.crease_angle_deg);
    mark_corners(features);
  }

  void run(int iterations) {
    for (int i = 0; i < iterations; ++i) {
      for (int pass = 0; pass < kMaxPasses && split_long_edges(4.0 / 3.0 * length_) > 0; ++pass) {
      }
      for (int pass = 0; pass < kMaxPasses && collapse_short_edges(0.8 * length_, 4.0 / 3.0 * length_) > 0; ++pass) {
      }
      for (int pass = 0; pass < kMaxPasses && flip_edges(FlipRule::RegularValence) > 0; ++pass) {
      }
      relax_free_vertices();
    }
    for (int pass = 0; pass < kMaxPasses && flip_edges(FlipRule::Delaunay) > 0; ++pass) {
    }
  }

  std::optional<RemeshedSurface> result();

 private:
  void mark_lines(const std::vector<char>& features, double crease_angle_deg);
  void mark_corners(const std::vector<char>& features);
  void rebuild();
  bool is_line(int e) const {
    const int h = mesh_.edge_halfedge[e];
    return mesh_.opposite[h] < 0 || lines_.count(edge_key(mesh_.from(h), mesh_.to(h)));
  }
  // The vertices v shares an edge with (lines_only: a line or boundary edge).
  std::vector<int> neighbors(int v, bool lines_only = false) const;
  // A face's normal `after` a change is not degenerate and within kMaxFaceTurnDeg of `before`.
  bool turns_little(const Vec3& before, const Vec3& after) const;
  Vec3 face_normal(const std::array<int, 3>& t) const {
    return triangle_normal(positions_[t[0]], positions_[t[1]], positions_[t[2]]);
  }
  // Whether face t turns little (turns_little) when its vertex v moves to p.
  bool turns_little_if_moved(const std::array<int, 3>& t, int v, const Vec3& p) const;

  int split_long_edges(double max_length);
  void split_edge(int h);
  int collapse_short_edges(double min_length, double max_length);
  bool can_remove(int a, int b, int e, double max_length) const;
  void remove_into(int a, int b, std::vector<char>& touched, std::vector<char>& dead);
  enum class FlipRule { RegularValence, Delaunay };
  int flip_edges(FlipRule rule);
  bool flip_improves(FlipRule rule, int h, const std::vector<int>& valence, const std::vector<char>& boundary) const;
  void relax_free_vertices();

  const TriMesh& input_;
  TriangleBvh bvh_;
  double length_;
  std::vector<Vec3> positions_;
  std::vector<std::array<int, 3>> faces_;
  std::vector<char> corner_;                       // #V: never moves, never goes
  std::unordered_set<uint64_t> lines_, features_;  // kept edges (features a subset), boundary implicit
  TriMesh mesh_;                                   // positions_ / faces_ with connectivity, per pass
  std::vector<int> line_degree_;                   // #V of mesh_: incident line and boundary edges
};

void Remesher::mark_lines(const std::vector<char>& features, double crease_angle_deg) {
  const double min_cos = std::cos(crease_angle_deg * M_PI / 180);
  for (int e = 0; e < input_.num_edges(); ++e) {
    const int h = input_.edge_halfedge[e], o = input_.opposite[h];
    const uint64_t key = edge_key(input_.from(h), input_.to(h));
    if (features[e]) features_.insert(key);
    if (features[e]) lines_.insert(key);
    if (o < 0 || features[e]) continue;
    const Vec3 n1 = input_.face_normal_unnormalized(h / 3), n2 = input_.face_normal_unnormalized(o / 3);
    if (n1.dot(n2) < min_cos * n1.norm() * n2.norm()) lines_.insert(key);
  }
}

// Corners: vertices with other than two line edges, where a feature meets a crease, or where the
// line turns sharply.
void Remesher::mark_corners(const std::vector<char>& features) {
  rebuild();
  corner_.assign(positions_.size(), 0);
  std::vector<int> feature_degree(positions_.size(), 0);
  for (int e = 0; e < input_.num_edges(); ++e)
    if (features[e]) {
      const int h = input_.edge_halfedge[e];
      ++feature_degree[input_.from(h)];
      ++feature_degree[input_.to(h)];
    }
  const double min_straight_cos = std::cos(kCornerTurnDeg * M_PI / 180);
  for (int v = 0; v < input_.num_vertices(); ++v) {
    if (line_degree_[v] == 0) continue;
    const std::vector<int> ends = neighbors(v, true);
    if (ends.size() != 2 || feature_degree[v] == 1) {
      corner_[v] = 1;
      continue;
    }
    const Vec3 in = positions_[v] - positions_[ends[0]], out = positions_[ends[1]] - positions_[v];
    corner_[v] = in.dot(out) < min_straight_cos * in.norm() * out.norm();
  }
}

void Remesher::rebuild() {
  mesh_.V.resize(static_cast<int>(positions_.size()), 3);
  for (size_t v = 0; v < positions_.size(); ++v) mesh_.V.row(static_cast<int>(v)) = positions_[v].transpose();
  mesh_.F.resize(static_cast<int>(faces_.size()), 3);
  for (size_t f = 0; f < faces_.size(); ++f)
    mesh_.F.row(static_cast<int>(f)) << faces_[f][0], faces_[f][1], faces_[f][2];
  build_connectivity(mesh_);
  line_degree_.assign(positions_.size(), 0);
  for (int e = 0; e < mesh_.num_edges(); ++e)
    if (is_line(e)) {
      ++line_degree_[mesh_.from(mesh_.edge_halfedge[e])];
      ++line_degree_[mesh_.to(mesh_.edge_halfedge[e])];
    }
}

std::vector<int> Remesher::neighbors(int v, bool lines_only) const {
  const std::vector<int> out = outgoing_halfedges(mesh_, v);
  std::vector<int> result;
  for (int h : out)
    if (!lines_only || is_line(mesh_.edge_of[h])) result.push_back(mesh_.to(h));
  // On the boundary, the incoming boundary edge's start (a line) is not the end of an outgoing one.
  if (!out.empty() && mesh_.opposite[TriMesh::prev(out.back())] < 0)
    result.push_back(mesh_.from(TriMesh::prev(out.back())));
  return result;
}

bool Remesher::turns_little(const Vec3& before, const Vec3& after) const {
  const double la = after.norm(), lb = before.norm();
  if (!(la > kMinAreaShare * length_ * length_) || !(lb > 0)) return false;
  return after.dot(before) >= std::cos(kMaxFaceTurnDeg * M_PI / 180) * la * lb;
}

bool Remesher::turns_little_if_moved(const std::array<int, 3>& t, int v, const Vec3& p) const {
  std::array<Vec3, 3> corners{positions_[t[0]], positions_[t[1]], positions_[t[2]]};
  const Vec3 before = triangle_normal(corners[0], corners[1], corners[2]);
  for (int k = 0; k < 3; ++k)
    if (t[k] == v) corners[k] = p;
  return turns_little(before, triangle_normal(corners[0], corners[1], corners[2]));
}

int Remesher::split_long_edges(double max_length) {
  rebuild();
  std::vector<std::pair<double, int>> longest;
  for (int e = 0; e < mesh_.num_edges(); ++e) {
    const double length = mesh_.edge_vector(mesh_.edge_halfedge[e]).norm();
    if (length > max_length) longest.emplace_back(-length, e);
  }
  std::sort(longest.begin(), longest.end());
  std::vector<char> touched(faces_.size(), 0);
  int splits = 0;
  for (const auto& [negative_length, e] : longest) {
    const int h = mesh_.edge_halfedge[e], o = mesh_.opposite[h];
    if (touched[h / 3] || (o >= 0 && touched[o / 3])) continue;
    touched[h / 3] = 1;
    if (o >= 0) touched[o / 3] = 1;
    split_edge(h);
    ++splits;
  }
  return splits;
}

// The edge's midpoint becomes a vertex (on the input surface unless the edge is a line, which lies on
// it); each face on the edge becomes two.
void Remesher::split_edge(int h) {
  const int a = mesh_.from(h), b = mesh_.to(h), m = static_cast<int>(positions_.size());
  const Vec3 midpoint = 0.5 * (positions_[a] + positions_[b]);
  positions_.push_back(is_line(mesh_.edge_of[h]) ? midpoint : bvh_.closest_point(midpoint).point);
  corner_.push_back(0);
  for (std::unordered_set<uint64_t>* set : {&lines_, &features_})
    if (set->erase(edge_key(a, b))) set->insert({edge_key(a, m), edge_key(m, b)});
  for (int side : {h, mesh_.opposite[h]}) {
    if (side < 0) continue;
    const int f = side / 3, from = mesh_.from(side), to = mesh_.to(side), apex = mesh_.to(TriMesh::next(side));
    faces_[f] = {from, m, apex};
    faces_.push_back({m, to, apex});
  }
}

int Remesher::collapse_short_edges(double min_length, double max_length) {
  rebuild();
  std::vector<std::pair<double, int>> shortest;
  for (int e = 0; e < mesh_.num_edges(); ++e) {
    const double length = mesh_.edge_vector(mesh_.edge_halfedge[e]).norm();
    if (length < min_length) shortest.emplace_back(length, e);
  }
  std::sort(shortest.begin(), shortest.end());
  std::vector<char> touched(positions_.size(), 0), dead(faces_.size(), 0);
  int collapses = 0;
  for (const auto& [length, e] : shortest) {
    const int a = mesh_.from(mesh_.edge_halfedge[e]), b = mesh_.to(mesh_.edge_halfedge[e]);
    if (touched[a] || touched[b]) continue;
    if (can_remove(a, b, e, max_length)) {
      remove_into(a, b, touched, dead);
    } else if (can_remove(b, a, e, max_length)) {
      remove_into(b, a, touched, dead);
    } else {
      continue;
    }
    ++collapses;
  }
  std::vector<std::array<int, 3>> alive;
  for (size_t f = 0; f < faces_.size(); ++f)
    if (!dead[f]) alive.push_back(faces_[f]);
  faces_ = std::move(alive);
  return collapses;
}

// Whether edge e's vertex a can go into its other vertex b: a moves only along its line, keeps the
// line within kChordShare of the new chord, and the surface keeps its topology (link condition),
// its edges at most max_length and its faces turned by less than kMaxFaceTurnDeg.
bool Remesher::can_remove(int a, int b, int e, double max_length) const {
  if (corner_[a]) return false;
  if (line_degree_[a] > 0) {
    if (!is_line(e)) return false;
    for (int c : neighbors(a, true))
      if (c != b && distance_to_segment(positions_[a], positions_[b], positions_[c]) > kChordShare * length_)
        return false;
  }
  const std::vector<int> around_a = neighbors(a), around_b = neighbors(b);
  int shared = 0;
  for (int x : around_a) shared += std::count(around_b.begin(), around_b.end(), x) > 0;
  const int h = mesh_.edge_halfedge[e];
  if (shared != (mesh_.opposite[h] < 0 ? 1 : 2)) return false;
  for (int side : {h, mesh_.opposite[h]})
    if (side >= 0 && neighbors(mesh_.to(TriMesh::next(side))).size() <= 3) return false;
  for (int x : around_a)
    if (x != b && (positions_[b] - positions_[x]).norm() > max_length) return false;
  for (int out : outgoing_halfedges(mesh_, a)) {
    const std::array<int, 3>& t = faces_[out / 3];
    if (std::find(t.begin(), t.end(), b) == t.end() && !turns_little_if_moved(t, a, positions_[b])) return false;
  }
  return true;
}

void Remesher::remove_into(int a, int b, std::vector<char>& touched, std::vector<char>& dead) {
  const std::vector<int> around_a = neighbors(a), around_b = neighbors(b);
  for (int out : outgoing_halfedges(mesh_, a)) {
    std::array<int, 3>& t = faces_[out / 3];
    if (std::find(t.begin(), t.end(), b) != t.end()) {
      dead[out / 3] = 1;
      continue;
    }
    for (int& x : t)
      if (x == a) x = b;
  }
  for (std::unordered_set<uint64_t>* set : {&lines_, &features_})
    for (int x : around_a)
      if (set->erase(edge_key(a, x)) && x != b) set->insert(edge_key(b, x));
  touched[a] = touched[b] = 1;
  for (int x : around_a) touched[x] = 1;
  for (int x : around_b) touched[x] = 1;
}

// Whether flipping inner edge h brings the four vertices' valences closer to 6 (4 on the boundary),
// or makes the edge locally Delaunay (its opposite angles sum to more than 180 degrees).
bool Remesher::flip_improves(FlipRule rule, int h, const std::vector<int>& valence,
                             const std::vector<char>& boundary) const {
  const int o = mesh_.opposite[h];
  const int a = mesh_.from(h), b = mesh_.to(h), c = mesh_.to(TriMesh::next(h)), d = mesh_.to(TriMesh::next(o));
  if (rule == FlipRule::Delaunay)
    return corner_angle(mesh_, TriMesh::prev(h)) + corner_angle(mesh_, TriMesh::prev(o)) > M_PI + 1e-9;
  auto deviation = [&](int v, int change) {
    const int d = valence[v] + change - (boundary[v] ? 4 : 6);
    return d * d;
  };
  const int before = deviation(a, 0) + deviation(b, 0) + deviation(c, 0) + deviation(d, 0);
  return deviation(a, -1) + deviation(b, -1) + deviation(c, 1) + deviation(d, 1) < before;
}

// Flips inner non-line edges where the rule says it improves, the two new faces are not
// degenerate and turn little from the old ones.
int Remesher::flip_edges(FlipRule rule) {
  rebuild();
  std::vector<int> valence(positions_.size(), 0);
  std::vector<char> boundary(positions_.size(), 0);
  for (int e = 0; e < mesh_.num_edges(); ++e) {
    const int h = mesh_.edge_halfedge[e];
    ++valence[mesh_.from(h)];
    ++valence[mesh_.to(h)];
    if (mesh_.opposite[h] < 0) boundary[mesh_.from(h)] = boundary[mesh_.to(h)] = 1;
  }
  std::vector<char> touched(faces_.size(), 0);
  int flips = 0;
  for (int e = 0; e < mesh_.num_edges(); ++e) {
    if (is_line(e)) continue;
    const int h = mesh_.edge_halfedge[e], o = mesh_.opposite[h];
    if (touched[h / 3] || touched[o / 3]) continue;
    const int a = mesh_.from(h), b = mesh_.to(h), c = mesh_.to(TriMesh::next(h)), d = mesh_.to(TriMesh::next(o));
    if (c == d || valence[a] <= 3 || valence[b] <= 3 || !flip_improves(rule, h, valence, boundary)) continue;
    const std::vector<int> around_c = neighbors(c);
    if (std::find(around_c.begin(), around_c.end(), d) != around_c.end()) continue;
    const std::array<int, 3> first{a, d, c}, second{d, b, c};
    const Vec3 old_normal = face_normal(faces_[h / 3]).normalized() + face_normal(faces_[o / 3]).normalized();
    if (!turns_little(old_normal, face_normal(first)) || !turns_little(old_normal, face_normal(second))) continue;
    faces_[h / 3] = first;
    faces_[o / 3] = second;
    touched[h / 3] = touched[o / 3] = 1;
    valence[a] -= 1;
    valence[b] -= 1;
    valence[c] += 1;
    valence[d] += 1;
    ++flips;
  }
  return flips;
}

// Each free vertex (on no line) moves to its neighbours' centroid within its tangent plane, then
// onto the input surface, unless that turns one of its faces too far.
void Remesher::relax_free_vertices() {
  rebuild();
  for (int v = 0; v < static_cast<int>(positions_.size()); ++v) {
    if (corner_[v] || line_degree_[v] > 0 || mesh_.vertex_halfedge[v] < 0) continue;
    const std::vector<int> out = outgoing_halfedges(mesh_, v);
    Vec3 centroid = Vec3::Zero(), normal = Vec3::Zero();
    for (int h : out) {
      centroid += positions_[mesh_.to(h)];
      normal += face_normal(faces_[h / 3]);
    }
    centroid /= static_cast<double>(out.size());
    if (!(normal.norm() > 0)) continue;
    normal.normalize();
    Vec3 step = centroid - positions_[v];
    step -= step.dot(normal) * normal;
    const Vec3 target = bvh_.closest_point(positions_[v] + step).point;
    bool keeps_faces = true;
    for (int h : out) keeps_faces = keeps_faces && turns_little_if_moved(faces_[h / 3], v, target);
    if (keeps_faces) positions_[v] = target;
  }
}

std::optional<RemeshedSurface> Remesher::result() {
  std::vector<int> index(positions_.size(), -1);
  RemeshedSurface out;
  std::vector<int> kept;
  for (const std::array<int, 3>& t : faces_)
    for (int v : t)
      if (index[v] < 0) index[v] = 0;
  for (size_t v = 0; v < positions_.size(); ++v)
    if (index[v] == 0) {
      index[v] = static_cast<int>(kept.size());
      kept.push_back(static_cast<int>(v));
    }
  out.mesh.V.resize(static_cast<int>(kept.size()), 3);
  for (size_t i = 0; i < kept.size(); ++i) out.mesh.V.row(static_cast<int>(i)) = positions_[kept[i]].transpose();
  out.mesh.F.resize(static_cast<int>(faces_.size()), 3);
  for (size_t f = 0; f < faces_.size(); ++f)
    out.mesh.F.row(static_cast<int>(f)) << index[faces_[f][0]], index[faces_[f][1]], index[faces_[f][2]];
  try {
    build_connectivity(out.mesh);
  } catch (const Error&) {
    return std::nullopt;
  }
  auto euler = [](const TriMesh& m) { return m.num_vertices() - m.num_edges() + m.num_faces(); };
  if (euler(out.mesh) != euler(input_) || count_boundary_loops(out.mesh) != count_boundary_loops(input_))
    return std::nullopt;
  out.feature_edges.assign(out.mesh.num_edges(), 0);
  for (int e = 0; e < out.mesh.num_edges(); ++e) {
    const int h = out.mesh.edge_halfedge[e];
    out.feature_edges[e] = features_.count(edge_key(kept[out.mesh.from(h)], kept[out.mesh.to(h)])) > 0;
  }
  for (int v = 0; v < out.mesh.num_vertices(); ++v) {
    const Vec3 p = out.mesh.position(v);
    const int t = bvh_.closest_point(p).triangle;
    int nearest = input_.F(t, 0);
    for (int k = 1; k < 3; ++k)
      if ((input_.position(input_.F(t, k)) - p).squaredNorm() < (input_.position(nearest) - p).squaredNorm())
        nearest = input_.F(t, k);
    out.nearest_input_vertex.push_back(nearest);
  }
  return out;
}

}  // namespace

std::optional<RemeshedSurface> remesh_isotropic(const TriMesh& mesh, const std::vector<char>& feature_edges,
                                                const IsotropicRemeshOptions& options) {
  if (!(options.edge_length > 0) || mesh.num_faces() == 0) return std::nullopt;
  Remesher remesher(mesh, feature_edges, options);
  remesher.run(options.iterations);
  return remesher.result();
}

namespace {

// Share of the mesh's area in the faces f for which selected(f) holds (0 for a mesh without area).
template <class Selected>
double area_share_of(const TriMesh& mesh, Selected&& selected) {
  double chosen = 0, total = 0;
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const double area = 0.5 * mesh.face_normal_unnormalized(f).norm();
    total += area;
    if (selected(f)) chosen += area;
  }
  return total > 0 ? chosen / total : 0.0;
}

}  // namespace

double needle_area_share(const TriMesh& mesh) {
  const double min_angle = kNeedleAngleDeg * M_PI / 180;
  return area_share_of(mesh, [&](int f) {
    return std::min({corner_angle(mesh, 3 * f), corner_angle(mesh, 3 * f + 1), corner_angle(mesh, 3 * f + 2)}) <
           min_angle;
  });
}

double coarse_area_share(const TriMesh& mesh, double edge_length) {
  return area_share_of(mesh, [&](int f) {
    double longest = 0;
    for (int k = 0; k < 3; ++k) longest = std::max(longest, mesh.edge_vector(3 * f + k).norm());
    return longest > edge_length;
  });
}

}  // namespace qgp

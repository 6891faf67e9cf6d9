#include "atlas/stitch_seams.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <tuple>
#include <unordered_map>

#include "atlas/corner_faces.h"
#include "atlas/packing.h"
#include "core/error.h"
#include "core/union_find.h"

namespace qgp {
namespace {

using Uv = std::array<double, 2>;  // in texels: (u * W, v * H)

constexpr double kGridTolerance = 0.01;  // texels: how far a transition may be from the texel grid
constexpr double kLargestUv = 1e6;       // atlas coordinates beyond are refused (no texture is that far off)

// A transition between the two sides of a seam, in texel coordinates: p -> rotate(p, turns) + shift.
struct Transition {
  int turns = 0;
  double shift[2] = {0, 0};
  Uv apply(const Uv& p) const {
    const Uv r = quarter_turns(p, turns);
    return {r[0] + shift[0], r[1] + shift[1]};
  }
};

using AtlasFaces = CornerFaces;  // corners in texels

// A side of a face (from corner c to the next) on a seam, and the transition to the other side.
struct SeamSide {
  int corner;
  int chart_across;
  Transition transition;
};

bool near(const Uv& a, const Uv& b) {
  return std::abs(a[0] - b[0]) <= kGridTolerance && std::abs(a[1] - b[1]) <= kGridTolerance;
}

// The transition taking a0 -> b0 and a1 -> b1 when it is a quarter turn plus whole texels, else false.
bool grid_transition(const Uv& a0, const Uv& a1, const Uv& b0, const Uv& b1, Transition* t) {
  const Uv da = {a1[0] - a0[0], a1[1] - a0[1]}, db = {b1[0] - b0[0], b1[1] - b0[1]};
  for (int turns = 0; turns < 4; ++turns) {  // on a side shorter than the tolerance, the first turn with whole texels
    Transition candidate;
    candidate.turns = turns;
    if (!near(candidate.apply(da), db)) continue;
    const Uv ra = candidate.apply(a0);
    bool whole = true;
    for (int d = 0; d < 2; ++d) {
      candidate.shift[d] = std::round(b0[d] - ra[d]);
      whole = whole && std::abs(b0[d] - ra[d] - candidate.shift[d]) <= kGridTolerance;
    }
    if (!whole) continue;
    *t = candidate;
    return true;
  }
  return false;
}

// Charts: faces joined across sides whose two corners coincide in the atlas.
std::vector<int> face_charts(const AtlasFaces& faces, const std::vector<int>& across, int* count) {
  UnionFind<int> charts(faces.soup.num_faces());
  for (size_t c = 0; c < across.size(); ++c) {
    const int o = across[c];
    if (o < 0) continue;
    if (near(faces.uv[c], faces.uv[faces.next(o)]) && near(faces.uv[faces.next(static_cast<int>(c))], faces.uv[o]))
      charts.unite(faces.corner_face[c], faces.corner_face[o]);
  }
  std::vector<int> chart(faces.soup.num_faces());
  std::unordered_map<int, int> id;
  for (int f = 0; f < faces.soup.num_faces(); ++f)
    chart[f] = id.emplace(charts.find(f), static_cast<int>(id.size())).first->second;
  *count = static_cast<int>(id.size());
  return chart;
}

// Per face, its sides on seams with a texel-grid transition; counts seam edges in the report.
std::vector<std::vector<SeamSide>> seam_sides(const AtlasFaces& faces, const std::vector<int>& across,
                                              const std::vector<int>& chart, StitchReport& report) {
  std::vector<std::vector<SeamSide>> seams(faces.soup.num_faces());
  for (size_t c = 0; c < across.size(); ++c) {
    const int o = across[c];
    if (o < 0) continue;
    const Uv &a0 = faces.uv[c], &a1 = faces.uv[faces.next(static_cast<int>(c))];
    const Uv &b0 = faces.uv[faces.next(o)], &b1 = faces.uv[o];
    if (near(a0, b0) && near(a1, b1)) continue;  // the same chart continues
    Transition t;
    const bool matched = grid_transition(a0, a1, b0, b1, &t);
    if (o > static_cast<int>(c)) ++(matched ? report.seam_edges : report.unmatched_seam_edges);
    if (matched) seams[faces.corner_face[c]].push_back({static_cast<int>(c), chart[faces.corner_face[o]], t});
  }
  return seams;
}

// Per texel, the face whose polygon holds its centre (crossing number), or -1.
std::vector<int> texel_owners(const AtlasFaces& faces, int width, int height) {
  std::vector<int> owner(static_cast<size_t>(width) * height, -1);
  const PolygonSoup& soup = faces.soup;
  for (int f = 0; f < soup.num_faces(); ++f) {
    const int begin = soup.face_start[f], end = soup.face_start[f + 1];
    double lo[2] = {1e300, 1e300}, hi[2] = {-1e300, -1e300};
    for (int c = begin; c < end; ++c)
      for (int d = 0; d < 2; ++d) lo[d] = std::min(lo[d], faces.uv[c][d]), hi[d] = std::max(hi[d], faces.uv[c][d]);
    auto clamped = [](double value, int size) { return static_cast<int>(std::clamp(value, 0.0, size - 1.0)); };
    const int x0 = clamped(std::floor(lo[0]), width), x1 = clamped(std::ceil(hi[0]), width);
    const int y0 = clamped(std::floor(lo[1]), height), y1 = clamped(std::ceil(hi[1]), height);
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        const double px = x + 0.5, py = y + 0.5;
        bool inside = false;
        for (int c = begin, p = end - 1; c < end; p = c++) {
          const Uv &a = faces.uv[c], &b = faces.uv[p];
          if ((a[1] > py) != (b[1] > py) && px < a[0] + (py - a[1]) * (b[0] - a[0]) / (b[1] - a[1])) inside = !inside;
        }
        if (inside) owner[static_cast<size_t>(y) * width + x] = f;
      }
  }
  return owner;
}

// Per texel, its nearest covered texel (itself where covered; -1 when nothing is covered). Distance is the
// larger of the two axes' (then the Euclidean, then the texel index): charts packed as rectangles apart by a
// gutter in x or in y then each keep the square ring of half the gutter around their bounding box, corners
// included, as mip levels need. A breadth-first search over the 8 neighbours visits the texels in rings of
// that distance; each takes the best site among its neighbours of the previous ring.
std::vector<int> nearest_covered(const std::vector<int>& owner, int width, int height) {
  std::vector<int> site(owner.size(), -1), ring_of(owner.size(), -1), ring;
  for (size_t t = 0; t < owner.size(); ++t)
    if (owner[t] >= 0) site[t] = static_cast<int>(t), ring_of[t] = 0, ring.push_back(static_cast<int>(t));
  auto closer = [&](int t, int a, int b) {  // site a is closer to texel t than site b
    const int64_t ax = t % width - a % width, ay = t / width - a / width;
    const int64_t bx = t % width - b % width, by = t / width - b / width;
    const int64_t da = ax * ax + ay * ay, db = bx * bx + by * by;
    return da < db || (da == db && a < b);
  };
  for (int r = 1; !ring.empty(); ++r) {
    std::vector<int> next;
    for (int t : ring) {
      const int x = t % width, y = t / width;
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int nx = x + dx, ny = y + dy;
          if (nx < 0 || ny < 0 || nx >= width || ny >= height) continue;
          const int n = ny * width + nx;
          if (ring_of[n] < 0) {
            ring_of[n] = r, site[n] = site[t];
            next.push_back(n);
          } else if (ring_of[n] == r && closer(n, site[t], site[n])) {
            site[n] = site[t];
          }
        }
    }
    ring.swap(next);
  }
  return site;
}

double distance_to_segment(const Uv& p, const Uv& a, const Uv& b) {
  const double ux = b[0] - a[0], uy = b[1] - a[1], len2 = ux * ux + uy * uy;
  const double s = len2 > 0 ? std::clamp(((p[0] - a[0]) * ux + (p[1] - a[1]) * uy) / len2, 0.0, 1.0) : 0.0;
  return std::hypot(p[0] - a[0] - s * ux, p[1] - a[1] - s * uy);
}

// The stitching of one image: the atlas, the texel owners, nearest covered texels and charts.
class Stitcher {
 public:
  Stitcher(const AtlasFaces& faces, AtlasImage& image, StitchReport& report) : faces_(faces), image_(image) {
    const std::vector<int> across = sides_across(faces);
    chart_ = face_charts(faces, across, &report.charts);
    seams_ = seam_sides(faces, across, chart_, report);
    owner_ = texel_owners(faces, image.width, image.height);
    site_ = nearest_covered(owner_, image.width, image.height);
  }

  long long covered_texels() const {
    return std::count_if(owner_.begin(), owner_.end(), [](int f) { return f >= 0; });
  }

  // Steps 2 and 3 of the header; returns (seam texels, filled texels).
  std::pair<long long, long long> fill() {
    const size_t n = owner_.size();
    std::vector<int> source(n, -1);  // per uncovered texel, the texel it copies (step 2)
    std::vector<char> stitched(n, 0);
    for (int round = 0; round < 2; ++round) {
      std::vector<int> found(n, -1);
      for (size_t t = 0; t < n; ++t)
        if (owner_[t] < 0 && site_[t] >= 0 && !stitched[t]) found[t] = texel_across(static_cast<int>(t), stitched);
      for (size_t t = 0; t < n; ++t)
        if (found[t] >= 0) source[t] = found[t], stitched[t] = 1;
    }
    std::pair<long long, long long> counts{0, 0};
    for (size_t t = 0; t < n; ++t) {  // stitched texels first: a round-2 texel copies a stitched one
      if (owner_[t] >= 0 || site_[t] < 0) continue;
      if (stitched[t]) ++counts.first;
      if (stitched[t] && owner_[source[t]] >= 0) copy(source[t], t);
    }
    for (size_t t = 0; t < n; ++t)
      if (stitched[t] && owner_[source[t]] < 0) copy(source[t], t);
    for (size_t t = 0; t < n; ++t)
      if (owner_[t] < 0 && site_[t] >= 0 && !stitched[t]) copy(site_[t], t), ++counts.second;
    return counts;
  }

 private:
  // The texel across a seam that uncovered texel t continues into: covered by the chart across, or (given
  // `stitched`) a stitched gutter texel nearest to that chart. Sides of the faces at and around t's nearest
  // covered texel are tried nearest first, up to one texel farther than the nearest; -1 when none fits.
  int texel_across(int t, const std::vector<char>& stitched) {
    const int w = image_.width;
    const Uv centre = {t % w + 0.5, t / w + 0.5};
    std::vector<std::pair<double, const SeamSide*>>& candidates = candidates_;
    candidates.clear();
    for (int f : faces_near(site_[t]))
      for (const SeamSide& side : seams_[f]) {
        const Uv &a = faces_.uv[side.corner], &b = faces_.uv[faces_.next(side.corner)];
        candidates.emplace_back(distance_to_segment(centre, a, b), &side);
      }
    std::sort(candidates.begin(), candidates.end(), [](const auto& p, const auto& q) {
      return p.first < q.first || (p.first == q.first && p.second->corner < q.second->corner);
    });
    for (const auto& [distance, side] : candidates) {
      if (distance > candidates.front().first + 1.0) break;
      const Uv p = side->transition.apply(centre);
      if (!(p[0] >= 0 && p[1] >= 0 && p[0] < w && p[1] < image_.height)) continue;
      const int x = static_cast<int>(p[0]), y = static_cast<int>(p[1]);
      const int s = y * w + x;
      const int f = owner_[s] >= 0 ? owner_[s] : (stitched[s] && site_[s] >= 0 ? owner_[site_[s]] : -1);
      if (f >= 0 && chart_[f] == side->chart_across) return s;
    }
    return -1;
  }

  // The faces covering texel s and its 8 neighbours.
  const std::vector<int>& faces_near(int s) {
    std::vector<int>& result = faces_near_;
    result.clear();
    const int x = s % image_.width, y = s / image_.width;
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        const int nx = x + dx, ny = y + dy;
        if (nx < 0 || ny < 0 || nx >= image_.width || ny >= image_.height) continue;
        const int f = owner_[ny * image_.width + nx];
        if (f >= 0 && std::find(result.begin(), result.end(), f) == result.end()) result.push_back(f);
      }
    return result;
  }

  void copy(int from, int to) {
    const int w = image_.width;
    std::copy_n(image_.texel(from % w, from / w), image_.channels, image_.texel(to % w, to / w));
  }

  const AtlasFaces& faces_;
  AtlasImage& image_;
  std::vector<int> chart_, owner_, site_;
  std::vector<std::vector<SeamSide>> seams_;
  std::vector<int> faces_near_;  // scratch space of texel_across
  std::vector<std::pair<double, const SeamSide*>> candidates_;
};

void check_inputs(const PolygonSoup& faces, const std::vector<Uv>& corner_uv, const AtlasImage& image) {
  if (image.width <= 0 || image.height <= 0 || image.channels <= 0 ||
      image.texels.size() != static_cast<size_t>(image.width) * image.height * image.channels)
    throw Error(ErrorCode::InvalidArgument, "stitch: the image is empty or its texels do not match its size");
  if (corner_uv.size() != faces.face_vertices.size())
    throw Error(ErrorCode::InvalidArgument, "stitch: " + std::to_string(corner_uv.size()) + " atlas coordinates for " +
                                                std::to_string(faces.face_vertices.size()) + " face corners");
  for (size_t c = 0; c < corner_uv.size(); ++c)
    if (!(std::abs(corner_uv[c][0]) <= kLargestUv && std::abs(corner_uv[c][1]) <= kLargestUv))
      throw Error(ErrorCode::InvalidArgument, "stitch: face corner " + std::to_string(c) +
                                                  " has the atlas coordinate (" + std::to_string(corner_uv[c][0]) +
                                                  ", " + std::to_string(corner_uv[c][1]) +
                                                  "), not a number within 1e6 of the texture");
}

}  // namespace

StitchReport stitch_seams(const PolygonSoup& soup, const std::vector<Uv>& corner_uv, AtlasImage& image) {
  check_inputs(soup, corner_uv, image);
  std::vector<Uv> texels(corner_uv.size());
  for (size_t c = 0; c < corner_uv.size(); ++c)
    texels[c] = {corner_uv[c][0] * image.width, corner_uv[c][1] * image.height};
  const AtlasFaces faces(soup, std::move(texels));
  StitchReport report;
  report.faces = soup.num_faces();
  Stitcher stitcher(faces, image, report);
  std::tie(report.seam_texels, report.filled_texels) = stitcher.fill();
  report.covered_texels = stitcher.covered_texels();
  return report;
}

void to_json(Json& j, const StitchReport& r) {
  j = Json{{"faces", r.faces},
           {"charts", r.charts},
           {"seam_edges", r.seam_edges},
           {"unmatched_seam_edges", r.unmatched_seam_edges},
           {"covered_texels", r.covered_texels},
           {"seam_texels", r.seam_texels},
           {"filled_texels", r.filled_texels}};
}

}  // namespace qgp

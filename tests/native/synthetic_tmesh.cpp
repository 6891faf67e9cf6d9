#include "synthetic_tmesh.h"

#include <algorithm>
#include <map>
#include <random>
#include <string>

#include "core/error.h"

namespace qgp {

namespace {

[[noreturn]] void bad_layout(const std::string& what) {
  throw Error(ErrorCode::InvalidArgument, "synthetic layout: " + what);
}

struct Rect {
  int64_t u0, v0, u1, v1;
};

// Gluing of patch sides: side s of patch p runs from corner[s] to corner[s+1].
struct Gluing {
  std::vector<std::array<int, 2>> partner;  // 4P: (patch, side) glued to (p, s), or (-1, -1)
};

Gluing glue(const PatchLayout& layout) {
  const int P = static_cast<int>(layout.patches.size());
  std::map<std::pair<int, int>, int> directed;  // (corner a, corner b) -> 4p + s
  for (int p = 0; p < P; ++p)
    for (int s = 0; s < 4; ++s) {
      const auto& c = layout.patches[p].corner;
      if (c[s] == c[(s + 1) % 4]) bad_layout("patch " + std::to_string(p) + " has a degenerate side");
      if (!directed.emplace(std::make_pair(c[s], c[(s + 1) % 4]), 4 * p + s).second)
        bad_layout("side (" + std::to_string(c[s]) + "," + std::to_string(c[(s + 1) % 4]) +
                   ") is used twice in the same direction (non-manifold or inconsistently oriented)");
    }
  Gluing g;
  g.partner.assign(4 * P, {-1, -1});
  for (int p = 0; p < P; ++p)
    for (int s = 0; s < 4; ++s) {
      const auto& c = layout.patches[p].corner;
      const auto it = directed.find({c[(s + 1) % 4], c[s]});
      if (it == directed.end()) continue;
      const int q = it->second / 4, t = it->second % 4;
      const auto& pp = layout.patches[p];
      const auto& qq = layout.patches[q];
      if ((s % 2 ? pp.height : pp.width) != (t % 2 ? qq.height : qq.width))
        bad_layout("glued sides of patches " + std::to_string(p) + " and " + std::to_string(q) + " differ in length");
      g.partner[4 * p + s] = {q, t};
    }
  return g;
}

int64_t side_length(const PatchLayout::Patch& p, int s) { return s % 2 ? p.height : p.width; }

// Point of patch coordinates at parameter t along side s (counter-clockwise from corner s).
std::array<int64_t, 2> side_point(const PatchLayout::Patch& p, int s, int64_t t) {
  switch (s) {
    case 0: return {t, 0};
    case 1: return {p.width, t};
    case 2: return {p.width - t, p.height};
    default: return {0, p.height - t};
  }
}

// Sides of the patch boundary the point lies on (corner: two), with their parameters.
std::vector<std::pair<int, int64_t>> sides_of(const PatchLayout::Patch& p, int64_t u, int64_t v) {
  std::vector<std::pair<int, int64_t>> out;
  if (v == 0) out.push_back({0, u});
  if (u == p.width) out.push_back({1, v});
  if (v == p.height) out.push_back({2, p.width - u});
  if (u == 0) out.push_back({3, p.height - v});
  return out;
}

}  // namespace

PatchLayout make_grid_layout(const std::vector<int64_t>& widths, const std::vector<int64_t>& heights, bool periodic_u,
                             bool periodic_v) {
  const int nu = static_cast<int>(widths.size()), nv = static_cast<int>(heights.size());
  if (nu < 1 || nv < 1) bad_layout("empty grid");
  if ((periodic_u && nu < 3) || (periodic_v && nv < 3)) bad_layout("periodic grids need at least 3 patches per period");
  const int cu = periodic_u ? nu : nu + 1, cv = periodic_v ? nv : nv + 1;
  auto id = [&](int i, int j) { return (i % cu) + cu * (j % cv); };
  PatchLayout layout;
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      PatchLayout::Patch p;
      p.corner = {id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)};
      p.width = widths[i];
      p.height = heights[j];
      layout.patches.push_back(p);
    }
  return layout;
}

PatchLayout make_polycube_layout(const std::vector<std::array<int, 3>>& voxels, const std::vector<int64_t>& dx,
                                 const std::vector<int64_t>& dy, const std::vector<int64_t>& dz,
                                 bool sharp_edges_are_features) {
  const int nx = static_cast<int>(dx.size()), ny = static_cast<int>(dy.size()), nz = static_cast<int>(dz.size());
  std::vector<char> filled(static_cast<size_t>(nx) * ny * nz, 0);
  auto cell = [&](int i, int j, int k) -> char {
    if (i < 0 || j < 0 || k < 0 || i >= nx || j >= ny || k >= nz) return 0;
    return filled[(static_cast<size_t>(k) * ny + j) * nx + i];
  };
  for (const auto& v : voxels) {
    if (v[0] < 0 || v[1] < 0 || v[2] < 0 || v[0] >= nx || v[1] >= ny || v[2] >= nz) bad_layout("voxel out of grid");
    filled[(static_cast<size_t>(v[2]) * ny + v[1]) * nx + v[0]] = 1;
  }
  auto vid = [&](int i, int j, int k) { return i + (nx + 1) * (j + (ny + 1) * k); };
  PatchLayout layout;
  std::vector<int> normal;  // per patch: axis * 2 + (positive ? 1 : 0)
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        if (!cell(i, j, k)) continue;
        auto add = [&](std::array<int, 4> c, int64_t w, int64_t h, int n) {
          layout.patches.push_back({c, w, h});
          normal.push_back(n);
        };
        if (!cell(i, j, k - 1))
          add({vid(i, j, k), vid(i, j + 1, k), vid(i + 1, j + 1, k), vid(i + 1, j, k)}, dy[j], dx[i], 4);
        if (!cell(i, j, k + 1))
          add({vid(i, j, k + 1), vid(i + 1, j, k + 1), vid(i + 1, j + 1, k + 1), vid(i, j + 1, k + 1)}, dx[i], dy[j],
              5);
        if (!cell(i, j - 1, k))
          add({vid(i, j, k), vid(i + 1, j, k), vid(i + 1, j, k + 1), vid(i, j, k + 1)}, dx[i], dz[k], 2);
        if (!cell(i, j + 1, k))
          add({vid(i, j + 1, k), vid(i, j + 1, k + 1), vid(i + 1, j + 1, k + 1), vid(i + 1, j + 1, k)}, dz[k], dx[i],
              3);
        if (!cell(i - 1, j, k))
          add({vid(i, j, k), vid(i, j, k + 1), vid(i, j + 1, k + 1), vid(i, j + 1, k)}, dz[k], dy[j], 0);
        if (!cell(i + 1, j, k))
          add({vid(i + 1, j, k), vid(i + 1, j + 1, k), vid(i + 1, j + 1, k + 1), vid(i + 1, j, k + 1)}, dy[j], dz[k],
              1);
      }
  if (sharp_edges_are_features) {
    const Gluing g = glue(layout);
    layout.feature_side.assign(4 * layout.patches.size(), 0);
    for (size_t p = 0; p < layout.patches.size(); ++p)
      for (int s = 0; s < 4; ++s) {
        const auto partner = g.partner[4 * p + s];
        layout.feature_side[4 * p + s] = partner[0] >= 0 && normal[partner[0]] != normal[p];
      }
  }
  return layout;
}

namespace {

// Checks that every corner's patches form one cycle (or one fan on the boundary).
bool corners_manifold(const PatchLayout& layout, const Gluing& g) {
  std::map<int, int> count;
  for (const auto& p : layout.patches)
    for (int c : p.corner) ++count[c];
  std::map<int, int> walked;
  for (size_t p0 = 0; p0 < layout.patches.size(); ++p0)
    for (int k0 = 0; k0 < 4; ++k0) {
      const int id = layout.patches[p0].corner[k0];
      if (walked.count(id)) continue;
      int n = 0, p = static_cast<int>(p0), k = k0;
      // Counter-clockwise: across side k-1 into the partner, at its corner `side`.
      for (;;) {
        ++n;
        const auto partner = g.partner[4 * p + (k + 3) % 4];
        if (partner[0] < 0 || (partner[0] == static_cast<int>(p0) && partner[1] == k0)) break;
        p = partner[0], k = partner[1];
        if (n > static_cast<int>(layout.patches.size()) * 4) return false;
      }
      walked[id] = n;
      // A boundary fan may start in the middle; count the clockwise part too.
      if (g.partner[4 * p + (k + 3) % 4][0] < 0) {
        int m = 0, pp = static_cast<int>(p0), kk = k0;
        for (;;) {
          const auto partner = g.partner[4 * pp + kk];
          if (partner[0] < 0) break;
          pp = partner[0], kk = (partner[1] + 1) % 4;
          ++m;
          if (m > static_cast<int>(layout.patches.size()) * 4) return false;
        }
        walked[id] = n + m;
      }
      if (walked[id] != count[id]) return false;
    }
  return true;
}

}  // namespace

std::vector<std::array<int, 3>> random_manifold_polycube(int count, int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::vector<std::array<int, 3>> voxels{{n / 2, n / 2, n / 2}};
  std::vector<int64_t> unit(n, 1);
  std::vector<char> filled(static_cast<size_t>(n) * n * n, 0);
  auto at = [&](const std::array<int, 3>& v) -> char& {
    return filled[(static_cast<size_t>(v[2]) * n + v[1]) * n + v[0]];
  };
  at(voxels[0]) = 1;
  const int dirs[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  for (int attempts = 0; static_cast<int>(voxels.size()) < count && attempts < 200 * count; ++attempts) {
    const auto& base = voxels[std::uniform_int_distribution<size_t>(0, voxels.size() - 1)(rng)];
    const auto& d = dirs[std::uniform_int_distribution<int>(0, 5)(rng)];
    const std::array<int, 3> v{base[0] + d[0], base[1] + d[1], base[2] + d[2]};
    if (v[0] < 0 || v[1] < 0 || v[2] < 0 || v[0] >= n || v[1] >= n || v[2] >= n || at(v)) continue;
    voxels.push_back(v);
    at(v) = 1;
    bool ok = true;
    try {
      const PatchLayout layout = make_polycube_layout(voxels, unit, unit, unit, false);
      ok = corners_manifold(layout, glue(layout));
    } catch (const Error&) {
      ok = false;
    }
    if (!ok) {
      voxels.pop_back();
      at(v) = 0;
    }
  }
  return voxels;
}

TMesh build_patch_tmesh(const PatchLayout& layout, int splits, unsigned seed) {
  // Cells: random splits of random cells (each side at least one tick).
  std::vector<PatchRect> rects;
  for (int p = 0; p < static_cast<int>(layout.patches.size()); ++p)
    rects.push_back({p, 0, 0, layout.patches[p].width, layout.patches[p].height});
  std::mt19937 rng(seed);
  for (int k = 0, attempts = 0; k < splits && attempts < 20 * splits + 100; ++attempts) {
    PatchRect& r = rects[std::uniform_int_distribution<size_t>(0, rects.size() - 1)(rng)];
    const int64_t w = r.u1 - r.u0, h = r.v1 - r.v0;
    int axis = std::uniform_real_distribution<double>(0, 1)(rng) < 0.7 ? (w >= h ? 0 : 1) : (w >= h ? 1 : 0);
    if ((axis == 0 ? w : h) < 2) axis = 1 - axis;
    if ((axis == 0 ? w : h) < 2) continue;
    const int64_t lo = axis == 0 ? r.u0 : r.v0, hi = axis == 0 ? r.u1 : r.v1;
    const int64_t at = std::uniform_int_distribution<int64_t>(lo + 1, hi - 1)(rng);
    PatchRect a = r, b = r;
    if (axis == 0)
      a.u1 = b.u0 = at;
    else
      a.v1 = b.v0 = at;
    r = a;
    rects.push_back(b);
    ++k;
  }
  return build_patch_tmesh(layout, rects);
}

TMesh build_patch_tmesh(const PatchLayout& layout, const std::vector<PatchRect>& cells) {
  const int P = static_cast<int>(layout.patches.size());
  if (P == 0) bad_layout("no patches");
  for (const auto& p : layout.patches)
    if (p.width < 1 || p.height < 1) bad_layout("patch sides must be at least one tick");
  const Gluing g = glue(layout);
  if (!corners_manifold(layout, g)) bad_layout("a corner is not manifold");
  std::vector<std::pair<int, Rect>> rects;
  std::vector<int64_t> covered(P, 0);
  for (const PatchRect& r : cells) {
    if (r.patch < 0 || r.patch >= P || r.u0 < 0 || r.v0 < 0 || r.u1 <= r.u0 || r.v1 <= r.v0 ||
        r.u1 > layout.patches[r.patch].width || r.v1 > layout.patches[r.patch].height)
      bad_layout("a cell rectangle is empty or outside its patch");
    rects.push_back({r.patch, {r.u0, r.v0, r.u1, r.v1}});
    covered[r.patch] += (r.u1 - r.u0) * (r.v1 - r.v0);
  }
  for (int p = 0; p < P; ++p)
    if (covered[p] != layout.patches[p].width * layout.patches[p].height)
      bad_layout("the cells of patch " + std::to_string(p) + " do not tile it");

  // Points on lines, per patch: horizontal lines v -> sorted u, vertical lines u -> sorted v.
  std::vector<std::map<int64_t, std::vector<int64_t>>> hline(P), vline(P);
  auto add_point = [&](int p, int64_t u, int64_t v) {
    hline[p][v].push_back(u);
    vline[p][u].push_back(v);
  };
  for (const auto& [p, r] : rects) {
    const std::array<std::array<int64_t, 2>, 4> corners{{{r.u0, r.v0}, {r.u1, r.v0}, {r.u1, r.v1}, {r.u0, r.v1}}};
    for (const auto& c : corners) {
      add_point(p, c[0], c[1]);
      for (const auto& [s, t] : sides_of(layout.patches[p], c[0], c[1])) {
        const auto partner = g.partner[4 * p + s];
        if (partner[0] < 0) continue;
        const auto& q = layout.patches[partner[0]];
        const auto pt = side_point(q, partner[1], side_length(q, partner[1]) - t);
        add_point(partner[0], pt[0], pt[1]);
      }
    }
  }
  for (auto* lines : {&hline, &vline})
    for (auto& patch_lines : *lines)
      for (auto& [coord, list] : patch_lines) {
        std::sort(list.begin(), list.end());
        list.erase(std::unique(list.begin(), list.end()), list.end());
      }

  // Nodes, keyed canonically: (2, corner id), (1, patch, side, t) minimal over the glued pair, or
  // (0, patch, u, v). The node's frame is the patch of its key (or a sector frame at corners).
  TMesh tm;
  std::map<std::array<int64_t, 4>, int> node_of;
  std::vector<std::array<int64_t, 4>> node_key;
  auto node_at = [&](int p, int64_t u, int64_t v) {
    const auto& patch = layout.patches[p];
    std::array<int64_t, 4> key;
    const auto sides = sides_of(patch, u, v);
    if (sides.size() == 2) {
      const int s = sides[0].first == 0 && sides[1].first == 3 ? 0 : sides[1].first;  // corner index
      key = {2, patch.corner[s], 0, 0};
    } else if (sides.size() == 1) {
      const auto [s, t] = sides[0];
      key = {1, p, s, t};
      const auto partner = g.partner[4 * p + s];
      if (partner[0] >= 0) {
        const std::array<int64_t, 4> other{1, partner[0], partner[1], side_length(patch, s) - t};
        key = std::min(key, other);
      }
    } else {
      key = {0, p, u, v};
    }
    const auto [it, inserted] = node_of.emplace(key, static_cast<int>(tm.nodes.size()));
    if (inserted) {
      tm.nodes.emplace_back();
      node_key.push_back(key);
    }
    return it->second;
  };

  // Edges, keyed canonically like nodes; created in the frame of the first cell that meets them.
  // A segment on a patch side is keyed by its side parameters (canonical over the gluing).
  auto segment_key = [&](int p, const std::array<int64_t, 2>& pa, const std::array<int64_t, 2>& pb, bool horizontal,
                         bool* boundary, bool* feature) {
    const auto& patch = layout.patches[p];
    const int64_t coord = horizontal ? pa[1] : pa[0];
    std::array<int64_t, 6> key{0, p, horizontal ? 0 : 1, coord, horizontal ? pa[0] : pa[1], horizontal ? pb[0] : pb[1]};
    for (const auto& [ps, ta] : sides_of(patch, pa[0], pa[1])) {
      bool on_side = false;
      int64_t tb = 0;
      for (const auto& [qs, t] : sides_of(patch, pb[0], pb[1]))
        if (qs == ps) on_side = true, tb = t;
      if (!on_side) continue;
      key = {1, p, ps, std::min(ta, tb), std::max(ta, tb), 0};
      const auto partner = g.partner[4 * p + ps];
      if (partner[0] < 0)
        *boundary = true;
      else {
        const int64_t L = side_length(patch, ps);
        key = std::min(
            key, std::array<int64_t, 6>{1, partner[0], partner[1], L - std::max(ta, tb), L - std::min(ta, tb), 0});
      }
      if (!layout.feature_side.empty() && layout.feature_side[4 * p + ps]) *feature = true;
    }
    return key;
  };
  std::map<std::array<int64_t, 6>, int> edge_of;
  std::vector<int> edge_patch;       // patch whose frame the edge's direction refers to
  std::vector<int> edge_first_slot;  // slot (0 left / 1 right) of the first cell
  tm.cells.resize(rects.size());
  for (size_t c = 0; c < rects.size(); ++c) {
    const auto& [p, r] = rects[c];
    for (int s = 0; s < 4; ++s) {
      const bool horizontal = s % 2 == 0;
      const int64_t coord = s == 0 ? r.v0 : s == 1 ? r.u1 : s == 2 ? r.v1 : r.u0;
      const int64_t lo = horizontal ? r.u0 : r.v0, hi = horizontal ? r.u1 : r.v1;
      const auto& list = (horizontal ? hline[p] : vline[p])[coord];
      std::vector<int64_t> pos(std::lower_bound(list.begin(), list.end(), lo),
                               std::upper_bound(list.begin(), list.end(), hi));
      if (s >= 2) std::reverse(pos.begin(), pos.end());  // counter-clockwise order
      for (size_t k = 0; k + 1 < pos.size(); ++k) {
        const int64_t a = std::min(pos[k], pos[k + 1]), b = std::max(pos[k], pos[k + 1]);
        const auto pa = horizontal ? std::array<int64_t, 2>{a, coord} : std::array<int64_t, 2>{coord, a};
        const auto pb = horizontal ? std::array<int64_t, 2>{b, coord} : std::array<int64_t, 2>{coord, b};
        bool boundary = false, feature = false;
        const auto key = segment_key(p, pa, pb, horizontal, &boundary, &feature);
        const auto [it, inserted] = edge_of.emplace(key, static_cast<int>(tm.edges.size()));
        const int e = it->second;
        const int slot = s < 2 ? 0 : 1;  // sides 0,1 run along +u/+v in this patch: left cell
        if (inserted) {
          TMeshEdge edge;
          edge.from = node_at(p, pa[0], pa[1]);
          edge.to = node_at(p, pb[0], pb[1]);
          edge.axis = horizontal ? 0 : 1;
          edge.length = static_cast<double>(b - a) * layout.unit;
          edge.on_feature = boundary || feature;
          edge.cells[slot] = static_cast<int>(c);
          tm.edges.push_back(edge);
          edge_patch.push_back(p);
          edge_first_slot.push_back(slot);
        } else {
          if (tm.edges[e].cells[1 - edge_first_slot[e]] != -1) bad_layout("an edge lies on more than two cells");
          tm.edges[e].cells[1 - edge_first_slot[e]] = static_cast<int>(c);
        }
        tm.cells[c].sides[s].push_back(e);
      }
    }
  }

  // Incidences. Rotation from the frame of patch q to that of patch p across glued sides:
  // side s of p (tangent direction s) meets side t of q reversed, so d_p = d_q + s - t - 2.
  auto rotation_between = [&](int q, int p, int node) -> int {
    if (q == p) return 0;
    const auto& key = node_key[node];
    // The node lies on side key[2] of patch key[1] == p; find the glued side of q.
    const auto partner = g.partner[4 * p + key[2]];
    if (partner[0] != q) bad_layout("inconsistent frames at a patch side");
    return static_cast<int>(((key[2] - partner[1] - 2) % 4 + 8) % 4);
  };
  const int N = static_cast<int>(tm.nodes.size());
  std::vector<std::vector<TMeshIncidence>> inc(N);
  std::vector<char> is_corner(N, 0);
  for (int n = 0; n < N; ++n) is_corner[n] = node_key[n][0] == 2;
  for (int e = 0; e < static_cast<int>(tm.edges.size()); ++e) {
    const TMeshEdge& edge = tm.edges[e];
    const int q = edge_patch[e], d = edge.axis;  // +u = 0, +v = 1 in q's frame
    for (int end = 0; end < 2; ++end) {
      const int n = end == 0 ? edge.from : edge.to;
      if (is_corner[n]) continue;
      const int frame = static_cast<int>(node_key[n][1]);
      const int dir = ((end == 0 ? d : d + 2) + rotation_between(q, frame, n)) % 4;
      inc[n].push_back({e, dir, end == 0});
    }
  }
  // Corners: walk the patches counter-clockwise; each contributes its edge along side k.
  std::vector<int> corner_index(N, 0);
  std::vector<char> corner_boundary(N, 0);
  std::vector<char> corner_done(N, 0);
  auto first_edge_on_side = [&](int p, int s) {
    const auto& patch = layout.patches[p];
    const bool horizontal = s % 2 == 0;
    const auto a = side_point(patch, s, 0);
    const int64_t coord = horizontal ? a[1] : a[0];
    const auto& list = (horizontal ? hline[p] : vline[p])[coord];
    const int64_t start = horizontal ? a[0] : a[1];
    const int64_t next = (s < 2) ? *std::upper_bound(list.begin(), list.end(), start)
                                 : *(std::lower_bound(list.begin(), list.end(), start) - 1);
    const auto b = horizontal ? std::array<int64_t, 2>{next, coord} : std::array<int64_t, 2>{coord, next};
    bool boundary = false, feature = false;
    const auto key = next > start ? segment_key(p, a, b, horizontal, &boundary, &feature)
                                  : segment_key(p, b, a, horizontal, &boundary, &feature);
    const auto it = edge_of.find(key);
    if (it == edge_of.end()) bad_layout("corner edge not found");
    return it->second;
  };
  for (int p0 = 0; p0 < P; ++p0)
    for (int k0 = 0; k0 < 4; ++k0) {
      const int n = node_at(p0, side_point(layout.patches[p0], k0, 0)[0], side_point(layout.patches[p0], k0, 0)[1]);
      if (corner_done[n]) continue;
      corner_done[n] = 1;
      // Start clockwise-most: go clockwise (across side k) until the boundary or back at start.
      int p = p0, k = k0;
      for (int guard = 0; guard < 4 * P; ++guard) {
        const auto partner = g.partner[4 * p + k];
        if (partner[0] < 0) {
          corner_boundary[n] = 1;
          break;
        }
        p = partner[0], k = (partner[1] + 1) % 4;
        if (p == p0 && k == k0) break;
      }
      const int ps = p, ks = k;
      std::vector<int> edges;
      int patches = 0;
      for (;;) {
        edges.push_back(first_edge_on_side(p, k));
        ++patches;
        const auto partner = g.partner[4 * p + (k + 3) % 4];
        if (partner[0] < 0) {
          edges.push_back(first_edge_on_side(p, (k + 3) % 4));
          break;
        }
        p = partner[0], k = partner[1];
        if (p == ps && k == ks) break;
      }
      const int index = corner_boundary[n] ? 2 - patches : 4 - patches;
      corner_index[n] = index;
      for (size_t i = 0; i < edges.size(); ++i) {
        const int e = edges[i];
        const int dir = index == 0 ? static_cast<int>((ks + i) % 4) : static_cast<int>(i);
        inc[n].push_back({e, dir, tm.edges[e].from == n});
      }
    }

  for (int n = 0; n < N; ++n) {
    TMeshNode& node = tm.nodes[n];
    auto& list = inc[n];
    if (!is_corner[n])
      std::sort(list.begin(), list.end(), [](const auto& a, const auto& b) { return a.direction < b.direction; });
    node.incidences = list;
    int feature_edges = 0, boundary_edges = 0;
    std::vector<int> feature_dirs;
    for (const auto& i : list) {
      if (tm.edges[i.edge].on_feature) ++feature_edges, feature_dirs.push_back(i.direction);
      if (tm.edges[i.edge].cells[0] < 0 || tm.edges[i.edge].cells[1] < 0) ++boundary_edges;
    }
    node.on_feature = feature_edges > 0;
    node.index = is_corner[n] ? corner_index[n] : 0;
    const bool curve_corner =
        feature_edges > 0 && (feature_edges != 2 || (node.index == 0 && (feature_dirs[0] + 2) % 4 != feature_dirs[1]));
    // Kinds as the tracer assigns them (tmesh/tmesh.h).
    if (node.index != 0 || curve_corner)
      node.kind = boundary_edges > 0 ? TMeshNode::Kind::BoundaryNode
                  : node.on_feature  ? TMeshNode::Kind::FeatureCorner
                                     : TMeshNode::Kind::Singularity;
    else
      node.kind = list.size() >= 4 ? TMeshNode::Kind::Crossing : TMeshNode::Kind::TJunction;
  }
  return tm;
}

}  // namespace qgp

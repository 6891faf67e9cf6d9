#include "core/sanitize_isolines.h"

#include <algorithm>
#include <cmath>
#include <climits>
#include <cstdlib>
#include <numeric>

#include "core/error.h"

namespace qgp {

namespace {

// Sparse integer linear expression: (variable, coefficient), sorted by variable.
using Expr = std::vector<std::pair<int, int64_t>>;

void add_scaled(Expr& acc, const Expr& e, int64_t scale) {
  Expr out;
  out.reserve(acc.size() + e.size());
  size_t i = 0, j = 0;
  while (i < acc.size() || j < e.size()) {
    if (j == e.size() || (i < acc.size() && acc[i].first < e[j].first)) {
      out.push_back(acc[i++]);
    } else if (i == acc.size() || e[j].first < acc[i].first) {
      out.push_back({e[j].first, e[j].second * scale});
      ++j;
    } else {
      const int64_t c = acc[i].second + e[j].second * scale;
      if (c != 0) out.push_back({acc[i].first, c});
      ++i, ++j;
    }
  }
  acc.swap(out);
}

Expr make_expr(std::vector<std::pair<int, int64_t>> terms) {
  std::sort(terms.begin(), terms.end());
  Expr out;
  for (const auto& t : terms) {
    if (!out.empty() && out.back().first == t.first) out.back().second += t.second;
    else out.push_back(t);
  }
  out.erase(std::remove_if(out.begin(), out.end(), [](const auto& t) { return t.second == 0; }), out.end());
  return out;
}

// Component `axis` of R^r (x, y) as a combination of x (index 0) and y (index 1): {which, sign}.
std::pair<int, int> rotated_component(int r, int axis) {
  switch (((r % 4) + 4) % 4) {
    case 0: return {axis, 1};
    case 1: return axis == 0 ? std::pair{1, -1} : std::pair{0, 1};   // (-y, x)
    case 2: return {axis, -1};
    default: return axis == 0 ? std::pair{1, 1} : std::pair{0, -1};  // (y, -x)
  }
}

// Rounding to the grid flips or collapses triangles whose height in the continuous map is below
// a few grid units (e.g. slivers of the input surface, mapped faithfully). Such a face is made
// positively oriented by moving one of its corners' wedges to a nearby grid point, provided the
// wedge is movable (no equation involves it, so every other value stays as it is) and the move
// keeps every positive face around it positive. All decisions are exact orientation tests;
// kMaxMove only bounds the search (in grid units, far below any parameter-space feature size).
void reorient_faces(const TriMesh& mesh, const std::vector<int>& wedge_of, const std::vector<char>& movable,
                    const std::vector<char>& target, std::vector<IVec2>& uv, SanitizeResult& result) {
  const int nf = mesh.num_faces();
  auto positive = [&](int f) { return orient2d_exact(uv[3 * f], uv[3 * f + 1], uv[3 * f + 2]) > 0; };
  std::vector<int> bad;
  for (int f = 0; f < nf; ++f)
    if (target[f] && !positive(f)) bad.push_back(f);
  if (bad.empty()) return;

  // Corners of each wedge (CSR).
  const int nw = static_cast<int>(movable.size());
  std::vector<int> start(nw + 1, 0), corners(wedge_of.size());
  for (int w : wedge_of) ++start[w + 1];
  for (int w = 0; w < nw; ++w) start[w + 1] += start[w];
  std::vector<int> fill(start.begin(), start.end() - 1);
  for (size_t c = 0; c < wedge_of.size(); ++c) corners[fill[wedge_of[c]]++] = static_cast<int>(c);

  // Grid offsets by increasing distance (ties in a fixed order).
  constexpr int kMaxMove = 16;
  std::vector<IVec2> offsets;
  for (int64_t dx = -kMaxMove; dx <= kMaxMove; ++dx)
    for (int64_t dy = -kMaxMove; dy <= kMaxMove; ++dy)
      if (dx != 0 || dy != 0) offsets.push_back({dx, dy});
  std::stable_sort(offsets.begin(), offsets.end(), [](const IVec2& a, const IVec2& b) {
    return a[0] * a[0] + a[1] * a[1] < b[0] * b[0] + b[1] * b[1];
  });

  // Moves wedge w so that face target becomes positive and no positive face of its star stops
  // being positive; returns whether such a grid point exists.
  std::vector<char> was_positive;
  auto move_wedge = [&](int w, int target) {
    const IVec2 base = uv[corners[start[w]]];
    was_positive.resize(start[w + 1] - start[w]);
    for (int i = start[w]; i < start[w + 1]; ++i) was_positive[i - start[w]] = positive(corners[i] / 3);
    for (const IVec2& d : offsets) {
      const IVec2 p = {base[0] + d[0], base[1] + d[1]};
      for (int i = start[w]; i < start[w + 1]; ++i) uv[corners[i]] = p;
      bool ok = positive(target);
      for (int i = start[w]; ok && i < start[w + 1]; ++i)
        ok = !was_positive[i - start[w]] || positive(corners[i] / 3);
      if (ok) return true;
    }
    for (int i = start[w]; i < start[w + 1]; ++i) uv[corners[i]] = base;
    return false;
  };

  const size_t initially = bad.size();
  for (bool changed = true; changed && !bad.empty();) {
    changed = false;
    std::vector<int> still;
    for (int f : bad) {
      if (positive(f)) continue;  // fixed by a move for another face
      bool fixed = false;
      for (int k = 0; k < 3 && !fixed; ++k)
        if (movable[wedge_of[3 * f + k]]) fixed = move_wedge(wedge_of[3 * f + k], f);
      if (fixed) changed = true;
      else still.push_back(f);
    }
    bad.swap(still);
  }
  result.non_positive_faces = static_cast<int>(bad.size());
  result.reoriented_faces = static_cast<int>(initially - bad.size());
}

}  // namespace

std::vector<IsolineConstraint> isoline_constraints(const TriMesh& mesh, const Parametrization& param,
                                                   const std::vector<char>& edges, bool include_boundary) {
  std::vector<IsolineConstraint> out;
  for (int e = 0; e < mesh.num_edges(); ++e) {
    const bool flagged = !edges.empty() && edges[e];
    if (!flagged && !(include_boundary && mesh.is_boundary_edge(e))) continue;
    const int h = mesh.edge_halfedge[e];
    const Vec2 d = param.corner(h / 3, (h % 3 + 1) % 3) - param.corner(h / 3, h % 3);
    out.push_back({h, std::fabs(d.x()) <= std::fabs(d.y()) ? 0 : 1});
  }
  return out;
}

SanitizeResult sanitize_with_isolines(const TriMesh& mesh, const Parametrization& param,
                                      const std::vector<IsolineConstraint>& isolines, const SanitizeOptions& options) {
  const int nf = mesh.num_faces(), nc = 3 * nf;
  if (param.uv.rows() != nc || static_cast<int>(param.rotation.size()) != nc)
    throw Error(ErrorCode::Internal, "sanitize: parametrization does not match the mesh");
  auto is_cut = [&](int h) {
    return (!param.is_cut.empty() && param.is_cut[mesh.edge_of[h]]) || param.rotation[h] % 4 != 0;
  };

  // Wedges: corners joined across non-cut interior edges.
  std::vector<int> parent(nc);
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (int h = 0; h < nc; ++h) {
    const int o = mesh.opposite[h];
    if (o < 0 || o < h || is_cut(h)) continue;
    parent[find(h)] = find(3 * (o / 3) + (o % 3 + 1) % 3);
    parent[find(3 * (h / 3) + (h % 3 + 1) % 3)] = find(o);
  }
  std::vector<int> wedge_of(nc), wedge_vertex, root_wedge(nc, -1);
  for (int c = 0; c < nc; ++c) {
    const int r = find(c);
    if (root_wedge[r] < 0) root_wedge[r] = static_cast<int>(wedge_vertex.size()), wedge_vertex.push_back(mesh.F(c / 3, c % 3));
    wedge_of[c] = root_wedge[r];
  }
  const int nw = static_cast<int>(wedge_vertex.size());

  // Unknowns: 2 per wedge (u, v), then 2 per cut edge translation. Continuous values and snapping.
  std::vector<double> value(2 * nw, 0);
  std::vector<int> count(nw, 0);
  for (int c = 0; c < nc; ++c) {
    value[2 * wedge_of[c]] += param.uv(c, 0);
    value[2 * wedge_of[c] + 1] += param.uv(c, 1);
    ++count[wedge_of[c]];
  }
  for (int w = 0; w < nw; ++w) value[2 * w] /= count[w], value[2 * w + 1] /= count[w];
  std::vector<char> snapped(2 * nw, 0);
  for (int w = 0; w < nw; ++w)
    if (!options.snap_vertex.empty() && options.snap_vertex[wedge_vertex[w]]) snapped[2 * w] = snapped[2 * w + 1] = 1;
  if (!options.snap_corner_axes.empty())
    for (int c = 0; c < nc; ++c)
      for (int a = 0; a < 2; ++a)
        if ((options.snap_corner_axes[c] >> a) & 1) snapped[2 * wedge_of[c] + a] = 1;
  std::vector<int> wedges_at_vertex(mesh.num_vertices(), 0);
  for (int w = 0; w < nw; ++w) ++wedges_at_vertex[wedge_vertex[w]];

  // Transition equations W_g - R^r W_f - T = 0 per endpoint of each cut edge, per coordinate;
  // those at singular vertices first, so that translations become their pivots.
  std::vector<int> holonomy(mesh.num_vertices(), 0);
  for (int h = 0; h < nc; ++h)
    if (mesh.opposite[h] >= 0) holonomy[mesh.to(h)] += param.rotation[h];
  std::vector<int> translation_var(nc, -1);
  std::vector<Expr> first, later;
  for (int h = 0; h < nc; ++h) {
    const int o = mesh.opposite[h];
    if (o < 0 || o < h || !is_cut(h)) continue;
    const int t = static_cast<int>(value.size());
    translation_var[h] = t;
    const Vec2 tr = param.translation(mesh, h);
    value.push_back(tr.x()), value.push_back(tr.y());
    const char snap_t = options.snap_vertex.empty() ? 0 : 1;
    snapped.push_back(snap_t), snapped.push_back(snap_t);
    const int f = h / 3, g = o / 3, r = param.rotation[h];
    const bool singular_end = holonomy[mesh.from(h)] % 4 != 0 || holonomy[mesh.to(h)] % 4 != 0;
    const int ends[2][2] = {{3 * f + h % 3, 3 * g + (o % 3 + 1) % 3}, {3 * f + (h % 3 + 1) % 3, 3 * g + o % 3}};
    for (const auto& end : ends)
      for (int a = 0; a < 2; ++a) {
        const auto [which, sgn] = rotated_component(r, a);
        Expr e = make_expr({{2 * wedge_of[end[1]] + a, 1}, {2 * wedge_of[end[0]] + which, -sgn}, {t + a, -1}});
        (singular_end ? first : later).push_back(std::move(e));
      }
  }
  std::vector<Expr> equations = std::move(first);
  for (const IsolineConstraint& iso : isolines) {
    const int h = iso.halfedge;
    if (h < 0 || h >= nc || iso.axis < 0 || iso.axis > 1)
      throw Error(ErrorCode::InvalidArgument, "sanitize: isoline constraint out of range");
    equations.push_back(make_expr({{2 * wedge_of[h] + iso.axis, 1}, {2 * wedge_of[TriMesh::next(h)] + iso.axis, -1}}));
  }
  for (Expr& e : later) equations.push_back(std::move(e));

  // Elimination with unit pivots; definition[x] expresses x by variables free at that time.
  std::vector<char> in_equation(value.size(), 0);  // unknowns that occur in some equation
  for (const Expr& eq : equations)
    for (const auto& term : eq) in_equation[term.first] = 1;
  std::vector<Expr> definition(value.size());
  std::vector<char> eliminated(value.size(), 0);
  std::vector<int> order;
  auto rank = [&](int var) {
    const int base = var < 2 * nw ? 10 + wedges_at_vertex[wedge_vertex[var / 2]] : 0;  // translations first
    return (snapped[var] ? 1000000 : 0) + base;
  };
  int unresolved = 0;
  for (Expr& eq : equations) {
    for (bool again = true; again;) {
      again = false;
      for (size_t i = 0; i < eq.size(); ++i) {
        if (!eliminated[eq[i].first]) continue;
        const auto term = eq[i];
        eq.erase(eq.begin() + static_cast<long>(i));
        add_scaled(eq, definition[term.first], term.second);
        again = true;
        break;
      }
    }
    if (eq.empty()) continue;  // implied by earlier equations
    int64_t common = 0;
    for (const auto& term : eq) common = std::gcd(common, std::abs(term.second));
    if (common > 1)
      for (auto& term : eq) term.second /= common;
    auto find_pivot = [&] {
      int pivot = -1;
      for (size_t i = 0; i < eq.size(); ++i)
        if (std::abs(eq[i].second) == 1 && (pivot < 0 || rank(eq[i].first) < rank(eq[pivot].first)))
          pivot = static_cast<int>(i);
      return pivot;
    };
    int pivot = find_pivot();
    // Fill-in can leave an equation without a unit coefficient (e.g. 2a + 3b = 0; coprime after
    // the division above). Then a unimodular change of variables makes one: with m the unsnapped
    // unknown of smallest |coefficient| c_m, x_m = y - sum_j q_j x_j (y a new free unknown,
    // q_j = c_j / c_m rounded) leaves coefficients c_j - q_j c_m of magnitude <= |c_m| / 2, not
    // all zero as their gcd is 1; repeated, a unit coefficient appears.
    // Only unsnapped unknowns change, so the smallest unsnapped |coefficient| must drop every
    // round; when it does not (the rest is snapped), the equation stays unresolved.
    for (int64_t smallest = INT64_MAX; pivot < 0 && eq.size() >= 2;) {
      int m = -1;
      for (size_t i = 0; i < eq.size(); ++i)
        if (!snapped[eq[i].first] && (m < 0 || std::abs(eq[i].second) < std::abs(eq[m].second))) m = static_cast<int>(i);
      if (m < 0 || std::abs(eq[m].second) >= smallest) break;
      smallest = std::abs(eq[m].second);
      const auto [xm, cm] = eq[m];
      const int y = static_cast<int>(value.size());
      Expr def;  // x_m = y - sum_j q_j x_j
      double y_value = value[xm];
      for (const auto& [xj, cj] : eq) {
        if (xj == xm) continue;
        const int64_t q = (cj >= 0 ? cj + std::abs(cm) / 2 : cj - std::abs(cm) / 2) / cm;  // nearest
        if (q == 0) continue;
        def.push_back({xj, -q});
        y_value += static_cast<double>(q) * value[xj];
      }
      def.push_back({y, 1});
      value.push_back(y_value);
      snapped.push_back(0);
      in_equation.push_back(1);
      eliminated.push_back(0);
      definition.push_back({});
      Expr rest;
      for (const auto& term : eq)
        if (term.first != xm) rest.push_back(term);
      add_scaled(rest, def, cm);
      definition[xm] = std::move(def);
      eliminated[xm] = 1;
      order.push_back(xm);
      eq.swap(rest);
      pivot = find_pivot();
    }
    if (pivot < 0) {
      ++unresolved;
      continue;
    }
    const int var = eq[pivot].first;
    const int64_t inv = -eq[pivot].second;  // x = -(rest) / c with c = +-1
    Expr def;
    for (const auto& term : eq)
      if (term.first != var) def.push_back({term.first, term.second * inv});
    definition[var] = std::move(def);
    eliminated[var] = 1;
    order.push_back(var);
  }

  // Round the free unknowns, then back-substitute.
  SanitizeResult result;
  ExactParametrization& ex = result.param;
  ex.fraction_bits = options.fraction_bits;
  const double scale = std::ldexp(1.0, options.fraction_bits);
  const int64_t snap_unit = int64_t(1) << std::max(0, options.fraction_bits - options.snap_bits);
  const int nvars = static_cast<int>(value.size());
  std::vector<int64_t> exact(nvars, 0);
  for (int x = 0; x < nvars; ++x) {
    if (eliminated[x]) continue;
    exact[x] = snapped[x] ? static_cast<int64_t>(std::llround(value[x] * scale / snap_unit)) * snap_unit
                          : static_cast<int64_t>(std::llround(value[x] * scale));
  }
  for (auto it = order.rbegin(); it != order.rend(); ++it) {
    int64_t sum = 0;
    for (const auto& term : definition[*it]) sum += term.second * exact[term.first];
    exact[*it] = sum;
  }
  ex.uv.resize(nc);
  for (int c = 0; c < nc; ++c) ex.uv[c] = {exact[2 * wedge_of[c]], exact[2 * wedge_of[c] + 1]};
  std::vector<char> movable(nw, 0);  // wedges no equation and no snapping ties to anything else
  for (int w = 0; w < nw; ++w)
    movable[w] = !in_equation[2 * w] && !in_equation[2 * w + 1] && !snapped[2 * w] && !snapped[2 * w + 1];
  // Faces to keep positive: those positive in the continuous map (flips there are the solver's
  // to report; this only limits the search, every outcome is decided by exact tests).
  std::vector<char> target(nf, 0);
  for (int f = 0; f < nf; ++f) {
    const Vec2 a = param.corner(f, 0), b = param.corner(f, 1), c = param.corner(f, 2);
    target[f] = (b - a).x() * (c - a).y() - (b - a).y() * (c - a).x() > 0;
  }
  reorient_faces(mesh, wedge_of, movable, target, ex.uv, result);
  if (result.non_positive_faces > 0) {
    // Faces still not positive have a corner tied to others by equations (cuts, isolines). Move
    // one unsnapped free unknown the corner depends on, together with everything that depends on
    // it (so every equation still holds), by up to kMaxShift grid units; accept when the face
    // becomes positive and no positive face touched stops being so.
    constexpr int64_t kMaxShift = 16;
    std::vector<std::vector<int>> corners_of(nw);
    for (int c = 0; c < nc; ++c) corners_of[wedge_of[c]].push_back(c);
    auto positive = [&](int f) { return orient2d_exact(ex.uv[3 * f], ex.uv[3 * f + 1], ex.uv[3 * f + 2]) > 0; };
    std::vector<int64_t> k(nvars, 0);
    std::vector<char> seen(nvars, 0);
    int fixed = 0, still = 0;
    for (int f = 0; f < nf; ++f) {
      if (!target[f] || positive(f)) continue;
      // Free unknowns the face's corners depend on.
      std::vector<int> stack, candidates, touched;
      for (int j = 0; j < 3; ++j)
        for (int a = 0; a < 2; ++a) stack.push_back(2 * wedge_of[3 * f + j] + a);
      while (!stack.empty()) {
        const int x = stack.back();
        stack.pop_back();
        if (seen[x]) continue;
        seen[x] = 1;
        touched.push_back(x);
        if (!eliminated[x]) {
          if (!snapped[x]) candidates.push_back(x);
          continue;
        }
        for (const auto& term : definition[x]) stack.push_back(term.first);
      }
      for (int x : touched) seen[x] = 0;
      bool done = false;
      for (size_t ci = 0; ci < candidates.size() && !done; ++ci) {
        // k[x] = d x / d y for y = candidates[ci] (back-substitution order).
        std::fill(k.begin(), k.end(), 0);
        const int y = candidates[ci];
        k[y] = 1;
        for (auto it = order.rbegin(); it != order.rend(); ++it) {
          int64_t sum = 0;
          for (const auto& term : definition[*it]) sum += term.second * k[term.first];
          k[*it] = sum;
        }
        bool keeps_snapping = true;
        for (int x = 0; x < nvars && keeps_snapping; ++x) keeps_snapping = !(snapped[x] && k[x] != 0);
        if (!keeps_snapping) continue;
        std::vector<int> faces, moved_corners;
        for (int w = 0; w < nw; ++w)
          if (k[2 * w] != 0 || k[2 * w + 1] != 0)
            for (int c : corners_of[w]) moved_corners.push_back(c), faces.push_back(c / 3);
        std::sort(faces.begin(), faces.end());
        faces.erase(std::unique(faces.begin(), faces.end()), faces.end());
        std::vector<char> was_positive(faces.size());
        for (size_t i = 0; i < faces.size(); ++i) was_positive[i] = positive(faces[i]);
        for (int64_t step = 1; step <= 2 * kMaxShift && !done; ++step) {
          const int64_t d = (step + 1) / 2 * (step % 2 ? 1 : -1);  // 1, -1, 2, -2, ...
          for (int c : moved_corners) {
            const int w = wedge_of[c];
            ex.uv[c] = {exact[2 * w] + k[2 * w] * d, exact[2 * w + 1] + k[2 * w + 1] * d};
          }
          bool ok = positive(f);
          for (size_t i = 0; i < faces.size() && ok; ++i) ok = !was_positive[i] || positive(faces[i]);
          if (ok) {
            for (int x = 0; x < nvars; ++x) exact[x] += k[x] * d;
            done = true;
          }
        }
        if (!done)
          for (int c : moved_corners) ex.uv[c] = {exact[2 * wedge_of[c]], exact[2 * wedge_of[c] + 1]};
      }
      (done ? fixed : still) += 1;
    }
    result.reoriented_faces += fixed;
    result.non_positive_faces = still;
  }
  for (int c = 0; c < nc; ++c)
    for (int a = 0; a < 2; ++a)
      result.max_change = std::max(result.max_change, std::fabs(ex.uv[c][a] / scale - param.uv(c, a)));
  ex.rotation = param.rotation;
  ex.translation.assign(nc, {0, 0});
  ex.is_cut.assign(mesh.num_edges(), 0);
  for (int h = 0; h < nc; ++h) {
    if (translation_var[h] < 0) continue;
    const int o = mesh.opposite[h];
    ex.translation[h] = {exact[translation_var[h]], exact[translation_var[h] + 1]};
    ex.translation[o] = rotate_quarter(IVec2{-ex.translation[h][0], -ex.translation[h][1]}, -param.rotation[h]);
    ex.is_cut[mesh.edge_of[h]] = 1;
  }
  result.unresolved_equations = unresolved;
  return result;
}

}  // namespace qgp

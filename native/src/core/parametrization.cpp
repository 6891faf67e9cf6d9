#include "core/parametrization.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <cstdio>
#include <cstdlib>

#include "core/error.h"

namespace qgp {

Vec2 Parametrization::translation(const TriMesh& mesh, int h) const {
  const int o = mesh.opposite[h];
  const int f = h / 3, g = o / 3;
  // from(h) is corner h%3 of f and corner (o%3 + 1) % 3 of g.
  const Vec2 pf = corner(f, h % 3), pg = corner(g, (o % 3 + 1) % 3);
  return pg - rotate_quarter(pf, rotation[h]);
}

double max_transition_residual(const TriMesh& mesh, const Parametrization& param) {
  double worst = 0;
  for (int h = 0; h < mesh.num_halfedges(); ++h) {
    const int o = mesh.opposite[h];
    if (o < 0 || o < h) continue;
    const Vec2 t = param.translation(mesh, h);
    const Vec2 pf = param.corner(h / 3, (h % 3 + 1) % 3), pg = param.corner(o / 3, o % 3);
    worst = std::max(worst, (rotate_quarter(pf, param.rotation[h]) + t - pg).cwiseAbs().maxCoeff());
  }
  return worst;
}

std::vector<double> parametric_areas(const Parametrization& param) {
  const int nf = static_cast<int>(param.uv.rows() / 3);
  std::vector<double> area(nf);
  for (int f = 0; f < nf; ++f) {
    const Vec2 a = param.corner(f, 0), b = param.corner(f, 1), c = param.corner(f, 2);
    area[f] = 0.5 * ((b - a).x() * (c - a).y() - (b - a).y() * (c - a).x());
  }
  return area;
}

Parametrization ExactParametrization::to_double() const {
  Parametrization p;
  p.uv.resize(static_cast<int>(uv.size()), 2);
  for (size_t c = 0; c < uv.size(); ++c) p.uv.row(c) = Vec2(to_double(uv[c][0]), to_double(uv[c][1])).transpose();
  p.rotation = rotation;
  p.is_cut = is_cut;
  return p;
}

int orient2d_exact(const IVec2& a, const IVec2& b, const IVec2& c) {
  const __int128 bx = static_cast<__int128>(b[0]) - a[0], by = static_cast<__int128>(b[1]) - a[1];
  const __int128 cx = static_cast<__int128>(c[0]) - a[0], cy = static_cast<__int128>(c[1]) - a[1];
  const __int128 d = bx * cy - by * cx;
  return (d > 0) - (d < 0);
}

double exact_corner_angle(const ExactParametrization& param, int c) {
  const int f = c / 3, k = c % 3;
  const IVec2 &p = param.uv[c], &a = param.uv[3 * f + (k + 1) % 3], &b = param.uv[3 * f + (k + 2) % 3];
  const double ax = a[0] - p[0], ay = a[1] - p[1], bx = b[0] - p[0], by = b[1] - p[1];
  return std::atan2(ax * by - ay * bx, ax * bx + ay * by);
}

std::vector<int> exact_angle_sums(const TriMesh& mesh, const ExactParametrization& param) {
  std::vector<double> angle(mesh.num_vertices(), 0);
  for (int c = 0; c < 3 * mesh.num_faces(); ++c) angle[mesh.F(c / 3, c % 3)] += exact_corner_angle(param, c);
  std::vector<int> turns(angle.size());
  for (size_t v = 0; v < angle.size(); ++v) turns[v] = static_cast<int>(std::lround(angle[v] / (M_PI / 2)));
  return turns;
}

int64_t exact_transition_residual(const TriMesh& mesh, const ExactParametrization& param) {
  int64_t worst = 0;
  for (int h = 0; h < mesh.num_halfedges(); ++h) {
    const int o = mesh.opposite[h];
    if (o < 0) continue;
    const int f = h / 3, g = o / 3;
    const IVec2 pairs[2][2] = {{param.corner(f, h % 3), param.corner(g, (o % 3 + 1) % 3)},
                               {param.corner(f, (h % 3 + 1) % 3), param.corner(g, o % 3)}};
    for (const auto& p : pairs) {
      const IVec2 q = param.transfer(h, p[0]);
      worst = std::max({worst, std::abs(q[0] - p[1][0]), std::abs(q[1] - p[1][1])});
    }
  }
  return worst;
}

// ---------------------------------------------------------------------------------------------
// Sanitization by exact elimination over the Gaussian integers: a 2D value (u,v) is the complex
// number u + iv, a rotation by r quarter turns is multiplication by i^r. Unknowns are one value
// per wedge (corners of a vertex joined through non-cut edges) and one translation per cut edge.
// Each cut edge gives, per endpoint x, the equation  W_g(x) - i^r W_f(x) - T_e = 0.
// Pivots always have a unit coefficient (+-1, +-i), so every derived value is an integer
// combination of rounded free values and all equations hold exactly.
namespace {

struct Gauss {
  int64_t re = 0, im = 0;
  bool zero() const { return re == 0 && im == 0; }
  bool unit() const { return (std::abs(re) + std::abs(im)) == 1; }
};
Gauss operator*(Gauss a, Gauss b) { return {a.re * b.re - a.im * b.im, a.re * b.im + a.im * b.re}; }
Gauss operator+(Gauss a, Gauss b) { return {a.re + b.re, a.im + b.im}; }
Gauss operator-(Gauss a) { return {-a.re, -a.im}; }
Gauss unit_inverse(Gauss u) { return {u.re, -u.im}; }  // for units the inverse is the conjugate
Gauss power_of_i(int r) {
  switch (((r % 4) + 4) % 4) {
    case 0: return {1, 0};
    case 1: return {0, 1};
    case 2: return {-1, 0};
    default: return {0, -1};
  }
}

int64_t norm(Gauss a) { return a.re * a.re + a.im * a.im; }
int64_t round_div(int64_t a, int64_t b) {  // nearest integer to a / b, b > 0
  return a >= 0 ? (2 * a + b) / (2 * b) : -((-2 * a + b) / (2 * b));
}
// Exact quotient if b divides a (rounded otherwise).
Gauss divide(Gauss a, Gauss b) {
  const Gauss num = a * Gauss{b.re, -b.im};
  const int64_t n = norm(b);
  return {round_div(num.re, n), round_div(num.im, n)};
}
Gauss gcd(Gauss a, Gauss b) {
  while (!b.zero()) {
    const Gauss q = divide(a, b);
    const Gauss r = a + -(q * b);
    a = b;
    b = r;
  }
  return a;
}

using Expr = std::vector<std::pair<int, Gauss>>;  // sorted by variable

void add_scaled(Expr& acc, const Expr& e, Gauss scale) {
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
      const Gauss c = acc[i].second + e[j].second * scale;
      if (!c.zero()) out.push_back({acc[i].first, c});
      ++i;
      ++j;
    }
  }
  acc.swap(out);
}

}  // namespace

SanitizeResult sanitize_parametrization(const TriMesh& mesh, const Parametrization& param,
                                        const SanitizeOptions& options) {
  const int nf = mesh.num_faces(), nc = 3 * nf;
  if (param.uv.rows() != nc || static_cast<int>(param.rotation.size()) != nc)
    throw Error(ErrorCode::Internal, "sanitize: parametrization does not match the mesh");
  auto is_cut = [&](int h) {
    const int e = mesh.edge_of[h];
    return (!param.is_cut.empty() && param.is_cut[e]) || param.rotation[h] % 4 != 0;
  };

  // Wedges: union corners across non-cut interior edges.
  std::vector<int> parent(nc);
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (int h = 0; h < nc; ++h) {
    const int o = mesh.opposite[h];
    if (o < 0 || o < h || is_cut(h)) continue;
    const int f = h / 3, g = o / 3;
    parent[find(3 * f + h % 3)] = find(3 * g + (o % 3 + 1) % 3);
    parent[find(3 * f + (h % 3 + 1) % 3)] = find(3 * g + o % 3);
  }
  std::vector<int> wedge_of(nc), wedge_vertex;
  std::vector<int> root_wedge(nc, -1);
  for (int c = 0; c < nc; ++c) {
    const int r = find(c);
    if (root_wedge[r] < 0) {
      root_wedge[r] = static_cast<int>(wedge_vertex.size());
      wedge_vertex.push_back(mesh.F(c / 3, c % 3));
    }
    wedge_of[c] = root_wedge[r];
  }
  const int nw = static_cast<int>(wedge_vertex.size());

  // Variables: wedges [0, nw), then one translation per cut halfedge pair.
  std::vector<std::array<double, 2>> value(nw, {0, 0});
  std::vector<int> wedge_count(nw, 0);
  for (int c = 0; c < nc; ++c) {
    value[wedge_of[c]][0] += param.uv(c, 0);
    value[wedge_of[c]][1] += param.uv(c, 1);
    ++wedge_count[wedge_of[c]];
  }
  for (int w = 0; w < nw; ++w) value[w] = {value[w][0] / wedge_count[w], value[w][1] / wedge_count[w]};
  std::vector<int> translation_var(nc, -1);
  std::vector<char> snapped(nw, 0);
  std::vector<uint8_t> snap_axes(nw, 0);
  for (int w = 0; w < nw; ++w)
    if (!options.snap_vertex.empty() && options.snap_vertex[wedge_vertex[w]]) snapped[w] = 1, snap_axes[w] = 3;
  if (!options.snap_corner_axes.empty())
    for (int c = 0; c < nc; ++c) snap_axes[wedge_of[c]] |= options.snap_corner_axes[c];

  // Equations at singular vertices (non-zero rotation around them) go first: there the wedge
  // coefficient (1 - i^k) is no unit, so the translations must be the pivots.
  std::vector<int> holonomy(mesh.num_vertices(), 0);
  for (int h = 0; h < nc; ++h)
    if (mesh.opposite[h] >= 0) holonomy[mesh.to(h)] += param.rotation[h];  // crossing prev(h')
  std::vector<int> halfedge_order;
  for (int pass = 0; pass < 2; ++pass)
    for (int h = 0; h < nc; ++h) {
      const bool singular_end = holonomy[mesh.from(h)] % 4 != 0 || holonomy[mesh.to(h)] % 4 != 0;
      if (singular_end == (pass == 0)) halfedge_order.push_back(h);
    }
  std::vector<Expr> equations;
  for (int h : halfedge_order) {
    const int o = mesh.opposite[h];
    if (o < 0 || o < h || !is_cut(h)) continue;
    const int t = static_cast<int>(value.size());
    value.push_back({0, 0});
    snapped.push_back(options.snap_vertex.empty() ? 0 : 1);  // translations integral with snapping
    snap_axes.push_back(options.snap_vertex.empty() ? 0 : 3);
    translation_var[h] = t;
    const Vec2 tr = param.translation(mesh, h);
    value[t] = {tr.x(), tr.y()};
    const int f = h / 3, g = o / 3;
    const int ends[2][2] = {{3 * f + h % 3, 3 * g + (o % 3 + 1) % 3}, {3 * f + (h % 3 + 1) % 3, 3 * g + o % 3}};
    for (const auto& end : ends) {
      Expr e = {{wedge_of[end[1]], Gauss{1, 0}}, {wedge_of[end[0]], -power_of_i(param.rotation[h])},
                {t, Gauss{-1, 0}}};
      std::sort(e.begin(), e.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
      // Merge duplicates (a wedge on both sides of a cut at a singular leaf).
      Expr merged;
      for (const auto& term : e) {
        if (!merged.empty() && merged.back().first == term.first) merged.back().second = merged.back().second + term.second;
        else merged.push_back(term);
      }
      merged.erase(std::remove_if(merged.begin(), merged.end(), [](const auto& x) { return x.second.zero(); }),
                   merged.end());
      equations.push_back(std::move(merged));
    }
  }

  // Gaussian elimination with unit pivots. definition[v] expresses an eliminated variable in
  // terms of variables that were free when it was eliminated.
  const int nvars = static_cast<int>(value.size());
  std::vector<Expr> definition(nvars);
  std::vector<char> eliminated(nvars, 0);
  std::vector<int> order;
  // Vertex wedge counts: prefer pivots at vertices with few wedges (arc interiors).
  std::vector<int> wedges_at_vertex(mesh.num_vertices(), 0);
  for (int w = 0; w < nw; ++w) ++wedges_at_vertex[wedge_vertex[w]];
  auto pivot_rank = [&](int var) {
    const int snap = snapped[var] || snap_axes[var] ? 1 : 0;
    const int crowd = var < nw ? wedges_at_vertex[wedge_vertex[var]] : 1;
    return snap * 1000000 + crowd;
  };
  int unresolved = 0;
  for (Expr& eq : equations) {
    // Substitute eliminated variables until only free ones remain.
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
    if (eq.empty()) continue;  // redundant (e.g. the loop closing around a regular vertex)
    // A common non-unit factor (e.g. 1+i on the closing relation of singularity positions on a
    // sphere) does not change the solutions; dividing it out exposes unit pivots.
    Gauss common = eq[0].second;
    for (const auto& term : eq) common = gcd(common, term.second);
    if (!common.unit())
      for (auto& term : eq) term.second = divide(term.second, common);
    int pivot = -1;
    for (const auto& term : eq)
      if (term.second.unit() && (pivot < 0 || pivot_rank(term.first) < pivot_rank(eq[pivot].first)))
        pivot = static_cast<int>(&term - eq.data());
    if (pivot < 0) {
      if (getenv("QGP_DEBUG_SANITIZE")) {
        for (const auto& term : eq)
          fprintf(stderr, "  var %d (%s vertex %d) coef %lld%+lldi\n", term.first, term.first < nw ? "wedge" : "transl",
                  term.first < nw ? wedge_vertex[term.first] : -1, (long long)term.second.re, (long long)term.second.im);
        fprintf(stderr, "--\n");
      }
      ++unresolved;
      continue;
    }
    const int var = eq[pivot].first;
    const Gauss inv = -unit_inverse(eq[pivot].second);
    Expr def;
    for (const auto& term : eq)
      if (term.first != var) def.push_back({term.first, term.second * inv});
    definition[var] = std::move(def);
    eliminated[var] = 1;
    order.push_back(var);
  }

  SanitizeResult result;
  ExactParametrization& ex = result.param;
  ex.fraction_bits = options.fraction_bits;
  const double scale = std::ldexp(1.0, options.fraction_bits);
  const int64_t snap_unit = int64_t(1) << std::max(0, options.fraction_bits - options.snap_bits);
  std::vector<IVec2> exact(nvars);
  for (int v = 0; v < nvars; ++v) {
    if (eliminated[v]) continue;
    for (int a = 0; a < 2; ++a) {
      if ((snap_axes[v] >> a) & 1) {
        exact[v][a] = static_cast<int64_t>(std::llround(value[v][a] * scale / snap_unit)) * snap_unit;
      } else {
        exact[v][a] = static_cast<int64_t>(std::llround(value[v][a] * scale));
      }
    }
  }
  for (auto it = order.rbegin(); it != order.rend(); ++it) {
    Gauss sum{0, 0};
    for (const auto& term : definition[*it]) sum = sum + term.second * Gauss{exact[term.first][0], exact[term.first][1]};
    exact[*it] = {sum.re, sum.im};
  }
  ex.uv.resize(nc);
  for (int c = 0; c < nc; ++c) {
    ex.uv[c] = exact[wedge_of[c]];
    for (int a = 0; a < 2; ++a)
      result.max_change = std::max(result.max_change, std::abs(ex.uv[c][a] / scale - param.uv(c, a)));
  }
  ex.rotation = param.rotation;
  ex.translation.assign(nc, {0, 0});
  for (int h = 0; h < nc; ++h) {
    if (translation_var[h] < 0) continue;
    const int o = mesh.opposite[h];
    ex.translation[h] = exact[translation_var[h]];
    // The opposite transition is the inverse: p_f = i^-r (p_g - t).
    const IVec2 back = rotate_quarter(IVec2{-ex.translation[h][0], -ex.translation[h][1]}, -param.rotation[h]);
    ex.translation[o] = back;
  }
  ex.is_cut.assign(mesh.num_edges(), 0);
  for (int h = 0; h < nc; ++h)
    if (translation_var[h] >= 0) ex.is_cut[mesh.edge_of[h]] = 1;
  result.unresolved_equations = unresolved;
  return result;
}

}  // namespace qgp

#include "core/parametrization.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numeric>

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

// Cut equations W_g(x) - i^r W_f(x) - T_e = 0 of one cut edge, at both its endpoints: one term per
// variable, sorted, merged.
Expr cut_equation(int wedge_g, int wedge_f, int rotation, int t) {
  Expr e = {{wedge_g, Gauss{1, 0}}, {wedge_f, -power_of_i(rotation)}, {t, Gauss{-1, 0}}};
  std::sort(e.begin(), e.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  // Merge duplicates (a wedge on both sides of a cut at a singular leaf).
  Expr merged;
  for (const auto& term : e) {
    if (!merged.empty() && merged.back().first == term.first)
      merged.back().second = merged.back().second + term.second;
    else
      merged.push_back(term);
  }
  merged.erase(std::remove_if(merged.begin(), merged.end(), [](const auto& x) { return x.second.zero(); }),
               merged.end());
  return merged;
}

// State of one sanitize_parametrization solve: wedges, Gaussian-integer variables (wedges
// [0, nw), then one translation per cut halfedge pair), the cut equations, their elimination with
// unit pivots and the rounded exact map.
class GaussianSanitizer {
 public:
  // Checks that param matches the mesh (throws Error(Internal) otherwise).
  GaussianSanitizer(const TriMesh& mesh, const Parametrization& param, const SanitizeOptions& options);
  // Runs every phase; returns the exact map whose transitions hold exactly.
  SanitizeResult run();

 private:
  // Whether the charts of the faces of halfedge h may disagree (cut edge or rotation).
  bool is_cut(int h) const;
  // Fills wedge_of_ / wedge_vertex_: corners joined across non-cut interior edges.
  void build_wedges();
  // Continuous value of each wedge (mean of its corners) and its snapping.
  void init_wedge_variables();
  // All halfedges, those with an endpoint at a singular vertex first.
  std::vector<int> singular_first_halfedges() const;
  // Translation variables of the cut edges and their equations, in elimination order.
  void build_equations();
  // Pivot preference of a variable (lower first): few wedges at its vertex; snapped ones last.
  int pivot_rank(int var) const;
  // Eliminates every equation in turn, recording definitions (or counting it unresolved).
  void eliminate();
  // Eliminates one equation: substitution, division by a common factor, pivot choice.
  void eliminate_equation(Expr& eq);
  // Replaces eliminated variables in eq by their definitions until only free ones remain.
  void substitute_eliminated(Expr& eq) const;
  // Prints an equation without a unit pivot to stderr when QGP_DEBUG_SANITIZE is set.
  void report_unresolved(const Expr& eq) const;
  // Rounds the free variables to the grid (snapped axes to snap units), then back-substitutes.
  void round_and_back_substitute();
  // Corners, max_change, the exact transitions and cut flags of the result.
  void finish();

  const TriMesh& mesh_;
  const Parametrization& param_;
  const SanitizeOptions& options_;
  const int nf_, nc_;
  std::vector<int> wedge_of_, wedge_vertex_;
  int nw_ = 0;
  std::vector<std::array<double, 2>> value_;  // continuous value of each variable
  std::vector<int> translation_var_;          // per halfedge: its translation variable, or -1
  std::vector<char> snapped_;
  std::vector<uint8_t> snap_axes_;  // bit 0 = u, bit 1 = v rounded to snap units
  std::vector<Expr> equations_;
  std::vector<Expr> definition_;  // definition[v]: v in terms of variables free when eliminated
  std::vector<char> eliminated_;
  std::vector<int> order_;  // eliminated variables in elimination order
  std::vector<int> wedges_at_vertex_;
  int unresolved_ = 0;
  double scale_ = 1;          // grid units per parameter unit
  std::vector<IVec2> exact_;  // exact value of every variable
  SanitizeResult result_;
};

GaussianSanitizer::GaussianSanitizer(const TriMesh& mesh, const Parametrization& param, const SanitizeOptions& options)
    : mesh_(mesh), param_(param), options_(options), nf_(mesh.num_faces()), nc_(3 * mesh.num_faces()) {
  if (param.uv.rows() != nc_ || static_cast<int>(param.rotation.size()) != nc_)
    throw Error(ErrorCode::Internal, "sanitize: parametrization does not match the mesh");
}

SanitizeResult GaussianSanitizer::run() {
  build_wedges();
  init_wedge_variables();
  build_equations();
  eliminate();
  round_and_back_substitute();
  finish();
  return std::move(result_);
}

bool GaussianSanitizer::is_cut(int h) const {
  const int e = mesh_.edge_of[h];
  return (!param_.is_cut.empty() && param_.is_cut[e]) || param_.rotation[h] % 4 != 0;
}

void GaussianSanitizer::build_wedges() {
  // Wedges: union corners across non-cut interior edges.
  std::vector<int> parent(nc_);
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (int h = 0; h < nc_; ++h) {
    const int o = mesh_.opposite[h];
    if (o < 0 || o < h || is_cut(h)) continue;
    const int f = h / 3, g = o / 3;
    parent[find(3 * f + h % 3)] = find(3 * g + (o % 3 + 1) % 3);
    parent[find(3 * f + (h % 3 + 1) % 3)] = find(3 * g + o % 3);
  }
  wedge_of_.assign(nc_, 0);
  std::vector<int> root_wedge(nc_, -1);
  for (int c = 0; c < nc_; ++c) {
    const int r = find(c);
    if (root_wedge[r] < 0) {
      root_wedge[r] = static_cast<int>(wedge_vertex_.size());
      wedge_vertex_.push_back(mesh_.F(c / 3, c % 3));
    }
    wedge_of_[c] = root_wedge[r];
  }
  nw_ = static_cast<int>(wedge_vertex_.size());
}

void GaussianSanitizer::init_wedge_variables() {
  // Variables: wedges [0, nw), then one translation per cut halfedge pair.
  value_.assign(nw_, {0, 0});
  std::vector<int> wedge_count(nw_, 0);
  for (int c = 0; c < nc_; ++c) {
    value_[wedge_of_[c]][0] += param_.uv(c, 0);
    value_[wedge_of_[c]][1] += param_.uv(c, 1);
    ++wedge_count[wedge_of_[c]];
  }
  for (int w = 0; w < nw_; ++w) value_[w] = {value_[w][0] / wedge_count[w], value_[w][1] / wedge_count[w]};
  translation_var_.assign(nc_, -1);
  snapped_.assign(nw_, 0);
  snap_axes_.assign(nw_, 0);
  for (int w = 0; w < nw_; ++w)
    if (!options_.snap_vertex.empty() && options_.snap_vertex[wedge_vertex_[w]]) snapped_[w] = 1, snap_axes_[w] = 3;
  if (!options_.snap_corner_axes.empty())
    for (int c = 0; c < nc_; ++c) snap_axes_[wedge_of_[c]] |= options_.snap_corner_axes[c];
}

std::vector<int> GaussianSanitizer::singular_first_halfedges() const {
  // Equations at singular vertices (non-zero rotation around them) go first: there the wedge
  // coefficient (1 - i^k) is no unit, so the translations must be the pivots.
  std::vector<int> holonomy(mesh_.num_vertices(), 0);
  for (int h = 0; h < nc_; ++h)
    if (mesh_.opposite[h] >= 0) holonomy[mesh_.to(h)] += param_.rotation[h];  // crossing prev(h')
  std::vector<int> halfedge_order;
  for (int pass = 0; pass < 2; ++pass)
    for (int h = 0; h < nc_; ++h) {
      const bool singular_end = holonomy[mesh_.from(h)] % 4 != 0 || holonomy[mesh_.to(h)] % 4 != 0;
      if (singular_end == (pass == 0)) halfedge_order.push_back(h);
    }
  return halfedge_order;
}

void GaussianSanitizer::build_equations() {
  for (int h : singular_first_halfedges()) {
    const int o = mesh_.opposite[h];
    if (o < 0 || o < h || !is_cut(h)) continue;
    const int t = static_cast<int>(value_.size());
    value_.push_back({0, 0});
    snapped_.push_back(options_.snap_vertex.empty() ? 0 : 1);  // translations integral with snapping
    snap_axes_.push_back(options_.snap_vertex.empty() ? 0 : 3);
    translation_var_[h] = t;
    const Vec2 tr = param_.translation(mesh_, h);
    value_[t] = {tr.x(), tr.y()};
    const int f = h / 3, g = o / 3;
    const int ends[2][2] = {{3 * f + h % 3, 3 * g + (o % 3 + 1) % 3}, {3 * f + (h % 3 + 1) % 3, 3 * g + o % 3}};
    for (const auto& end : ends)
      equations_.push_back(cut_equation(wedge_of_[end[1]], wedge_of_[end[0]], param_.rotation[h], t));
  }
}

int GaussianSanitizer::pivot_rank(int var) const {
  const int snap = snapped_[var] || snap_axes_[var] ? 1 : 0;
  const int crowd = var < nw_ ? wedges_at_vertex_[wedge_vertex_[var]] : 1;
  return snap * 1000000 + crowd;
}

void GaussianSanitizer::eliminate() {
  // Gaussian elimination with unit pivots. definition[v] expresses an eliminated variable in
  // terms of variables that were free when it was eliminated.
  const int nvars = static_cast<int>(value_.size());
  definition_.assign(nvars, {});
  eliminated_.assign(nvars, 0);
  // Vertex wedge counts: prefer pivots at vertices with few wedges (arc interiors).
  wedges_at_vertex_.assign(mesh_.num_vertices(), 0);
  for (int w = 0; w < nw_; ++w) ++wedges_at_vertex_[wedge_vertex_[w]];
  for (Expr& eq : equations_) eliminate_equation(eq);
}

void GaussianSanitizer::eliminate_equation(Expr& eq) {
  substitute_eliminated(eq);
  if (eq.empty()) return;  // redundant (e.g. the loop closing around a regular vertex)
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
    report_unresolved(eq);
    ++unresolved_;
    return;
  }
  const int var = eq[pivot].first;
  const Gauss inv = -unit_inverse(eq[pivot].second);
  Expr def;
  for (const auto& term : eq)
    if (term.first != var) def.push_back({term.first, term.second * inv});
  definition_[var] = std::move(def);
  eliminated_[var] = 1;
  order_.push_back(var);
}

void GaussianSanitizer::substitute_eliminated(Expr& eq) const {
  // Substitute eliminated variables until only free ones remain.
  for (bool again = true; again;) {
    again = false;
    for (size_t i = 0; i < eq.size(); ++i) {
      if (!eliminated_[eq[i].first]) continue;
      const auto term = eq[i];
      eq.erase(eq.begin() + static_cast<long>(i));
      add_scaled(eq, definition_[term.first], term.second);
      again = true;
      break;
    }
  }
}

void GaussianSanitizer::report_unresolved(const Expr& eq) const {
  if (!getenv("QGP_DEBUG_SANITIZE")) return;
  for (const auto& term : eq)
    fprintf(stderr, "  var %d (%s vertex %d) coef %lld%+lldi\n", term.first, term.first < nw_ ? "wedge" : "transl",
            term.first < nw_ ? wedge_vertex_[term.first] : -1, (long long)term.second.re, (long long)term.second.im);
  fprintf(stderr, "--\n");
}

void GaussianSanitizer::round_and_back_substitute() {
  result_.param.fraction_bits = options_.fraction_bits;
  scale_ = std::ldexp(1.0, options_.fraction_bits);
  const int64_t snap_unit = int64_t(1) << std::max(0, options_.fraction_bits - options_.snap_bits);
  const int nvars = static_cast<int>(value_.size());
  exact_.assign(nvars, IVec2{});
  for (int v = 0; v < nvars; ++v) {
    if (eliminated_[v]) continue;
    for (int a = 0; a < 2; ++a) {
      if ((snap_axes_[v] >> a) & 1) {
        exact_[v][a] = static_cast<int64_t>(std::llround(value_[v][a] * scale_ / snap_unit)) * snap_unit;
      } else {
        exact_[v][a] = static_cast<int64_t>(std::llround(value_[v][a] * scale_));
      }
    }
  }
  for (auto it = order_.rbegin(); it != order_.rend(); ++it) {
    Gauss sum{0, 0};
    for (const auto& term : definition_[*it])
      sum = sum + term.second * Gauss{exact_[term.first][0], exact_[term.first][1]};
    exact_[*it] = {sum.re, sum.im};
  }
}

void GaussianSanitizer::finish() {
  ExactParametrization& ex = result_.param;
  ex.uv.resize(nc_);
  for (int c = 0; c < nc_; ++c) {
    ex.uv[c] = exact_[wedge_of_[c]];
    for (int a = 0; a < 2; ++a)
      result_.max_change = std::max(result_.max_change, std::abs(ex.uv[c][a] / scale_ - param_.uv(c, a)));
  }
  ex.rotation = param_.rotation;
  ex.translation.assign(nc_, {0, 0});
  for (int h = 0; h < nc_; ++h) {
    if (translation_var_[h] < 0) continue;
    const int o = mesh_.opposite[h];
    ex.translation[h] = exact_[translation_var_[h]];
    // The opposite transition is the inverse: p_f = i^-r (p_g - t).
    const IVec2 back = rotate_quarter(IVec2{-ex.translation[h][0], -ex.translation[h][1]}, -param_.rotation[h]);
    ex.translation[o] = back;
  }
  ex.is_cut.assign(mesh_.num_edges(), 0);
  for (int h = 0; h < nc_; ++h)
    if (translation_var_[h] >= 0) ex.is_cut[mesh_.edge_of[h]] = 1;
  result_.unresolved_equations = unresolved_;
}

}  // namespace

SanitizeResult sanitize_parametrization(const TriMesh& mesh, const Parametrization& param,
                                        const SanitizeOptions& options) {
  return GaussianSanitizer(mesh, param, options).run();
}

}  // namespace qgp

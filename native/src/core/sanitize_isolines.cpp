#include "core/sanitize_isolines.h"

#include <algorithm>
#include <climits>
#include <cmath>
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
    if (!out.empty() && out.back().first == t.first)
      out.back().second += t.second;
    else
      out.push_back(t);
  }
  out.erase(std::remove_if(out.begin(), out.end(), [](const auto& t) { return t.second == 0; }), out.end());
  return out;
}

// Component `axis` of R^r (x, y) as a combination of x (index 0) and y (index 1): {which, sign}.
std::pair<int, int> rotated_component(int r, int axis) {
  switch (((r % 4) + 4) % 4) {
    case 0: return {axis, 1};
    case 1: return axis == 0 ? std::pair{1, -1} : std::pair{0, 1};  // (-y, x)
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
      for (int i = start[w]; ok && i < start[w + 1]; ++i) ok = !was_positive[i - start[w]] || positive(corners[i] / 3);
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
      if (fixed)
        changed = true;
      else
        still.push_back(f);
    }
    bad.swap(still);
  }
  result.non_positive_faces = static_cast<int>(bad.size());
  result.reoriented_faces = static_cast<int>(initially - bad.size());
}

// Largest move, in grid units, of a free unknown (with everything that depends on it) that tries
// to make a face positive whose corners are tied to others by equations.
constexpr int64_t kMaxShift = 16;

// State of one sanitize_with_isolines solve: wedges, integer unknowns (2 per wedge (u, v), then 2
// per cut edge translation, then the new unknowns of unimodular changes), the transition and
// isoline equations, their elimination with unit pivots and the rounded exact map.
class IsolineSanitizer {
 public:
  // Checks that param matches the mesh (throws Error(Internal) otherwise).
  IsolineSanitizer(const TriMesh& mesh, const Parametrization& param, const SanitizeOptions& options);
  // Runs every phase; returns the exact map with every isoline constraint holding exactly.
  SanitizeResult run(const std::vector<IsolineConstraint>& isolines);

 private:
  // Whether the charts of the faces of halfedge h may disagree (cut edge or rotation).
  bool is_cut(int h) const;
  // Fills wedge_of_ / wedge_vertex_: corners joined across non-cut interior edges.
  void build_wedges();
  // Continuous value of each wedge unknown (mean of its corners) and which unknowns are snapped.
  void init_wedge_unknowns();
  // Translation unknowns of the cut edges and the equations of the cuts and the isolines, in
  // elimination order.
  void build_equations(const std::vector<IsolineConstraint>& isolines);
  // Pivot preference of an unknown (lower first): translations, then wedges at vertices with few
  // wedges; snapped unknowns last.
  int rank(int var) const;
  // Eliminates every equation in turn, recording definitions (or counting it unresolved).
  void eliminate();
  // Eliminates one equation: substitution, division by the coefficients' gcd, pivot choice.
  void eliminate_equation(Expr& eq);
  // Replaces eliminated unknowns in eq by their definitions until only free ones remain.
  void substitute_eliminated(Expr& eq) const;
  // Index in eq of the unit coefficient of lowest rank, or -1.
  int find_pivot(const Expr& eq) const;
  // Unimodular changes of variables until eq has a unit coefficient; returns its pivot or -1.
  int make_unit_coefficient(Expr& eq);
  // Replaces the unknown of eq[m] by a new free unknown y (x_m = y - sum_j q_j x_j) in eq.
  void change_variable(Expr& eq, int m);
  // Records the definition of the pivot unknown of eq by the other terms.
  void define_pivot(const Expr& eq, int pivot);
  // Rounds the free unknowns to the grid (snapped ones to snap units), then back-substitutes.
  void round_and_back_substitute();
  // The exact corner coordinates of every corner from the exact wedge unknowns.
  void write_corners();
  // Makes the faces positive in the continuous map positive on the grid where moves allow.
  void keep_faces_positive();
  // Whether face f is positively oriented in the exact map (exact test).
  bool positive(int f) const;
  // Moves free unknowns (with everything depending on them) to make the faces of target that are
  // still not positive positive; updates the face counts of the result.
  void shift_free_unknowns(const std::vector<char>& target);
  // Unsnapped free unknowns that the corners of face f depend on (seen: all-zero scratch flags).
  std::vector<int> free_unknowns_of_face(int f, std::vector<char>& seen) const;
  // k[x] = d x / d y for the free unknown y (back-substitution order).
  void derivatives(int y, std::vector<int64_t>& k) const;
  // Tries shifts of unknown y by +-1, +-2, ... (k its derivatives) that make face f positive and
  // keep the positive faces touched positive; returns whether one was applied.
  bool shift_along(int f, const std::vector<int64_t>& k, const std::vector<std::vector<int>>& corners_of);
  // max_change, the exact transitions and cut flags of the result.
  void finish();

  const TriMesh& mesh_;
  const Parametrization& param_;
  const SanitizeOptions& options_;
  const int nf_, nc_;
  std::vector<int> wedge_of_, wedge_vertex_;
  int nw_ = 0;
  std::vector<double> value_;  // continuous value of each unknown
  std::vector<char> snapped_;  // unknowns rounded to snap units and never changed
  std::vector<int> wedges_at_vertex_;
  std::vector<int> translation_var_;  // per halfedge: its first translation unknown, or -1
  std::vector<Expr> equations_;
  std::vector<char> in_equation_;  // unknowns that occur in some equation
  std::vector<Expr> definition_;   // definition[x] expresses x by unknowns free at that time
  std::vector<char> eliminated_;
  std::vector<int> order_;  // eliminated unknowns in elimination order
  int unresolved_ = 0;
  double scale_ = 1;            // grid units per parameter unit
  std::vector<int64_t> exact_;  // exact value of every unknown
  SanitizeResult result_;
};

IsolineSanitizer::IsolineSanitizer(const TriMesh& mesh, const Parametrization& param, const SanitizeOptions& options)
    : mesh_(mesh), param_(param), options_(options), nf_(mesh.num_faces()), nc_(3 * mesh.num_faces()) {
  if (param.uv.rows() != nc_ || static_cast<int>(param.rotation.size()) != nc_)
    throw Error(ErrorCode::Internal, "sanitize: parametrization does not match the mesh");
}

SanitizeResult IsolineSanitizer::run(const std::vector<IsolineConstraint>& isolines) {
  build_wedges();
  init_wedge_unknowns();
  build_equations(isolines);
  eliminate();
  round_and_back_substitute();
  keep_faces_positive();
  finish();
  return std::move(result_);
}

bool IsolineSanitizer::is_cut(int h) const {
  return (!param_.is_cut.empty() && param_.is_cut[mesh_.edge_of[h]]) || param_.rotation[h] % 4 != 0;
}

void IsolineSanitizer::build_wedges() {
  // Wedges: corners joined across non-cut interior edges.
  std::vector<int> parent(nc_);
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (int h = 0; h < nc_; ++h) {
    const int o = mesh_.opposite[h];
    if (o < 0 || o < h || is_cut(h)) continue;
    parent[find(h)] = find(3 * (o / 3) + (o % 3 + 1) % 3);
    parent[find(3 * (h / 3) + (h % 3 + 1) % 3)] = find(o);
  }
  wedge_of_.assign(nc_, 0);
  std::vector<int> root_wedge(nc_, -1);
  for (int c = 0; c < nc_; ++c) {
    const int r = find(c);
    if (root_wedge[r] < 0)
      root_wedge[r] = static_cast<int>(wedge_vertex_.size()), wedge_vertex_.push_back(mesh_.F(c / 3, c % 3));
    wedge_of_[c] = root_wedge[r];
  }
  nw_ = static_cast<int>(wedge_vertex_.size());
}

void IsolineSanitizer::init_wedge_unknowns() {
  // Unknowns: 2 per wedge (u, v), then 2 per cut edge translation. Continuous values and snapping.
  value_.assign(2 * nw_, 0);
  std::vector<int> count(nw_, 0);
  for (int c = 0; c < nc_; ++c) {
    value_[2 * wedge_of_[c]] += param_.uv(c, 0);
    value_[2 * wedge_of_[c] + 1] += param_.uv(c, 1);
    ++count[wedge_of_[c]];
  }
  for (int w = 0; w < nw_; ++w) value_[2 * w] /= count[w], value_[2 * w + 1] /= count[w];
  snapped_.assign(2 * nw_, 0);
  for (int w = 0; w < nw_; ++w)
    if (!options_.snap_vertex.empty() && options_.snap_vertex[wedge_vertex_[w]])
      snapped_[2 * w] = snapped_[2 * w + 1] = 1;
  if (!options_.snap_corner_axes.empty())
    for (int c = 0; c < nc_; ++c)
      for (int a = 0; a < 2; ++a)
        if ((options_.snap_corner_axes[c] >> a) & 1) snapped_[2 * wedge_of_[c] + a] = 1;
  wedges_at_vertex_.assign(mesh_.num_vertices(), 0);
  for (int w = 0; w < nw_; ++w) ++wedges_at_vertex_[wedge_vertex_[w]];
}

void IsolineSanitizer::build_equations(const std::vector<IsolineConstraint>& isolines) {
  // Transition equations W_g - R^r W_f - T = 0 per endpoint of each cut edge, per coordinate;
  // those at singular vertices first, so that translations become their pivots.
  std::vector<int> holonomy(mesh_.num_vertices(), 0);
  for (int h = 0; h < nc_; ++h)
    if (mesh_.opposite[h] >= 0) holonomy[mesh_.to(h)] += param_.rotation[h];
  translation_var_.assign(nc_, -1);
  std::vector<Expr> first, later;
  for (int h = 0; h < nc_; ++h) {
    const int o = mesh_.opposite[h];
    if (o < 0 || o < h || !is_cut(h)) continue;
    const int t = static_cast<int>(value_.size());
    translation_var_[h] = t;
    const Vec2 tr = param_.translation(mesh_, h);
    value_.push_back(tr.x()), value_.push_back(tr.y());
    const char snap_t = options_.snap_vertex.empty() ? 0 : 1;
    snapped_.push_back(snap_t), snapped_.push_back(snap_t);
    const int f = h / 3, g = o / 3, r = param_.rotation[h];
    const bool singular_end = holonomy[mesh_.from(h)] % 4 != 0 || holonomy[mesh_.to(h)] % 4 != 0;
    const int ends[2][2] = {{3 * f + h % 3, 3 * g + (o % 3 + 1) % 3}, {3 * f + (h % 3 + 1) % 3, 3 * g + o % 3}};
    for (const auto& end : ends)
      for (int a = 0; a < 2; ++a) {
        const auto [which, sgn] = rotated_component(r, a);
        Expr e = make_expr({{2 * wedge_of_[end[1]] + a, 1}, {2 * wedge_of_[end[0]] + which, -sgn}, {t + a, -1}});
        (singular_end ? first : later).push_back(std::move(e));
      }
  }
  equations_ = std::move(first);
  for (const IsolineConstraint& iso : isolines) {
    const int h = iso.halfedge;
    if (h < 0 || h >= nc_ || iso.axis < 0 || iso.axis > 1)
      throw Error(ErrorCode::InvalidArgument, "sanitize: isoline constraint out of range");
    equations_.push_back(
        make_expr({{2 * wedge_of_[h] + iso.axis, 1}, {2 * wedge_of_[TriMesh::next(h)] + iso.axis, -1}}));
  }
  for (Expr& e : later) equations_.push_back(std::move(e));
}

int IsolineSanitizer::rank(int var) const {
  const int base = var < 2 * nw_ ? 10 + wedges_at_vertex_[wedge_vertex_[var / 2]] : 0;  // translations first
  return (snapped_[var] ? 1000000 : 0) + base;
}

void IsolineSanitizer::eliminate() {
  // Elimination with unit pivots; definition[x] expresses x by variables free at that time.
  in_equation_.assign(value_.size(), 0);
  for (const Expr& eq : equations_)
    for (const auto& term : eq) in_equation_[term.first] = 1;
  definition_.assign(value_.size(), {});
  eliminated_.assign(value_.size(), 0);
  for (Expr& eq : equations_) eliminate_equation(eq);
}

void IsolineSanitizer::eliminate_equation(Expr& eq) {
  substitute_eliminated(eq);
  if (eq.empty()) return;  // implied by earlier equations
  int64_t common = 0;
  for (const auto& term : eq) common = std::gcd(common, std::abs(term.second));
  if (common > 1)
    for (auto& term : eq) term.second /= common;
  int pivot = find_pivot(eq);
  if (pivot < 0) pivot = make_unit_coefficient(eq);
  if (pivot < 0) {
    ++unresolved_;
    return;
  }
  define_pivot(eq, pivot);
}

void IsolineSanitizer::substitute_eliminated(Expr& eq) const {
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

int IsolineSanitizer::find_pivot(const Expr& eq) const {
  int pivot = -1;
  for (size_t i = 0; i < eq.size(); ++i)
    if (std::abs(eq[i].second) == 1 && (pivot < 0 || rank(eq[i].first) < rank(eq[pivot].first)))
      pivot = static_cast<int>(i);
  return pivot;
}

int IsolineSanitizer::make_unit_coefficient(Expr& eq) {
  // Fill-in can leave an equation without a unit coefficient (e.g. 2a + 3b = 0; coprime after
  // the division above). Then a unimodular change of variables makes one: with m the unsnapped
  // unknown of smallest |coefficient| c_m, x_m = y - sum_j q_j x_j (y a new free unknown,
  // q_j = c_j / c_m rounded) leaves coefficients c_j - q_j c_m of magnitude <= |c_m| / 2, not
  // all zero as their gcd is 1; repeated, a unit coefficient appears.
  // Only unsnapped unknowns change, so the smallest unsnapped |coefficient| must drop every
  // round; when it does not (the rest is snapped), the equation stays unresolved.
  int pivot = -1;
  for (int64_t smallest = INT64_MAX; pivot < 0 && eq.size() >= 2;) {
    int m = -1;
    for (size_t i = 0; i < eq.size(); ++i)
      if (!snapped_[eq[i].first] && (m < 0 || std::abs(eq[i].second) < std::abs(eq[m].second))) m = static_cast<int>(i);
    if (m < 0 || std::abs(eq[m].second) >= smallest) break;
    smallest = std::abs(eq[m].second);
    change_variable(eq, m);
    pivot = find_pivot(eq);
  }
  return pivot;
}

void IsolineSanitizer::change_variable(Expr& eq, int m) {
  const auto [xm, cm] = eq[m];
  const int y = static_cast<int>(value_.size());
  Expr def;  // x_m = y - sum_j q_j x_j
  double y_value = value_[xm];
  for (const auto& [xj, cj] : eq) {
    if (xj == xm) continue;
    const int64_t q = (cj >= 0 ? cj + std::abs(cm) / 2 : cj - std::abs(cm) / 2) / cm;  // nearest
    if (q == 0) continue;
    def.push_back({xj, -q});
    y_value += static_cast<double>(q) * value_[xj];
  }
  def.push_back({y, 1});
  value_.push_back(y_value);
  snapped_.push_back(0);
  in_equation_.push_back(1);
  eliminated_.push_back(0);
  definition_.push_back({});
  Expr rest;
  for (const auto& term : eq)
    if (term.first != xm) rest.push_back(term);
  add_scaled(rest, def, cm);
  definition_[xm] = std::move(def);
  eliminated_[xm] = 1;
  order_.push_back(xm);
  eq.swap(rest);
}

void IsolineSanitizer::define_pivot(const Expr& eq, int pivot) {
  const int var = eq[pivot].first;
  const int64_t inv = -eq[pivot].second;  // x = -(rest) / c with c = +-1
  Expr def;
  for (const auto& term : eq)
    if (term.first != var) def.push_back({term.first, term.second * inv});
  definition_[var] = std::move(def);
  eliminated_[var] = 1;
  order_.push_back(var);
}

void IsolineSanitizer::round_and_back_substitute() {
  // Round the free unknowns, then back-substitute.
  result_.param.fraction_bits = options_.fraction_bits;
  scale_ = std::ldexp(1.0, options_.fraction_bits);
  const int64_t snap_unit = int64_t(1) << std::max(0, options_.fraction_bits - options_.snap_bits);
  const int nvars = static_cast<int>(value_.size());
  exact_.assign(nvars, 0);
  for (int x = 0; x < nvars; ++x) {
    if (eliminated_[x]) continue;
    exact_[x] = snapped_[x] ? static_cast<int64_t>(std::llround(value_[x] * scale_ / snap_unit)) * snap_unit
                            : static_cast<int64_t>(std::llround(value_[x] * scale_));
  }
  for (auto it = order_.rbegin(); it != order_.rend(); ++it) {
    int64_t sum = 0;
    for (const auto& term : definition_[*it]) sum += term.second * exact_[term.first];
    exact_[*it] = sum;
  }
  write_corners();
}

void IsolineSanitizer::write_corners() {
  std::vector<IVec2>& uv = result_.param.uv;
  uv.resize(nc_);
  for (int c = 0; c < nc_; ++c) uv[c] = {exact_[2 * wedge_of_[c]], exact_[2 * wedge_of_[c] + 1]};
}

void IsolineSanitizer::keep_faces_positive() {
  std::vector<char> movable(nw_, 0);  // wedges no equation and no snapping ties to anything else
  for (int w = 0; w < nw_; ++w)
    movable[w] = !in_equation_[2 * w] && !in_equation_[2 * w + 1] && !snapped_[2 * w] && !snapped_[2 * w + 1];
  // Faces to keep positive: those positive in the continuous map (flips there are the solver's
  // to report; this only limits the search, every outcome is decided by exact tests).
  std::vector<char> target(nf_, 0);
  for (int f = 0; f < nf_; ++f) {
    const Vec2 a = param_.corner(f, 0), b = param_.corner(f, 1), c = param_.corner(f, 2);
    target[f] = (b - a).x() * (c - a).y() - (b - a).y() * (c - a).x() > 0;
  }
  reorient_faces(mesh_, wedge_of_, movable, target, result_.param.uv, result_);
  if (result_.non_positive_faces > 0) shift_free_unknowns(target);
}

bool IsolineSanitizer::positive(int f) const {
  const std::vector<IVec2>& uv = result_.param.uv;
  return orient2d_exact(uv[3 * f], uv[3 * f + 1], uv[3 * f + 2]) > 0;
}

void IsolineSanitizer::shift_free_unknowns(const std::vector<char>& target) {
  // Faces still not positive have a corner tied to others by equations (cuts, isolines). Move
  // one unsnapped free unknown the corner depends on, together with everything that depends on
  // it (so every equation still holds), by up to kMaxShift grid units; accept when the face
  // becomes positive and no positive face touched stops being so.
  const int nvars = static_cast<int>(value_.size());
  std::vector<std::vector<int>> corners_of(nw_);
  for (int c = 0; c < nc_; ++c) corners_of[wedge_of_[c]].push_back(c);
  std::vector<int64_t> k(nvars, 0);
  std::vector<char> seen(nvars, 0);
  int fixed = 0, still = 0;
  for (int f = 0; f < nf_; ++f) {
    if (!target[f] || positive(f)) continue;
    const std::vector<int> candidates = free_unknowns_of_face(f, seen);
    bool done = false;
    for (size_t ci = 0; ci < candidates.size() && !done; ++ci) {
      derivatives(candidates[ci], k);
      bool keeps_snapping = true;
      for (int x = 0; x < nvars && keeps_snapping; ++x) keeps_snapping = !(snapped_[x] && k[x] != 0);
      if (!keeps_snapping) continue;
      done = shift_along(f, k, corners_of);
    }
    (done ? fixed : still) += 1;
  }
  result_.reoriented_faces += fixed;
  result_.non_positive_faces = still;
}

std::vector<int> IsolineSanitizer::free_unknowns_of_face(int f, std::vector<char>& seen) const {
  // Free unknowns the face's corners depend on.
  std::vector<int> stack, candidates, touched;
  for (int j = 0; j < 3; ++j)
    for (int a = 0; a < 2; ++a) stack.push_back(2 * wedge_of_[3 * f + j] + a);
  while (!stack.empty()) {
    const int x = stack.back();
    stack.pop_back();
    if (seen[x]) continue;
    seen[x] = 1;
    touched.push_back(x);
    if (!eliminated_[x]) {
      if (!snapped_[x]) candidates.push_back(x);
      continue;
    }
    for (const auto& term : definition_[x]) stack.push_back(term.first);
  }
  for (int x : touched) seen[x] = 0;
  return candidates;
}

void IsolineSanitizer::derivatives(int y, std::vector<int64_t>& k) const {
  // k[x] = d x / d y for the free unknown y (back-substitution order).
  std::fill(k.begin(), k.end(), 0);
  k[y] = 1;
  for (auto it = order_.rbegin(); it != order_.rend(); ++it) {
    int64_t sum = 0;
    for (const auto& term : definition_[*it]) sum += term.second * k[term.first];
    k[*it] = sum;
  }
}

bool IsolineSanitizer::shift_along(int f, const std::vector<int64_t>& k,
                                   const std::vector<std::vector<int>>& corners_of) {
  std::vector<IVec2>& uv = result_.param.uv;
  std::vector<int> faces, moved_corners;
  for (int w = 0; w < nw_; ++w)
    if (k[2 * w] != 0 || k[2 * w + 1] != 0)
      for (int c : corners_of[w]) moved_corners.push_back(c), faces.push_back(c / 3);
  std::sort(faces.begin(), faces.end());
  faces.erase(std::unique(faces.begin(), faces.end()), faces.end());
  std::vector<char> was_positive(faces.size());
  for (size_t i = 0; i < faces.size(); ++i) was_positive[i] = positive(faces[i]);
  for (int64_t step = 1; step <= 2 * kMaxShift; ++step) {
    const int64_t d = (step + 1) / 2 * (step % 2 ? 1 : -1);  // 1, -1, 2, -2, ...
    for (int c : moved_corners) {
      const int w = wedge_of_[c];
      uv[c] = {exact_[2 * w] + k[2 * w] * d, exact_[2 * w + 1] + k[2 * w + 1] * d};
    }
    bool ok = positive(f);
    for (size_t i = 0; i < faces.size() && ok; ++i) ok = !was_positive[i] || positive(faces[i]);
    if (ok) {
      for (size_t x = 0; x < exact_.size(); ++x) exact_[x] += k[x] * d;
      return true;
    }
  }
  for (int c : moved_corners) uv[c] = {exact_[2 * wedge_of_[c]], exact_[2 * wedge_of_[c] + 1]};
  return false;
}

void IsolineSanitizer::finish() {
  ExactParametrization& ex = result_.param;
  for (int c = 0; c < nc_; ++c)
    for (int a = 0; a < 2; ++a)
      result_.max_change = std::max(result_.max_change, std::fabs(ex.uv[c][a] / scale_ - param_.uv(c, a)));
  ex.rotation = param_.rotation;
  ex.translation.assign(nc_, {0, 0});
  ex.is_cut.assign(mesh_.num_edges(), 0);
  for (int h = 0; h < nc_; ++h) {
    if (translation_var_[h] < 0) continue;
    const int o = mesh_.opposite[h];
    ex.translation[h] = {exact_[translation_var_[h]], exact_[translation_var_[h] + 1]};
    ex.translation[o] = rotate_quarter(IVec2{-ex.translation[h][0], -ex.translation[h][1]}, -param_.rotation[h]);
    ex.is_cut[mesh_.edge_of[h]] = 1;
  }
  result_.unresolved_equations = unresolved_;
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
  return IsolineSanitizer(mesh, param, options).run(isolines);
}

}  // namespace qgp

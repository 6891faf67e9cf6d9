#include "seamless_map/linear_elimination.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>

#include "core/error.h"

namespace qgp {

void normalize_form(LinearForm& form) {
  std::sort(form.begin(), form.end(), [](const LinearTerm& a, const LinearTerm& b) { return a.var < b.var; });
  size_t out = 0;
  for (size_t i = 0; i < form.size();) {
    LinearTerm t = form[i++];
    while (i < form.size() && form[i].var == t.var) t.coeff += form[i++].coeff;
    if (std::abs(t.coeff) > kZeroCoefficient) form[out++] = t;
  }
  form.resize(out);
}

LinearElimination::LinearElimination(int num_vars)
    : definition_(num_vars), constant_(num_vars, 0.0), eliminated_(num_vars, 0), priority_(num_vars, 0) {}

bool LinearElimination::is_dirty(int var) const {
  for (const LinearTerm& t : definition_[var])
    if (eliminated_[t.var]) return true;
  return false;
}

void LinearElimination::rebuild(int var) {
  LinearForm out;
  double c = constant_[var];
  for (const LinearTerm& t : definition_[var]) {
    if (!eliminated_[t.var]) {
      out.push_back(t);
      continue;
    }
    for (const LinearTerm& s : definition_[t.var]) out.push_back({s.var, s.coeff * t.coeff});
    c += t.coeff * constant_[t.var];
  }
  normalize_form(out);
  definition_[var] = std::move(out);
  constant_[var] = c;
}

void LinearElimination::compress(int var) {
  if (!is_dirty(var)) return;
  // Post-order walk over dirty definitions (they form a DAG ordered by elimination time).
  std::vector<std::pair<int, size_t>> stack{{var, 0}};
  while (!stack.empty()) {
    const int u = stack.back().first;
    const size_t i = stack.back().second;
    if (i < definition_[u].size()) {
      ++stack.back().second;
      const int w = definition_[u][i].var;
      if (eliminated_[w] && is_dirty(w)) stack.push_back({w, 0});
      continue;
    }
    rebuild(u);
    stack.pop_back();
  }
}

LinearElimination::Outcome LinearElimination::add_equation(LinearForm terms, double rhs) {
  for (const LinearTerm& t : terms)
    if (t.var < 0 || t.var >= num_vars() || !std::isfinite(t.coeff))
      throw Error(ErrorCode::Internal, "linear elimination: bad term in an equation");
  if (!std::isfinite(rhs)) throw Error(ErrorCode::Internal, "linear elimination: non-finite right-hand side");
  normalize_form(terms);
  // Substitute eliminated variables by their definitions over free variables.
  double scale = std::abs(rhs);
  LinearForm eq;
  for (const LinearTerm& t : terms) {
    if (!eliminated_[t.var]) {
      eq.push_back(t);
      continue;
    }
    compress(t.var);
    for (const LinearTerm& s : definition_[t.var]) eq.push_back({s.var, s.coeff * t.coeff});
    rhs -= t.coeff * constant_[t.var];
    scale += std::abs(t.coeff * constant_[t.var]);
  }
  normalize_form(eq);
  if (eq.empty()) {
    if (std::abs(rhs) <= 1e-9 * std::max(1.0, scale)) {
      ++redundant_;
      return Outcome::Redundant;
    }
    ++inconsistent_;
    return Outcome::Inconsistent;
  }
  // Divide out a common integer factor (e.g. 2 in 2u - 2v = 0) to expose unit pivots.
  bool integral = true;
  for (const LinearTerm& t : eq) integral = integral && t.coeff == std::round(t.coeff) && std::abs(t.coeff) < 9e15;
  if (integral) {
    int64_t g = 0;
    for (const LinearTerm& t : eq) g = std::gcd(g, static_cast<int64_t>(std::llround(std::abs(t.coeff))));
    if (g > 1) {
      for (LinearTerm& t : eq) t.coeff /= static_cast<double>(g);
      rhs /= static_cast<double>(g);
    }
  }
  int pivot = -1;
  for (size_t i = 0; i < eq.size(); ++i)
    if (std::abs(eq[i].coeff) == 1 && (pivot < 0 || priority_[eq[i].var] > priority_[eq[pivot].var]))
      pivot = static_cast<int>(i);
  if (pivot < 0) {
    ++non_integer_pivots_;
    for (size_t i = 0; i < eq.size(); ++i)
      if (pivot < 0 || std::abs(eq[i].coeff) > std::abs(eq[pivot].coeff)) pivot = static_cast<int>(i);
  }
  const int var = eq[pivot].var;
  const double c = eq[pivot].coeff;
  LinearForm def;
  def.reserve(eq.size() - 1);
  for (const LinearTerm& t : eq)
    if (t.var != var) def.push_back({t.var, -t.coeff / c});
  definition_[var] = std::move(def);
  constant_[var] = rhs / c;
  eliminated_[var] = 1;
  ++num_eliminated_;
  return Outcome::Eliminated;
}

LinearForm LinearElimination::expansion(int var, double* constant) {
  if (!eliminated_[var]) {
    *constant = 0;
    return {{var, 1.0}};
  }
  compress(var);
  *constant = constant_[var];
  return definition_[var];
}

std::vector<int> LinearElimination::free_variables() const {
  std::vector<int> out;
  for (int v = 0; v < num_vars(); ++v)
    if (!eliminated_[v]) out.push_back(v);
  return out;
}

std::vector<int> LinearElimination::free_index() const {
  std::vector<int> index(num_vars(), -1);
  int k = 0;
  for (int v = 0; v < num_vars(); ++v)
    if (!eliminated_[v]) index[v] = k++;
  return index;
}

}  // namespace qgp

// Elimination of linear equality constraints with integer coefficients (transition, isoline and
// quantization constraints of a parametrization). Every variable becomes
//     x_var = sum_j coeff_j * x_free_j + constant
// over the variables that stay free. Pivots are unit coefficients (+-1), so the coefficients stay
// integers and constrained quantities (e.g. the two copies of a vertex across a cut) agree up to
// floating-point rounding of the final sums, not of a solver tolerance.
#pragma once
#include <vector>

namespace qgp {

struct LinearTerm {
  int var = 0;
  double coeff = 0;
};
using LinearForm = std::vector<LinearTerm>;  // sorted by var, no zero coefficients

// Sorts by variable, merges duplicates and drops zeros, and the rounding residue that cancelled
// rational coefficients leave after a non-integer pivot (|coeff| <= kZeroCoefficient): the
// coefficients are small integers and their quotients, so nothing else is that small. Kept, such a
// residue became a pivot with a constant of about 1e15 (block with sharp edges at 60 degrees: 539
// of its integer-grid map's equations then counted as inconsistent).
constexpr double kZeroCoefficient = 1e-12;
void normalize_form(LinearForm& form);

class LinearElimination {
 public:
  enum class Outcome { Eliminated, Redundant, Inconsistent };

  explicit LinearElimination(int num_vars);

  // Pivot preference: among unit coefficients the variable with the highest priority is
  // eliminated (ties: the lowest index). Default 0.
  void set_priority(int var, int priority) { priority_[var] = priority; }

  // Adds  sum coeff * x_var = rhs  and eliminates one variable if the equation is independent of
  // the previous ones. A dependent equation is Redundant if it holds (|residual| <= 1e-9 scale)
  // and Inconsistent otherwise; both are counted and otherwise ignored.
  Outcome add_equation(LinearForm terms, double rhs);

  int num_vars() const { return static_cast<int>(eliminated_.size()); }
  bool is_eliminated(int var) const { return eliminated_[var] != 0; }

  // x_var in terms of free variables (original indices) plus *constant.
  LinearForm expansion(int var, double* constant);

  // Free variables in increasing order, and each variable's position among them (-1: eliminated).
  std::vector<int> free_variables() const;
  std::vector<int> free_index() const;

  int num_eliminated() const { return num_eliminated_; }
  int redundant_equations() const { return redundant_; }
  int inconsistent_equations() const { return inconsistent_; }
  // Equations whose pivot was no unit even after dividing out the common factor (0 expected; the
  // elimination then stays exact up to rounding of a rational coefficient).
  int non_integer_pivots() const { return non_integer_pivots_; }

 private:
  bool is_dirty(int var) const;  // definition refers to an eliminated variable
  void compress(int var);        // rewrites definition_[var] over currently free variables
  void rebuild(int var);

  std::vector<LinearForm> definition_;
  std::vector<double> constant_;
  std::vector<char> eliminated_;
  std::vector<int> priority_;
  int num_eliminated_ = 0, redundant_ = 0, inconsistent_ = 0, non_integer_pivots_ = 0;
};

}  // namespace qgp

// Convex quadratic program with linear inequality constraints:
//     minimize 1/2 x^T H x + g^T x   subject to  A x >= lower,  x >= variable_lower.
// The seamless map's and the integer-grid map's repair rounds solve one per round.
#pragma once
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <string>
#include <vector>

#include "core/progress.h"

namespace qgp {

struct SparseQP {
  Eigen::SparseMatrix<double> hessian;                       // n x n, symmetric positive semi-definite (both triangles)
  Eigen::VectorXd linear;                                    // n
  Eigen::SparseMatrix<double, Eigen::RowMajor> constraints;  // m x n
  Eigen::VectorXd lower;                                     // m
  Eigen::VectorXd variable_lower;                            // n, or empty: no bounds (-inf entries allowed)
  Eigen::VectorXd start;                                     // n: starting point (need not be feasible)
};

struct QPOptions {
  int max_iterations = 300;
  double tolerance = 1e-9;
  // Progress fraction range of the current stage covered by this solve.
  double progress_begin = 0, progress_end = 1;
  // Threads of the interior-point method's normal matrix assembly (0: as many as the machine has,
  // up to 8). The solution is the same, bit for bit, whatever the number.
  int threads = 0;
};

struct QPResult {
  enum class Status { Solved, Acceptable, IterationLimit, Infeasible, Failed };
  Status status = Status::Failed;
  Eigen::VectorXd x;  // the last iterate (meaningful unless Failed)
  int iterations = 0;
  std::string message;    // the solver's return status in words
  bool by_ipopt = false;  // the interior-point method did not converge and Ipopt solved it
};

// Solves with the interior-point method of interior_point_qp.h; where it does not reach Solved or
// Acceptable (a program whose constraints cannot all hold, or a failed factorization), Ipopt
// solves it again from the same start (ipopt_qp.h), and its result is returned. Throws
// Error(Internal) on inconsistent sizes and Error(Cancelled) on a cancel.
QPResult solve_qp(const SparseQP& qp, const QPOptions& options, Progress& progress);

}  // namespace qgp

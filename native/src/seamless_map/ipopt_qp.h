// Convex quadratic program with linear inequality constraints, solved with Ipopt (MUMPS):
//     minimize 1/2 x^T H x + g^T x   subject to  A x >= lower,  x >= variable_lower.
// Silent (no banner, print level 0), cancellable through Progress.
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
};

struct QPResult {
  enum class Status { Solved, Acceptable, IterationLimit, Infeasible, Failed };
  Status status = Status::Failed;
  Eigen::VectorXd x;  // the last iterate (meaningful unless Failed)
  int iterations = 0;
  std::string message;  // Ipopt's return status in words
};

// Throws Error(Cancelled) when progress reports a cancel (checked in Ipopt's intermediate
// callback, i.e. at least once per interior-point iteration).
QPResult solve_qp(const SparseQP& qp, const QPOptions& options, Progress& progress);

}  // namespace qgp

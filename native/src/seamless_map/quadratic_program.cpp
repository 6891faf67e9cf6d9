#include "seamless_map/quadratic_program.h"

#include "core/error.h"
#include "seamless_map/interior_point_qp.h"
#include "seamless_map/ipopt_qp.h"

namespace qgp {
namespace {

void check_sizes(const SparseQP& qp) {
  const Eigen::Index n = qp.linear.size();
  if (qp.hessian.rows() != n || qp.hessian.cols() != n || qp.constraints.cols() != n ||
      qp.lower.size() != qp.constraints.rows() || qp.start.size() != n ||
      (qp.variable_lower.size() != 0 && qp.variable_lower.size() != n))
    throw Error(ErrorCode::Internal, "quadratic program: inconsistent sizes");
}

bool converged(const QPResult& result) {
  return result.status == QPResult::Status::Solved || result.status == QPResult::Status::Acceptable;
}

}  // namespace

QPResult solve_qp(const SparseQP& qp, const QPOptions& options, Progress& progress) {
  check_sizes(qp);
  progress.check_cancel();
  if (qp.linear.size() == 0) {
    QPResult empty;
    empty.status = QPResult::Status::Solved;
    return empty;
  }
  QPResult result = solve_qp_interior_point(qp, options, progress);
  if (converged(result)) return result;
  const int own_iterations = result.iterations;
  result = solve_qp_ipopt(qp, options, progress);
  result.iterations += own_iterations;
  result.by_ipopt = true;
  return result;
}

}  // namespace qgp

// The convex quadratic programs of the repair (quadratic_program.h), solved with Ipopt (MUMPS).
// Silent (no banner, print level 0); solves are serialized (Ipopt with the sequential MUMPS is
// not known to be re-entrant). Throws Error(Cancelled) when progress reports a cancel (checked in
// Ipopt's intermediate callback, at least once per interior-point iteration).
#pragma once
#include "seamless_map/quadratic_program.h"

namespace qgp {

QPResult solve_qp_ipopt(const SparseQP& qp, const QPOptions& options, Progress& progress);

}  // namespace qgp

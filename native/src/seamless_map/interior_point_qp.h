// The convex quadratic programs of the repair (quadratic_program.h), solved by a primal-dual
// interior-point method of our own: Mehrotra's predictor-corrector (Nocedal & Wright,
// "Numerical Optimization", 2nd ed., §16.6) on the normal equations
//     (H + C^T (Z/S) C) dx = r,
// which are symmetric positive definite, factored by CHOLMOD with one symbolic analysis for all
// iterations. Ipopt solves the same programs through MUMPS's LDL^T of the indefinite KKT matrix,
// twice the size, analysed anew on every solve; on the repair's small programs (a few thousand
// variables) that overhead was most of the time (perf: MUMPS and OpenBLAS 53 % of beetle at 2 000
// quads, Ipopt itself 4.5 %).
//
// The variable bounds become rows of C. The iterate stays strictly inside s > 0, z > 0; the primal
// residual goes to zero with the step (the start need not be feasible).
//
// Status: Solved when the relative primal and dual residuals and the duality gap are below
// options.tolerance / 100 (Ipopt's tolerance applies to errors it scales down by the multipliers;
// at options.tolerance itself the solutions were visibly rougher than Ipopt's, and a twisted
// field's repair took another path); Acceptable within 100x that at the iteration limit or a
// failed factorization; Infeasible when the multipliers diverge (the constraints cannot all hold);
// IterationLimit after min(options.max_iterations, 100); Failed when the factorization fails at
// the start or a step does not shrink the dual residual as it must (the normal equations were
// solved inaccurately). x is the last iterate in every case but Failed. Re-entrant (no shared
// state). Throws Error(Cancelled) when progress reports a cancel (checked every iteration).
#pragma once
#include "seamless_map/quadratic_program.h"

namespace qgp {

QPResult solve_qp_interior_point(const SparseQP& qp, const QPOptions& options, Progress& progress);

}  // namespace qgp

// The repair's convex quadratic programs: the interior-point method against closed-form optima,
// against Ipopt on many generated programs, and the fallback to Ipopt where it cannot converge.
#include <gtest/gtest.h>

#include <atomic>
#include <random>
#include <vector>

#include "core/error.h"
#include "seamless_map/interior_point_qp.h"
#include "seamless_map/ipopt_qp.h"
#include "seamless_map/quadratic_program.h"

namespace qgp {
namespace {

using Triplets = std::vector<Eigen::Triplet<double>>;

double objective(const SparseQP& qp, const Eigen::VectorXd& x) {
  return 0.5 * x.dot(qp.hessian * x) + qp.linear.dot(x);
}

// The largest amount by which x violates a constraint row or a variable bound.
double violation(const SparseQP& qp, const Eigen::VectorXd& x) {
  double worst = 0;
  const Eigen::VectorXd value = qp.constraints * x;
  for (Eigen::Index r = 0; r < value.size(); ++r) worst = std::max(worst, qp.lower[r] - value[r]);
  for (Eigen::Index j = 0; j < qp.variable_lower.size(); ++j) worst = std::max(worst, qp.variable_lower[j] - x[j]);
  return worst;
}

SparseQP dense_qp(const Eigen::MatrixXd& h, const Eigen::VectorXd& g, const Eigen::MatrixXd& a,
                  const Eigen::VectorXd& lower) {
  SparseQP qp;
  qp.hessian = h.sparseView();
  qp.linear = g;
  qp.constraints = a.sparseView();
  qp.lower = lower;
  qp.start = Eigen::VectorXd::Zero(g.size());
  return qp;
}

bool converged(const QPResult& r) {
  return r.status == QPResult::Status::Solved || r.status == QPResult::Status::Acceptable;
}

// The rows that get a slack variable, one entry per slack: every fourth row; with `mixed`, also
// two slacks on every other fourth row (only one of them is a pivot of its own in the solver).
std::vector<int> slack_rows(int cells, bool mixed) {
  std::vector<int> rows;
  for (int k = 0; k < cells; ++k) {
    if (k % 4 == 0) rows.push_back(k);
    if (mixed && k % 4 == 2) rows.push_back(k), rows.push_back(k);
  }
  return rows;
}

// Entries of the long rows of repair_like_qp's mixed programs.
constexpr int kLongRow = 48;

// A program shaped like a repair round's: a chain of "triangles" (3 variables pairs each) with a
// Laplacian-like energy towards a random target, sector-like rows a.x >= b that the target breaks
// for some of them, elastic rows with a slack variable x_s >= 0 at a cost, and a start that is
// infeasible. Scaled by `scale` to test the method's independence of units. With `mixed`, some
// rows have two slacks, every third slack also has a quadratic cost, every fifth is coupled to
// the next one in the Hessian, and every tenth cell starts a row of kLongRow variables.
SparseQP repair_like_qp(int cells, double scale, std::mt19937& rng, bool mixed = false) {
  std::uniform_real_distribution<double> u(-1, 1);
  const std::vector<int> slack_row = slack_rows(cells, mixed);
  const int n_plain = 2 * (cells + 2), slacks = static_cast<int>(slack_row.size()), n = n_plain + slacks;
  Triplets h;
  Eigen::VectorXd target(n_plain);
  for (int i = 0; i < n_plain; ++i) target[i] = u(rng) * scale;
  for (int i = 0; i + 2 < n_plain; ++i) {  // springs between neighbours, and a weak anchor
    const double w = 1 + 0.5 * u(rng);
    h.emplace_back(i, i, w), h.emplace_back(i + 2, i + 2, w), h.emplace_back(i, i + 2, -w),
        h.emplace_back(i + 2, i, -w);
  }
  for (int i = 0; i < n_plain; ++i) h.emplace_back(i, i, 1e-3);
  for (int k = 0; mixed && k < slacks; ++k) {
    const int j = n_plain + k;
    if (k % 3 == 0) h.emplace_back(j, j, 0.5 / scale);
    if (k % 5 != 0 || k + 1 >= slacks) continue;
    const double w = 0.1 / scale;
    h.emplace_back(j, j, w), h.emplace_back(j + 1, j + 1, w), h.emplace_back(j, j + 1, w), h.emplace_back(j + 1, j, w);
  }
  SparseQP qp;
  qp.hessian.resize(n, n);
  qp.hessian.setFromTriplets(h.begin(), h.end());
  qp.linear = Eigen::VectorXd::Zero(n);
  qp.linear.head(n_plain) = -(qp.hessian.topLeftCorner(n_plain, n_plain) * target);
  Triplets c;
  std::vector<double> lower;
  int row = 0;
  for (int k = 0; k < cells; ++k, ++row) {
    const int base = 2 * k;
    for (int j = 0; j < 6; ++j) c.emplace_back(row, base + j, u(rng));
    lower.push_back(0.2 * u(rng) * scale);
  }
  for (int k = 0; mixed && 2 * k + kLongRow <= n_plain; k += 10, ++row) {
    for (int j = 0; j < kLongRow; ++j) c.emplace_back(row, 2 * k + j, u(rng));
    lower.push_back(0.2 * u(rng) * scale);
  }
  for (int k = 0; k < slacks; ++k) c.emplace_back(slack_row[k], n_plain + k, k % 2 ? 1.0 : 0.5);
  qp.constraints.resize(row, n);
  qp.constraints.setFromTriplets(c.begin(), c.end());
  qp.lower = Eigen::Map<Eigen::VectorXd>(lower.data(), row);
  qp.variable_lower = Eigen::VectorXd::Constant(n, -2e19);
  for (int j = n_plain; j < n; ++j) {
    qp.variable_lower[j] = 0;
    qp.linear[j] = 10 * scale;
  }
  qp.start = Eigen::VectorXd::Zero(n);
  for (int i = 0; i < n_plain; ++i) qp.start[i] = target[i] + 0.1 * scale * u(rng);
  return qp;
}

// Our solution is Ipopt's, up to the tolerance, and feasible.
void expect_agrees_with_ipopt(const SparseQP& qp, double scale) {
  Progress progress;
  QPOptions options;
  options.tolerance = 1e-7;
  const QPResult own = solve_qp_interior_point(qp, options, progress);
  const QPResult ipopt = solve_qp_ipopt(qp, options, progress);
  ASSERT_TRUE(converged(ipopt)) << ipopt.message;
  ASSERT_TRUE(converged(own)) << own.message;
  const double f_own = objective(qp, own.x), f_ipopt = objective(qp, ipopt.x);
  const double size = 1 + std::abs(f_ipopt);
  EXPECT_LT(std::abs(f_own - f_ipopt) / size, 1e-5);
  EXPECT_LE(violation(qp, own.x), 1e-9 * scale);
  EXPECT_LT(own.iterations, 60);
}

TEST(InteriorPointQP, ProjectionOntoAHalfSpace) {
  // min 1/2 |x - p|^2 s.t. a.x >= b: x* = p + max(0, b - a.p) / |a|^2 a.
  const Eigen::Vector3d p(1, -2, 0.5), a(1, 2, -1);
  const double b = 3;
  const SparseQP qp = dense_qp(Eigen::Matrix3d::Identity(), -p, a.transpose(), Eigen::VectorXd::Constant(1, b));
  Progress progress;
  const QPResult r = solve_qp_interior_point(qp, QPOptions{}, progress);
  ASSERT_EQ(r.status, QPResult::Status::Solved);
  const Eigen::Vector3d expected = p + (b - a.dot(p)) / a.squaredNorm() * a;
  EXPECT_LT((r.x - expected).norm(), 1e-6);
  EXPECT_LE(violation(qp, r.x), 1e-8);  // on the right side, up to the tolerance
}

TEST(InteriorPointQP, InactiveConstraintsLeaveTheUnconstrainedOptimum) {
  const Eigen::Vector2d p(0.3, 0.7);
  Eigen::MatrixXd a(2, 2);
  a << 1, 0, 0, 1;
  const SparseQP qp = dense_qp(2 * Eigen::Matrix2d::Identity(), -2 * p, a, Eigen::Vector2d(-5, -5));
  Progress progress;
  const QPResult r = solve_qp_interior_point(qp, QPOptions{}, progress);
  ASSERT_EQ(r.status, QPResult::Status::Solved);
  EXPECT_LT((r.x - p).norm(), 1e-6);
}

TEST(InteriorPointQP, ALinearProgramInABoxReachesItsCorner) {
  // H = 0 (the Hessian is only semi-definite): min x0 + 2 x1 s.t. x >= (2, -1) as variable bounds,
  // x0 + x1 >= 0.
  SparseQP qp =
      dense_qp(Eigen::Matrix2d::Zero(), Eigen::Vector2d(1, 2), Eigen::RowVector2d(1, 1), Eigen::VectorXd::Zero(1));
  qp.variable_lower = Eigen::Vector2d(2, -1);
  Progress progress;
  const QPResult r = solve_qp_interior_point(qp, QPOptions{}, progress);
  ASSERT_TRUE(converged(r));
  EXPECT_NEAR(r.x[0], 2, 1e-5);
  EXPECT_NEAR(r.x[1], -1, 1e-5);
}

// `trials` generated programs of base + step * (trial % sizes) cells, at the scales 1e-3, 1 and 1e3
// in turn, each solved by both methods.
void expect_agreement_over_trials(unsigned seed, int trials, int base, int step, int sizes, bool mixed_slacks) {
  std::mt19937 rng(seed);
  for (int trial = 0; trial < trials; ++trial) {
    const int cells = base + step * (trial % sizes);
    const double scale = trial % 3 == 0 ? 1e-3 : (trial % 3 == 1 ? 1.0 : 1e3);
    SCOPED_TRACE("trial " + std::to_string(trial) + ", " + std::to_string(cells) + " cells, scale " +
                 std::to_string(scale));
    expect_agrees_with_ipopt(repair_like_qp(cells, scale, rng, mixed_slacks), scale);
  }
}

TEST(InteriorPointQP, AgreesWithIpoptOnGeneratedRepairPrograms) {
  expect_agreement_over_trials(7, 40, 10, 37, 8, false);
}

// Slacks the normal equations cannot eliminate by their own pivots (two in one row, or coupled
// in the Hessian) stay in the factorized matrix beside those they can; rows longer than the
// solver's stored-places limit (32 entries) are summed into the normal matrix through a dense
// column, shorter ones by stored places.
TEST(InteriorPointQP, SlacksSharingARowOrTheHessianAndLongRowsAgreeWithIpopt) {
  expect_agreement_over_trials(11, 12, 12, 41, 4, true);
}

TEST(InteriorPointQP, SameProgramSameBits) {
  std::mt19937 rng(3);
  const SparseQP qp = repair_like_qp(200, 1.0, rng);
  Progress progress;
  const QPResult a = solve_qp_interior_point(qp, QPOptions{}, progress);
  const QPResult b = solve_qp_interior_point(qp, QPOptions{}, progress);
  ASSERT_TRUE(converged(a));
  ASSERT_EQ(a.x.size(), b.x.size());
  for (Eigen::Index i = 0; i < a.x.size(); ++i) EXPECT_EQ(a.x[i], b.x[i]);
}

// repair_like_qp with `rows` more rows of `length` consecutive variables each: enough products of
// long rows (rows * length^2 / 2) for the normal matrix's assembly to use several threads.
SparseQP with_long_rows(SparseQP qp, int rows, int length, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1, 1);
  const int n = static_cast<int>(qp.linear.size()), old_rows = static_cast<int>(qp.constraints.rows());
  Triplets c;
  for (int r = 0; r < old_rows; ++r)
    for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(qp.constraints, r); it; ++it)
      c.emplace_back(r, static_cast<int>(it.col()), it.value());
  Eigen::VectorXd lower(old_rows + rows);
  lower.head(old_rows) = qp.lower;
  for (int r = 0; r < rows; ++r) {
    const int first = (r * 7) % (n - length);
    for (int j = 0; j < length; ++j) c.emplace_back(old_rows + r, first + j, u(rng));
    lower[old_rows + r] = 0.2 * u(rng);
  }
  qp.constraints.resize(old_rows + rows, n);
  qp.constraints.setFromTriplets(c.begin(), c.end());
  qp.lower = lower;
  return qp;
}

// The long rows' products are summed column by column of the normal matrix, the columns shared
// out among threads: one, three or as many as the machine has give the same bits.
TEST(InteriorPointQP, SameBitsWhateverTheNumberOfThreads) {
  std::mt19937 rng(5);
  const SparseQP qp = with_long_rows(repair_like_qp(400, 1.0, rng), 300, 250, rng);
  Progress progress;
  QPOptions options;
  options.threads = 1;
  const QPResult one = solve_qp_interior_point(qp, options, progress);
  ASSERT_TRUE(converged(one)) << one.message;
  for (int threads : {3, 0}) {
    options.threads = threads;
    const QPResult many = solve_qp_interior_point(qp, options, progress);
    ASSERT_EQ(many.iterations, one.iterations) << threads << " threads";
    for (Eigen::Index i = 0; i < one.x.size(); ++i) ASSERT_EQ(many.x[i], one.x[i]) << threads << " threads";
  }
  expect_agrees_with_ipopt(qp, 1.0);
}

TEST(InteriorPointQP, ConflictingConstraintsFallBackToIpopt) {
  // x >= 1 and -x >= 0 cannot both hold: the interior-point method does not claim a solution, and
  // solve_qp hands the program to Ipopt, which reports it infeasible.
  Eigen::MatrixXd a(2, 1);
  a << 1, -1;
  const SparseQP qp = dense_qp(Eigen::MatrixXd::Identity(1, 1), Eigen::VectorXd::Zero(1), a, Eigen::Vector2d(1, 0));
  Progress progress;
  const QPResult own = solve_qp_interior_point(qp, QPOptions{}, progress);
  EXPECT_FALSE(converged(own));
  const QPResult r = solve_qp(qp, QPOptions{}, progress);
  EXPECT_TRUE(r.by_ipopt);
  EXPECT_EQ(r.status, QPResult::Status::Infeasible);
}

TEST(InteriorPointQP, RepairProgramsDoNotNeedIpopt) {
  std::mt19937 rng(11);
  const SparseQP qp = repair_like_qp(300, 1.0, rng);
  Progress progress;
  const QPResult r = solve_qp(qp, QPOptions{}, progress);
  EXPECT_TRUE(converged(r));
  EXPECT_FALSE(r.by_ipopt);
}

TEST(InteriorPointQP, ACancelStopsTheSolve) {
  std::mt19937 rng(5);
  const SparseQP qp = repair_like_qp(100, 1.0, rng);
  std::atomic<bool> cancel(true);
  Progress progress(nullptr, &cancel);
  try {
    solve_qp_interior_point(qp, QPOptions{}, progress);
    FAIL() << "the solve did not stop";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::Cancelled);
  }
}

TEST(InteriorPointQP, InconsistentSizesAreAnInternalError) {
  SparseQP qp =
      dense_qp(Eigen::Matrix2d::Identity(), Eigen::Vector2d(1, 2), Eigen::RowVector2d(1, 1), Eigen::VectorXd::Zero(1));
  qp.start = Eigen::VectorXd::Zero(3);
  Progress progress;
  try {
    solve_qp(qp, QPOptions{}, progress);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::Internal);
  }
}

}  // namespace
}  // namespace qgp

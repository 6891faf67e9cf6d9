#include "seamless_map/interior_point_qp.h"

#include <Eigen/CholmodSupport>
#include <algorithm>
#include <cmath>
#include <vector>

#include "core/blas_kernels.h"
#include "core/error.h"

namespace qgp {
namespace {

using SpMat = Eigen::SparseMatrix<double>;
using Vec = Eigen::VectorXd;

constexpr double kNoBound = -1e19;          // variable_lower at or below this: no bound
constexpr int kOwnMaxIterations = 100;      // Mehrotra's method needs 10-40; more means it is stuck
constexpr double kStepToBoundary = 0.995;   // share of the step to the boundary of s, z > 0
constexpr double kTighterThanIpopt = 1e-2;  // Ipopt's tolerance is on scaled errors (its multipliers
                                            // bound the scale); the relative errors here need less
constexpr double kAcceptableFactor = 100;   // Acceptable: within this factor of the tolerance
constexpr double kDivergedMultipliers = 1e12;
constexpr int kMaxRefinements = 4;       // iterative refinement steps per Newton solve, at most
constexpr double kResidualGrowth = 10;   // lost accuracy: the dual residual this much above
constexpr double kResidualFloor = 1e-8;  // its expected value plus this share of its scale (or the
                                         // tolerance's: a residual within it does no harm)
constexpr double kFirstShift = 1e-12;    // diagonal shift of the normal matrix, relative to H's diagonal

// The constraints C x >= d in compressed rows: the program's rows, then one per bounded variable.
struct Rows {
  std::vector<int> start{0};
  std::vector<int> col;
  std::vector<double> coeff;
  std::vector<double> rhs;
  int size() const { return static_cast<int>(rhs.size()); }
  void add(int c, double a) { col.push_back(c), coeff.push_back(a); }
  void end_row(double d) { start.push_back(static_cast<int>(col.size())), rhs.push_back(d); }
};

Rows constraint_rows(const SparseQP& qp) {
  Rows rows;
  for (int r = 0; r < qp.constraints.rows(); ++r) {
    for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(qp.constraints, r); it; ++it)
      if (it.value() != 0) rows.add(static_cast<int>(it.col()), it.value());
    rows.end_row(qp.lower[r]);
  }
  for (int j = 0; j < qp.variable_lower.size(); ++j)
    if (qp.variable_lower[j] > kNoBound) rows.add(j, 1.0), rows.end_row(qp.variable_lower[j]);
  return rows;
}

Vec times(const Rows& c, const Vec& x) {  // C x
  Vec y(c.size());
  for (int r = 0; r < c.size(); ++r) {
    double v = 0;
    for (int k = c.start[r]; k < c.start[r + 1]; ++k) v += c.coeff[k] * x[c.col[k]];
    y[r] = v;
  }
  return y;
}

Vec times_transposed(const Rows& c, const Vec& y, int n) {  // C^T y
  Vec x = Vec::Zero(n);
  for (int r = 0; r < c.size(); ++r)
    for (int k = c.start[r]; k < c.start[r + 1]; ++k) x[c.col[k]] += c.coeff[k] * y[r];
  return x;
}

// K = H + C^T diag(w) C, lower triangle. Its pattern depends on those of H and C only (w > 0),
// so one symbolic analysis serves every iteration. Formed by sparse products: a row with k entries
// adds k^2 products but few entries (a row of the integer-grid map's repair on dragon-genus1 has
// 623: 110 M products, 2.3 M entries), so nothing is stored per product.
class NormalMatrix {
 public:
  NormalMatrix(const SpMat& hessian, const Rows& rows) {
    const int n = static_cast<int>(hessian.rows());
    std::vector<Eigen::Triplet<double>> entries;
    for (int r = 0; r < rows.size(); ++r)
      for (int k = rows.start[r]; k < rows.start[r + 1]; ++k) entries.emplace_back(r, rows.col[k], rows.coeff[k]);
    c_.resize(rows.size(), n);
    c_.setFromTriplets(entries.begin(), entries.end());
    ct_ = c_.transpose();
    SpMat diagonal(n, n);  // explicit, so that the shift has entries to go to
    diagonal.setIdentity();
    hessian_lower_ = SpMat(hessian.triangularView<Eigen::Lower>()) + 0.0 * diagonal;
  }

  const SpMat& assemble(const Vec& w) {
    const SpMat weighted = ct_ * w.asDiagonal();
    const SpMat product = weighted * c_;
    k_ = hessian_lower_ + SpMat(product.triangularView<Eigen::Lower>());
    return k_;
  }

 private:
  SpMat c_, ct_;  // C (m x n) and its transpose
  SpMat hessian_lower_;
  SpMat k_;
};

double max_abs(const Vec& v) { return v.size() ? v.lpNorm<Eigen::Infinity>() : 0.0; }

// The largest a in (0, 1] with v + a dv >= 0 (v > 0).
double step_to_boundary(const Vec& v, const Vec& dv) {
  double a = 1;
  for (Eigen::Index i = 0; i < v.size(); ++i)
    if (dv[i] < 0) a = std::min(a, -v[i] / dv[i]);
  return a;
}

struct Direction {
  Vec dx, ds, dz;
};

class InteriorPoint {
 public:
  InteriorPoint(const SparseQP& qp, const QPOptions& options, Progress& progress)
      : qp_(qp),
        options_(options),
        progress_(progress),
        n_(static_cast<int>(qp.linear.size())),
        rows_(constraint_rows(qp)),
        m_(rows_.size()),
        normal_(qp.hessian, rows_) {
    cholesky_.cholmod().print = 0;
    cholesky_.cholmod().nmethods = 1;
    cholesky_.cholmod().method[0].ordering = CHOLMOD_AMD;  // deterministic
    d_ = Eigen::Map<const Vec>(rows_.rhs.data(), m_);
    tolerance_ = kTighterThanIpopt * options.tolerance;
    hessian_scale_ = 1.0;
    for (int j = 0; j < n_; ++j) hessian_scale_ = std::max(hessian_scale_, std::abs(qp.hessian.coeff(j, j)));
  }

  QPResult run() {
    QPResult result;
    x_ = qp_.start;
    pin_blas_kernels();
    if (!start_point()) return finish(result, QPResult::Status::Failed, "the first factorization failed");
    const int max_iterations = std::min(options_.max_iterations, kOwnMaxIterations);
    double a = 1;  // the last step's length
    for (int it = 0; it < max_iterations; ++it) {
      result.iterations = it;
      progress_.check_cancel();
      progress_.update(options_.progress_begin + it / (it + 20.0) * (options_.progress_end - options_.progress_begin));
      const double expected_rd = (1 - a) * max_abs(rd_);
      update_residuals();
      if (it > 0 && lost_accuracy(expected_rd))
        return finish(result, QPResult::Status::Failed, "the Newton steps lost accuracy");
      if (error() <= tolerance_) return finish(result, QPResult::Status::Solved, "solved");
      if (multipliers_diverge()) return finish(result, QPResult::Status::Infeasible, "infeasible");
      if (!factor()) return finish(result, fallback_status(QPResult::Status::Failed), "factorization failed");
      a = step();
    }
    result.iterations = max_iterations;
    update_residuals();
    if (error() <= tolerance_) return finish(result, QPResult::Status::Solved, "solved");
    return finish(result, fallback_status(QPResult::Status::IterationLimit), "stopped before convergence");
  }

 private:
  // The start: x as given, s its constraint values (at least a small floor), z = 1; then one
  // affine step, and s and z moved to at least the floors (Nocedal & Wright (16.60), scaled).
  bool start_point() {
    const Vec w = times(rows_, x_) - d_;
    const double floor = 1e-3 * std::max(1.0, max_abs(w));
    s_ = w.cwiseMax(floor);
    z_ = Vec::Constant(m_, 1.0);
    update_residuals();
    if (!factor()) return false;
    const Direction affine = newton(s_.cwiseProduct(z_));
    s_ = (s_ + affine.ds).cwiseAbs().cwiseMax(floor);
    z_ = (z_ + affine.dz).cwiseAbs().cwiseMax(1.0);
    return true;
  }

  // One predictor-corrector step (Mehrotra); returns its length.
  double step() {
    const Vec sz = s_.cwiseProduct(z_);
    const double mu = m_ ? sz.sum() / m_ : 0.0;
    const Direction affine = newton(sz);
    const double a_affine = std::min(step_to_boundary(s_, affine.ds), step_to_boundary(z_, affine.dz));
    double sigma = 0;
    if (m_) {
      const double mu_affine = (s_ + a_affine * affine.ds).dot(z_ + a_affine * affine.dz) / m_;
      sigma = std::pow(mu_affine / mu, 3);
    }
    const Vec rc = sz + affine.ds.cwiseProduct(affine.dz) - Vec::Constant(m_, sigma * mu);
    const Direction d = newton(rc);
    const double a = std::min(1.0, kStepToBoundary * std::min(step_to_boundary(s_, d.ds), step_to_boundary(z_, d.dz)));
    x_ += a * d.dx;
    s_ += a * d.ds;
    z_ += a * d.dz;
    return a;
  }

  // The Newton direction for H dx - C^T dz = -rd, C dx - ds = -rp, Z ds + S dz = -rc, through the
  // normal equations (H + C^T (Z/S) C) dx = -rd - C^T S^-1 (rc + Z rp).
  Direction newton(const Vec& rc) const {
    Direction d;
    const Vec t = (rc + z_.cwiseProduct(rp_)).cwiseQuotient(s_);
    const Vec rhs = -rd_ - times_transposed(rows_, t, n_);
    d.dx = cholesky_.solve(rhs);
    // Iterative refinement against K without the shift, while it halves the residual.
    double residual = (rhs - normal_times(d.dx)).lpNorm<Eigen::Infinity>();
    for (int k = 0; k < kMaxRefinements && residual > 1e-15 * max_abs(rhs); ++k) {
      const Vec next = d.dx + cholesky_.solve(rhs - normal_times(d.dx));
      const double next_residual = (rhs - normal_times(next)).lpNorm<Eigen::Infinity>();
      if (!(next_residual < residual)) break;
      d.dx = next;
      if (next_residual > 0.5 * residual) break;
      residual = next_residual;
    }
    d.ds = times(rows_, d.dx) + rp_;
    d.dz = -(rc + z_.cwiseProduct(d.ds)).cwiseQuotient(s_);
    return d;
  }

  Vec normal_times(const Vec& v) const {  // (H + C^T (Z/S) C) v
    return qp_.hessian * v + times_transposed(rows_, z_.cwiseQuotient(s_).cwiseProduct(times(rows_, v)), n_);
  }

  bool factor() {
    const SpMat& k = normal_.assemble(z_.cwiseQuotient(s_));
    if (!analysed_) {
      cholesky_.analyzePattern(k);
      analysed_ = true;
    }
    double shift = kFirstShift * hessian_scale_;
    for (int attempt = 0; attempt < 4; ++attempt, shift *= 1e3) {
      cholesky_.setShift(shift);
      cholesky_.factorize(k);
      if (cholesky_.info() == Eigen::Success) return true;
    }
    return false;
  }

  void update_residuals() {
    const Vec cx = times(rows_, x_);
    hx_ = qp_.hessian * x_;
    rp_ = cx - s_ - d_;
    rd_ = hx_ + qp_.linear - times_transposed(rows_, z_, n_);
    primal_scale_ = 1 + std::max(max_abs(d_), max_abs(cx));
    dual_scale_ = 1 + std::max(max_abs(qp_.linear), max_abs(hx_));
  }

  // The largest of the relative primal residual, dual residual and duality gap.
  double error() const {
    const double objective = 0.5 * x_.dot(hx_) + qp_.linear.dot(x_);
    const double gap = m_ ? s_.dot(z_) : 0.0;
    return std::max({max_abs(rp_) / primal_scale_, max_abs(rd_) / dual_scale_, gap / (1 + std::abs(objective))});
  }

  // A step of length a scales the dual residual by 1 - a (it is linear in the step); a larger one
  // means the normal equations were solved inaccurately, and the iterate cannot be trusted.
  bool lost_accuracy(double expected_rd) const {
    return max_abs(rd_) > kResidualGrowth * expected_rd + std::max(kResidualFloor, tolerance_) * dual_scale_;
  }

  bool multipliers_diverge() const { return max_abs(z_) > kDivergedMultipliers * dual_scale_; }

  QPResult::Status fallback_status(QPResult::Status status) const {
    return error() <= kAcceptableFactor * tolerance_ ? QPResult::Status::Acceptable : status;
  }

  QPResult& finish(QPResult& result, QPResult::Status status, const char* message) {
    result.status = status;
    result.message = status == QPResult::Status::Acceptable ? "solved to acceptable level" : message;
    result.x = x_;
    return result;
  }

  const SparseQP& qp_;
  const QPOptions& options_;
  Progress& progress_;
  const int n_;
  const Rows rows_;
  const int m_;
  NormalMatrix normal_;
  Eigen::CholmodDecomposition<SpMat, Eigen::Lower> cholesky_;
  bool analysed_ = false;
  Vec d_, x_, s_, z_, hx_, rp_, rd_;
  double tolerance_ = 0;
  double hessian_scale_ = 1, primal_scale_ = 1, dual_scale_ = 1;
};

}  // namespace

QPResult solve_qp_interior_point(const SparseQP& qp, const QPOptions& options, Progress& progress) {
  InteriorPoint solver(qp, options, progress);
  return solver.run();
}

}  // namespace qgp

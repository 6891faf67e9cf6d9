#include "seamless_map/interior_point_qp.h"

#include <Eigen/CholmodSupport>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "core/blas_kernels.h"
#include "core/error.h"
#include "core/parallel.h"

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
// Normal matrices of at least this many variables are ordered by nested dissection (METIS), smaller
// ones by minimum degree (AMD), whose analysis is cheaper. Both are deterministic. The local repair
// rounds of mnf07 (20 466 variables) need 54 instead of 96 Mflop per factorization.
constexpr int kNestedDissectionVariables = 10000;

// The constraints C x >= d: the program's rows, then one per bounded variable.
struct Constraints {
  SpMat c, ct;  // C (m x n) and its transpose
  Vec d;
};

Constraints constraint_rows(const SparseQP& qp) {
  const int n = static_cast<int>(qp.linear.size());
  std::vector<Eigen::Triplet<double>> entries;
  std::vector<double> rhs;
  for (int r = 0; r < qp.constraints.rows(); ++r) {
    for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(qp.constraints, r); it; ++it)
      if (it.value() != 0) entries.emplace_back(r, static_cast<int>(it.col()), it.value());
    rhs.push_back(qp.lower[r]);
  }
  for (int j = 0; j < qp.variable_lower.size(); ++j)
    if (qp.variable_lower[j] > kNoBound) {
      entries.emplace_back(static_cast<int>(rhs.size()), j, 1.0);
      rhs.push_back(qp.variable_lower[j]);
    }
  Constraints cs;
  cs.c.resize(static_cast<Eigen::Index>(rhs.size()), n);
  cs.c.setFromTriplets(entries.begin(), entries.end());
  cs.ct = cs.c.transpose();
  cs.d = Eigen::Map<const Vec>(rhs.data(), static_cast<Eigen::Index>(rhs.size()));
  return cs;
}

// The variables the normal equations eliminate by their own pivot: those with no Hessian entry
// off the diagonal that share exactly one row of C with other variables, and no other such
// variable in it (the slacks of elastic rows: the field-frame solve of mnf07 has 131 000 of them
// beside 24 000 map coordinates). Every other variable is kept.
struct Singletons {
  std::vector<int> kept_of;  // variable -> index among the kept ones, or -1: eliminated
  int kept = 0;
  std::vector<int> var, row;  // each eliminated variable and the row it shares
  std::vector<double> coeff;  // C(row, var)
};

bool couples_in_hessian(const SpMat& hessian, int j) {
  for (SpMat::InnerIterator it(hessian, j); it; ++it)
    if (it.row() != j && it.value() != 0) return true;
  return false;
}

Singletons find_singletons(const SpMat& hessian, const Constraints& cs) {
  const int n = static_cast<int>(cs.c.cols());
  std::vector<int> row_length(cs.c.rows(), 0);
  for (int j = 0; j < n; ++j)
    for (SpMat::InnerIterator it(cs.c, j); it; ++it) ++row_length[it.row()];
  Singletons sg;
  sg.kept_of.assign(n, -1);
  std::vector<char> row_taken(cs.c.rows(), 0);
  for (int j = 0; j < n; ++j) {
    int shared = -1, count = 0;
    double coeff = 0;
    for (SpMat::InnerIterator it(cs.c, j); it; ++it)
      if (row_length[it.row()] > 1) shared = static_cast<int>(it.row()), coeff = it.value(), ++count;
    if (count == 1 && !row_taken[shared] && !couples_in_hessian(hessian, j)) {
      row_taken[shared] = 1;
      sg.var.push_back(j), sg.row.push_back(shared), sg.coeff.push_back(coeff);
    } else {
      sg.kept_of[j] = sg.kept++;
    }
  }
  return sg;
}

// Columns of `m` (whose rows are variables) of the kept variables, renumbered.
SpMat kept_columns(const SpMat& m, const Singletons& sg) {
  std::vector<Eigen::Triplet<double>> entries;
  for (int j = 0; j < m.cols(); ++j)
    if (sg.kept_of[j] >= 0)
      for (SpMat::InnerIterator it(m, j); it; ++it) entries.emplace_back(it.row(), sg.kept_of[j], it.value());
  SpMat kept(m.rows(), sg.kept);
  kept.setFromTriplets(entries.begin(), entries.end());
  return kept;
}

// The normal equations K dx = b, K = H + C^T diag(w) C. Each eliminated variable j, sharing row r,
// has the pivot p_j = q_j + w_r C_rj^2, q_j = H_jj + sum over its other rows i of w_i C_ij^2; K on
// the kept variables u is then
//     K_u = H_uu + C_u^T diag(w~) C_u,  w~_r = w_r - (w_r C_rj)^2 / p_j = w_r q_j / p_j
// (w~ = w on other rows; the last form has no cancellation where w_r dwarfs q_j). Its pattern
// depends on those of H and C only (w > 0): one symbolic analysis serves every iteration, and the
// values are summed into that pattern in place, row by row of C (a row with entries a_1 < ... < a_k
// adds w~_r C_ra C_rb at (b, a) for a <= b). Where each such product goes is stored for rows of up
// to kStoredRowEntries entries. Longer rows would need too many places (a row of the integer-grid
// map's repair on dragon-genus1 has 623 entries: 194 000 products; its field-frame solve without
// cancelled pairs has 5 348 rows of 200 on average: 107 M products), so their products are summed
// column by column of K into a dense column each time.
class NormalEquations {
 public:
  // threads: see QPOptions::threads.
  NormalEquations(const SpMat& hessian, const Constraints& cs, int threads)
      : threads_(threads),
        cs_(cs),
        sg_(find_singletons(hessian, cs)),
        hessian_diagonal_(hessian.diagonal()),
        pivot_(Vec::Zero(hessian.rows())) {
    const SpMat h_kept = kept_columns(SpMat(kept_columns(hessian, sg_).transpose()), sg_);
    SpMat diagonal(sg_.kept, sg_.kept);  // explicit, so that the shift has entries to go to
    diagonal.setIdentity();
    const SpMat hessian_lower = SpMat(h_kept.triangularView<Eigen::Lower>()) + 0.0 * diagonal;
    c_kept_ = kept_columns(cs.c, sg_);
    ct_kept_ = c_kept_.transpose();
    const SpMat pattern = ct_kept_ * c_kept_;
    k_ = hessian_lower + SpMat(pattern.triangularView<Eigen::Lower>());
    k_.makeCompressed();
    place_hessian(hessian_lower);
    store_product_slots();
    index_long_rows();
  }

  int kept_variables() const { return sg_.kept; }
  const Vec& weights() const { return w_; }  // w of the last assembly

  // K_u for the weights w, lower triangle.
  const SpMat& assemble(const Vec& w) {
    w_ = w;
    Vec reduced_w = w;
    for (size_t k = 0; k < sg_.var.size(); ++k) {
      const int j = sg_.var[k], r = sg_.row[k];
      double own = hessian_diagonal_[j];  // q_j
      for (SpMat::InnerIterator it(cs_.c, j); it; ++it)
        if (it.row() != r) own += w[it.row()] * it.value() * it.value();
      pivot_[j] = own + w[r] * sg_.coeff[k] * sg_.coeff[k];
      reduced_w[r] = w[r] * own / pivot_[j];
    }
    add_products(reduced_w);
    return k_;
  }

  // dx with K dx = b, given the factorization of the last assembled K_u.
  template <class Factor>
  Vec solve(const Factor& factor, const Vec& b) const {
    Vec g = Vec::Zero(cs_.c.rows());
    Vec reduced_b(sg_.kept);
    for (int j = 0; j < static_cast<int>(b.size()); ++j)
      if (sg_.kept_of[j] >= 0) reduced_b[sg_.kept_of[j]] = b[j];
    for (size_t k = 0; k < sg_.var.size(); ++k)
      g[sg_.row[k]] = w_[sg_.row[k]] * sg_.coeff[k] * b[sg_.var[k]] / pivot_[sg_.var[k]];
    reduced_b -= ct_kept_ * g;
    const Vec dx_kept = factor.solve(reduced_b);
    const Vec c_dx = c_kept_ * dx_kept;
    Vec dx(b.size());
    for (int j = 0; j < static_cast<int>(b.size()); ++j)
      if (sg_.kept_of[j] >= 0) dx[j] = dx_kept[sg_.kept_of[j]];
    for (size_t k = 0; k < sg_.var.size(); ++k) {
      const int j = sg_.var[k], r = sg_.row[k];
      dx[j] = (b[j] - w_[r] * sg_.coeff[k] * c_dx[r]) / pivot_[j];
    }
    return dx;
  }

 private:
  static constexpr int kStoredRowEntries = 32;
  // The long rows' products are shared among threads (threads_for: up to 8), each with at least
  // kProductsPerThread of them, so that starting a thread pays.
  static constexpr double kProductsPerThread = 2000000;

  int row_entries(int r) const { return ct_kept_.outerIndexPtr()[r + 1] - ct_kept_.outerIndexPtr()[r]; }

  // Where each product of a short row goes in K: for every pair t <= s of its entries, in the
  // order of add_products.
  void store_product_slots() {
    for (int r = 0; r < ct_kept_.cols(); ++r) {
      const int k = row_entries(r);
      if (k > kStoredRowEntries) continue;
      const int* variable = ct_kept_.innerIndexPtr() + ct_kept_.outerIndexPtr()[r];
      for (int t = 0; t < k; ++t) {
        int slot = k_.outerIndexPtr()[variable[t]];
        for (int s = t; s < k; ++s) {
          while (k_.innerIndexPtr()[slot] != variable[s]) ++slot;
          product_slot_.push_back(slot);
        }
      }
    }
  }

  // H's lower triangle in K's pattern, the start of every assembly.
  void place_hessian(const SpMat& hessian_lower) {
    hessian_values_.assign(k_.nonZeros(), 0.0);
    for (int j = 0; j < k_.cols(); ++j) {
      int slot = k_.outerIndexPtr()[j];
      for (SpMat::InnerIterator it(hessian_lower, j); it; ++it) {
        while (k_.innerIndexPtr()[slot] != it.row()) ++slot;
        hessian_values_[slot] = it.value();
      }
    }
  }

  // K = C^T diag(w) C + H on the kept variables, in place (H added last, as the products'
  // sums can dwarf it).
  void add_products(const Vec& w) {
    double* value = k_.valuePtr();
    std::fill(value, value + k_.nonZeros(), 0.0);
    size_t stored = 0;
    for (int r = 0; r < ct_kept_.cols(); ++r) {
      const int k = row_entries(r);
      if (k > kStoredRowEntries) continue;
      const double* c = ct_kept_.valuePtr() + ct_kept_.outerIndexPtr()[r];
      for (int t = 0; t < k; ++t) {
        const double wc = w[r] * c[t];
        for (int s = t; s < k; ++s) value[product_slot_[stored++]] += wc * c[s];
      }
    }
    add_long_row_products(w);
    for (size_t i = 0; i < hessian_values_.size(); ++i) value[i] += hessian_values_[i];
  }

  // The long rows' products, column by column of K: those of each row entry at or below the
  // column are summed into a dense column, which is then gathered into K's pattern. Each column's
  // sums are its own, so the columns are shared out among threads by their products (where there
  // are enough of them): the same sums in the same order, whatever the number of threads.
  void add_long_row_products(const Vec& w) {
    run_chunks(static_cast<int>(split_.size()) - 1,
               [&](int t) { add_long_row_columns(w, split_[t], split_[t + 1], t == 0 ? column_ : scratch_[t - 1]); });
  }

  // add_long_row_products for columns [begin, end) of K, with `column` (zero, left zero) to sum in.
  void add_long_row_columns(const Vec& w, int begin, int end, std::vector<double>& column) {
    const int* row_start = ct_kept_.outerIndexPtr();
    const int* variable = ct_kept_.innerIndexPtr();
    const double* c = ct_kept_.valuePtr();
    for (int j = begin; j < end; ++j) {
      if (long_entry_start_[j] == long_entry_start_[j + 1]) continue;
      for (int e = long_entry_start_[j]; e < long_entry_start_[j + 1]; ++e) {
        const int r = long_entry_row_[e], stop = row_start[r + 1];
        const double wc = w[r] * c[long_entry_[e]];
        for (int i = long_entry_[e]; i < stop; ++i) column[variable[i]] += wc * c[i];
      }
      for (int slot = k_.outerIndexPtr()[j]; slot < k_.outerIndexPtr()[j + 1]; ++slot) {
        k_.valuePtr()[slot] += column[k_.innerIndexPtr()[slot]];
        column[k_.innerIndexPtr()[slot]] = 0;
      }
    }
  }

  // For every kept variable, the entries of the long rows in its column of C (as positions in
  // ct_kept_, rows in increasing order). Columns are visited in increasing order, so each row's
  // next entry is the one at its cursor.
  void index_long_rows() {
    std::vector<int> cursor(ct_kept_.outerIndexPtr(), ct_kept_.outerIndexPtr() + ct_kept_.cols());
    long_entry_start_.assign(1, 0);
    long_products_.assign(1, 0);
    for (int j = 0; j < c_kept_.cols(); ++j) {
      int64_t products = long_products_.back();
      for (SpMat::InnerIterator it(c_kept_, j); it; ++it) {
        const int r = static_cast<int>(it.row()), i = cursor[r]++;
        if (row_entries(r) <= kStoredRowEntries) continue;
        long_entry_.push_back(i), long_entry_row_.push_back(r);
        products += ct_kept_.outerIndexPtr()[r + 1] - i;
      }
      long_entry_start_.push_back(static_cast<int>(long_entry_.size()));
      long_products_.push_back(products);
    }
    column_.assign(k_.cols(), 0.0);
    share_out_long_rows();
  }

  // split_: the columns of each thread of add_long_row_products, with about equal products.
  void share_out_long_rows() {
    const int columns = static_cast<int>(k_.cols());
    const int threads = threads_for(static_cast<double>(long_products_.back()), kProductsPerThread, threads_);
    split_.assign(threads + 1, columns);
    split_[0] = 0;
    for (int t = 1; t < threads; ++t)
      split_[t] = static_cast<int>(
          std::lower_bound(long_products_.begin(), long_products_.end(), long_products_.back() * t / threads) -
          long_products_.begin());
    scratch_.assign(threads - 1, std::vector<double>(columns, 0.0));
  }

  const int threads_;  // QPOptions::threads (0: the machine's count)
  const Constraints& cs_;
  const Singletons sg_;
  const Vec hessian_diagonal_;
  SpMat c_kept_, ct_kept_;
  SpMat k_;                                                          // its pattern is fixed at construction
  std::vector<double> hessian_values_;                               // H's lower triangle in K's pattern
  std::vector<int> product_slot_;                                    // where each product of a short row goes in K
  std::vector<int> long_entry_start_, long_entry_, long_entry_row_;  // see index_long_rows
  std::vector<int64_t> long_products_;        // the long rows' products in the columns before each column
  std::vector<int> split_;                    // thread t sums columns [split_[t], split_[t + 1])
  std::vector<double> column_;                // zero between assemblies
  std::vector<std::vector<double>> scratch_;  // the other threads' columns, zero between assemblies
  Vec w_, pivot_;                             // the weights and pivots of the last assembly
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
        cs_(constraint_rows(qp)),
        m_(static_cast<int>(cs_.d.size())),
        normal_(qp.hessian, cs_, options.threads) {
    cholesky_.cholmod().print = 0;
    cholesky_.cholmod().nmethods = 1;
    cholesky_.cholmod().method[0].ordering =
        normal_.kept_variables() >= kNestedDissectionVariables ? CHOLMOD_METIS : CHOLMOD_AMD;
    tolerance_ = kTighterThanIpopt * options.tolerance;
    hessian_scale_ = std::max(1.0, max_abs(qp.hessian.diagonal()));
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
    const Vec w = times(x_) - cs_.d;
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
    const Vec rhs = -rd_ - times_transposed(t);
    d.dx = normal_.solve(cholesky_, rhs);
    // Iterative refinement against K without the shift, while it halves the residual.
    Vec residual = rhs - normal_times(d.dx);
    for (int k = 0; k < kMaxRefinements && max_abs(residual) > 1e-15 * max_abs(rhs); ++k) {
      const Vec next = d.dx + normal_.solve(cholesky_, residual);
      Vec next_residual = rhs - normal_times(next);
      if (!(max_abs(next_residual) < max_abs(residual))) break;
      d.dx = next;
      if (max_abs(next_residual) > 0.5 * max_abs(residual)) break;
      residual = std::move(next_residual);
    }
    d.ds = times(d.dx) + rp_;
    d.dz = -(rc + z_.cwiseProduct(d.ds)).cwiseQuotient(s_);
    return d;
  }

  Vec times(const Vec& x) const { return cs_.c * x; }              // C x
  Vec times_transposed(const Vec& y) const { return cs_.ct * y; }  // C^T y

  Vec normal_times(const Vec& v) const {  // (H + C^T W C) v, W = Z/S of the last factorization
    return qp_.hessian * v + times_transposed(normal_.weights().cwiseProduct(times(v)));
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
    const Vec cx = times(x_);
    hx_ = qp_.hessian * x_;
    rp_ = cx - s_ - cs_.d;
    rd_ = hx_ + qp_.linear - times_transposed(z_);
    primal_scale_ = 1 + std::max(max_abs(cs_.d), max_abs(cx));
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
  const Constraints cs_;
  const int m_;
  NormalEquations normal_;
  Eigen::CholmodDecomposition<SpMat, Eigen::Lower> cholesky_;
  bool analysed_ = false;
  Vec x_, s_, z_, hx_, rp_, rd_;
  double tolerance_ = 0;
  double hessian_scale_ = 1, primal_scale_ = 1, dual_scale_ = 1;
};

}  // namespace

QPResult solve_qp_interior_point(const SparseQP& qp, const QPOptions& options, Progress& progress) {
  InteriorPoint solver(qp, options, progress);
  return solver.run();
}

}  // namespace qgp

// The greedy quantizer of paper §6.3 (stages I and II) and the shared helpers.
#include <gmpxx.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <queue>

#include "core/error.h"
#include "core/timer.h"
#include "quantization/cell_system.h"
#include "quantization/generating_vectors.h"
#include "quantization/quantization.h"
#include "quantization/validity.h"

namespace qgp {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Three-tier weight of §6.2 for d = d+(e) or d-(e); eta = number of T-edges.
double tier_weight(double d, double eta) {
  if (d >= 1) return 1 / (d + 1);
  if (d >= 0) return eta / (d + 1);
  return eta * eta * (1 - d);
}

struct Change {
  int edge;
  int64_t delta;
};

// Change of (x/xi - 1)^2 when x grows by delta.
double term_change(int64_t x, int64_t delta, double xi) {
  return static_cast<double>(delta) * (static_cast<double>(2 * x + delta) - 2 * xi) / (xi * xi);
}

// Exact sign of the objective change of a step; *approx receives its floating-point value.
// The floating sum decides unless it is within its rounding error bound of zero, then GMP
// rationals (every double is an exact rational) decide.
int objective_change_sign(const std::vector<Change>& changes, const std::vector<int64_t>& x,
                          const std::vector<double>& ideal, double* approx) {
  double sum = 0, magnitude = 0;
  for (const Change& c : changes) {
    const double t = term_change(x[c.edge], c.delta, ideal[c.edge]);
    sum += t;
    magnitude += std::abs(t);
  }
  *approx = sum;
  const double bound = (static_cast<double>(changes.size()) + 8) * std::ldexp(magnitude, -52);
  if (sum > bound) return 1;
  if (sum < -bound) return -1;
  mpq_class exact(0);
  for (const Change& c : changes) {
    const mpq_class xi(ideal[c.edge]);
    const mpq_class d(static_cast<long>(c.delta));
    exact += d * (mpq_class(static_cast<long>(2 * x[c.edge] + c.delta)) - 2 * xi) / (xi * xi);
  }
  return sgn(exact);
}

class GreedyQuantizer {
 public:
  GreedyQuantizer(const TMesh& tmesh, const QuantizationOptions& options, Progress& progress)
      : tmesh_(tmesh), options_(options), progress_(progress), system_(tmesh), search_(system_), validity_(system_) {
    const int E = system_.num_edges();
    eta_ = std::max(1, E);
    ideal_.resize(E);
    for (int e = 0; e < E; ++e) ideal_[e] = std::max(options.scale * tmesh.edges[e].length, options.min_ideal_length);
    min_length_ = options.min_length.empty() ? std::vector<int64_t>(E, 0) : options.min_length;
    x_.assign(E, 0);
    change_index_.assign(E, 0);
    w_plus_.resize(E);
    w_minus_.resize(E);
    for (int e = 0; e < E; ++e) update_weights(e);
  }

  QuantizationResult run() {
    QuantizationResult r;
    r.quantizer = Quantizer::Greedy;
    r.scale = options_.scale;
    Timer total;
    stage1(r);
    r.stage1_seconds = total.seconds();
    const QuantizationValidity v = validity_.commit_full(x_);
    ++r.validity_checks;
    if (!v.valid)
      throw Error(ErrorCode::StageFailed, "quantization: no valid quantization reachable (" +
                                              std::to_string(r.unreachable_edges) +
                                              " T-edge(s) admit no generating vector): " + v.reason);
    objective_ = full_objective();
    r.objective_history.push_back(objective_);
    Timer timer2;
    stage2(r);
    r.stage2_seconds = timer2.seconds();

    r.x = x_;
    r.valid = validity_.check(x_).valid;
    ++r.validity_checks;
    r.objective = full_objective();
    r.zero_edges = static_cast<int>(std::count(x_.begin(), x_.end(), 0));
    r.consistency_residual = quantization_consistency_residual(tmesh_, x_);
    r.quads_expected = quantization_quads(tmesh_, x_);
    r.searches = searches_;
    r.searched_nodes = search_.labelled_nodes();
    r.validity_searches = validity_.searched_singularities();
    r.seconds = total.seconds();
    return r;
  }

 private:
  void update_weights(int e) {
    w_plus_[e] = tier_weight(ideal_[e] - static_cast<double>(x_[e]), eta_);
    w_minus_[e] = x_[e] <= min_length_[e] ? kInf : tier_weight(static_cast<double>(x_[e]) - ideal_[e], eta_);
  }
  double full_objective() const {
    double sum = 0;
    for (size_t e = 0; e < x_.size(); ++e) {
      const double d = static_cast<double>(x_[e]) / ideal_[e] - 1;
      sum += d * d;
    }
    return sum;
  }
  // Aggregates a circuit/path into per-edge changes of sign `sign`.
  void collect_changes(const std::vector<int>& dnodes, int sign) {
    changes_.clear();
    for (int n : dnodes) {
      const int e = n / 2;
      const int at = change_index_[e];
      if (at < static_cast<int>(changes_.size()) && changes_[at].edge == e)
        changes_[at].delta += sign;
      else
        change_index_[e] = static_cast<int>(changes_.size()), changes_.push_back({e, sign});
    }
  }
  void apply_changes(int sign) {
    for (const Change& c : changes_) {
      x_[c.edge] += sign * c.delta;
      update_weights(c.edge);
    }
  }

  void stage1(QuantizationResult& r) {
    progress_.update(0);
    const int E = system_.num_edges();
    std::vector<int> order(E);
    for (int e = 0; e < E; ++e) order[e] = e;
    // x = 0 everywhere, so w+ depends on the ideal length only: the order is fixed.
    std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return w_plus_[a] < w_plus_[b]; });
    Timer tick;
    for (int k = 0; k < E; ++k) {
      const int e = order[k];
      if (tick.seconds() > 0.1) progress_.update(0.3 * k / E), tick = Timer();
      while (x_[e] < std::max<int64_t>(1, min_length_[e])) {
        ++searches_;
        if (!search_.find(e, w_plus_, dnodes_, nullptr)) {
          ++r.unreachable_edges;
          break;
        }
        collect_changes(dnodes_, +1);
        apply_changes(+1);
        ++r.stage1_steps;
      }
    }
  }

  // Stage II: candidates (edge, add/subtract) in order of increasing weight; the first one whose
  // generating vector keeps validity and decreases the objective is applied, then the order is
  // re-evaluated. A candidate that failed is not retried while its failure provably persists:
  // its circuit stays a minimum-weight one as long as no edge of the circuit changes and no edge
  // of the explored region becomes lighter (the search's optimality bound uses only the weights of
  // labelled nodes); the objective change depends on the circuit's edges only; a collapse found by
  // the validity test persists while the edges of its witness keep their lengths.
  void stage2(QuantizationResult& r) {
    start_stage2();
    Timer tick, elapsed;
    int64_t evaluated = 0;
    double fraction = 0.3;
    while (!heap_.empty()) {
      if (options_.stage2_time_limit > 0 && elapsed.seconds() > options_.stage2_time_limit) {
        r.stage2_converged = false;
        break;
      }
      const HeapEntry top = heap_.top();
      heap_.pop();
      if (top.generation != generation_[top.candidate]) continue;
      if (tick.seconds() > 0.1) {
        fraction = std::max(fraction, 0.3 + 0.7 * static_cast<double>(evaluated) / (evaluated + heap_.size() + 1));
        progress_.update(fraction);
        tick = Timer();
      }
      ++evaluated;
      evaluate_candidate(top.candidate, r);
    }
    progress_.update(1);
  }
  // Clears the failure cache and queues every candidate.
  void start_stage2() {
    const int E = system_.num_edges();
    const int num_candidates = 2 * E;  // candidate 2e: subtract at e, 2e+1: add at e
    generation_.assign(num_candidates, 0);
    dependency_count_.assign(num_candidates, 0);
    build_clusters(1);  // exact: one edge per cluster, until the memory budget is reached
    strong_deps_.assign(E, {});
    weak_deps_.assign(num_clusters_, {});
    live_dependencies_ = stored_dependencies_ = 0;
    for (int cand = 0; cand < num_candidates; ++cand) push_candidate(cand);
    edge_seen_.assign(E, 0);
    cluster_seen_.assign(E, 0);
    seen_stamp_ = 0;
  }
  // The weight of a candidate's edge in the direction it changes (w+ to add, w- to subtract).
  double candidate_weight(int cand) const { return (cand & 1) ? w_plus_[cand / 2] : w_minus_[cand / 2]; }
  // (Re)queues a candidate with its current weight, dropping its cached failure; not if excluded.
  void push_candidate(int cand) {
    ++generation_[cand];
    live_dependencies_ -= dependency_count_[cand];
    dependency_count_[cand] = 0;
    const double w = candidate_weight(cand);
    if (w < kInf) heap_.push({w, cand, generation_[cand]});
  }
  // Searches the candidate's generating vector and applies it if it improves the objective and
  // keeps validity; otherwise caches the failure with what it depends on.
  void evaluate_candidate(int cand, QuantizationResult& r) {
    const int e = cand / 2, sign = (cand & 1) ? +1 : -1;
    const std::vector<double>& weights = sign > 0 ? w_plus_ : w_minus_;
    explored_.clear();
    strong_.clear();
    ++searches_;
    if (!search_.find(e, weights, dnodes_, &explored_)) {
      remember_failure(cand);
      return;
    }
    collect_changes(dnodes_, sign);
    for (const Change& c : changes_) strong_.push_back(c.edge);
    double approx = 0;
    if (!step_is_feasible() || objective_change_sign(changes_, x_, ideal_, &approx) >= 0) {
      ++r.stage2_not_improving;
      remember_failure(cand);
      return;
    }
    if (!apply_if_valid(r)) {
      ++r.stage2_rejected_invalid;
      strong_.insert(strong_.end(), witness_.begin(), witness_.end());
      remember_failure(cand);
      return;
    }
    accept_step(sign, approx, r);
  }
  // Whether the lengths after changes_ are allowed.
  bool step_is_feasible() const {
    bool feasible = true;
    // x >= 0, and >= min_length unless stage I left the edge below it (no generating vector).
    for (const Change& c : changes_)
      feasible = feasible && x_[c.edge] + c.delta >= std::min(min_length_[c.edge], x_[c.edge]);
    return feasible;
  }
  // Applies changes_ and keeps them if the validity test passes (committing the lengths); else
  // reverts them, leaving the test's witness in witness_. Returns whether they were kept.
  bool apply_if_valid(QuantizationResult& r) {
    apply_changes(+1);
    witness_.clear();
    ++r.validity_checks;
    Timer check_timer;
    changed_edges_.clear();
    for (const Change& c : changes_) changed_edges_.push_back(c.edge);
    const bool valid = validity_.check_changed(x_, changed_edges_, &witness_, true).valid;
    r.validity_seconds += check_timer.seconds();
    if (!valid) apply_changes(-1);
    return valid;
  }
  // Counts an accepted (applied) step, updates the objective and re-queues the candidates whose
  // evaluation it may change.
  void accept_step(int sign, double approx, QuantizationResult& r) {
    ++r.stage2_steps;
    (sign > 0 ? r.stage2_additions : r.stage2_subtractions)++;
    objective_ = options_.recompute_objective_each_step ? full_objective() : objective_ + approx;
    r.objective_history.push_back(objective_);
    // An addition makes w- lighter (subtraction candidates), a subtraction makes w+ lighter.
    const int lighter_parity = sign > 0 ? 0 : 1;
    for (const Change& c : changes_) {
      push_candidate(2 * c.edge);
      push_candidate(2 * c.edge + 1);
      requeue_dependents(strong_deps_[c.edge], [](int) { return false; });
      requeue_dependents(weak_deps_[cluster_of_[c.edge]], [&](int cand) { return (cand & 1) != lighter_parity; });
    }
  }
  // The candidate stays out of the heap until an edge in `strong_` changes, or an edge in
  // `explored_` gets lighter for it (recorded per cluster of edges, to bound memory: a lighter
  // edge anywhere in the cluster re-evaluates the candidate, which is merely conservative).
  void remember_failure(int cand) {
    const uint32_t gen = ++generation_[cand];
    if (++seen_stamp_ == 0) {
      std::fill(edge_seen_.begin(), edge_seen_.end(), 0);
      std::fill(cluster_seen_.begin(), cluster_seen_.end(), 0);
      seen_stamp_ = 1;
    }
    int64_t count = 0;
    for (int e : strong_)
      if (edge_seen_[e] != seen_stamp_) edge_seen_[e] = seen_stamp_, strong_deps_[e].push_back({cand, gen}), ++count;
    for (int e : explored_) {
      const int k = cluster_of_[e];
      if (cluster_seen_[k] != seen_stamp_)
        cluster_seen_[k] = seen_stamp_, weak_deps_[k].push_back({cand, gen}), ++count;
    }
    dependency_count_[cand] = count;
    live_dependencies_ += count;
    stored_dependencies_ += count;
    if (stored_dependencies_ > 4 * live_dependencies_ + (int64_t(1) << 20)) compact_dependencies();
    if (live_dependencies_ > options_.cache_budget && num_clusters_ == system_.num_edges()) coarsen_weak_dependencies();
  }
  // Drops the stale entries of a dependency list and re-queues the live ones `keep` rejects.
  template <class Keep>
  void requeue_dependents(std::vector<std::pair<int, uint32_t>>& list, Keep&& keep) {
    size_t kept = 0;
    for (const auto& d : list) {
      if (generation_[d.first] != d.second) continue;  // stale
      if (keep(d.first))
        list[kept++] = d;
      else
        push_candidate(d.first);
    }
    stored_dependencies_ -= static_cast<int64_t>(list.size() - kept);
    list.resize(kept);
  }

  // Groups of about `size` edges that are close in the T-mesh (grown through cells).
  void build_clusters(int size) {
    const int kClusterSize = size;
    const int E = system_.num_edges();
    cluster_of_.assign(E, -1);
    num_clusters_ = 0;
    std::vector<int> queue;
    for (int seed = 0; seed < E; ++seed) {
      if (cluster_of_[seed] >= 0) continue;
      const int k = num_clusters_++;
      int size = 0;
      queue.assign(1, seed);
      cluster_of_[seed] = k;
      for (size_t q = 0; q < queue.size() && size < kClusterSize; ++q) {
        ++size;
        for (const EdgeSlot& sl : system_.slot[queue[q]]) {
          if (sl.cell < 0) continue;
          for (int o = system_.side_begin(sl.cell, 0); o < system_.side_end(sl.cell, 3); ++o) {
            const int f = system_.occ_edge[o];
            if (cluster_of_[f] >= 0 || static_cast<int>(queue.size()) >= kClusterSize) continue;
            cluster_of_[f] = k;
            queue.push_back(f);
          }
        }
      }
    }
  }
  // Memory bound: beyond options_.cache_budget live entries the region dependencies are kept per
  // cluster of edges instead of per edge (a lighter edge then re-evaluates every candidate whose
  // region touched its cluster: more searches, same results).
  static constexpr int kCoarseClusterSize = 16;
  void coarsen_weak_dependencies() {
    const std::vector<int> edge_cluster_before = cluster_of_;  // identity
    build_clusters(kCoarseClusterSize);
    std::vector<std::vector<std::pair<int, uint32_t>>> coarse(num_clusters_);
    for (size_t e = 0; e < weak_deps_.size(); ++e) {
      for (const auto& d : weak_deps_[e])
        if (generation_[d.first] == d.second) coarse[cluster_of_[edge_cluster_before[e]]].push_back(d);
      std::vector<std::pair<int, uint32_t>>().swap(weak_deps_[e]);
    }
    live_dependencies_ = stored_dependencies_ = 0;
    std::fill(dependency_count_.begin(), dependency_count_.end(), 0);
    for (auto& list : coarse) {
      std::sort(list.begin(), list.end());
      list.erase(std::unique(list.begin(), list.end()), list.end());
      for (const auto& d : list) ++dependency_count_[d.first];
      live_dependencies_ += static_cast<int64_t>(list.size());
    }
    for (const auto& list : strong_deps_)
      for (const auto& d : list)
        if (generation_[d.first] == d.second) ++dependency_count_[d.first], ++live_dependencies_;
    weak_deps_.swap(coarse);
    compact_dependencies();
  }
  // Drops entries of candidates evaluated again since (their generation moved on).
  void compact_dependencies() {
    stored_dependencies_ = 0;
    for (auto* lists : {&strong_deps_, &weak_deps_})
      for (auto& list : *lists) {
        size_t kept = 0;
        for (const auto& d : list)
          if (generation_[d.first] == d.second) list[kept++] = d;
        list.resize(kept);
        list.shrink_to_fit();
        stored_dependencies_ += static_cast<int64_t>(kept);
      }
  }
  struct HeapEntry {
    double weight;
    int candidate;
    uint32_t generation;
    // Smallest weight first; on ties subtraction (even candidate) before addition, then by edge.
    bool operator<(const HeapEntry& o) const {
      if (weight != o.weight) return weight > o.weight;
      if ((candidate & 1) != (o.candidate & 1)) return (candidate & 1) > (o.candidate & 1);
      return candidate > o.candidate;
    }
  };

  const TMesh& tmesh_;
  const QuantizationOptions& options_;
  Progress& progress_;
  CellSystem system_;
  GeneratingVectorSearch search_;
  ValidityChecker validity_;
  double eta_ = 1;
  std::vector<double> ideal_, w_plus_, w_minus_;
  std::vector<int64_t> min_length_;
  std::vector<int64_t> x_;
  double objective_ = 0;
  int64_t searches_ = 0;
  std::vector<int> dnodes_;
  std::vector<Change> changes_;
  std::vector<int> change_index_;
  std::vector<int> changed_edges_;  // #edges: position in changes_ (valid if it points back)
  std::priority_queue<HeapEntry> heap_;
  std::vector<uint32_t> generation_;
  // Cached failures: (candidate, generation) per edge (strong) and per edge cluster (weak).
  std::vector<std::vector<std::pair<int, uint32_t>>> strong_deps_, weak_deps_;
  std::vector<int> cluster_of_;
  int num_clusters_ = 0;
  std::vector<int64_t> dependency_count_;
  int64_t live_dependencies_ = 0, stored_dependencies_ = 0;
  // Stage II scratch: the explored region, the validity witness and the edges a failure depends
  // on strongly (see remember_failure); per edge and cluster the stamp deduplicating them.
  std::vector<int> explored_, witness_, strong_;
  std::vector<uint32_t> edge_seen_, cluster_seen_;
  uint32_t seen_stamp_ = 0;
};

}  // namespace

QuantizationResult quantize(const TMesh& tmesh, const QuantizationOptions& options, Progress& progress) {
  if (!(options.scale > 0) || !std::isfinite(options.scale))
    throw Error(ErrorCode::InvalidArgument, "quantization: the scale must be a positive finite number");
  if (options.cache_budget < 0) throw Error(ErrorCode::InvalidArgument, "quantization: negative cache budget");
  if (!options.min_length.empty() && options.min_length.size() != tmesh.edges.size())
    throw Error(ErrorCode::InvalidArgument, "quantization: min_length must have one value per T-edge");
  for (int64_t m : options.min_length)
    if (m < 0) throw Error(ErrorCode::InvalidArgument, "quantization: min_length values must be non-negative");
  if (!(options.min_ideal_length > 0))
    throw Error(ErrorCode::InvalidArgument, "quantization: min_ideal_length must be positive");
  GreedyQuantizer quantizer(tmesh, options, progress);
  return quantizer.run();
}

namespace {

// The side of cell c that opens it (PinchedCell), or -1 when no node is at two of its corners.
int side_to_open(const CellSystem& sys, int c) {
  std::array<int, 4> corner{};
  for (int s = 0; s < 4; ++s) corner[s] = sys.occ_start_node[sys.side_begin(c, s)];
  for (int s = 0; s < 4; ++s)
    if (corner[s] == corner[(s + 1) % 4]) return s;
  if (corner[0] != corner[2] && corner[1] != corner[3]) return -1;
  const TMesh& tmesh = sys.tmesh();
  double length[2] = {0, 0};
  for (int s = 0; s < 2; ++s)
    for (int e : tmesh.cells[c].sides[s]) length[s] += tmesh.edges[e].length;
  return length[1] > length[0] ? 1 : 0;
}

}  // namespace

std::vector<PinchedCell> pinched_cells(const TMesh& tmesh) {
  const CellSystem sys(tmesh);
  std::vector<PinchedCell> pinched;
  for (int c = 0; c < sys.num_cells(); ++c)
    if (const int side = side_to_open(sys, c); side >= 0) pinched.push_back({c, side});
  return pinched;
}

bool keep_pinched_cell_open(const TMesh& tmesh, const PinchedCell& pinched, std::vector<int64_t>& min_length) {
  std::vector<int> edges = tmesh.cells.at(pinched.cell).sides.at(pinched.side);
  if (min_length.size() != tmesh.edges.size() || edges.empty())
    throw Error(ErrorCode::InvalidArgument, "quantization: one bound per T-edge and a side with edges expected");
  auto raise = [&](int e, int64_t bound) {
    const bool rises = min_length[e] < bound;
    min_length[e] = std::max(min_length[e], bound);
    return rises;
  };
  if (edges.size() == 1) return raise(edges[0], 2);
  std::partial_sort(edges.begin(), edges.begin() + 2, edges.end(), [&](int a, int b) {
    return tmesh.edges[a].length > tmesh.edges[b].length || (tmesh.edges[a].length == tmesh.edges[b].length && a < b);
  });
  const bool first = raise(edges[0], 1);
  return raise(edges[1], 1) || first;
}

QuantizationValidity check_quantization_validity(const TMesh& tmesh, const std::vector<int64_t>& x) {
  if (x.size() != tmesh.edges.size())
    throw Error(ErrorCode::InvalidArgument, "quantization: one length per T-edge expected");
  for (int64_t v : x)
    if (v < 0) throw Error(ErrorCode::InvalidArgument, "quantization: negative T-edge length");
  if (quantization_consistency_residual(tmesh, x) != 0)
    throw Error(ErrorCode::InvalidArgument, "quantization: lengths violate the cell equations (Ax != 0)");
  const CellSystem system(tmesh);
  ValidityChecker checker(system);
  return checker.check(x);
}

namespace {
int64_t side_sum(const TMesh& tmesh, const std::vector<int64_t>& x, int c, int s) {
  int64_t sum = 0;
  for (int e : tmesh.cells[c].sides[s]) sum += x.at(e);
  return sum;
}
}  // namespace

int64_t quantization_consistency_residual(const TMesh& tmesh, const std::vector<int64_t>& x) {
  int64_t worst = 0;
  for (size_t c = 0; c < tmesh.cells.size(); ++c)
    for (int s = 0; s < 2; ++s)
      worst = std::max(worst, std::abs(side_sum(tmesh, x, c, s) - side_sum(tmesh, x, c, s + 2)));
  return worst;
}

int64_t quantization_quads(const TMesh& tmesh, const std::vector<int64_t>& x) {
  int64_t quads = 0;
  for (size_t c = 0; c < tmesh.cells.size(); ++c) quads += side_sum(tmesh, x, c, 0) * side_sum(tmesh, x, c, 1);
  return quads;
}

double quantization_objective(const TMesh& tmesh, const std::vector<int64_t>& x, double scale,
                              double min_ideal_length) {
  double sum = 0;
  for (size_t e = 0; e < tmesh.edges.size(); ++e) {
    const double ideal = std::max(scale * tmesh.edges[e].length, min_ideal_length);
    const double d = static_cast<double>(x.at(e)) / ideal - 1;
    sum += d * d;
  }
  return sum;
}

double quantization_scale_for_quads(const TMesh& tmesh, double target_quads) {
  if (!(target_quads > 0) || !std::isfinite(target_quads))
    throw Error(ErrorCode::InvalidArgument, "quantization: the target quad count must be positive");
  double area = 0;
  for (const TMeshCell& cell : tmesh.cells) {
    double side[4] = {0, 0, 0, 0};
    for (int s = 0; s < 4; ++s)
      for (int e : cell.sides[s]) side[s] += tmesh.edges.at(e).length;
    area += 0.25 * (side[0] + side[2]) * (side[1] + side[3]);
  }
  if (!(area > 0)) throw Error(ErrorCode::InvalidArgument, "quantization: the T-mesh has zero parametric area");
  return std::sqrt(target_quads / area);
}

double quantization_scale_for_edge_length(const TMesh& tmesh, double surface_area, double edge_length) {
  if (!(surface_area > 0) || !(edge_length > 0))
    throw Error(ErrorCode::InvalidArgument, "quantization: surface area and edge length must be positive");
  return quantization_scale_for_quads(tmesh, surface_area / (edge_length * edge_length));
}

const char* quantizer_name(Quantizer quantizer) { return quantizer == Quantizer::Greedy ? "greedy" : "round"; }

Quantizer parse_quantizer(const std::string& name) {
  if (name == "greedy") return Quantizer::Greedy;
  if (name == "round") return Quantizer::Round;
  throw Error(ErrorCode::InvalidArgument, "unknown quantizer '" + name + "' (use greedy or round)");
}

void to_json(Json& j, const QuantizationResult& r) {
  j["method"] = quantizer_name(r.quantizer);
  j["scale"] = r.scale;
  j["valid"] = r.valid;
  if (!r.invalid_reason.empty()) j["invalid_reason"] = r.invalid_reason;
  j["objective"] = std::isfinite(r.objective) ? Json(r.objective) : Json(nullptr);
  j["zero_edges"] = r.zero_edges;
  j["stage1_steps"] = r.stage1_steps;
  j["stage2_steps"] = r.stage2_steps;
  j["stage2_converged"] = r.stage2_converged;
  j["consistency_residual"] = r.consistency_residual;
  j["quads_expected"] = r.quads_expected;
  j["seconds"] = r.seconds;
  j["edges"] = r.x.size();
  j["stage2_additions"] = r.stage2_additions;
  j["stage2_subtractions"] = r.stage2_subtractions;
  j["stage2_rejected_invalid"] = r.stage2_rejected_invalid;
  j["unreachable_edges"] = r.unreachable_edges;
  j["searches"] = r.searches;
  j["validity_checks"] = r.validity_checks;
}

}  // namespace qgp

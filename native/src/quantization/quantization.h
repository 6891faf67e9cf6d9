// Quantization (paper §6): integer, non-negative lengths x for the T-edges of a T-mesh with
// Ax = 0 (the cell equations (4)) that are valid (§5.2, §9.1: no two singularities, and no
// singularity and feature/boundary, collapse in parameter space) and close to the ideal lengths
// x_ideal(e) = scale * length(e).
//
// Greedy method (the paper's): stage I walks from x = 0 to a valid quantization by adding
// generating vectors through zero edges; stage II greedily adds/subtracts generating vectors that
// keep validity and decrease  sum_e (x(e)/x_ideal(e) - 1)^2. Generating vectors are minimum-weight
// circuits (or boundary-to-boundary paths, §9.2) of the directed graph D, found by a bidirectional
// Dijkstra search.
//
// Pipeline use (Session): the T-mesh is computed once per component; a new density only needs a
// new scale (quantization_scale_for_quads / _for_edge_length) and a new quantize() call, then the
// later stages. The `round` baseline is quantize_by_rounding() (round_quantization.h).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "core/json.h"
#include "core/progress.h"
#include "tmesh/tmesh.h"

namespace qgp {

// The quantizers: the paper's greedy one (quantize(), below) and the direct-rounding baseline
// (quantize_by_rounding(), round_quantization.h), kept so that its failures can be counted beside.
enum class Quantizer { Greedy, Round };
// "greedy" / "round"; parse_quantizer throws Error(InvalidArgument) for any other name.
const char* quantizer_name(Quantizer quantizer);
Quantizer parse_quantizer(const std::string& name);

struct QuantizationOptions {
  double scale = 1;  // x_ideal(e) = scale * length(e); see quantization_scale_for_quads()
  // Ideal lengths below this (in quad units) are raised to it in the objective and the weights, so
  // that edges of zero continuous length get a finite, very large penalty for x > 0.
  double min_ideal_length = 1e-3;
  // Stage II may stop early: the quantization is valid after every step (paper §8). Seconds of
  // stage II after which it stops; 0: run until no generating vector improves (deterministic).
  double stage2_time_limit = 0;
  // Memory bound of the stage II failure cache, in entries (8 bytes each): beyond it the cache
  // records explored regions per cluster of 16 edges instead of per edge (same result, more
  // generating-vector searches).
  int64_t cache_budget = int64_t(1) << 24;
  // Per T-edge lower bound of x (empty: 0 everywhere; otherwise #edges values >= 0): stage I adds
  // generating vectors through an edge until it reaches max(1, bound), stage II never goes below it.
  // The session raises it to 1 on zero edges whose collapse folds the quad layout, and to 2 across
  // pinched cells whose single quad repeats a node (keep_pinched_cell_open).
  std::vector<int64_t> min_length;
  // Tests: recompute the full objective from scratch after every accepted stage II step (O(#edges)
  // each) instead of recording the incrementally updated value.
  bool recompute_objective_each_step = false;
};

struct QuantizationResult {
  std::vector<int64_t> x;  // #edges: integer length of each T-edge, >= 0
  Quantizer quantizer = Quantizer::Greedy;
  double scale = 1;
  bool valid = false;
  std::string invalid_reason;  // empty when valid
  double objective = 0;        // sum_e (x(e)/x_ideal(e) - 1)^2 of the result
  int zero_edges = 0;          // edges with x = 0
  int stage1_steps = 0;        // generating vectors added in stage I
  int stage2_steps = 0;        // accepted stage II steps (additions + subtractions)
  int stage2_additions = 0, stage2_subtractions = 0;
  bool stage2_converged = true;     // false if stage II stopped at its time limit
  int stage2_rejected_invalid = 0;  // improving candidates rejected by the validity test
  int unreachable_edges = 0;        // edges through which no generating vector exists
  int64_t searches = 0;             // generating-vector searches run
  int64_t searched_nodes = 0;       // graph nodes labelled by all searches together
  int64_t validity_checks = 0;
  int64_t validity_searches = 0;     // zero-distance searches from singular nodes (all checks)
  int64_t stage2_not_improving = 0;  // candidates whose generating vector does not improve
  double validity_seconds = 0;       // time spent in validity checks
  int64_t consistency_residual = 0;  // max |Ax| (0 for every result)
  int64_t quads_expected = 0;        // sum over cells of width * height
  // Objective after stage I, then after every accepted stage II step (never increasing).
  std::vector<double> objective_history;
  double stage1_seconds = 0, stage2_seconds = 0, seconds = 0;
};

// The greedy quantizer (paper §6). Throws Error(InvalidArgument) for a malformed T-mesh,
// Error(StageFailed) if no valid quantization is reachable, Error(Cancelled) on cancel.
QuantizationResult quantize(const TMesh& tmesh, const QuantizationOptions& options, Progress& progress);

// Validity of a complete consistent quantization (§5.2 extended by §9.1): from every singular node
// (index != 0, and every feature corner / boundary corner, including the virtual ones of §9.1,
// i.e. TMeshNode::Kind FeatureCorner and BoundaryNode) the set of points at
// zero parametric distance is explored; it must contain no other such node and no point of a
// feature/boundary edge except the zero-length continuation of the node's own feature curves.
struct QuantizationValidity {
  bool valid = true;
  int node = -1;          // the singularity whose zero-distance set is violated
  int other_node = -1;    // the singularity it collapses with, or -1
  int feature_edge = -1;  // the feature edge it collapses with, or -1
  std::string reason;     // human-readable, empty when valid
};
// x: #edges, must be >= 0 with Ax = 0 (throws Error(InvalidArgument) otherwise).
QuantizationValidity check_quantization_validity(const TMesh& tmesh, const std::vector<int64_t>& x);

// A pinched cell: its boundary meets one node at two of its corners (a cell wrapped around part of
// a singularity's one-ring whose separatrices return to it, as between clustered singularities). At
// width and height 1 its single layout quad repeats that node, so no map of those lengths is a quad
// mesh. The side that must be at least 2 long to open it: for two adjacent corners the side
// between them; for opposite corners side 0 or 1, whichever is longer in the seamless map.
struct PinchedCell {
  int cell = -1;
  int side = -1;
};
std::vector<PinchedCell> pinched_cells(const TMesh& tmesh);
// Raises min_length (#edges) so that the pinched cell's side sums to at least 2: a side of one
// edge to 2, otherwise its two longest edges to 1. Returns whether any bound rose.
bool keep_pinched_cell_open(const TMesh& tmesh, const PinchedCell& pinched, std::vector<int64_t>& min_length);

// Scale such that sum over cells of scale^2 * width * height (continuous) equals target_quads.
double quantization_scale_for_quads(const TMesh& tmesh, double target_quads);
// Scale for a target quad edge length in model units, given the surface area in model units:
// the target quad count is surface_area / edge_length^2.
double quantization_scale_for_edge_length(const TMesh& tmesh, double surface_area, double edge_length);

// Helpers on integer lengths (x: #edges).
int64_t quantization_consistency_residual(const TMesh& tmesh, const std::vector<int64_t>& x);  // max |Ax|
int64_t quantization_quads(const TMesh& tmesh, const std::vector<int64_t>& x);                 // sum width*height
double quantization_objective(const TMesh& tmesh, const std::vector<int64_t>& x, double scale,
                              double min_ideal_length = 1e-3);

// Report object `quantization.components[i]`: method, scale, valid, objective, zero_edges,
// stage1_steps, stage2_steps, consistency_residual, quads_expected, seconds (+ a few diagnostics).
void to_json(Json& j, const QuantizationResult& result);

}  // namespace qgp

#include "pipeline/policy.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <string>
#include <utility>

#include "core/error.h"
#include "core/run_ahead.h"
#include "core/timer.h"
#include "igm/untangle_map.h"
#include "intake/working_mesh.h"
#include "metrics/quad_metrics.h"
#include "quad_extraction/collapse_quads.h"
#include "quad_extraction/split_triangles.h"
#include "quad_extraction/surface_projection.h"

namespace qgp {
namespace {

// Zero T-edges (x = 0) on the sides of the cells of the layout quads marked `bad`, and of the cells
// up to `rings` cells away.
std::vector<int> zero_edges_around(const TMesh& tm, const LayoutQuads& layout, const std::vector<char>& bad,
                                   const std::vector<int64_t>& x, int rings) {
  std::vector<char> in_region(tm.cells.size(), 0);
  std::vector<int> region;
  for (size_t q = 0; q < bad.size(); ++q)
    if (bad[q] && !in_region[layout.quad_cell[q]]) {
      in_region[layout.quad_cell[q]] = 1;
      region.push_back(layout.quad_cell[q]);
    }
  if (region.empty()) return {};
  for (int ring = 0, begin = 0; ring < rings; ++ring) {
    const int end = static_cast<int>(region.size());
    for (int i = begin; i < end; ++i)
      for (const auto& side : tm.cells[region[i]].sides)
        for (int e : side)
          for (int c : tm.edges[e].cells)
            if (c >= 0 && !in_region[c]) {
              in_region[c] = 1;
              region.push_back(c);
            }
    begin = end;
  }
  std::vector<int> edges;
  for (int c : region)
    for (const auto& side : tm.cells[c].sides)
      for (int e : side)
        if (x[e] == 0) edges.push_back(e);
  return edges;
}

// Lower bounds that unfold the quad layout of x where it is not a manifold: the zero T-edges
// around the cells of its non-manifold quads (zero_edges_around) are kept at 1, and those cells
// that are pinched (a quad repeating a node) are kept open (keep_pinched_cell_open). Returns
// whether any bound rose; false when the layout is a manifold quad mesh (the connectivity every
// map with this quantization gives).
bool raise_bounds_where_layout_folds(const ComponentState& state, const std::vector<int64_t>& x, int rings,
                                     std::vector<int64_t>& min_length) {
  Progress quiet;
  const TMesh& tm = state.traced->tmesh;
  const LayoutQuads layout = extract_layout_quads(state.mesh, state.traced->exact, tm, x, quiet, false);
  const std::vector<char> bad = non_manifold_quads(layout.quads);
  if (std::find(bad.begin(), bad.end(), 1) == bad.end()) return false;
  min_length.resize(tm.edges.size(), 0);
  bool raised = false;
  for (int e : zero_edges_around(tm, layout, bad, x, rings)) {
    raised = raised || min_length[e] < 1;
    min_length[e] = std::max<int64_t>(min_length[e], 1);
  }
  std::vector<char> bad_cell(tm.cells.size(), 0);
  for (size_t q = 0; q < bad.size(); ++q) bad_cell[layout.quad_cell[q]] |= bad[q];
  for (const PinchedCell& pinched : pinched_cells(tm))
    if (bad_cell[pinched.cell]) raised = keep_pinched_cell_open(tm, pinched, min_length) || raised;
  return raised;
}

UntangleStats untangle_on_surface(const ComponentState& state, const std::vector<char>& feature_edges, QuadMesh& quads,
                                  Progress& progress);
std::string quad_mesh_defects(const QuadTopology& t, int euler);

// The layout quads of a quantization, placed on the surface and untangled as choose_quads places
// them, and which of them stay flipped against the input surface.
struct LayoutFlips {
  LayoutQuads layout;
  UntangleStats untangle;
  std::vector<char> flipped;  // per layout quad
  int count = 0;
  bool valid = false;  // a consistently oriented 2-manifold of the part's Euler characteristic
  // Valid, with fewer flipped quads.
  bool better_than(const LayoutFlips& o) const { return valid && (!o.valid || count < o.count); }
};

LayoutFlips layout_flips(const ComponentState& state, const std::vector<int64_t>& x, Progress& progress) {
  LayoutFlips flips;
  flips.layout =
      extract_layout_quads(state.mesh, state.traced->exact, state.traced->tmesh, x, progress, true, state.tip_vertices);
  QuadMesh& quads = flips.layout.quads;
  flips.flipped.assign(quads.num_quads(), 0);
  flips.valid = quad_mesh_defects(quad_topology(quads), state.euler_characteristic).empty();
  if (!flips.valid) return flips;
  flips.untangle = untangle_on_surface(state, state.field->feature_edge, quads, progress);
  const TriMesh& surface = state.full_mesh ? *state.full_mesh : state.mesh;
  const TriangleBvh bvh(surface);
  for (int q = 0; q < quads.num_quads(); ++q) {
    flips.flipped[q] = quad_is_flipped(quads, q, surface, bvh);
    flips.count += flips.flipped[q];
  }
  return flips;
}

// One flip round's trial: the zero T-edges within `rings` cells of the flipped layout quads of
// `best` (the layout of quantization x) kept at length 1, the T-mesh quantized again and, unless it
// has more than `most_quads` quads, its layout judged.
struct FlipTrial {
  bool nothing_to_try = false;  // no zero T-edge within `rings` cells
  QuantizationOptions options;
  QuantizationResult result;
  bool too_many_quads = false;
  LayoutFlips flips;
};

FlipTrial flip_trial(const ComponentState& state, const QuantizationOptions& options, const std::vector<int64_t>& x,
                     const LayoutFlips& best, int rings, double most_quads, Progress& progress) {
  FlipTrial trial;
  const TMesh& tmesh = state.traced->tmesh;
  const std::vector<int> edges = zero_edges_around(tmesh, best.layout, best.flipped, x, rings);
  trial.nothing_to_try = edges.empty();
  if (trial.nothing_to_try) return trial;
  trial.options = options;
  trial.options.min_length.resize(tmesh.edges.size(), 0);
  for (int e : edges) trial.options.min_length[e] = 1;
  trial.result = quantize(tmesh, trial.options, progress);
  trial.too_many_quads = trial.result.quads_expected > most_quads;
  if (!trial.too_many_quads) trial.flips = layout_flips(state, trial.result.x, progress);
  return trial;
}

// Flip rounds: while the layout's quads stay flipped against the surface (they cross a thin or
// sharply curved part: cells collapsed beside them squeeze the quads there), the zero T-edges around
// their cells, then up to kMaxFlipRings cells away, are kept at length 1 and the T-mesh is
// quantized again, up to kMaxFlipRounds times; a round is kept only when its layout is valid and
// has fewer flipped quads, and at most kMaxFlipRoundGrowth times the quads of the first. No round is
// tried when more than kMaxFlipShare of the quads stay flipped.
void keep_zero_edges_where_layout_flips(const ComponentState& state, QuantizationOptions& options, Quantized& q,
                                        Progress& progress) {
  Timer timer;
  q.quads_before_flip_rounds = q.result.quads_expected;
  LayoutFlips best = layout_flips(state, q.result.x, progress);
  q.flipped_layout_quads_before = best.valid ? best.count : -1;
  const bool hopeless = best.count > kMaxFlipShare * best.layout.quads.num_quads();
  const double most_quads = kMaxFlipRoundGrowth * q.result.quads_expected;
  // The trial one ring wider follows every trial not kept: it runs beside it (core/run_ahead.h).
  RunAhead<FlipTrial> trials;
  for (int round = 0, rings = 0;
       !hopeless && best.valid && best.count > 0 && round < kMaxFlipRounds && rings <= kMaxFlipRings;) {
    const bool next_may_follow = rings < kMaxFlipRings && round + 1 < kMaxFlipRounds;
    const auto trial_at = [&](int r, Progress& p) {
      return flip_trial(state, options, q.result.x, best, r, most_quads, p);
    };
    // The rounds go on to the next ring after a trial with nothing to try or not kept.
    const auto goes_on = [&](const FlipTrial& t) {
      return t.nothing_to_try || (!t.too_many_quads && !t.flips.better_than(best));
    };
    FlipTrial trial = trials.take(rings, next_may_follow, trial_at, goes_on, progress);
    round += !trial.nothing_to_try;
    if (goes_on(trial)) {
      ++rings;
      continue;
    }
    if (trial.too_many_quads) break;  // wider rings keep more edges at 1
    trials.forget();
    q.result = std::move(trial.result);
    options = std::move(trial.options);
    best = std::move(trial.flips);
    ++q.flip_rounds;
  }
  q.flipped_layout_quads = best.valid ? best.count : -1;
  if (best.valid) q.placed_layout = Quantized::PlacedLayout{std::move(best.layout), best.untangle};
  q.flip_seconds = timer.seconds();
}

// The effort counters of every attempt so far (`latest`, the last attempt's stats) on the kept map.
void count_every_attempt(IgmStats& kept, const IgmStats& latest) {
  kept.penalty_iterations = latest.penalty_iterations;
  kept.penalty_violation = latest.penalty_violation;
  kept.ipopt_solves = latest.ipopt_solves;
  kept.ipopt_iterations = latest.ipopt_iterations;
  kept.qp_by_ipopt = latest.qp_by_ipopt;
  kept.seconds_solve = latest.seconds_solve;
  kept.seconds_sanitize = latest.seconds_sanitize;
}

// Moves the map's vertices where flipped or degenerate triangles remain (igm/untangle_map).
void untangle_remaining(const ComponentState& state, IntegerGridMap& map, Progress& progress) {
  IgmStats& s = map.stats;
  if (s.flipped_triangles + s.degenerate_triangles == 0) return;
  const MapUntangleStats u = untangle_map(state.mesh, map.snapped_vertices, map.isolines, map.param, progress);
  s.untangled_vertices = u.moved_vertices;
  s.flipped_before_untangle = u.flipped_before;
  s.degenerate_before_untangle = u.degenerate_before;
  s.flipped_triangles = u.flipped_after;
  s.degenerate_triangles = u.degenerate_after;
  s.seconds += u.seconds;
  s.winding_defects = count_exact_winding_defects(state.mesh, map.param, cone_quarter_turns(state.mesh, *state.field));
}

// Untangles a copy of `map` (untangle_remaining); when the copy has no flipped or degenerate
// triangle nor wound one-ring, `map` becomes it. Returns what the copy kept of them. The untangle
// moves a few vertices and keeps the map exact; the all-faces attempt it spares re-solves every face
// (on face.obj's grid UVs, 60 Ipopt solves and 380 s for 2 triangles).
int untangle_if_it_regularizes(const ComponentState& state, IntegerGridMap& map, Progress& progress) {
  IntegerGridMap untangled = map;
  untangle_remaining(state, untangled, progress);
  const int left = irregular_elements(untangled.stats);
  if (left > 0) return left;
  const int before = irregular_elements(map.stats);
  map = std::move(untangled);
  map.stats.path += "; untangled (" + std::to_string(before) + " irregular triangles or one-rings before)";
  return 0;
}

// Why a quad mesh is not a consistently oriented 2-manifold with Euler characteristic `euler`
// ("" when it is).
std::string quad_mesh_defects(const QuadTopology& t, int euler) {
  std::string defects;
  auto add = [&](int count, const char* what) {
    if (count > 0) defects += (defects.empty() ? "" : "; ") + std::to_string(count) + " " + what;
  };
  add(t.non_manifold_edges, "non-manifold edge(s)");
  add(t.inconsistent_edges, "inconsistently oriented edge(s)");
  add(t.degenerate_quads, "degenerate quad(s)");
  if (t.faces == 0) defects = "no quads";  // a torus's empty layout has its Euler characteristic, 0
  if (defects.empty() && t.euler_characteristic != euler)
    defects = "Euler characteristic " + std::to_string(t.euler_characteristic) + " instead of " + std::to_string(euler);
  return defects;
}

// Unfolds flipped quads on the working mesh, then, projected back, on the input surface.
UntangleStats untangle_on_surface(const ComponentState& state, const std::vector<char>& feature_edges, QuadMesh& quads,
                                  Progress& progress) {
  UntangleStats stats = untangle_flipped_quads(quads, state.mesh, feature_edges, progress);
  if (state.full_mesh) {
    project_to_surface(quads, *state.full_mesh, progress);
    const UntangleStats projected = untangle_flipped_quads(quads, *state.full_mesh, state.full_feature_edges, progress);
    stats.flipped_after = projected.flipped_after;
    stats.moved_vertices += projected.moved_vertices;
    stats.seconds += projected.seconds;
  }
  return stats;
}

// The integer-grid map's quads, untangled, when the map is regular and they form a valid mesh;
// otherwise nothing, and *why_not says why.
std::optional<QuadChoice> quads_of_the_map(const ComponentState& state, Progress& progress, std::string* why_not) {
  const IgmStats& igm = state.igm->stats;
  if (irregular_elements(igm) > 0) {
    *why_not = std::to_string(igm.flipped_triangles) + " flipped and " + std::to_string(igm.degenerate_triangles) +
               " degenerate triangle(s) and " + std::to_string(igm.winding_defects) +
               " wound one-ring(s) in the integer-grid map";
    return std::nullopt;
  }
  try {
    QuadChoice choice;
    choice.extraction = extract_quads(state.mesh, state.igm->map, QuadExtractionOptions{}, progress);
    *why_not = quad_mesh_defects(quad_topology(choice.extraction.quads), state.euler_characteristic);
    if (!why_not->empty()) return std::nullopt;
    choice.source = QuadSource::IntegerGridMap;
    choice.untangle = untangle_on_surface(state, state.field->feature_edge, choice.extraction.quads, progress);
    return choice;
  } catch (const Error& e) {
    if (e.code() != ErrorCode::StageFailed) throw;
    *why_not = e.what();
    return std::nullopt;
  }
}

// The quantized T-mesh layout's quads, untangled, when they form a valid mesh; otherwise nothing,
// and *defects says why (*collapsed: they form a manifold, oriented mesh of another topology).
std::optional<QuadChoice> quads_of_the_layout(const ComponentState& state, Progress& progress, std::string* defects,
                                              bool* collapsed) {
  const std::optional<Quantized::PlacedLayout>& placed = state.quantization->placed_layout;
  LayoutQuads layout = placed ? placed->layout
                              : extract_layout_quads(state.mesh, state.traced->exact, state.traced->tmesh,
                                                     state.quantization->result.x, progress, true, state.tip_vertices);
  const QuadTopology topology = quad_topology(layout.quads);
  *defects = quad_mesh_defects(topology, state.euler_characteristic);
  *collapsed = topology.non_manifold_edges + topology.inconsistent_edges + topology.degenerate_quads == 0;
  if (!defects->empty()) return std::nullopt;
  QuadChoice choice;
  choice.source = QuadSource::TMeshLayout;
  choice.extraction.quads = std::move(layout.quads);
  choice.extraction.stats.expected_quads = layout.stats.quads;
  choice.extraction.stats.seconds = layout.stats.seconds;
  for (char s : choice.extraction.quads.vertex_singular) choice.extraction.stats.singular_vertices += s;
  choice.layout = layout.stats;
  choice.untangle = placed ? placed->untangle
                           : untangle_on_surface(state, state.field->feature_edge, choice.extraction.quads, progress);
  return choice;
}

// The component's field has close +1/-1 pairs cancelled (the field without them is its fallback).
bool field_cancelled_pairs(const ComponentState& state) {
  return state.field.has_value() && state.field.key().cancel_pairs && state.field->num_close_pairs > 0;
}

}  // namespace

bool field_serves(const FieldKey& stored, double edge_length, bool cancel_pairs) {
  return (!stored.cancel_pairs || cancel_pairs) && seamless_map_serves(stored.edge_length, edge_length);
}

bool seamless_map_folds_where_pairs_were_cancelled(const ComponentState& state) {
  const SeamlessMapStats& s = state.seamless->stats;
  return field_cancelled_pairs(state) && s.flipped_triangles + s.degenerate_triangles + s.winding_defects > 0;
}

void bound_repair_where_pairs_were_cancelled(const ComponentState& state, SeamlessMapOptions& options) {
  if (!field_cancelled_pairs(state)) return;
  options.count_stagnation_rounds = kCancelledPairsStagnantRounds;
  options.field_frame_solve = false;
  options.move_shared_coordinates = false;
}

namespace {

// A remesh part on its own triangles (no working mesh).
bool remesh_on_own_triangles(const ComponentState& state, Job job) { return job == Job::Remesh && !state.full_mesh; }

// Such a part with feature edges across needles.
bool on_needles_across_features(const ComponentState& state, Job job) {
  return remesh_on_own_triangles(state, job) && has_needles_across_features(state.mesh, state.feature_edges);
}

}  // namespace

bool remesh_may_bring_quads_closer(const ComponentState& state, Job job, double edge_length) {
  if (state.failure || !state.quads.has_value()) return false;
  return on_needles_across_features(state, job) ||
         (remesh_on_own_triangles(state, job) &&
          has_coarse_triangles_across_features(state.mesh, state.feature_edges, edge_length));
}

bool retry_on_isotropic_remesh(const ComponentState& state, Job job) {
  return state.failure && on_needles_across_features(state, job);
}

bool remesh_follows_a_folded_start(const ComponentState& state, Job job, bool rescues_failed_parts) {
  return rescues_failed_parts && on_needles_across_features(state, job);
}

bool retry_without_cancelled_pairs(const ComponentState& state) {
  return state.failure && field_cancelled_pairs(state) && finer_density_may_help(state.failure->stage);
}

bool seamless_map_serves(double solved_for, double edge_length) {
  const double rescale = solved_for / edge_length;
  return std::max(rescale, 1 / rescale) <= kMaxSeamlessRescale * (1 + 1e-9);
}

std::vector<char> sharp_tip_vertices(const TriMesh& mesh) {
  const std::vector<double> angle_sum = vertex_angle_sums(mesh);
  std::vector<char> tips(mesh.num_vertices(), 0);
  for (int v = 0; v < mesh.num_vertices(); ++v)
    tips[v] = mesh.vertex_halfedge[v] >= 0 && !is_boundary_vertex(mesh, v) && angle_sum[v] < kMaxTipAngleSum;
  return tips;
}

Quantized quantize_without_folds(const ComponentState& state, QuantizationResult first, Progress& progress) {
  const TMesh& tmesh = state.traced->tmesh;
  QuantizationOptions options;
  options.scale = first.scale;
  Quantized q;
  q.result = std::move(first);
  for (int round = 0; round < kMaxFoldRounds; ++round) {
    if (!raise_bounds_where_layout_folds(state, q.result.x, round, options.min_length)) break;
    q.result = quantize(tmesh, options, progress);
    q.fold_rounds = round + 1;
  }
  keep_zero_edges_where_layout_flips(state, options, q, progress);
  for (int64_t m : options.min_length) q.kept_positive_edges += m > 0;
  return q;
}

namespace {

// A quantization at `scale` without bounds (the start of quantize_without_folds), kept so that the
// count search's best trial is not quantized again.
QuantizationResult quantize_at_scale(const TMesh& tmesh, double scale, Progress& progress) {
  QuantizationOptions options;
  options.scale = scale;
  return quantize(tmesh, options, progress);
}

struct CountTrial {
  double scale = 0;
  int64_t quads = 0;
  std::shared_ptr<const QuantizationResult> result;  // none for the search's start before any trial
};

CountTrial quads_at_scale(const TMesh& tmesh, double scale, Progress& progress) {
  auto result = std::make_shared<const QuantizationResult>(quantize_at_scale(tmesh, scale, progress));
  return {scale, result->quads_expected, std::move(result)};
}

// The trials of one component's count search: the closest to the target, the largest scale that
// gave fewer quads than the target and the smallest that gave more (the bracket), the fewest quads.
struct CountSearch {
  double target = 0;
  CountTrial best;
  double fewer = 0, more = std::numeric_limits<double>::infinity();
  int64_t fewest = std::numeric_limits<int64_t>::max();
  int64_t below = 0, above = 0;  // the closest counts under and over the target
  int rounds = 0;
  bool tried = false;

  bool on_target() const { return std::abs(best.quads - target) <= kCountTolerance * target; }
  // The count jumps over the target between two scales a thousandth apart (whole rows of quads,
  // such as a ring around a handle, come and go at once): no scale gives a count in between.
  bool at_step() const { return fewer > 0 && std::isfinite(more) && more - fewer < 1e-3 * more; }
  // A trial without quads (a part narrower than a quad everywhere, such as a thin torus's tube)
  // is the best only while no trial has quads.
  void add(const CountTrial& trial) {
    const bool closer = std::abs(trial.quads - target) < std::abs(best.quads - target);
    if (!tried || (trial.quads > 0 && (best.quads == 0 || closer))) best = trial;
    tried = true;
    if (trial.quads < target) fewer = std::max(fewer, trial.scale), below = std::max(below, trial.quads);
    if (trial.quads > target)
      more = std::min(more, trial.scale), above = above ? std::min(above, trial.quads) : trial.quads;
    fewest = std::min(fewest, trial.quads);
  }
  // The proportional step from `last`, or the bracket's middle when that step leaves the bracket.
  double next_scale(const CountTrial& last) const {
    const double step = last.scale * std::sqrt(target / static_cast<double>(std::max<int64_t>(last.quads, 1)));
    if (step > fewer && step < more) return step;
    return fewer > 0 && std::isfinite(more) ? 0.5 * (fewer + more) : step;
  }
};

// Moves the scale from `last` toward the search's target, up to kMaxCountRounds trials.
void search_count_scale(const TMesh& tmesh, CountTrial last, CountSearch& search, Progress& progress) {
  for (int trial = 0; trial < kMaxCountRounds && !search.on_target() && !search.at_step(); ++trial, ++search.rounds) {
    last = quads_at_scale(tmesh, search.next_scale(last), progress);
    search.add(last);
  }
}

}  // namespace

Quantized quantize_to_count(const ComponentState& state, double scale, double target_quads, Progress& progress) {
  CountSearch search;
  search.target = target_quads;
  search.best.scale = scale;
  int64_t fewest = -1;
  if (target_quads > 0) {
    const TMesh& tmesh = state.traced->tmesh;
    const CountTrial first = quads_at_scale(tmesh, scale, progress);
    search.add(first);
    if (std::abs(first.quads - target_quads) > 2 * kCountTolerance * target_quads)
      search_count_scale(tmesh, first, search, progress);
    if (search.best.quads > (1 + 2 * kCountTolerance) * target_quads) {
      // Too many quads still: at a vanishing scale the quantizer keeps only the lengths validity
      // needs. When that gives fewer than the target, the search goes on inside the bracket.
      const CountTrial floor = quads_at_scale(tmesh, scale * 1e-3, progress);
      search.fewest = std::min(search.fewest, floor.quads);
      if (floor.quads < target_quads) {
        search.fewer = std::max(search.fewer, floor.scale);
        search_count_scale(tmesh, search.best, search, progress);
      }
      fewest = search.fewest;
    }
  }
  QuantizationResult closest =
      search.best.result ? *search.best.result : quantize_at_scale(state.traced->tmesh, scale, progress);
  Quantized q = quantize_without_folds(state, std::move(closest), progress);
  if (q.result.quads_expected == 0)  // its map and quads would be empty: fail before solving them
    throw Error(ErrorCode::StageFailed,
                "quantization: the layout collapses to no quad at this density (the part is narrower than one "
                "quad)");
  if (search.at_step() && !search.on_target()) q.count_step = {search.below, search.above};
  q.target_quads = target_quads;
  q.nominal_scale = scale;
  q.count_rounds = search.rounds;
  q.fewest_quads = fewest;
  return q;
}

bool escalates_integer_grid_map(Job job) { return job == Job::GridUV; }

bool integer_grid_map_serves(const IgmResult& map, bool escalate) {
  return !escalate || map.escalated || irregular_elements(map.stats) == 0;
}

int irregular_elements(const IgmStats& s) { return s.flipped_triangles + s.degenerate_triangles + s.winding_defects; }

namespace {

// The attempts of one component's integer-grid map, run in turn: each is recorded, and kept only
// when it has fewer flipped or degenerate triangles or wound one-rings than the map so far.
class AttemptLadder {
 public:
  AttemptLadder(IntegerGridMapSolver& solver, IntegerGridMap& map) : solver_(solver), map_(map) {}

  // The first attempt: it becomes the map.
  void start(IgmAttempt attempt, double begin, double end) {
    Timer timer;
    map_ = solver_.solve(attempt, begin, end);
    latest_ = map_.stats;
    record(igm_attempt_name(attempt), irregular_elements(map_.stats), map_.stats.repair_bad_faces, true,
           timer.seconds());
  }

  // True when `attempt` replaced the map.
  bool try_attempt(IgmAttempt attempt, double begin, double end) {
    Timer timer;
    IntegerGridMap next = solver_.solve(attempt, begin, end);
    latest_ = next.stats;
    const bool fewer = irregular_elements(next.stats) < irregular_elements(map_.stats);
    record(igm_attempt_name(attempt), irregular_elements(next.stats), next.stats.repair_bad_faces, fewer,
           timer.seconds());
    if (fewer) map_ = std::move(next);
    return fewer;
  }

  // True when the map untangle alone made the map regular (untangle_if_it_regularizes).
  bool try_untangle(const ComponentState& state, Progress& progress) {
    Timer timer;
    const int left = untangle_if_it_regularizes(state, map_, progress);
    record("untangle", left, {}, left == 0, timer.seconds());
    return left == 0;
  }

  IgmStats& stats() { return map_.stats; }
  bool regular() const { return irregular_elements(map_.stats) == 0; }
  std::string irregular_count() const {
    return std::to_string(irregular_elements(map_.stats)) + " irregular triangles or one-rings";
  }

  // The map's stats get every attempt's record and effort.
  void finish() {
    count_every_attempt(map_.stats, latest_);
    map_.stats.attempts = std::move(records_);
  }

 private:
  void record(const char* name, int irregular, std::vector<int> repair_bad_faces, bool kept, double seconds) {
    records_.push_back(IgmAttemptRecord{name, irregular, kept, std::move(repair_bad_faces), seconds});
  }

  IntegerGridMapSolver& solver_;
  IntegerGridMap& map_;
  IgmStats latest_;
  std::vector<IgmAttemptRecord> records_;
};

// For grid UVs, while the map has flipped or degenerate triangles or wound one-rings: the map
// untangle when it alone makes the map regular; else the re-linearized penalty attempt, the
// untangle again, then the all-faces attempt (on parts of at most kMaxAllFacesTriangles), each
// attempt kept only if it has fewer. The escalated attempts' repair stops once it stagnates
// (kEscalatedStagnantRounds, like the default attempt's).
void escalate_while_irregular(const ComponentState& state, AttemptLadder& ladder, Progress& progress) {
  if (ladder.regular() || ladder.try_untangle(state, progress)) return;
  const std::string before = ladder.irregular_count();
  const bool relinearized = ladder.try_attempt(IgmAttempt::RelinearizedPenalty, 0.45, 0.85);
  if (relinearized) ladder.stats().path = "global (penalty with regularity; " + before + " without)";
  if (ladder.regular() || (relinearized && ladder.try_untangle(state, progress))) return;
  const std::string still = ladder.irregular_count();
  if (state.mesh.num_faces() > kMaxAllFacesTriangles) {
    ladder.stats().path += "; all-faces attempt skipped (" + std::to_string(state.mesh.num_faces()) + " triangles)";
    return;
  }
  if (ladder.try_attempt(IgmAttempt::AllFaces, 0.88, 0.99)) {
    ladder.stats().fallback_used = true;
    ladder.stats().path = "fallback: all-faces Ipopt (" + still + " before)";
  } else {
    ladder.stats().path = "global (all-faces fallback did not help)";
  }
}

// Why a quad job's integer-grid map is left as solved, without the untangle ("": untangle it).
std::string why_quad_job_leaves_map_as_solved(const IgmStats& s) {
  if (s.forced_degenerate > 0)
    return "global, not repaired (" + std::to_string(s.forced_degenerate) +
           " triangles degenerate in every map of these integer values)";
  const int left = s.flipped_triangles + s.degenerate_triangles;
  if (left > kMaxShareToUntangle * s.faces)
    return "global, not untangled (" + std::to_string(left) + " flipped or degenerate triangles)";
  return "";
}

}  // namespace

IgmResult solve_integer_grid_map(const ComponentState& state, bool escalate, Progress& progress) {
  Timer timer;
  IgmOptions options;
  options.edge_length = state.seamless_edge_length();
  options.count_stagnation_rounds = escalate ? kEscalatedStagnantRounds : kStagnantRoundsWithoutEscalation;
  if (!escalate) {
    options.max_repair_rounds = kRepairRoundsWithoutEscalation;
    options.halving_rounds = kHalvingRoundsWithoutEscalation;
    options.skip_repair_if_forced = true;
    options.finish_by_untangle_up_to_share = kMaxShareToUntangle;
    options.finish_by_untangle_moves = kMaxUntangleMovesToFinish;
  }
  IntegerGridMapSolver solver(state.mesh, *state.field, *state.cut, *state.seamless, state.traced->exact,
                              state.traced->tmesh, state.quantization->result, options, progress);
  IntegerGridMap map;
  AttemptLadder ladder(solver, map);
  ladder.start(IgmAttempt::Default, 0, 0.4);
  ladder.stats().path = "global (penalty without regularity)";
  if (escalate) escalate_while_irregular(state, ladder, progress);
  ladder.finish();
  map.stats.seconds = timer.seconds();
  progress.update(1.0);
  const std::string left_as_solved = escalate ? "" : why_quad_job_leaves_map_as_solved(map.stats);
  if (left_as_solved.empty())
    untangle_remaining(state, map, progress);
  else
    map.stats.path = left_as_solved;
  return IgmResult{std::move(map.param), std::move(map.stats), escalate};
}

IgmResult rounded_integer_grid_map(const RoundedMap& rounded) {
  IgmResult r;
  r.map = rounded.param;
  r.stats.path = "round";
  r.stats.flipped_triangles = rounded.flipped_triangles;
  r.stats.degenerate_triangles = rounded.degenerate_triangles;
  r.stats.unresolved_equations = rounded.unresolved_equations;
  r.escalated = true;
  return r;
}

CellMapFallback fallback_cell_map(const ComponentState& state, Progress& progress) {
  CellMapFallback fallback;
  const IgmStats& s = state.igm->stats;
  if (s.flipped_triangles + s.winding_defects == 0) return fallback;
  fallback.ran = true;
  try {
    CellMapOptions options;
    options.cone_turns = cone_quarter_turns(state.mesh, *state.field);
    CellMap map =
        map_cells_to_rectangles(state.mesh, state.traced->tmesh, state.quantization->result.x, progress, options);
    fallback.stats = map.stats;
    fallback.used = map.stats.flipped_triangles + map.stats.wound_vertices == 0;
    if (fallback.used) fallback.map = std::move(map);
  } catch (const Error& e) {
    if (e.code() != ErrorCode::StageFailed) throw;
    fallback.failure = e.what();
  }
  return fallback;
}

const CellMap* cell_map_in_use(const ComponentState& state) {
  if (!state.cell_map.computed_from(state.igm.id()) || !state.cell_map->map) return nullptr;
  return &*state.cell_map->map;
}

QuadChoice choose_quads(const ComponentState& state, Progress& progress) {
  std::string why_not_map;
  std::optional<QuadChoice> chosen = quads_of_the_map(state, progress, &why_not_map);
  if (chosen && chosen->untangle.flipped_after == 0) return std::move(*chosen);
  std::string defects;
  bool collapsed = false;
  std::optional<QuadChoice> layout = quads_of_the_layout(state, progress, &defects, &collapsed);
  if (!chosen && !layout)
    throw Error(ErrorCode::StageFailed,
                "quad extraction: the quads do not form a valid mesh (" + defects + ")" +
                    (collapsed ? ". A hole or handle of this part is narrower than one quad: try more quads" : ""));
  if (layout && (!chosen || layout->untangle.flipped_after < chosen->untangle.flipped_after)) {
    if (chosen)
      why_not_map = std::to_string(chosen->untangle.flipped_after) + " of the integer-grid map's quads stay flipped";
    layout->why_not_map = why_not_map;
    return std::move(*layout);
  }
  return std::move(*chosen);
}

namespace {

// The component's working triangles, decimated to `max_faces` when it has more than twice as many,
// split into quads on the component's surface.
QuadChoice split_triangles_on_surface(const ComponentState& state, int max_faces, Progress& progress) {
  const WorkingMesh coarse = make_working_mesh(state.mesh, state.feature_edges, max_faces, 0, progress);
  QuadChoice choice;
  choice.source = QuadSource::SplitTriangles;
  QuadMesh& quads = choice.extraction.quads;
  quads = split_triangles_into_quads(coarse.mesh);
  if (coarse.decimated) project_to_surface(quads, state.mesh, progress);
  choice.untangle = untangle_on_surface(state, state.feature_edges, quads, progress);
  choice.extraction.stats.expected_quads = quads.num_quads();
  for (char s : quads.vertex_singular) choice.extraction.stats.singular_vertices += s;
  return choice;
}

}  // namespace

bool finer_density_may_help(const std::string& failed_stage) {
  return failed_stage == "quantization" || failed_stage == "igm" || failed_stage == "quad_extraction";
}

QuadChoice quads_of_split_triangles(const ComponentState& state, double target_quads, Progress& progress,
                                    double max_quads) {
  double max_faces = std::min(std::max(std::ceil(target_quads / 3), 1.0), double(state.mesh.num_faces()));
  QuadChoice choice = split_triangles_on_surface(state, static_cast<int>(max_faces), progress);
  while (choice.untangle.flipped_after > 0 && choice.extraction.quads.num_quads() < 3 * state.mesh.num_faces() &&
         3 * kSplitFacesGrowth * max_faces <= max_quads) {
    max_faces = std::min(kSplitFacesGrowth * max_faces, double(state.mesh.num_faces()));
    QuadChoice finer = split_triangles_on_surface(state, static_cast<int>(max_faces), progress);
    if (finer.untangle.flipped_after >= choice.untangle.flipped_after) break;  // more quads, no fewer flips
    choice = std::move(finer);
  }
  const std::string defects = quad_mesh_defects(quad_topology(choice.extraction.quads), state.euler_characteristic);
  if (!defects.empty())
    throw Error(ErrorCode::StageFailed, "the triangles split into quads do not form a valid mesh (" + defects + ")");
  return choice;
}

std::optional<QuadChoice> collapse_folds(const ComponentState& state, const QuadChoice& choice, Progress& progress) {
  if (choice.untangle.flipped_after == 0 && !has_slivers(choice.extraction.quads)) return std::nullopt;
  QuadChoice collapsed = choice;
  QuadMesh& quads = collapsed.extraction.quads;
  const bool split = choice.source == QuadSource::SplitTriangles || !state.field.has_value();
  const std::vector<char>& features = split ? state.feature_edges : state.field->feature_edge;
  const UntangleStats collapse =
      state.full_mesh ? collapse_folded_quads(quads, *state.full_mesh, state.full_feature_edges, progress)
                      : collapse_folded_quads(quads, state.mesh, features, progress);
  if (collapse.collapsed_quads == 0 && collapse.moved_vertices == 0) return std::nullopt;
  collapsed.untangle.flipped_after = collapse.flipped_after;
  collapsed.untangle.collapsed_quads = collapse.collapsed_quads;
  collapsed.untangle.collapsed_before = collapse.collapsed_before;
  collapsed.untangle.collapsed_after = collapse.collapsed_after;
  collapsed.untangle.moved_vertices += collapse.moved_vertices;
  collapsed.untangle.seconds += collapse.seconds;
  collapsed.extraction.stats.singular_vertices = 0;
  for (char s : quads.vertex_singular) collapsed.extraction.stats.singular_vertices += s;
  return collapsed;
}

}  // namespace qgp

#include "pipeline/component_stages.h"

#include <tuple>

#include "core/error.h"
#include "core/sanitize_isolines.h"
#include "pipeline/policy.h"
#include "sizing/sizing.h"
#include "tmesh/trace_tmesh.h"

namespace qgp {
namespace {

// The round baseline: the seamless map's integer variables rounded; its T-mesh traced again.
Quantized quantize_by_rounding_baseline(const ComponentState& state, double scale, Progress& progress) {
  QuantizationOptions options;
  options.scale = scale;
  const TracedMap& traced = *state.traced;
  const TraceFunction trace = [&](const ExactParametrization& param, Progress& p) {
    TraceOptions trace_options;
    trace_options.feature_edges = traced.isoline_edges;
    return trace_tmesh(state.mesh, param, trace_options, p);
  };
  RoundingResult rounded = quantize_by_rounding(state.mesh, state.seamless->param, traced.isoline_edges, traced.tmesh,
                                                options, trace, progress);
  if (!rounded.quantization.valid)
    throw Error(ErrorCode::StageFailed, "quantization (round): " + rounded.quantization.invalid_reason);
  Quantized q;
  q.result = std::move(rounded.quantization);
  q.rounded = std::move(rounded.map);
  return q;
}

// A map whose repair was declined (it started folded on needle triangles) fails the stage.
void throw_if_repair_declined(const ComponentState& state) {
  const SeamlessMapStats& s = state.seamless->stats;
  if (!s.repair_declined) return;
  throw Error(ErrorCode::StageFailed,
              "seamless map: " + std::to_string(s.flipped_triangles + s.degenerate_triangles) + " of " +
                  std::to_string(state.mesh.num_faces()) +
                  " triangles flipped or degenerate on needle triangles across features, not repaired there");
}

CrossFieldOptions cross_field_options(const ComponentState& state, double edge_length, bool cancel_pairs) {
  CrossFieldOptions options;
  options.feature_edges = state.feature_edges;
  options.sharp_angle_deg = -1;  // dihedral features are already in feature_edges
  options.cancel_pairs_within = cancel_pairs ? kCancelPairsWithin * edge_length : 0;
  return options;
}

}  // namespace

void update_cross_field(ComponentState& state, double edge_length, bool cancel_pairs, Progress& progress) {
  if (state.field.has_value() && field_serves(state.field.key(), edge_length, cancel_pairs)) return;
  const CrossFieldOptions options = cross_field_options(state, edge_length, cancel_pairs);
  state.field.store({edge_length, cancel_pairs}, compute_cross_field(state.mesh, options, progress));
}

bool keep_pairs_near_folds(ComponentState& state, Progress& progress) {
  const FieldKey key = state.field.key();
  CrossFieldOptions options = cross_field_options(state, key.edge_length, key.cancel_pairs);
  options.keep_pairs_near = state.seamless->bad_vertices;
  CrossField field = compute_cross_field(state.mesh, options, progress);
  if (field.num_pairs_kept_near_folds == 0) return false;
  state.field.store(key, std::move(field));
  return true;
}

void update_cut_graph(ComponentState& state, Progress& progress) {
  if (state.cut.computed_from(state.field.id())) return;
  state.cut.store(state.field.id(), compute_cut_graph(state.mesh, *state.field, progress));
}

void update_seamless_map(ComponentState& state, double edge_length, std::vector<double> face_size, Progress& progress,
                         bool remesh_follows) {
  const uint64_t sizing = sizes_hash(face_size);
  const bool stored_serves = state.seamless.has_value() && state.seamless.key().cut == state.cut.id() &&
                             state.seamless.key().sizing == sizing &&
                             seamless_map_serves(state.seamless.key().edge_length, edge_length);
  if (!stored_serves) {  // otherwise re-quantized only
    SeamlessMapOptions options;
    options.edge_length = edge_length;
    options.face_size = std::move(face_size);
    options.region_stagnation_rounds = kSeamlessStagnantRounds;
    bound_repair_where_pairs_were_cancelled(state, options);
    if (remesh_follows) options.max_bad_share_to_repair = kMaxBadShareToRepairOnNeedles;
    state.seamless.store({state.cut.id(), edge_length, sizing},
                         compute_seamless_map(state.mesh, *state.field, *state.cut, options, progress));
  }
  throw_if_repair_declined(state);
}

void update_tmesh(ComponentState& state, Progress& progress) {
  if (state.traced.computed_from(state.seamless.id())) return;
  TracedMap traced;
  // Feature edges the seamless map left free (their isolines would collapse a triangle) are not
  // walls of the T-mesh.
  traced.isoline_edges = state.feature_edges;
  for (int e : state.seamless->stats.dropped_isoline_edges) traced.isoline_edges[e] = 0;
  const Parametrization& param = state.seamless->param;
  SanitizeResult exact = sanitize_with_isolines(
      state.mesh, param, isoline_constraints(state.mesh, param, traced.isoline_edges, true), SanitizeOptions{});
  if (exact.unresolved_equations > 0)
    throw Error(ErrorCode::StageFailed,
                "T-mesh: " + std::to_string(exact.unresolved_equations) +
                    " transition or isoline equation(s) of the seamless map cannot hold exactly");
  TraceOptions trace_options;
  trace_options.feature_edges = traced.isoline_edges;
  traced.tmesh = trace_tmesh(state.mesh, exact.param, trace_options, progress);
  traced.exact = std::move(exact.param);
  state.traced.store(state.seamless.id(), std::move(traced));
}

void update_quantization(ComponentState& state, double edge_length, double target_quads, Quantizer quantizer,
                         Progress& progress) {
  const QuantizationKey key{state.traced.id(), state.seamless_edge_length() / edge_length, target_quads, quantizer};
  if (state.quantization.computed_from(key)) return;
  switch (quantizer) {
    case Quantizer::Greedy:
      state.quantization.store(key, quantize_to_count(state, key.scale, target_quads, progress));
      return;
    case Quantizer::Round:
      state.quantization.store(key, quantize_by_rounding_baseline(state, key.scale, progress));
      return;
  }
}

void update_integer_grid_map(ComponentState& state, Job job, Progress& progress) {
  const bool escalate = escalates_integer_grid_map(job);
  if (state.igm.computed_from(state.quantization.id()) && integer_grid_map_serves(*state.igm, escalate)) return;
  if (state.quantization->rounded)
    state.igm.store(state.quantization.id(), rounded_integer_grid_map(*state.quantization->rounded));
  else
    state.igm.store(state.quantization.id(), solve_integer_grid_map(state, escalate, progress));
}

void update_cell_map(ComponentState& state, Progress& progress) {
  if (state.cell_map.computed_from(state.igm.id())) return;
  state.cell_map.store(state.igm.id(), fallback_cell_map(state, progress));
}

void update_quads(ComponentState& state, Progress& progress) {
  if (state.quads.computed_from(state.igm.id())) return;
  state.quads.store(state.igm.id(), choose_quads(state, progress));
}

}  // namespace qgp

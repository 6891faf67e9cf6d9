// The stages of one component, each run only when its stored result was computed from other
// inputs (pipeline/stage_result.h). Every function leaves the component's result of its stage up
// to date and returns; failures throw Error as the stage does.
#pragma once
#include "core/progress.h"
#include "pipeline/component_state.h"
#include "pipeline/options.h"

namespace qgp {

// Stage 1a, 1b: the cross field (hard-constrained on the component's feature edges) and its cut graph.
// cancel_pairs: the field with its close singularity pairs cancelled (policy.h kCancelPairsWithin);
// a stored field without them serves either (see field_serves).
void update_cross_field(ComponentState& state, double edge_length, bool cancel_pairs, Progress& progress);
// The field again with the close pairs near the stored seamless map's bad vertices left uncancelled
// (where the map with them folded). False, and the field kept, when no cancelled pair is near them.
bool keep_pairs_near_folds(ComponentState& state, Progress& progress);
void update_cut_graph(ComponentState& state, Progress& progress);
// Stage 1c: the seamless map for quads of `edge_length` times face_size (the sizing field, #F, or
// empty; a map solved for a nearby length and the same sizes is rescaled instead, see
// seamless_map_serves). remesh_follows: a map that starts folded on the part's own triangles is not
// repaired; Error(StageFailed) says so (policy.h: remesh_follows_a_folded_start).
void update_seamless_map(ComponentState& state, double edge_length, std::vector<double> face_size, Progress& progress,
                         bool remesh_follows = false);
// Stage 2: the seamless map made exact with features and boundary on isolines, and its T-mesh.
void update_tmesh(ComponentState& state, Progress& progress);
// Stage 3: integer T-edge lengths for quads of `edge_length`, by the chosen quantizer; the greedy
// one moves toward `target_quads` quads when it is > 0 (quantize_to_count).
void update_quantization(ComponentState& state, double edge_length, double target_quads, Quantizer quantizer,
                         Progress& progress);
// Stage 4: the integer-grid map (escalating for grid-UV jobs), and for fallback_uv_map the cell map.
void update_integer_grid_map(ComponentState& state, Job job, Progress& progress);
void update_cell_map(ComponentState& state, Progress& progress);
// Stage 5: the component's quads.
void update_quads(ComponentState& state, Progress& progress);

}  // namespace qgp

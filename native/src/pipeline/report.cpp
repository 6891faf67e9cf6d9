#include "pipeline/report.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "intake/working_mesh.h"
#include "tmesh/tmesh_system.h"

namespace qgp {

namespace {

// A component that failed at or before the stage being reported has no result of it: its entry in
// the per-component list is null (report: failed_components says why).
bool failed_before_report(const ComponentState& state, Json& per_component) {
  if (!state.failure) return false;
  per_component.push_back(nullptr);
  return true;
}

}  // namespace

void to_json(Json& j, const CellMapFallback& fallback) {
  if (!fallback.ran) {
    j = nullptr;
  } else if (!fallback.failure.empty()) {
    j = {{"used", false}, {"failure", fallback.failure}};
  } else {
    j = fallback.stats;
    j["used"] = fallback.used;
  }
}

const char* quad_source_name(QuadSource source) {
  switch (source) {
    case QuadSource::IntegerGridMap: return "integer-grid map";
    case QuadSource::TMeshLayout: return "T-mesh layout";
    case QuadSource::SplitTriangles: return "split triangles";
  }
  return "";
}

void to_json(Json& j, const QuadChoice& choice) {
  j = choice.extraction.stats;
  j["path"] = choice.source == QuadSource::IntegerGridMap
                  ? std::string(quad_source_name(choice.source))
                  : std::string(quad_source_name(choice.source)) + " (" + choice.why_not_map + ")";
  if (choice.source == QuadSource::TMeshLayout) j["layout"] = choice.layout;
  j["untangle"] = choice.untangle;
}

Json working_mesh_report(const std::vector<ComponentState>& components) {
  int decimated = 0, remeshed = 0, input_faces = 0, working_faces = 0, feature_edges = 0;
  for (const ComponentState& state : components) {
    const std::vector<char>& own = state.full_mesh ? state.full_feature_edges : state.feature_edges;
    feature_edges += static_cast<int>(std::count(own.begin(), own.end(), 1));  // of the component itself
    decimated += state.full_mesh.has_value() && !state.remeshed;
    remeshed += state.remeshed;
    input_faces += state.full_mesh ? state.full_mesh->num_faces() : state.mesh.num_faces();
    working_faces += state.mesh.num_faces();
  }
  return {{"decimated_components", decimated},    {"remeshed_components", remeshed},
          {"input_faces", input_faces},           {"working_faces", working_faces},
          {"input_feature_edges", feature_edges}, {"faces_per_quad", kWorkingFacesPerQuad},
          {"min_faces", kMinWorkingFaces}};
}

Json field_report(const std::vector<ComponentState>& components) {
  // index_sum is in full index units (quarter turns / 4) so that it reads as the Euler characteristic.
  Json per_component = Json::array();
  int singularities = 0, index_quarters = 0, euler = 0, feature_edges = 0, cut_edges = 0, overconstrained = 0,
      collapsed = 0;
  for (const ComponentState& state : components) {
    if (failed_before_report(state, per_component)) continue;
    const CrossField& field = *state.field;
    int features = 0;
    for (char f : field.feature_edge) features += f;
    per_component.push_back({{"faces", state.mesh.num_faces()},
                             {"singularities", field.num_singularities},
                             {"index_sum", field.index_sum / 4},
                             {"euler_characteristic", field.euler_characteristic},
                             {"feature_edges", features},
                             {"overconstrained_faces", field.num_overconstrained_faces},
                             {"collapsed_sectors", field.num_collapsed_sectors},
                             {"close_pairs", field.num_close_pairs},
                             {"close_pairs_kept", !state.field.key().cancel_pairs},
                             {"pairs_kept_near_folds", field.num_pairs_kept_near_folds},
                             {"cancelled_pairs", field.num_cancelled_pairs},
                             {"untwisted_loops", field.num_untwisted_loops},
                             {"cut_edges", state.cut->num_cut_edges}});
    singularities += field.num_singularities;
    index_quarters += field.index_sum;
    euler += field.euler_characteristic;
    feature_edges += features;
    cut_edges += state.cut->num_cut_edges;
    overconstrained += field.num_overconstrained_faces;
    collapsed += field.num_collapsed_sectors;
  }
  return {
      {"singularities", singularities}, {"index_sum", index_quarters / 4},          {"euler_characteristic", euler},
      {"feature_edges", feature_edges}, {"overconstrained_faces", overconstrained}, {"collapsed_sectors", collapsed},
      {"cut_edges", cut_edges},         {"components", std::move(per_component)}};
}

Json seamless_report(const std::vector<ComponentState>& components, double edge_length) {
  Json per_component = Json::array();
  int flipped = 0, degenerate = 0, iterations = 0;
  double residual = 0, energy = 0;
  double seamless_edge_length = edge_length;
  for (const ComponentState& state : components) {
    if (failed_before_report(state, per_component)) continue;
    const SeamlessMapStats& s = state.seamless->stats;
    seamless_edge_length = state.seamless_edge_length();
    per_component.push_back(s);
    flipped += s.flipped_triangles;
    degenerate += s.degenerate_triangles;
    iterations += s.ipopt_iterations;
    residual = std::max(residual, s.max_transition_residual);
    energy += s.energy;
  }
  Json j = {{"flipped_triangles", flipped},          {"degenerate_triangles", degenerate},
            {"max_transition_residual", residual},   {"energy", energy},
            {"ipopt_iterations", iterations},        {"edge_length", seamless_edge_length},
            {"components", std::move(per_component)}};
  if (flipped + degenerate > 0)
    j["warnings"].push_back(std::to_string(flipped) + " flipped and " + std::to_string(degenerate) +
                            " degenerate triangle(s) remain in the seamless map");
  return j;
}

Json tmesh_report(const std::vector<ComponentState>& components) {
  Json per_component = Json::array();
  Json total = {{"nodes", 0}, {"edges", 0}, {"cells", 0}, {"singular_nodes", 0}};
  for (const ComponentState& state : components) {
    if (failed_before_report(state, per_component)) continue;
    per_component.push_back(state.traced->tmesh);
    for (auto& [key, value] : total.items()) value = value.get<int64_t>() + per_component.back().value(key, int64_t(0));
  }
  total["components"] = std::move(per_component);
  return total;
}

namespace {

// The quad count asked and made: {target, quads}, and when they are more than 5 % apart a note
// saying why, with fewest_quads (the sum over components of the fewest quads their layout allows
// where that was measured, else of their quads) or, where counts jump over the target, steps_from
// and steps_to (the totals with each such component on the lower and on the higher side).
Json count_report(const std::vector<ComponentState>& components, int copies) {
  double target = 0;
  int64_t quads = 0, fewest = 0, below = 0, above = 0, singular = 0;
  bool stepped = false;
  for (const ComponentState& state : components) {
    if (state.failure) continue;
    const Quantized& q = *state.quantization;
    target += q.target_quads;
    quads += q.result.quads_expected;
    fewest += q.fewest_quads >= 0 ? q.fewest_quads : q.result.quads_expected;
    below += q.count_step ? (*q.count_step)[0] : q.result.quads_expected;
    above += q.count_step ? (*q.count_step)[1] : q.result.quads_expected;
    stepped = stepped || q.count_step.has_value();
    for (int index : state.field->vertex_index) singular += index != 0;
  }
  target *= copies, quads *= copies, fewest *= copies, below *= copies, above *= copies;
  Json count = {{"target", std::lround(target)}, {"quads", quads}};
  if (!(target > 0) || std::abs(quads - target) <= 0.05 * target) return count;
  const std::string asked = std::to_string(std::lround(target)) + " quads asked, " + std::to_string(quads) + " made: ";
  if (fewest > 1.05 * target) {
    count["fewest_quads"] = fewest;
    count["note"] = asked + std::to_string(fewest) + " is the fewest this layout allows (the cross field's " +
                    std::to_string(singular) + " singular points" + (copies > 1 ? " per mirror copy" : "") +
                    " and the features and boundaries need whole quads " + "between them)";
  } else if (stepped) {
    count["steps_from"] = below;
    count["steps_to"] = above;
    count["note"] = asked + "this layout's count steps from " + std::to_string(below) + " to " + std::to_string(above) +
                    " near the target (whole rows of quads come and go at once)";
  } else {
    count["note"] = asked + "the quantization found no closer count";
  }
  return count;
}

}  // namespace

Json quantization_report(const std::vector<ComponentState>& components, Quantizer quantizer, int copies) {
  Json per_component = Json::array();
  int64_t quads = 0;
  for (const ComponentState& state : components) {
    if (failed_before_report(state, per_component)) continue;
    const Quantized& q = *state.quantization;
    quads += q.result.quads_expected;
    per_component.push_back(q.result);
    Json& entry = per_component.back();
    entry["fold_rounds"] = q.fold_rounds;
    entry["kept_positive_edges"] = q.kept_positive_edges;
    entry["flip_rounds"] = q.flip_rounds;
    entry["flipped_layout_quads_before"] = q.flipped_layout_quads_before;
    entry["flipped_layout_quads"] = q.flipped_layout_quads;
    entry["quads_before_flip_rounds"] = q.quads_before_flip_rounds;
    entry["flip_seconds"] = q.flip_seconds;
    entry["target_quads"] = q.target_quads;
    entry["nominal_scale"] = q.nominal_scale;
    entry["count_rounds"] = q.count_rounds;
    if (q.fewest_quads >= 0) entry["fewest_quads"] = q.fewest_quads;
    if (q.count_step) entry["count_step"] = *q.count_step;
  }
  return {{"method", quantizer_name(quantizer)},
          {"quads_expected", quads * copies},
          {"count", count_report(components, copies)},
          {"components", std::move(per_component)}};
}

Json igm_report(const std::vector<ComponentState>& components) {
  Json per_component = Json::array();
  int flipped = 0, degenerate = 0, wound = 0, fallbacks = 0, cell_maps = 0;
  double residual = 0;
  for (const ComponentState& state : components) {
    if (failed_before_report(state, per_component)) continue;
    const IgmStats& s = state.igm->stats;
    const bool cell_map = state.cell_map.computed_from(state.igm.id()) && state.cell_map->ran;
    flipped += s.flipped_triangles;
    degenerate += s.degenerate_triangles;
    wound += s.winding_defects;
    fallbacks += s.fallback_used;
    cell_maps += cell_map && state.cell_map->used;
    residual = std::max(residual, s.max_integer_residual);
    per_component.push_back(s);
    if (cell_map) per_component.back()["cell_map"] = *state.cell_map;
  }
  return {{"flipped_triangles", flipped},
          {"degenerate_triangles", degenerate},
          {"winding_defects", wound},
          {"max_integer_residual", residual},
          {"fallback_used", fallbacks + cell_maps > 0},
          {"cell_map_components", cell_maps},
          {"components", std::move(per_component)}};
}

Json extraction_report(const std::vector<ComponentState>& components, Json& igm) {
  Json per_component = Json::array();
  int from_layout = 0;
  for (const ComponentState& state : components) {
    if (failed_before_report(state, per_component)) continue;
    per_component.push_back(*state.quads);
    from_layout += state.quads->source == QuadSource::TMeshLayout;
  }
  if (from_layout > 0) {
    igm["fallback_used"] = true;
    igm["fallback"] = "quads of the T-mesh layout in " + std::to_string(from_layout) + " component(s)";
  }
  return {{"layout_components", from_layout}, {"components", std::move(per_component)}};
}

}  // namespace qgp

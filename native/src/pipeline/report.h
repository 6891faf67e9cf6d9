// The run report's stage objects, assembled from the components' stage results (totals plus one
// entry per component). docs/report.md describes every key.
#pragma once
#include <vector>

#include "core/json.h"
#include "pipeline/component_state.h"

namespace qgp {

void to_json(Json& j, const CellMapFallback& fallback);  // null when it did not run
void to_json(Json& j, const QuadChoice& choice);

Json working_mesh_report(const std::vector<ComponentState>& components);
Json field_report(const std::vector<ComponentState>& components);
Json seamless_report(const std::vector<ComponentState>& components, double edge_length);
Json tmesh_report(const std::vector<ComponentState>& components);
// copies: the mirror copies the quads are made into (symmetry), which multiply the counts.
Json quantization_report(const std::vector<ComponentState>& components, Quantizer quantizer, int copies = 1);
Json igm_report(const std::vector<ComponentState>& components);
// The `extraction` object; marks `igm` as having used a fallback where quads came from the layout.
Json extraction_report(const std::vector<ComponentState>& components, Json& igm);

}  // namespace qgp

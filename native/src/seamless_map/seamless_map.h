// Stage 1c: continuous, exactly seamless, flip-free field-aligned parametrization (Bommes et al.
// 2009 energy, transition constraints, features on isolines, regularity via Ipopt).
#pragma once
#include <vector>

#include "core/parametrization.h"
#include "core/progress.h"
#include "cross_field/cross_field.h"
#include "cut_graph/cut_graph.h"

namespace qgp {

struct SeamlessMapOptions {
  double edge_length = 1;  // target quad edge length in model units: 1 uv unit = edge_length
};

struct SeamlessMapStats {
  int flipped_triangles = 0;
  int degenerate_triangles = 0;
  double max_transition_residual = 0;  // uv units
  double energy = 0;
  int ipopt_iterations = 0;
};

struct SeamlessMap {
  Parametrization param;  // rotation[] and is_cut from the cut graph
  SeamlessMapStats stats;
};

SeamlessMap compute_seamless_map(const TriMesh& mesh, const CrossField& field, const CutGraph& cut,
                                 const SeamlessMapOptions& options, Progress& progress);

}  // namespace qgp

// Stage 2a: motorcycle graph / T-mesh of an exact seamless parametrization (paper §5, §9).
#pragma once
#include <vector>

#include "core/mesh.h"
#include "core/parametrization.h"
#include "core/progress.h"
#include "tmesh/tmesh.h"

namespace qgp {

struct TraceOptions {
  // #E: feature curves (they and the boundary are inserted first and stop separatrices); may be
  // empty. Features should be parameter isolines (exactly, for cell equations that hold exactly).
  std::vector<char> feature_edges;
  long long max_steps = 0;  // limit on face-to-face advances; 0: 200 * #F + 10^6
};

// mesh: one connected, oriented, manifold component (connectivity built); param: its exact
// seamless parametrization (sanitize_parametrization). Traces the separatrices of every
// singularity, feature/boundary corner (and a seed on surfaces without any) with exact
// predicates and builds the T-mesh: nodes, oriented edges with continuous lengths, four-sided
// cells and node incidences. Throws Error(StageFailed) with the reason where the
// parametrization cannot be traced (flipped or degenerate triangles on the way, singularities
// on feature corners with a flipped one-ring, non-terminating traces, ...); never hangs.
TMesh trace_tmesh(const TriMesh& mesh, const ExactParametrization& param, const TraceOptions& options,
                  Progress& progress);

}  // namespace qgp

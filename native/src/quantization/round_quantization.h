// The `round` baseline: direct rounding as the paper's §1 describes it (Kälberer et al. 2007).
// The independent integer variables of the continuous seamless map at the quantization scale —
// singularity (and corner, seed) positions, transition translations, feature/boundary isolines —
// are rounded, every dependent one derived from them exactly (sanitize_parametrization with
// snapping: its elimination keeps snapped variables free), and the map is solved again with them
// fixed (least-squares deviation from the continuous map's per-triangle gradients, cotangent
// weights). Its T-mesh, traced again, gives integer lengths x, checked with the same validity test
// as the greedy quantizer. A map the tracer cannot handle (flipped or collapsed triangles) counts
// as invalid, with the tracer's reason.
#pragma once
#include <functional>
#include <string>
#include <vector>

#include "core/mesh.h"
#include "core/parametrization.h"
#include "core/progress.h"
#include "quantization/quantization.h"
#include "tmesh/tmesh.h"

namespace qgp {

struct RoundedMap {
  ExactParametrization param;          // integer singular vertices, translations and isolines
  std::vector<char> snapped_vertices;  // #V: vertices whose position was rounded
  int flipped_triangles = 0;           // parametric area < 0 in `param` (exact sign)
  int degenerate_triangles = 0;        // parametric area == 0
  int unresolved_equations = 0;        // of the sanitization (0 expected)
  double max_change = 0;               // largest |rounded - continuous| over corners (quad units)
};

// mesh: one component; param: its continuous seamless map (T-mesh length units); feature_edges:
// #E (may be empty; boundary edges are always isolines); snap_vertices: #V, the vertices whose
// positions are independent variables (singular vertices, feature/boundary corners, seeds);
// scale: quad units per map unit. fraction_bits: of the result.
RoundedMap round_parametrization(const TriMesh& mesh, const Parametrization& param,
                                 const std::vector<char>& feature_edges, const std::vector<char>& snap_vertices,
                                 double scale, int fraction_bits = 20);

// The vertices carrying the T-mesh's singular nodes, feature/boundary corners and seeds, and every
// vertex with non-zero holonomy of `param`.
std::vector<char> independent_vertices(const TriMesh& mesh, const Parametrization& param, const TMesh& tmesh);

// Traces a T-mesh of an exact map (tmesh/trace_tmesh with the component's features).
using TraceFunction = std::function<TMesh(const ExactParametrization&, Progress&)>;

struct RoundingResult {
  QuantizationResult quantization;  // method Round; x refers to `tmesh`; objective NaN (the
                                    // rounded T-mesh has no continuous lengths to compare with)
  TMesh tmesh;                      // T-mesh of the rounded map (empty if it could not be traced)
  RoundedMap map;
};

// tmesh: the T-mesh of the continuous map (for the independent vertices); options.scale as for
// quantize(). Never throws for an invalid rounding (the result says why); throws
// Error(Cancelled) on cancel and Error(InvalidArgument) for malformed input.
RoundingResult quantize_by_rounding(const TriMesh& mesh, const Parametrization& param,
                                    const std::vector<char>& feature_edges, const TMesh& tmesh,
                                    const QuantizationOptions& options, const TraceFunction& trace, Progress& progress);

}  // namespace qgp

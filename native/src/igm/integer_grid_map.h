// Stage 2c: integer-grid map (paper §7). The seamless map is solved again at the quantization's
// scale with the quantized T-edge lengths as linear constraints Cz = b, then rounded exactly so
// that singular vertices sit on integer points, every transition is a 90°·k rotation plus an
// integer translation and feature/boundary edges lie on integer isolines.
//
// Constraints (§7): every T-edge e from node a to node b gives, in the chart of the face where its
// trace ends,   p_b = τ(p_a) + x_e · d_e,   where p_a, p_b are the node positions (barycentric
// combinations of the corners of the faces the trace starts / ends in), τ is the composition of
// the new map's transitions across the cut edges the trace crosses, and d_e is the unit
// axis direction of the edge in that chart. Both coordinates are constrained (the node offset
// along the edge is x_e, across it 0). One node (a singular one if any) is fixed at its rounded
// position, so all nodes reachable through T-edges get integer coordinates.
//
// Solve (§7.1): penalty λ‖Cz − b‖² with the seamless-map solver's regularity repair (Ipopt,
// re-linearized around each result) until ‖Cz − b‖∞ ≤ tolerance, then the hard-constrained
// solve linearized around the last pose. Then exact sanitization with snapping.
#pragma once
#include <string>
#include <vector>

#include "core/json.h"
#include "core/mesh.h"
#include "core/parametrization.h"
#include "core/progress.h"
#include "cross_field/cross_field.h"
#include "cut_graph/cut_graph.h"
#include "quantization/quantization.h"
#include "seamless_map/seamless_map.h"
#include "tmesh/tmesh.h"

namespace qgp {

struct IgmOptions {
  double edge_length = 1;        // model units per uv unit of the seamless map (SeamlessMapOptions)
  double penalty_weight = 1e6;   // λ of the penalty phase
  double penalty_tolerance = 1e-4;  // stop the penalty phase at ‖Cz − b‖∞ ≤ this (quad units)
  int max_penalty_rounds = 8;    // penalty solves (each re-linearized around the previous one)
  int max_repair_rounds = 24;    // Ipopt repair rounds per solve
  int fraction_bits = 20;        // of the exact result
  bool allow_fallback = true;    // §7.1.1 fallback when the global solve stays irregular
};

struct IgmStats {
  int flipped_triangles = 0;        // in the exact result (exact sign)
  int degenerate_triangles = 0;     // in the exact result
  double max_integer_residual = 0;  // before snapping: largest distance of a singular vertex /
                                    // transition translation / feature isoline from an integer
  double max_constraint_violation = 0;  // ‖Cz − b‖∞ of the hard solve (quad units)
  bool fallback_used = false;
  std::string path;                 // "global" or "fallback: <what ran>"
  int penalty_iterations = 0;       // penalty solves run
  int constraints = 0;              // scalar rows of C
  int unresolved_equations = 0;     // of the sanitization (0 expected)
  int64_t parametric_area = 0;      // Σ triangle areas in uv, in quad units (== quads_expected)
  bool area_is_integral = true;
  int ipopt_solves = 0, ipopt_iterations = 0;
  double seconds = 0, seconds_solve = 0, seconds_sanitize = 0;
};

struct IntegerGridMap {
  ExactParametrization param;  // exact integer-grid map (input of extract_quads)
  Parametrization continuous;  // the solved map before rounding (quad units)
  IgmStats stats;
};

// mesh: one component (connectivity built); field, cut: its cross field and cut graph (frames,
// feature edges, isolines); seamless: its continuous seamless map (1 uv unit = options.edge_length);
// sanitized: the exact map the T-mesh was traced on; tmesh: its T-mesh; quantization: a valid
// quantization of it (x, scale). Throws Error(InvalidArgument) for mismatched inputs,
// Error(StageFailed) if no integer-grid map is found, Error(Cancelled) on cancel. Reports progress
// with update() within the caller's stage.
IntegerGridMap compute_integer_grid_map(const TriMesh& mesh, const CrossField& field, const CutGraph& cut,
                                        const SeamlessMap& seamless, const ExactParametrization& sanitized,
                                        const TMesh& tmesh, const QuantizationResult& quantization,
                                        const IgmOptions& options, Progress& progress);

// Report object `igm`: flipped_triangles, degenerate_triangles, max_integer_residual,
// fallback_used, penalty_iterations, seconds (+ path, constraints, parametric_area).
Json igm_report(const IgmStats& stats);

}  // namespace qgp

// Stage 2c: integer-grid map (paper §7). The seamless map is solved again at the quantization's
// scale with the quantized T-edge lengths as linear constraints Cz = b, then rounded exactly so
// that singular vertices sit on integer points, every transition is a 90°·k rotation plus an
// integer translation and feature/boundary edges lie on integer isolines.
//
// Constraints (§7): for paths in T between singular / corner nodes (spanning tree plus loops, see
// integer_grid_rows), p_b = τ(p_a) + Σ x_e · d_e in the chart where the path ends. One node (a
// singular one if any) is fixed at its rounded position, so all of them get integer coordinates.
//
// Solve (§7.1), in escalating attempts until the exact map has no flipped/degenerate triangle:
//  1. (default) one equality-only penalty solve λ‖Cz − b‖² (λ = 1e6; it meets ‖Cz − b‖∞ ≤ 1e-4
//     on every mesh tested), then the hard solve with Ipopt repair of flipped triangles
//     (tri-sector constraints linearized around the seamless map);
//  2. the paper's penalty phase: penalty solves with the regularity repair, each re-linearized
//     around the previous result, until ‖Cz − b‖∞ ≤ 1e-4, then the hard solve around the last pose;
//  3. fallback: the hard solve with every triangle under tri-sector constraints around the
//     seamless map (stats.fallback_used). The paper's §7.1.1 per-cell fallback (T-mesh edges
//     inserted into the mesh, cells mapped onto their integer rectangles) is not implemented.
// The hard solve imposes the integer quantities that Cz = b determines (singular/corner vertex
// positions, cut translations, feature/boundary isoline values, rounded from the penalty optimum,
// which is within 1e-4 of them), exactly: unit coefficients keep the elimination integral (the
// path rows themselves carry barycentric coefficients). Finally sanitize_with_isolines snaps
// them to exact integers. stats.path names the attempt that produced the result.
#pragma once
#include <string>
#include <vector>

#include "core/json.h"
#include "core/mesh.h"
#include "core/parametrization.h"
#include "core/progress.h"
#include "core/sanitize_isolines.h"
#include "cross_field/cross_field.h"
#include "cut_graph/cut_graph.h"
#include "quantization/quantization.h"
#include "seamless_map/parametrization_problem.h"
#include "seamless_map/seamless_map.h"
#include "tmesh/tmesh.h"

namespace qgp {

struct IgmOptions {
  double edge_length = 1;        // model units per uv unit of the seamless map (SeamlessMapOptions)
  double penalty_weight = 1e6;   // λ of the penalty phase
  double penalty_tolerance = 1e-4;  // stop the penalty phase at ‖Cz − b‖∞ ≤ this (quad units)
  int max_penalty_rounds = 8;    // penalty solves (each re-linearized around the previous one)
  int max_repair_rounds = 24;    // Ipopt repair rounds per solve
  int relinearization_rounds = 1;  // extra re-linearizations inside each solve once regular
  int fraction_bits = 20;        // of the exact result
  bool regularity = true;        // Ipopt repair of flipped triangles (off: equality-only solves)
  // Regularity also in the penalty solves (paper §7.1). Off (default, much faster): one
  // equality-only penalty solve fixes the integer values (they follow from Cz = b, not from the
  // regularity) and the hard solve alone repairs flips, linearized around the seamless map; if
  // flips remain, the paper's re-linearized penalty phase runs as well and the better map is kept.
  bool penalty_regularity = false;
  // When the exact map has flipped/degenerate triangles: hard solve again with all triangles
  // under tri-sector constraints around the seamless map (not yet the paper's §7.1.1 per-cell map).
  bool allow_fallback = true;
  // false: stop after the first attempt (the caller has its own fallback, e.g. quads straight from
  // the T-mesh layout); the escalations can cost minutes on large meshes.
  bool escalate = true;
};

struct IgmStats {
  int flipped_triangles = 0;        // in the exact result (exact sign)
  int degenerate_triangles = 0;     // in the exact result
  int flipped_before_untangle = 0, degenerate_before_untangle = 0;  // set by the caller's untangle
  int untangled_vertices = 0;       // (untangle_map) of the solve's exact result
  int winding_defects = 0;          // vertices whose angle sum differs from their cone angle (a
                                    // flip-free map can wind a one-ring twice)
  double max_integer_residual = 0;  // before snapping: largest distance of a singular vertex /
                                    // transition translation / feature isoline from an integer
  double penalty_integer_residual = 0;  // the same after the penalty phase (<= 1e-4 expected)
  double max_constraint_violation = 0;  // ‖Cz − b‖∞ of the T-edge rows in the final continuous map
  bool fallback_used = false;
  std::string path;                 // "global" or "fallback: <what ran>"
  int penalty_iterations = 0;       // penalty solves run (all attempts)
  std::vector<double> penalty_violation;  // ‖Cz − b‖∞ after each penalty solve
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
  std::vector<char> snapped_vertices;     // #V: held on integer points (singular, corners, seeds)
  std::vector<IsolineConstraint> isolines;  // feature and boundary edges held on integer isolines
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

// The rows of C z = b for the given T-edge lengths (#edges, in uv units of the map to be solved):
// for paths of T-edges between singular / feature-corner / boundary-corner / seed nodes (a BFS
// spanning tree from `root` plus one loop per non-tree edge), over the corner coordinates of the
// new map:  p_end = τ(p_start) + Σ x_e d_e  with τ the new map's transitions along the traces,
// node positions barycentric in their faces (taken from `sanitized`, the map the T-mesh was
// traced on). Regular nodes (T-junctions, crossings) are passed, not constrained.
struct IgmRow {
  std::vector<CornerTerm> terms;
  double rhs = 0;
  int edge = -1;  // the T-edge that closes the loop / reaches the node (diagnostics)
};
std::vector<IgmRow> integer_grid_rows(const TriMesh& mesh, const ExactParametrization& sanitized, const TMesh& tmesh,
                                      const std::vector<double>& lengths, int root);

// Exact counts of flipped (area < 0) and degenerate (area == 0) triangles.
void count_exact_irregular(const ExactParametrization& param, int* flipped, int* degenerate);

// Vertices whose angle sum in the exact map, in quarter turns, is not cone_turns[v] (#V, e.g. the
// cross field's cone_quarter_turns).
int count_exact_winding_defects(const TriMesh& mesh, const ExactParametrization& param, const std::vector<int>& cone_turns);
// Sum of the signed triangle areas in uv (quad units), rounded toward zero; *integral tells
// whether it is a whole number.
int64_t exact_parametric_area(const ExactParametrization& param, bool* integral);

// Report object `igm`: flipped_triangles, degenerate_triangles, max_integer_residual,
// fallback_used, penalty_iterations, seconds (+ path, constraints, parametric_area).
Json igm_report(const IgmStats& stats);

}  // namespace qgp

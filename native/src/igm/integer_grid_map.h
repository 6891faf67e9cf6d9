// Stage 2c: integer-grid map (paper §7). The seamless map is solved again at the quantization's
// scale with the quantized T-edge lengths as linear constraints Cz = b, then rounded exactly so
// that singular vertices sit on integer points, every transition is a 90°·k rotation plus an
// integer translation and feature/boundary edges lie on integer isolines.
//
// Constraints (§7): for paths in T between singular / corner nodes (spanning tree plus loops, see
// integer_grid_rows), p_b = τ(p_a) + Σ x_e · d_e in the chart where the path ends. One node (a
// singular one if any) is fixed at its rounded position, so all of them get integer coordinates.
//
// Solve (§7.1): one IntegerGridMapSolver per component and quantization runs attempts (IgmAttempt):
// the default one, the paper's re-linearized penalty phase, and the hard solve with every triangle
// under tri-sector constraints. Which attempts run, and which map is kept, is the pipeline's
// decision (pipeline/policy.h). The hard solve imposes the integer quantities that Cz = b
// determines (singular/corner vertex positions, cut translations, feature/boundary isoline values,
// rounded from the penalty optimum, which is within 1e-4 of them), exactly: unit coefficients keep
// the elimination integral (the path rows themselves carry barycentric coefficients). Finally
// sanitize_with_isolines snaps them to exact integers. The fallback map of §7.1.1 (T-mesh edges
// inserted, each cell mapped onto its integer rectangle) is igm/cell_map.h.
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
  double edge_length = 1;           // model units per uv unit of the seamless map (SeamlessMapOptions)
  double penalty_weight = 1e6;      // λ of the penalty phase
  double penalty_tolerance = 1e-4;  // stop the penalty phase at ‖Cz − b‖∞ ≤ this (quad units)
  int max_penalty_rounds = 8;       // penalty solves of the re-linearized attempt
  int max_repair_rounds = 24;       // Ipopt repair rounds per solve
  int count_stagnation_rounds = 0;  // see ParametrizationSolveOptions
  int halving_rounds = 0;           // see ParametrizationSolveOptions
  int relinearization_rounds = 1;   // extra re-linearizations inside each solve once regular
  int fraction_bits = 20;           // of the exact result
  // No repair where the integer values make triangles degenerate (see ParametrizationSolveOptions).
  bool skip_repair_if_forced = false;
  // > 0: the hard solve's repair ends at the first round of a plateau (see
  // ParametrizationSolveOptions::caller_finishes) whose pose, rounded exactly, has at most this share
  // of its triangles flipped or degenerate and is regular once untangled (untangle_map, as the caller
  // then untangles it), the untangle moving at most finish_by_untangle_moves vertices per flipped or
  // degenerate triangle.
  double finish_by_untangle_up_to_share = 0;
  int finish_by_untangle_moves = 0;
};

// What one solve of the integer-grid map does (paper §7.1).
enum class IgmAttempt {
  // One equality-only penalty solve λ‖Cz − b‖² fixes the integer values (they follow from Cz = b,
  // not from the regularity; it meets ‖Cz − b‖∞ ≤ 1e-4 on every mesh tested), then the hard solve
  // repairs flipped triangles with Ipopt (tri-sector constraints linearized around the seamless map).
  Default,
  // The paper's penalty phase: penalty solves with the regularity repair, each re-linearized around
  // the previous result, until ‖Cz − b‖∞ ≤ penalty_tolerance, then the hard solve around the last pose.
  RelinearizedPenalty,
  // The last attempt's hard solve again with every triangle under tri-sector constraints
  // linearized around the (flip-free) seamless map: a convex problem whose feasible maps are all
  // regular. Needs an earlier attempt (its integer values).
  AllFaces,
};
const char* igm_attempt_name(IgmAttempt attempt);

// One attempt as the policy ran it (report `igm.components[i].attempts`).
struct IgmAttemptRecord {
  std::string attempt;                // igm_attempt_name, or "untangle"
  int irregular = 0;                  // flipped + degenerate triangles + wound one-rings of its exact map
  bool kept = false;                  // it replaced the map before it
  std::vector<int> repair_bad_faces;  // its hard solve's bad faces after each repair round
  double seconds = 0;
};
QGP_JSON_FIELDS(IgmAttemptRecord, attempt, irregular, kept, repair_bad_faces, seconds)

struct IgmStats {
  int flipped_triangles = 0;                                        // in the exact result (exact sign)
  int degenerate_triangles = 0;                                     // in the exact result
  int flipped_before_untangle = 0, degenerate_before_untangle = 0;  // set by the caller's untangle
  int untangled_vertices = 0;                                       // (untangle_map) of the solve's exact result
  int winding_defects = 0;                   // vertices whose angle sum differs from their cone angle (a
                                             // flip-free map can wind a one-ring twice)
  double max_integer_residual = 0;           // before snapping: largest distance of a singular vertex /
                                             // transition translation / feature isoline from an integer
  double penalty_integer_residual = 0;       // the same after the penalty phase (<= 1e-4 expected)
  double max_constraint_violation = 0;       // ‖Cz − b‖∞ of the T-edge rows in the final continuous map
  int flipped_initial = 0;                   // flipped triangles of the hard solve's equality-only optimum
  int forced_degenerate = 0;                 // triangles the integer values make degenerate in every map
  int faces = 0;                             // triangles of the component
  std::vector<int> repair_bad_faces;         // the hard solve's bad faces after each repair round
  std::vector<double> repair_seconds;        // and the time of each round
  bool repair_left_to_untangle = false;      // it ended at a plateau the untangle makes regular
                                             // (IgmOptions::finish_by_untangle_up_to_share)
  IgmAttempt attempt = IgmAttempt::Default;  // the attempt that made this map
  bool fallback_used = false;                // made by the all-faces attempt
  std::string path;                          // the policy's account of the attempts (pipeline/policy.h)
  std::vector<IgmAttemptRecord> attempts;    // every attempt the policy ran, in order
  int penalty_iterations = 0;                // penalty solves run (all attempts so far)
  std::vector<double> penalty_violation;     // ‖Cz − b‖∞ after each penalty solve
  int constraints = 0;                       // scalar rows of C
  int unresolved_equations = 0;              // of the sanitization (0 expected)
  int64_t parametric_area = 0;               // Σ triangle areas in uv, in quad units (== quads_expected)
  bool area_is_integral = true;
  int ipopt_solves = 0, ipopt_iterations = 0;  // all attempts so far
  int qp_by_ipopt = 0;                         // of those solves, finished by Ipopt (quadratic_program.h)
  double seconds = 0, seconds_solve = 0, seconds_sanitize = 0;
  double seconds_untangle_trials = 0;  // of IgmOptions::finish_by_untangle_up_to_share (in seconds_solve)
};

struct IntegerGridMap {
  ExactParametrization param;  // exact integer-grid map (input of extract_quads)
  Parametrization continuous;  // the solved map before rounding (quad units)
  IgmStats stats;
  std::vector<char> snapped_vertices;       // #V: held on integer points (singular, corners, seeds)
  std::vector<IsolineConstraint> isolines;  // feature and boundary edges held on integer isolines
};

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

// Solves the integer-grid map of one component for one quantization, attempt by attempt.
// mesh: one component (connectivity built); field, cut: its cross field and cut graph (frames,
// feature edges, isolines); seamless: its continuous seamless map (1 uv unit = options.edge_length);
// sanitized: the exact map the T-mesh was traced on; tmesh: its T-mesh; quantization: a valid
// quantization of it (x, scale). The constructor throws Error(InvalidArgument) for mismatched
// inputs and Error(StageFailed) for a T-mesh without consistent path constraints; solve() throws
// Error(Cancelled) on cancel. The solver keeps references to its inputs. Progress is reported with
// update() within the caller's stage.
class IntegerGridMapSolver {
 public:
  IntegerGridMapSolver(const TriMesh& mesh, const CrossField& field, const CutGraph& cut, const SeamlessMap& seamless,
                       const ExactParametrization& sanitized, const TMesh& tmesh,
                       const QuantizationResult& quantization, const IgmOptions& options, Progress& progress);
  ~IntegerGridMapSolver();

  // Runs one attempt and rounds its result exactly. The stats' effort counters (solves,
  // iterations, penalty rounds, seconds) count every attempt so far.
  IntegerGridMap solve(IgmAttempt attempt, double progress_begin, double progress_end);

 private:
  void add_seamless_isolines(const SeamlessMap& seamless, const CutGraph& cut);
  void build_path_rows(const ExactParametrization& sanitized, const QuantizationResult& quantization);
  // C z = b: the path rows, and the root node at its rounded position.
  void add_path_constraints();
  // Penalty solves of C z = b (with re-linearized regularity, or one equality-only solve).
  ParametrizationSolution penalty_phase(bool with_regularity, double begin, double end);
  // Replaces C z = b by the integer values it determines, rounded from `integers`.
  void impose_integers(const Parametrization& integers);
  // The solve under impose_integers()' constraints with Ipopt repair of flipped triangles.
  ParametrizationSolution hard_solve(bool after_relinearized_penalty, double begin, double end);
  // Penalty phase, then the hard solve.
  ParametrizationSolution solve_global(bool relinearized_penalty, double begin, double end);
  // The last hard solve with every triangle under tri-sector constraints around the seamless map.
  ParametrizationSolution solve_all_faces(double begin, double end);
  void count_solves(const ParametrizationSolution& solution);
  // What the exact rounding snaps: these vertices, and these edges' corners on their isoline axis.
  void set_snapping(const std::vector<char>& snap_vertices, const std::vector<IsolineConstraint>& isolines);
  // Largest |C z - b| of the path rows in `map`.
  double row_violation(const Parametrization& map) const;
  // Largest distance from an integer of what the exact rounding snaps.
  double integer_residual(const Parametrization& map) const;
  // The exact map of `solved` (snapped, sanitized) and its flipped / degenerate / wound counts.
  IntegerGridMap round_exactly(const Parametrization& solved);
  // True when `pose` rounded exactly has at most options_.finish_by_untangle_up_to_share of its
  // triangles flipped or degenerate and none of them, nor a wound one-ring, once untangled.
  bool untangles_to_regular(const Parametrization& pose);

  const TriMesh& mesh_;
  const CrossField& field_;
  const TMesh& tmesh_;
  const IgmOptions options_;
  Progress& progress_;
  bool inputs_checked_;
  ParametrizationProblem problem_;  // at the quantization's scale: 1 uv unit = one quad edge
  double scale_;
  std::vector<int> cones_;  // cone angle of each vertex, in quarter turns
  int root_ = 0;
  std::vector<IgmRow> rows_;
  Parametrization seamless_pose_;  // the seamless map at the quantization's scale
  Parametrization pose_;           // linearization pose of the penalty phase
  ParametrizationSolveOptions solve_options_;
  std::vector<char> snap_vertices_;
  std::vector<IsolineConstraint> isolines_;
  SanitizeOptions sanitize_;
  bool solved_once_ = false;
  IgmStats stats_;
};

// Exact counts of flipped (area < 0) and degenerate (area == 0) triangles.
void count_exact_irregular(const ExactParametrization& param, int* flipped, int* degenerate);

// Vertices whose angle sum in the exact map, in quarter turns, is not cone_turns[v] (#V, e.g. the
// cross field's cone_quarter_turns).
int count_exact_winding_defects(const TriMesh& mesh, const ExactParametrization& param,
                                const std::vector<int>& cone_turns);
// Sum of the signed triangle areas in uv (quad units), rounded toward zero; *integral tells
// whether it is a whole number.
int64_t exact_parametric_area(const ExactParametrization& param, bool* integral);

// Report object `igm.components[i]`.
QGP_JSON_FIELDS(IgmStats, flipped_triangles, degenerate_triangles, forced_degenerate, max_integer_residual,
                fallback_used, penalty_iterations, seconds, path, penalty_integer_residual, constraints,
                max_constraint_violation, unresolved_equations, parametric_area, ipopt_solves, ipopt_iterations,
                qp_by_ipopt, seconds_solve, seconds_sanitize, flipped_before_untangle, degenerate_before_untangle,
                untangled_vertices, winding_defects, flipped_initial, faces, repair_bad_faces, repair_seconds,
                repair_left_to_untangle, seconds_untangle_trials, attempts)

}  // namespace qgp

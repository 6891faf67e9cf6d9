// Field-guided seamless parametrization problem on a cut mesh, shared by the seamless map
// (stage 1c) and the integer-grid map (paper §7), which adds linear constraints Cz = b.
//
// Variables: (u,v) per wedge (the corners of a vertex joined across non-cut edges, i.e. a vertex
// of the cut-open disc) and a translation per cut edge. Hard constraints are eliminated exactly
// with integer coefficients (seamless_map/linear_elimination.h):
//   - transitions: across every cut edge, for both endpoints, p_g = R^r p_f + t (r from the cut
//     graph; t equal along a cut arc because the arc's inner vertices have one wedge per side),
//   - isolines: an edge's two corners share u (or v) in its face's chart,
//   - optionally the caller's linear constraints (or they enter as a penalty),
//   - optionally one wedge pinned at the origin (the energy does not see global translations).
// Energy (Bommes et al. 2009): sum_f area_f (|grad u - frame_u/L|^2 + |grad v - frame_v/L|^2),
// frame_v = n x frame_u, L = edge_length (one uv unit = L model units), times the face's size where a
// sizing field is given.
//
// Regularity (no flipped or degenerate triangle): the equality-only optimum is computed by sparse
// Cholesky (CHOLMOD). Where it has flipped, degenerate or nearly collapsed triangles, those faces
// plus `ring_size` rings around them are re-optimized with Ipopt under linear tri-sector
// constraints (Bommes et al. 2013): each edge vector of a constrained triangle stays in one of
// three sectors split by the bisectors of a positively oriented reference triangle (the current
// pose where it is healthy, else the reference pose given by the caller, else the ideal
// field-aligned shape), which conservatively guarantees positive area. Only variables of the
// region move; every face they influence is constrained. If Ipopt finds no regular solution the
// region grows. Afterwards the constraints are re-linearized around the new pose a few times to
// lower the energy (paper §7.1).
#pragma once
#include <array>
#include <functional>
#include <memory>
#include <vector>

#include "core/mesh.h"
#include "core/parametrization.h"
#include "core/progress.h"

namespace qgp {

// One coordinate of one corner: corner = 3f + k, axis 0 = u, 1 = v.
struct CornerTerm {
  int corner = 0;
  int axis = 0;
  double coeff = 1;
};

enum class ConstraintMode { Hard, Penalty };
enum class RegularityMode {
  Off,       // equality-only solve
  Repair,    // Ipopt on regions around bad triangles (active set), grown as needed
  AllFaces,  // Ipopt with every triangle constrained
};

struct ParametrizationSolveOptions {
  ConstraintMode linear_constraints = ConstraintMode::Hard;  // the caller's add_linear_constraint()s
  double penalty_weight = 1e6;                               // lambda of the penalty mode
  RegularityMode regularity = RegularityMode::Repair;
  const Parametrization* reference = nullptr;  // optional pose (same mesh) for linearization
  double margin = 0.05;                        // sector margin, fraction of the face's ideal mean edge length
  double min_area_ratio = 1e-4;                // faces with parametric / ideal area below this are repaired
  double elastic_weight = 1e5;                 // cost of sector violation of faces without a valid reference
                                               // (per uv unit, times the face's ideal edge length)
  int ring_size = 2;                           // rings of faces around bad faces whose variables move
  int max_ring_size = 32;                      // a face's rings double while it stays bad, up to this
  int max_repair_rounds = 24;                  // repair rounds (Ipopt solves) before giving up
  int stagnation_rounds = 8;                   // give up after this many rounds without a new best
  int count_stagnation_rounds = 0;             // > 0: also after this many rounds without fewer bad faces
                                               // (for callers with a fallback: a pose only less bad
                                               // rarely becomes regular later)
  int region_stagnation_rounds = 0;            // > 0: also after this many rounds over a region of at
                                               // least half the faces since the bad faces last became
                                               // fewer (each costs about a global solve and they only
                                               // take turns over the same faces: the global solve in
                                               // the field's frame follows)
  int halving_rounds = 0;                      // > 0: also once the bad faces have not halved over the
                                               // last this many rounds (a pose that creeps down to a
                                               // plateau of bad faces)
  bool winding_repair = true;                  // with cone angles: one-rings wound a full turn off their cone are
                                               // bad faces; when the local repair leaves bad faces, one global
                                               // solve in the field's frame, then max_repair_rounds / 2 more rounds
  bool field_frame_solve = true;               // with winding_repair: the global solve above (false: the
                                               // local repair only, for callers with a fallback)
  bool move_shared_coordinates = true;         // when the local repair leaves bad faces: max_repair_rounds / 2
                                               // more rounds whose regions also move the variables shared
                                               // by many vertices (isolines, cut arcs; false: not, for
                                               // callers with a fallback)
  bool skip_repair_if_forced = false;          // no repair where the hard constraints make faces
                                               // degenerate: no map can be regular then (for callers
                                               // that use a regular map or none)
  double max_bad_share_to_repair = 1;          // no repair when more than this share of the faces are
                                               // bad at the start (for callers with a fallback that
                                               // serves such a start better)
  // Called once per plateau of the local repair (the first round that leaves the best pose's bad
  // faces no fewer), with that pose; true ends the repair there with it. For callers that finish a
  // nearly regular pose themselves (the integer-grid map untangles it): a plateau's further rounds
  // grow their regions and cost the most. Empty: the repair runs to its other bounds.
  std::function<bool(const Parametrization&)> caller_finishes;
  int relinearization_rounds = 3;           // at most this many re-linearizations once regular
  double relinearization_tolerance = 1e-3;  // stop when the energy drops by less (relative)
  int max_ipopt_iterations = 300;
  double ipopt_tolerance = 1e-5;
  double progress_begin = 0, progress_end = 1;  // fraction range of the caller's stage
};

struct ParametrizationSolveStats {
  int free_variables = 0;
  int flipped_initial = 0, degenerate_initial = 0, thin_initial = 0;  // equality-only optimum
  int flipped = 0, degenerate = 0, thin = 0;                          // final map
  int winding_defects = 0;                     // see ParametrizationProblem::winding_defects (final map)
  int forced_degenerate = 0;                   // faces the hard constraints make degenerate (isolines)
  double min_area_ratio = 0;                   // min over faces of parametric / ideal area
  double energy = 0;                           // field energy of the final map (without penalty)
  double energy_initial = 0;                   // of the equality-only optimum
  double constraint_violation = 0;             // max |Cz - b| of the caller's linear constraints
  int ipopt_solves = 0, ipopt_iterations = 0;  // quadratic programs solved (quadratic_program.h), iterations
  int qp_by_ipopt = 0;                         // of them finished by Ipopt (the own method did not converge)
  int repair_rounds = 0, relinearizations = 0;
  std::vector<int> bad_after_round;       // bad faces of the kept pose after each repair round
  std::vector<double> seconds_of_round;   // time of each repair round
  int field_frame_solves = 0;             // global solves with every face in its field-frame sectors
  bool moved_shared_coordinates = false;  // regions moved shared coordinates (see the option above)
  bool finished_by_caller = false;        // the repair ended where options.caller_finishes said so
  bool repair_declined = false;           // not repaired: more bad faces than max_bad_share_to_repair
  int max_region_faces = 0, max_qp_variables = 0;
  int non_integer_pivots = 0, redundant_constraints = 0, inconsistent_constraints = 0;
  double seconds_assembly = 0, seconds_cholesky = 0, seconds_ipopt = 0;
};

struct ParametrizationSolution {
  Parametrization param;
  ParametrizationSolveStats stats;
};

class ParametrizationProblem {
 public:
  // mesh must outlive the problem. rotation: 3#F transition quarter turns (as
  // Parametrization::rotation); is_cut: #E (edges with rotation != 0 are cuts anyway);
  // frame_u: #F tangent directions (+u axis of each face's chart); edge_length > 0; face_size: #F
  // multiples of edge_length, the sizing field (sizing/sizing.h; empty: 1 everywhere).
  ParametrizationProblem(const TriMesh& mesh, std::vector<int8_t> rotation, std::vector<char> is_cut,
                         std::vector<Vec3> frame_u, double edge_length, const std::vector<double>& face_size = {});
  ~ParametrizationProblem();
  ParametrizationProblem(const ParametrizationProblem&) = delete;
  ParametrizationProblem& operator=(const ParametrizationProblem&) = delete;

  // Hard: edge of halfedge h is an isoline of `axis` (0: u constant, 1: v constant) in face(h)'s chart.
  void add_isoline(int halfedge, int axis);
  // sum coeff * coordinate = rhs over corner coordinates; hard or penalty chosen at solve time.
  void add_linear_constraint(std::vector<CornerTerm> terms, double rhs);
  void clear_linear_constraints();
  // Pins one wedge at the origin (default on). Turn off when the linear constraints fix absolute
  // positions (e.g. a singularity at an integer point).
  void set_pin_translation(bool pin);
  // Cone angle of every vertex in quarter turns (4 - index inside, 2 - index on the boundary, from
  // the cross field); #V or empty (no check). Solutions then report their winding defects.
  void set_cone_angles(std::vector<int> quarter_turns);
  // Vertices whose one-ring winds at least a full turn off their cone angle in `param` (a flip-free
  // map can do that: a valence-5 cone wound by 90 degrees). 0 without set_cone_angles.
  int winding_defects(const Parametrization& param) const;
  // Those vertices (ascending).
  std::vector<int> wound_vertices(const Parametrization& param) const;

  ParametrizationSolution solve(const ParametrizationSolveOptions& options, Progress& progress);

  // Paper §7.1: penalty solves re-linearized around each result until max |Cz - b| <= epsilon
  // (at most max_rounds), then a final solve with Cz = b hard, linearized around the last pose.
  ParametrizationSolution solve_with_relinearization(ParametrizationSolveOptions options, double epsilon,
                                                     int max_rounds, Progress& progress);

  // Faces the hard constraints alone make degenerate (three corners sharing u or v, or two equal
  // corners); the elimination is built (and cached for solve()) with hard linear constraints.
  std::vector<int> forced_degenerate_faces(Progress& progress);

  // Field energy of a pose (same corner layout), without penalty.
  double field_energy(const Parametrization& param) const;
  // max |sum coeff * coordinate - rhs| over the linear constraints.
  double constraint_violation(const Parametrization& param) const;

  const std::vector<int>& wedge_of_corner() const { return wedge_of_; }  // 3#F
  int num_wedges() const { return num_wedges_; }
  // Ideal (field-aligned) shape of face f in uv units: corner k at ideal_corner(f, k).
  Vec2 ideal_corner(int f, int k) const { return ideal_[3 * f + k]; }
  double ideal_area(int f) const { return ideal_area_[f]; }

 private:
  struct System;
  System& system(ConstraintMode mode, double penalty_weight, Progress& progress);
  class Solver;  // the state and phases of one solve()

  const TriMesh& mesh_;
  std::vector<int8_t> rotation_;
  std::vector<char> is_cut_;  // #E, including rotated edges
  bool pin_ = true;
  std::vector<int> cone_quarter_turns_;        // #V expected cone angles, or empty
  std::vector<std::pair<int, int>> isolines_;  // (halfedge, axis)
  struct LinearConstraint {
    std::vector<CornerTerm> terms;
    double rhs;
  };
  std::vector<LinearConstraint> constraints_;

  std::vector<int> wedge_of_;  // 3#F
  int num_wedges_ = 0;
  std::vector<int> cut_halfedges_;               // one halfedge (the lower index) per cut edge
  std::vector<Vec2> ideal_;                      // 3#F ideal corner positions (uv units)
  std::vector<double> ideal_area_;               // #F
  std::vector<std::array<double, 6>> gradient_;  // #F: 2x3 gradient operator (row-major) in the frame

  // Full turns by which each vertex's one-ring winds off its cone angle (#V; empty without cone
  // angles); corner(c) is the uv of corner c. Vertices next to flipped faces get arbitrary values.
  std::vector<int> winding_charges(const std::function<Vec2(int)>& corner) const;

  std::unique_ptr<System> system_;  // cached elimination + energy for one mode
};

}  // namespace qgp

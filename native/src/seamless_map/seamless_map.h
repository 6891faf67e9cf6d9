// Stage 1c: continuous, exactly seamless, flip-free field-aligned parametrization (Bommes et al.
// 2009 energy, transition constraints, features on isolines, regularity via Ipopt).
#pragma once
#include <vector>

#include "core/json.h"
#include "core/parametrization.h"
#include "core/progress.h"
#include "cross_field/cross_field.h"
#include "cut_graph/cut_graph.h"

namespace qgp {

struct SeamlessMapOptions {
  double edge_length = 1;               // target quad edge length in model units: 1 uv unit = edge_length
  std::vector<double> face_size;        // #F multiples of edge_length (sizing/sizing.h); empty: uniform
  bool regularity = true;               // repair flipped / degenerate triangles with Ipopt (off: Cholesky only)
  int max_repair_rounds = 24;           // Ipopt repair rounds at most (see ParametrizationSolveOptions)
  int region_stagnation_rounds = 0;     // see ParametrizationSolveOptions
  int count_stagnation_rounds = 0;      // see ParametrizationSolveOptions
  bool winding_repair = true;           // see ParametrizationSolveOptions
  bool field_frame_solve = true;        // see ParametrizationSolveOptions
  bool move_shared_coordinates = true;  // see ParametrizationSolveOptions
  double max_bad_share_to_repair = 1;   // see ParametrizationSolveOptions
};

struct SeamlessMapStats {
  int flipped_triangles = 0;           // parametric area < 0 (exact sign)
  int degenerate_triangles = 0;        // parametric area == 0 (exact sign)
  int winding_defects = 0;             // vertices whose one-ring winds by another angle than the
                                       // field's cone (a full turn off; 0 expected)
  double max_transition_residual = 0;  // uv units
  double energy = 0;                   // field-guided energy (Bommes et al. 2009)
  int ipopt_iterations = 0;
  // Details:
  int flipped_before_ipopt = 0, degenerate_before_ipopt = 0;  // equality-only optimum
  int forced_degenerate = 0;  // made degenerate by the isoline constraints alone (0 expected)
  int isoline_edges = 0;      // feature + boundary edges constrained to isolines
  int dropped_isolines = 0;   // feature edges left free (see select_isolines)
  std::vector<int> dropped_isoline_edges;
  int ipopt_solves = 0;
  int qp_by_ipopt = 0;                    // repair solves Ipopt finished (quadratic_program.h)
  int repair_rounds = 0;                  // Ipopt repair rounds (0: the Cholesky optimum was regular)
  int field_frame_solves = 0;             // global solves in the field frame after a failed local repair
  bool moved_shared_coordinates = false;  // repair rounds moved shared coordinates (after a failed local repair)
  bool repair_declined = false;           // not repaired: too many bad triangles at the start (options)
  int max_region_faces = 0;               // most faces constrained in one Ipopt solve
  std::vector<int> repair_bad_faces;      // bad triangles (flipped, degenerate, wound) after each repair round
  std::vector<double> repair_seconds;     // and the time of each round
  double min_area_ratio = 0;              // min parametric / ideal (field-aligned) triangle area
  double seconds_cholesky = 0, seconds_ipopt = 0;
};
// Report object `seamless.components[i]`.
QGP_JSON_FIELDS(SeamlessMapStats, flipped_triangles, degenerate_triangles, winding_defects, max_transition_residual,
                energy, ipopt_iterations, flipped_before_ipopt, isoline_edges, dropped_isolines, repair_rounds,
                field_frame_solves, moved_shared_coordinates, repair_declined, min_area_ratio, repair_bad_faces,
                repair_seconds, qp_by_ipopt)

struct SeamlessMap {
  Parametrization param;  // rotation[] and is_cut from the cut graph
  SeamlessMapStats stats;
  std::vector<double> face_size;  // the sizing field it was solved with (SeamlessMapOptions)
  std::vector<int> bad_vertices;  // where it is not regular (ascending): the corners of its flipped and
                                  // degenerate triangles and the vertices wound off their cone; empty
                                  // (not computed) when stats count none of them
};

// Feature and boundary edges that become isolines, from the cut graph's edge sectors. An edge is
// dropped (listed in `dropped`) when its triangle would otherwise have two isolines of one axis
// (degenerate); compute_seamless_map drops further edges whose isolines force a triangle to
// collapse.
struct Isoline {
  int halfedge = 0;         // face(halfedge)'s chart
  int axis = 0;             // coordinate constant along the edge: 0 = u, 1 = v
  double misalignment = 0;  // radians between the edge and its isoline direction in the field
};
struct IsolineSelection {
  std::vector<Isoline> isolines;
  std::vector<int> dropped;  // edges
};
IsolineSelection select_isolines(const TriMesh& mesh, const CrossField& field, const CutGraph& cut);

// mesh: one component (connectivity built). Feature edges (field.feature_edge) and boundary edges
// become isolines. Reports progress with update() within the caller's stage; throws
// Error(Cancelled) on cancel; never fails for flips (they are counted in the stats).
SeamlessMap compute_seamless_map(const TriMesh& mesh, const CrossField& field, const CutGraph& cut,
                                 const SeamlessMapOptions& options, Progress& progress);

}  // namespace qgp

// Stage invariants of the cross field, cut graph, seamless map, T-mesh, quantization and the
// fallback cell map on every manifold mesh of the shared set, at four densities, through the
// Session's own stage code (a job cancelled when the integer-grid map stage begins keeps
// everything before it).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>

#include "cell_map_checks.h"
#include "core/error.h"
#include "intake/read_mesh_file.h"
#include "pipeline/session.h"
#include "test_support.h"

namespace qgp {
namespace {

// Singular vertices of the field that are not T-mesh nodes (0 expected).
int singularities_without_node(const CrossField& field, const TMesh& tmesh) {
  std::vector<char> is_node(field.vertex_index.size(), 0);
  for (const TMeshNode& node : tmesh.nodes)
    if (node.mesh_vertex >= 0) is_node[node.mesh_vertex] = 1;
  int missing = 0;
  for (size_t v = 0; v < field.vertex_index.size(); ++v) missing += field.vertex_index[v] != 0 && !is_node[v];
  return missing;
}

// Mesh edges of the feature set or the boundary that no on-feature T-edge trace covers entirely
// (pieces of traces lying on a mesh edge, as intervals of the edge's parameter, must cover [0,1]).
int uncovered_wall_edges(const TriMesh& mesh, const std::vector<char>& feature_edges, const TMesh& tm) {
  std::vector<std::vector<std::pair<double, double>>> pieces(mesh.num_edges());
  for (const TMeshEdge& e : tm.edges) {
    if (!e.on_feature) continue;
    for (size_t k = 0; k + 1 < e.trace.size(); ++k) {
      const SurfacePoint& a = e.trace[k];
      const SurfacePoint& b = e.trace[k + 1];
      if (a.face != b.face) continue;
      for (int j = 0; j < 3; ++j) {
        if (a.barycentric[j] != 0 || b.barycentric[j] != 0) continue;
        // On the halfedge h from F(f, j+1) to F(f, j+2); parameter = weight of its end vertex,
        // measured from the edge's lower vertex.
        const int h = 3 * a.face + (j + 1) % 3;
        const bool forward = mesh.from(h) < mesh.to(h);
        double ta = a.barycentric[(j + 2) % 3], tb = b.barycentric[(j + 2) % 3];
        if (!forward) ta = 1 - ta, tb = 1 - tb;
        pieces[mesh.edge_of[h]].push_back({std::min(ta, tb), std::max(ta, tb)});
      }
    }
  }
  int uncovered = 0;
  for (int me = 0; me < mesh.num_edges(); ++me) {
    if (!(feature_edges[me] || mesh.is_boundary_edge(me))) continue;
    std::sort(pieces[me].begin(), pieces[me].end());
    double reached = 0;  // covered from 0 up to here (gaps below 1e-9: rounding of the doubles)
    for (const auto& [lo, hi] : pieces[me])
      if (lo <= reached + 1e-9) reached = std::max(reached, hi);
    uncovered += reached < 1 - 1e-9;
  }
  return uncovered;
}

// Stage invariants of component c after a greedy run that reached the integer-grid map; prints
// one table row. With walls, every feature and boundary edge must be covered by T-edges.
void expect_invariants(const std::string& name, const Session& session, size_t c, double target, bool walls) {
  const Json& report = session.report();
  const ComponentState& state = session.components()[c];
  const ComponentInfo& info = session.intake()->components[c];
  const std::string where = name + " component " + std::to_string(c) + " at " + std::to_string(int(target));
  // Field: Poincare-Hopf per component.
  EXPECT_EQ(state.field->index_sum, 4 * info.euler_characteristic) << where;
  // Seamless map: exact-enough transitions, no flips.
  const double diag = state.mesh.bounding_box_diagonal() / state.seamless_edge_length();
  EXPECT_LE(state.seamless->stats.max_transition_residual, 1e-9 * std::max(1.0, diag)) << where;
  // T-mesh: every singularity is a node, four-sided cells, Euler characteristic, exact walls.
  const TMesh& tm = state.traced->tmesh;
  const Json& tr = report["tmesh"]["components"][c];
  EXPECT_EQ(singularities_without_node(*state.field, tm), 0) << where;
  EXPECT_EQ(tr["cells_not_four_sided"], 0) << where;
  EXPECT_EQ(tm.euler_characteristic(), info.euler_characteristic) << where;
  EXPECT_LE(tr["max_cell_equation_residual"].get<double>(), 1e-9 * std::max(1.0, diag)) << where;
  EXPECT_EQ(tm.stats.walls_not_isolines, 0) << where;
  int features = 0, uncovered = 0;
  const int dropped = state.seamless->stats.dropped_isolines;
  if (walls) {
    // Every boundary edge and every feature edge the seamless map keeps as an isoline is covered.
    // The seamless map drops a feature edge only where isolines would collapse a triangle (block:
    // slivers between two feature edges); those are the only gaps, and rare.
    for (char f : state.feature_edges) features += f;
    uncovered = uncovered_wall_edges(state.mesh, state.feature_edges, tm);
    EXPECT_EQ(uncovered_wall_edges(state.mesh, state.traced->isoline_edges, tm), 0)
        << where << ": walls not covered by T-edges";
    EXPECT_EQ(uncovered, dropped) << where;
    EXPECT_LE(dropped, 0.01 * features) << where;
  }
  // Quantization: Ax = 0 exactly, x >= 0, valid, objective never increasing.
  const QuantizationResult& q = state.quantization->result;
  EXPECT_TRUE(q.valid) << where << ": " << q.invalid_reason;
  EXPECT_EQ(q.consistency_residual, 0) << where;
  EXPECT_EQ(quantization_consistency_residual(tm, q.x), 0) << where;
  for (int64_t x : q.x) EXPECT_GE(x, 0) << where;
  for (size_t i = 1; i < q.objective_history.size(); ++i)
    EXPECT_LE(q.objective_history[i], q.objective_history[i - 1] + 1e-12) << where << " step " << i;
  EXPECT_EQ(quantization_quads(tm, q.x), q.quads_expected) << where;
  EXPECT_TRUE(check_quantization_validity(tm, q.x).valid) << where;
  CellMapOptions cell_options;
  cell_options.open_degenerate = false;  // the Tutte embedding itself (the opening: igm_test)
  // Known defect: wingnut's cell map at 100 quads (features at 40 degrees) keeps one flipped
  // triangle, since the quantization moves its scale toward the count asked (2026-11-27); at 400
  // quads too (2026-12-01, when the sweep's 500 became 400).
  const int known_flipped = name == "wingnut.obj" && walls && target <= 400 ? 1 : 0;
  const CellMapStats cells = test::expect_cell_map_invariants(where, state.mesh, tm, q, cell_options, known_flipped);
  std::cout << name << " | " << c << " | " << state.field->num_singularities << " | " << tm.nodes.size() << " | "
            << tm.edges.size() << " | " << tm.cells.size() << " | " << tm.stats.trace_seconds << " | " << target
            << " | " << q.stage1_steps << " | " << q.stage2_steps << " | " << q.objective << " | " << q.zero_edges
            << " | " << q.seconds << " | " << cells.faces << " | " << cells.degenerate_triangles << " ("
            << cells.collapsed_cell_triangles << ") | " << cells.seconds;
  if (walls)
    std::cout << " | " << features << " feature edges, " << dropped << " dropped, " << uncovered << " uncovered";
  std::cout << " |" << std::endl;
}

struct SweepCounts {
  std::vector<std::string> failed;  // "mesh (error)" of runs that stopped before the IGM
  int round_runs = 0, round_invalid = 0;
};

// The densities of the sweep: the session solves the seamless map and traces its T-mesh twice (100
// and 400 quads share one, 2 000 and 8 000 the other: a map is rescaled for up to 4 times the quads,
// kMaxSeamlessRescale); every density re-quantizes. (100, 500, 2 000 and 10 000 quads solved the map
// three times.) The noisy scan, alone at 2 000: at four densities it took 109 s of the sweep's 166 s
// (2026-12-01), and SessionMeshes, SeamlessMapMeshes and LayoutQuadsMeshes run it too.
std::vector<double> sweep_targets(const std::string& name) {
  if (name == "dragon-genus1.obj") return {2000};
  return {100, 400, 2000, 8000};
}

// One session per mesh at each of its sweep_targets (and the rounding baseline, when asked).
void sweep_mesh(const std::string& name, double sharp_angle_deg, bool round_baseline, bool walls, SweepCounts& counts) {
  Session session(read_mesh_file(test::mesh_path(name)));
  for (double target : sweep_targets(name)) {
    std::vector<Quantizer> quantizers = {Quantizer::Greedy};
    if (round_baseline) quantizers.push_back(Quantizer::Round);
    for (Quantizer quantizer : quantizers) {
      RemeshOptions options;
      options.target_faces = target;
      options.quantizer = quantizer;
      options.sharp_angle_deg = sharp_angle_deg;
      session.set_options(options);
      const std::string error = test::run_until_stage(session, "igm");
      if (quantizer == Quantizer::Round) {
        // The baseline: count how often direct rounding gives no valid quantization.
        ++counts.round_runs;
        counts.round_invalid += !error.empty();
        if (!error.empty()) EXPECT_NE(error.find("round"), std::string::npos) << name << ": " << error;
        std::cout << "  round at " << target << ": " << (error.empty() ? "valid" : error.substr(0, 100)) << std::endl;
        continue;
      }
      if (!error.empty()) {
        counts.failed.push_back(name + " at " + std::to_string(int(target)) + " (" + error + ")");
        return;
      }
      for (size_t c = 0; c < session.components().size(); ++c) expect_invariants(name, session, c, target, walls);
    }
  }
}

void expect_no_failures(const SweepCounts& counts) {
  std::string list;
  for (const std::string& f : counts.failed) list += "\n  " + f;
  EXPECT_TRUE(counts.failed.empty()) << "failed before the integer-grid map:" << list;
}

// QGP_TEST_MESHES (test_support) restricts every sweep to the meshes it names.
bool selected(const std::string& name) {
  const std::vector<std::string> names = test::manifold_mesh_files();
  return std::find(names.begin(), names.end(), name) != names.end();
}

const char* kHeader =
    "mesh | component | singularities | T-nodes | T-edges | cells | trace s | target | stage I | stage II | "
    "objective | zero edges | quantization s | cell map faces | degenerate (in collapsed cells) | cell map s |";

TEST(LayoutMeshes, FieldSeamlessTMeshAndQuantizationInvariants) {
  std::cout << kHeader << " round\n";
  SweepCounts counts;
  for (const std::string& name : test::manifold_mesh_files()) {
    sweep_mesh(name, -1, true, false, counts);
  }
  std::cout << "round baseline: " << counts.round_invalid << " of " << counts.round_runs
            << " runs without a valid quantization\n";
  expect_no_failures(counts);
}

// CAD meshes with features at a 40 degree dihedral angle, and open meshes with their boundaries:
// every feature and boundary edge is covered by T-edges (paper §9), with the same invariants.
TEST(LayoutMeshes, FeaturesAndBoundariesAreTMeshEdges) {
  std::cout << kHeader << " walls\n";
  SweepCounts counts;
  for (const std::string name : {"fandisk.obj", "block.obj", "joint.obj", "wingnut.obj"})
    if (selected(name)) sweep_mesh(name, 40, false, true, counts);
  for (const std::string name : {"camelhead.off", "face.obj"})  // boundaries only
    if (selected(name)) sweep_mesh(name, -1, false, true, counts);
  expect_no_failures(counts);
}

}  // namespace
}  // namespace qgp

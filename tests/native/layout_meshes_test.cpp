// Stage invariants of the cross field, cut graph, seamless map, T-mesh and quantization on every
// manifold mesh of the shared set, at four densities, through the Session's own stage code (a job
// cancelled when the integer-grid map stage begins keeps everything before it).
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdlib>
#include <iostream>

#include "core/error.h"
#include "intake/read_mesh_file.h"
#include "pipeline/session.h"
#include "test_support.h"

namespace qgp {
namespace {

// Runs the remesh job up to (not including) the integer-grid map; returns the error message of a
// failure before that point ("" when every stage up to quantization completed).
std::string run_until_igm(Session& session) {
  std::atomic<bool> cancel{false};
  Progress progress(
      [&](const std::string& stage, double) {
        if (stage == "igm") cancel = true;
      },
      &cancel);
  try {
    session.run(Job::Remesh, progress);
  } catch (const Error& e) {
    if (e.code() == ErrorCode::Cancelled && cancel) return "";
    return e.what();
  }
  return "igm stage did not start";
}

// Singular vertices of the field that are not T-mesh nodes (0 expected).
int singularities_without_node(const CrossField& field, const TMesh& tmesh) {
  std::vector<char> is_node(field.vertex_index.size(), 0);
  for (const TMeshNode& node : tmesh.nodes)
    if (node.mesh_vertex >= 0) is_node[node.mesh_vertex] = 1;
  int missing = 0;
  for (size_t v = 0; v < field.vertex_index.size(); ++v) missing += field.vertex_index[v] != 0 && !is_node[v];
  return missing;
}

TEST(LayoutMeshes, FieldSeamlessTMeshAndQuantizationInvariants) {
  std::cout << "mesh | component | singularities | T-nodes | T-edges | cells | trace s | target | stage I | "
               "stage II | objective | zero edges | quantization s | round\n";
  std::vector<std::string> failed;
  int round_runs = 0, round_invalid = 0;
  for (const std::string& name : test::manifold_mesh_files()) {
    // dragon-genus1 (a noisy scan: ~2100 singularities for a 2000-quad target) spends many
    // minutes in the seamless map's repair; the seamless sweep covers it, this one does not.
    if (name == "dragon-genus1.obj" && !std::getenv("QGP_TEST_MESHES")) continue;
    // One session per mesh: field, cut, seamless map and T-mesh are computed once; every density
    // and quantizer only re-quantizes.
    Session session(read_mesh_file(test::mesh_path(name)));
    bool reached_quantization = true;
    for (double target : {100.0, 500.0, 2000.0, 10000.0}) {
      if (!reached_quantization) break;
      for (Quantizer quantizer : {Quantizer::Greedy, Quantizer::Round}) {
        RemeshOptions options;
        options.target_faces = target;
        options.quantizer = quantizer;
        session.set_options(options);
        const std::string error = run_until_igm(session);
        if (quantizer == Quantizer::Round) {
          // The baseline: count how often direct rounding gives no valid quantization.
          ++round_runs;
          round_invalid += !error.empty();
          if (!error.empty()) EXPECT_NE(error.find("round"), std::string::npos) << name << ": " << error;
          std::cout << "  round at " << target << ": " << (error.empty() ? "valid" : error.substr(0, 100)) << std::endl;
          continue;
        }
        if (!error.empty()) {
          failed.push_back(name + " (" + error + ")");
          reached_quantization = false;
          break;
        }
        const Json& report = session.report();
        for (size_t c = 0; c < session.components().size(); ++c) {
          const ComponentState& state = session.components()[c];
          const ComponentInfo& info = session.intake()->components[c];
          const std::string where = name + " component " + std::to_string(c);
          // Field: Poincare-Hopf per component.
          EXPECT_EQ(state.field->index_sum, 4 * info.euler_characteristic) << where;
          // Seamless map: exact-enough transitions, no flips.
          const double diag = state.mesh.bounding_box_diagonal() / state.seamless_edge_length;
          EXPECT_LE(state.seamless->stats.max_transition_residual, 1e-9 * std::max(1.0, diag)) << where;
          // T-mesh: every singularity is a node, four-sided cells, Euler characteristic, exact walls.
          const TMesh& tm = *state.tmesh;
          const Json& tr = report["tmesh"]["components"][c];
          EXPECT_EQ(singularities_without_node(*state.field, tm), 0) << where;
          EXPECT_EQ(tr["cells_not_four_sided"], 0) << where;
          EXPECT_EQ(tm.euler_characteristic(), info.euler_characteristic) << where;
          EXPECT_LE(tr["max_cell_equation_residual"].get<double>(), 1e-9 * std::max(1.0, diag)) << where;
          EXPECT_EQ(tm.stats.walls_not_isolines, 0) << where;
          // Quantization: Ax = 0 exactly, x >= 0, valid, objective never increasing.
          const QuantizationResult& q = *state.quantization;
          EXPECT_TRUE(q.valid) << where << ": " << q.invalid_reason;
          EXPECT_EQ(q.consistency_residual, 0) << where;
          EXPECT_EQ(quantization_consistency_residual(tm, q.x), 0) << where;
          for (int64_t x : q.x) EXPECT_GE(x, 0) << where;
          for (size_t i = 1; i < q.objective_history.size(); ++i)
            EXPECT_LE(q.objective_history[i], q.objective_history[i - 1] + 1e-12) << where << " step " << i;
          EXPECT_EQ(quantization_quads(tm, q.x), q.quads_expected) << where;
          EXPECT_TRUE(check_quantization_validity(tm, q.x).valid) << where;
          std::cout << name << " | " << c << " | " << state.field->num_singularities << " | " << tm.nodes.size()
                    << " | " << tm.edges.size() << " | " << tm.cells.size() << " | " << tm.stats.trace_seconds
                    << " | " << target << " | " << q.stage1_steps << " | " << q.stage2_steps << " | " << q.objective
                    << " | " << q.zero_edges << " | " << q.seconds << " |" << std::endl;
        }
      }
    }
  }
  std::cout << "round baseline: " << round_invalid << " of " << round_runs << " runs without a valid quantization\n";
  std::string list;
  for (const std::string& f : failed) list += "\n  " + f;
  // Known: block.obj without features: the exact (sanitized) seamless map has a triangle that is
  // flipped or degenerate where the continuous one is thin, and the tracer refuses it (named in
  // the notes); every other manifold mesh must pass.
  EXPECT_LE(failed.size(), 1u) << "failed before the integer-grid map:" << list;
  for (const std::string& f : failed) EXPECT_EQ(f.rfind("block.obj", 0), 0u) << f;
}

}  // namespace
}  // namespace qgp

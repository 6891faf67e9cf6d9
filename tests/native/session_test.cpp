// The whole pipeline through the Session: quad meshes and integer-grid UVs of real meshes, the
// report, density-only re-quantization, cancel in every stage, and the invariants of the output
// (closed 2-manifold pure-quad mesh with the input's topology, consistent orientation, faithful
// to the surface, feature curves kept).
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdlib>
#include <iostream>
#include <limits>
#include <map>
#include <set>

#include "core/error.h"
#include "core/timer.h"
#include "intake/polygon_soup.h"
#include "intake/read_mesh_file.h"
#include "intake/working_mesh.h"
#include "metrics/polygon_metrics.h"
#include "pipeline/policy.h"
#include "pipeline/session.h"
#include "quad_extraction/surface_projection.h"
#include "test_support.h"

namespace qgp {
namespace {

// Invariants of a successful remesh job's output; returns the measurements.
PolygonMeshMetrics expect_valid_output(const std::string& name, const Session& session, double sharp_angle,
                                       int known_flipped_quads = 0) {
  const QuadMesh* quads = session.quad_result();
  EXPECT_NE(quads, nullptr) << name;
  if (!quads) return {};
  const Json& report = session.report();
  EXPECT_EQ(report["status"], "ok") << name;
  // Exactly the quads the quantization promised, over all components, less those the collapse of
  // flipped quads and slivers removed (policy.h: collapse_folds). A rescued part's quads come from
  // another run than the one the stage reports describe (rescued_components gives their count).
  int64_t removed = 0;
  if (report["extraction"].contains("collapsed"))
    for (const Json& c : report["extraction"]["collapsed"]) removed += c["removed_quads"].get<int64_t>();
  if (!report.contains("rescued_components"))
    EXPECT_EQ(quads->num_quads(), report["quantization"]["quads_expected"].get<int64_t>() - removed) << name;
  EXPECT_EQ(session.quad_source_face().size(), static_cast<size_t>(quads->num_quads())) << name;
  for (int f : session.quad_source_face()) {
    EXPECT_GE(f, 0) << name;
    EXPECT_LT(f, session.input().num_faces()) << name;
  }
  Progress progress;
  const PolygonMeshMetrics m =
      measure_polygon_mesh(test::polygon_soup(*quads), session.intake()->mesh, sharp_angle, progress);
  EXPECT_EQ(m.non_quads, 0) << name;
  EXPECT_EQ(m.non_manifold_edges, 0) << name;
  EXPECT_EQ(m.quad.topology.inconsistent_edges, 0) << name;
  EXPECT_EQ(m.quad.topology.degenerate_quads, 0) << name;
  EXPECT_EQ(m.quad.topology.unreferenced_vertices, 0) << name;
  EXPECT_LE(m.quad.flipped_quads(), known_flipped_quads) << name;
  EXPECT_EQ(m.quad.collapsed_edge_quads(), 0) << name;
  // Irregular vertices only where the map is singular.
  EXPECT_EQ(test::irregular_vertices_off_singularities(*quads), 0) << name;
  EXPECT_EQ(report["quad"]["faces"], quads->num_quads()) << name;
  // Same topology as the input: Euler characteristic and number of boundary loops' presence.
  EXPECT_EQ(m.euler_characteristic, m.reference_euler_characteristic) << name;
  const TriMesh& input = session.intake()->mesh;
  bool input_has_boundary = false;
  for (int e = 0; e < input.num_edges(); ++e) input_has_boundary = input_has_boundary || input.is_boundary_edge(e);
  EXPECT_EQ(m.quad.topology.boundary_edges > 0, input_has_boundary) << name;
  // On the surface: within 5% of the bounding-box diagonal both ways even when coarse (metrics are
  // relative to it; the sweep asks 1% at 8000 quads). Known exception: mnf07 at 500 quads, 6.3 %
  // (507 quads from the T-mesh layout, untangled; measured 2026-11-27).
  // joint_rem_p at 500 quads: 5.3 % (507 quads from the layout, measured 2026-11-28 with intake's
  // canonical triangle order).
  const bool coarse = report["quantization"]["count"]["target"] < 1000;
  const bool coarse_mnf07 = name == "mnf07HeadFem_rem_rem_p.obj" && coarse;
  const bool coarse_joint = name == "joint_rem_p.obj" && coarse;
  // dragon-genus1 at 500 quads: 6.2 % (1 166 quads; its horns and claws are thinner than a quad;
  // measured 2026-12-07; 5.0 % with the 3 263 quads its flip rounds made before kMaxFlipRoundGrowth).
  const bool coarse_dragon = name == "dragon-genus1.obj" && coarse;
  EXPECT_LT(m.quad.hausdorff, coarse_mnf07 || coarse_dragon ? 0.065 : coarse_joint ? 0.06 : 0.05) << name;
  if (sharp_angle > 0) EXPECT_GT(m.sharp_edge_coverage, 0.95) << name;
  // Integer-grid UVs for every input triangle intake kept.
  const std::vector<double>& uv = session.corner_uv();
  EXPECT_EQ(uv.size(), static_cast<size_t>(session.input().num_faces()) * 6) << name;
  return m;
}

constexpr ErrorCode kCompleted = static_cast<ErrorCode>(0);
ErrorCode run_job(Session& session, Job job, Progress& progress, std::string* message = nullptr) {
  try {
    session.run(job, progress);
  } catch (const Error& e) {
    if (message) *message = e.what();
    return e.code();
  }
  return kCompleted;
}

struct StageCounter {
  std::map<std::string, int> updates;
  Progress progress() {
    return Progress([this](const std::string& stage, double fraction) { updates[stage] += fraction > 0; }, nullptr);
  }
};

// Sets the target quad count and sharp angle (the other options at their defaults).
void set_target(Session& session, double target, double sharp_angle) {
  RemeshOptions options;
  options.target_faces = target;
  options.sharp_angle_deg = sharp_angle;
  session.set_options(options);
}

// Sets the target quad count and sharp angle, then runs `job`, which must complete.
void run_completed(Session& session, Job job, double target, double sharp_angle = -1, Progress* progress = nullptr) {
  set_target(session, target, sharp_angle);
  Progress plain;
  std::string message;
  ASSERT_EQ(run_job(session, job, progress ? *progress : plain, &message), kCompleted) << message;
}

// The report's record of each component's integer-grid map attempts follows the grid-UV ladder
// (pipeline/policy.h): the default attempt first; when it is irregular, the map untangle; then the
// re-linearized and all-faces attempts; an attempt is kept only with fewer flipped or degenerate
// triangles or wound one-rings than the map so far, and the untangle only when it leaves none.
void expect_attempts_follow_the_ladder(const std::string& run, const Json& report) {
  const std::set<std::string> ladder = {"default", "untangle", "relinearized penalty", "all faces"};
  for (const Json& component : report["igm"]["components"]) {
    if (!component.contains("attempts")) continue;  // a part that failed before its map
    const Json& attempts = component["attempts"];
    ASSERT_FALSE(attempts.empty()) << run;
    EXPECT_EQ(attempts[0]["attempt"], "default") << run;
    EXPECT_TRUE(attempts[0]["kept"].get<bool>()) << run;
    int kept_irregular = attempts[0]["irregular"].get<int>();
    if (kept_irregular == 0) EXPECT_EQ(attempts.size(), 1u) << run;
    for (size_t i = 1; i < attempts.size(); ++i) {
      const Json& a = attempts[i];
      const std::string name = a["attempt"].get<std::string>();
      const int irregular = a["irregular"].get<int>();
      EXPECT_TRUE(ladder.count(name)) << run << ": " << name;
      EXPECT_GE(a["seconds"].get<double>(), 0) << run;
      if (name == "untangle")
        EXPECT_EQ(a["kept"].get<bool>(), irregular == 0) << run;
      else
        EXPECT_EQ(a["kept"].get<bool>(), irregular < kept_irregular) << run << ": " << name;
      if (a["kept"].get<bool>()) kept_irregular = irregular;
      if (i + 1 < attempts.size()) EXPECT_GT(kept_irregular, 0) << run << ": attempts went on after a regular map";
    }
    if (attempts.back()["attempt"] == "all faces")
      EXPECT_EQ(component["fallback_used"].get<bool>(), attempts.back()["kept"].get<bool>()) << run;
  }
}

// The quad count asked for: within 5 %; or the report names the fewest quads the layout allows,
// above the target, and the quads are no fewer; or the counts the layout steps between, around the
// target, one of them made.
void expect_count_asked_for(const std::string& run, const Json& report, double target) {
  const Json& count = report["quantization"]["count"];
  const double quads = count["quads"].get<double>();
  EXPECT_EQ(count["target"].get<double>(), target) << run;
  EXPECT_EQ(quads, report["quantization"]["quads_expected"].get<double>()) << run;
  if (std::abs(quads - target) <= 0.05 * target) return;
  const std::string note = count.value("note", "");
  if (count.contains("steps_from")) {
    const double from = count["steps_from"].get<double>(), to = count["steps_to"].get<double>();
    EXPECT_TRUE(from < target && target < to && (quads == from || quads == to)) << run << ": " << note;
    EXPECT_NE(note.find("count steps from"), std::string::npos) << run;
    return;
  }
  ASSERT_TRUE(count.contains("fewest_quads")) << run << ": " << note;
  EXPECT_GT(count["fewest_quads"].get<double>(), 1.05 * target) << run << ": " << note;
  EXPECT_GE(quads, count["fewest_quads"].get<double>()) << run;
  EXPECT_NE(note.find("is the fewest this layout allows"), std::string::npos) << run;
}

TEST(SessionPipeline, SpotBecomesAClosedQuadMeshOfTheRequestedSize) {
  Session session(read_mesh_file(test::mesh_path("spot.obj")));
  RemeshOptions options;
  options.target_faces = 1500;
  session.set_options(options);
  StageCounter counter;
  Progress progress = counter.progress();
  std::string message;
  const double peak_before = peak_resident_mb();
  ASSERT_EQ(run_job(session, Job::Remesh, progress, &message), kCompleted) << message;
  const double peak_after = peak_resident_mb();
  const PolygonMeshMetrics m = expect_valid_output("spot", session, -1);
  EXPECT_EQ(m.quad.topology.boundary_edges, 0);
  EXPECT_NEAR(m.quads, 1500, 0.05 * 1500);
  const Json& report = session.report();
  for (const char* key : {"input", "field", "seamless", "tmesh", "quantization", "igm", "extraction", "quad"})
    EXPECT_TRUE(report.contains(key)) << key;
  for (const char* stage :
       {"cross_field", "cut_graph", "seamless_map", "tmesh", "quantization", "igm", "quad_extraction"}) {
    EXPECT_TRUE(report["timings_s"].contains(stage)) << stage;
    EXPECT_GT(counter.updates[stage], 0) << stage;
  }
  // The process's peak resident memory, read at the end of the run: between the peaks before and
  // after it.
  EXPECT_GE(report.value("peak_memory_mb", 0.0), peak_before);
  EXPECT_LE(report.value("peak_memory_mb", 0.0), peak_after);
  // Debian's OpenBLAS picks its kernels by the CPU; the library pins them (core/blas_kernels.h).
  EXPECT_EQ(report.value("blas_kernels", ""), "Prescott");
  for (double c : session.corner_uv()) EXPECT_TRUE(std::isfinite(c));
  EXPECT_GT(session.cut_edges().size(), 0u);
}

// A generated mesh as the triangle soup a Session reads (V and F are row-major: the C API's arrays).
PolygonSoup triangle_soup(const TriMesh& mesh) {
  return soup_from_triangle_arrays(mesh.V.data(), mesh.num_vertices(), mesh.F.data(), mesh.num_faces());
}

// A quad count below what the layout allows (a cube's eight corners need at least a quad per
// side: 6, asked 3) is not a refusal: the fewest quads, and the report says so; an edge length
// asks no count, and its quantization keeps the density's scale.
TEST(SessionPipeline, CountBelowTheLayoutsFewestIsNamedAndEdgeLengthKeepsItsScale) {
  Session session(triangle_soup(test::make_grid_cube(6).mesh));  // the cube [0,6]^3
  ASSERT_NO_FATAL_FAILURE(run_completed(session, Job::Remesh, 3));
  expect_valid_output("cube@3", session, -1);
  expect_count_asked_for("cube@3", session.report(), 3);
  EXPECT_EQ(session.report()["quantization"]["count"]["fewest_quads"].get<int>(), 6);
  EXPECT_EQ(session.quad_result()->num_quads(), 6);
  RemeshOptions options;
  options.edge_length = 0.5;
  options.sharp_angle_deg = 40;  // the sides' edges are isolines: each side is exactly 12 x 12 quads
  session.set_options(options);
  Progress progress;
  std::string message;
  ASSERT_EQ(run_job(session, Job::Remesh, progress, &message), kCompleted) << message;
  const Json& quantization = session.report()["quantization"];
  EXPECT_EQ(quantization["count"]["target"], 0);
  EXPECT_FALSE(quantization["count"].contains("note"));
  EXPECT_EQ(quantization["components"][0]["scale"], quantization["components"][0]["nominal_scale"]);
  EXPECT_EQ(quantization["components"][0]["count_rounds"], 0);
  EXPECT_EQ(session.quad_result()->num_quads(), 6 * 12 * 12);  // sides of 6 / 0.5 quads
}

// Same input, same options: the same quads and UVs, bit for bit, in a fresh session. Camelhead at
// 2000 quads (a sweep-sized run: Release pass only) gave different quads from run to run while MUMPS ordered its KKT
// systems with the threaded SCOTCH (the seamless map's Ipopt solves); nefertiti and dragon-genus1 did too.
TEST(SessionMeshes, SameInputGivesTheSameOutputEveryRun) {
  const PolygonSoup input = read_mesh_file(test::mesh_path("camelhead.off"));
  auto run_once = [&](QuadMesh& quads, std::vector<double>& uv) {
    Session session(input);
    run_completed(session, Job::Remesh, 2000);
    ASSERT_NE(session.quad_result(), nullptr);
    quads = *session.quad_result();
    uv = session.corner_uv();
  };
  QuadMesh first, second;
  std::vector<double> first_uv, second_uv;
  run_once(first, first_uv);
  run_once(second, second_uv);
  ASSERT_EQ(first.num_quads(), second.num_quads());
  ASSERT_EQ(first.num_vertices(), second.num_vertices());
  EXPECT_TRUE(first.Q == second.Q);
  EXPECT_TRUE(first.V == second.V);  // exact, not approximate
  EXPECT_EQ(first_uv, second_uv);
}

// A remesh job with new options (a new density) that completes without running any stage before
// quantization again (working mesh, field, cut graph, seamless map, T-mesh), and re-quantizes.
void expect_remesh_only_requantizes(Session& session, const RemeshOptions& options) {
  session.set_options(options);
  StageCounter counter;
  Progress progress = counter.progress();
  std::string message;
  ASSERT_EQ(run_job(session, Job::Remesh, progress, &message), kCompleted) << message;
  for (const char* stage : {"working_mesh", "cross_field", "cut_graph", "seamless_map", "tmesh"})
    EXPECT_EQ(counter.updates[stage], 0) << stage << " ran again";
  EXPECT_GT(counter.updates["quantization"], 0);
}

TEST(SessionPipeline, NewDensityOnlyRequantizes) {
  Session session(read_mesh_file(test::mesh_path("kitten.obj")));  // genus 1
  RemeshOptions options;
  options.target_faces = 800;
  session.set_options(options);
  Progress first;
  std::string message;
  ASSERT_EQ(run_job(session, Job::Remesh, first, &message), kCompleted) << message;
  const int coarse = session.quad_result()->num_quads();
  options.target_faces = 3200;
  expect_remesh_only_requantizes(session, options);
  const PolygonMeshMetrics m = expect_valid_output("kitten", session, -1);
  EXPECT_EQ(m.euler_characteristic, 0);
  const double ratio = static_cast<double>(session.quad_result()->num_quads()) / coarse;
  EXPECT_GT(ratio, 3.0);
  EXPECT_LT(ratio, 5.3);
}

// A quantization that makes triangles degenerate in every integer-grid map of its values
// (stanford-bunny at 1 000 quads: 3, where a T-edge of length 0 collapses a sliver) leaves the map
// unrepaired in a quad job: no repair could make it regular. The quads come from the T-mesh layout.
TEST(SessionPipeline, AQuadJobDoesNotRepairAMapThatCannotBeRegular) {
  Session session(read_mesh_file(test::mesh_path("stanford-bunny.obj")));
  ASSERT_NO_FATAL_FAILURE(run_completed(session, Job::Remesh, 1000));
  const Json& report = session.report();
  ASSERT_EQ(report["igm"]["components"].size(), 1u);
  const Json& igm = report["igm"]["components"][0];
  EXPECT_GT(igm["forced_degenerate"].get<int>(), 0);
  EXPECT_GE(igm["degenerate_triangles"].get<int>(), igm["forced_degenerate"].get<int>());
  EXPECT_TRUE(igm["repair_bad_faces"].empty());
  EXPECT_NE(igm["path"].get<std::string>().find("not repaired"), std::string::npos) << igm["path"];
  EXPECT_EQ(report["extraction"]["layout_components"], 1);
  expect_valid_output("stanford-bunny.obj", session, -1);
}

// block with sharp edges at 60 degrees: its integer-grid map meets the quantization's path rows
// and gives the quads. Before the elimination dropped the rounding residue of non-integer pivots
// (kZeroCoefficient), 539 of its imposed integer equations counted as inconsistent, the map broke
// its rows by 149 quad units (area 25 079 for 1 951 quads), stayed flipped after 10 repair rounds
// (12 s), and the quads came from the T-mesh layout. (Since its quads lie 0.8 quad edges off its
// coarse triangles, the part is then quadded again on an isotropic remesh: the report's stages are
// those of the run on its own triangles.)
TEST(SessionPipeline, BlocksIntegerGridMapMeetsItsQuantization) {
  Session session(read_mesh_file(test::mesh_path("block.obj")));
  ASSERT_NO_FATAL_FAILURE(run_completed(session, Job::Remesh, 2000, 60));
  const Json& report = session.report();
  ASSERT_EQ(report["igm"]["components"].size(), 1u);
  const Json& igm = report["igm"]["components"][0];
  EXPECT_LT(igm["max_constraint_violation"].get<double>(), 1e-9);
  EXPECT_EQ(igm["parametric_area"], report["quantization"]["components"][0]["quads_expected"]);
  EXPECT_EQ(igm["flipped_triangles"], 0);
  EXPECT_EQ(igm["winding_defects"], 0);
  EXPECT_EQ(report["extraction"]["layout_components"], 0);
  expect_valid_output("block.obj", session, 60);
}

// A quad job's integer-grid map repair ends at the first plateau whose pose the untangle makes
// regular (policy.h kMaxShareToUntangle): stanford-bunny at 8 000 quads stalled at 4 and 3 bad
// triangles, then crept to 1 over six more rounds of growing regions (about 4 s), and the untangle
// then regularized it. The map ends regular and the quads come from it.
TEST(SessionPipeline, AQuadJobLeavesAStalledRepairToTheUntangle) {
  Session session(read_mesh_file(test::mesh_path("stanford-bunny.obj")));
  ASSERT_NO_FATAL_FAILURE(run_completed(session, Job::Remesh, 8000));
  const Json& report = session.report();
  ASSERT_EQ(report["igm"]["components"].size(), 1u);
  const Json& igm = report["igm"]["components"][0];
  EXPECT_TRUE(igm["repair_left_to_untangle"].get<bool>());
  const std::vector<int> bad = igm["repair_bad_faces"].get<std::vector<int>>();
  ASSERT_GE(bad.size(), 2u);
  EXPECT_GT(bad.back(), 0);                                              // it stopped with bad triangles left,
  EXPECT_GE(bad.back(), *std::min_element(bad.begin(), bad.end() - 1));  // at a plateau,
  EXPECT_GT(igm["untangled_vertices"].get<int>(), 0);                    // which the untangle removed
  EXPECT_EQ(igm["flipped_triangles"], 0);
  EXPECT_EQ(igm["degenerate_triangles"], 0);
  EXPECT_EQ(igm["winding_defects"], 0);
  EXPECT_EQ(report["extraction"]["layout_components"], 0);
  expect_valid_output("stanford-bunny.obj", session, -1);
}

// A density whose edge length is more than kMaxSeamlessRescale times the seamless map's solves the
// map again, and the cross field too (its close singularity pairs depend on the edge length,
// policy.h kCancelPairsWithin): block at 40 degrees, 500 then 8000 quads, ends as a fresh run at
// 8000 does (rescaled by 4 it had 6 658 quads and 1.35 % Hausdorff distance instead of 6 526 and
// 0.83 %; since the count asked is kept, a fresh run had 7 990 quads and 1.25 %, measured
// 2026-11-27; on an isotropic remesh of its coarse triangles since 2026-12-07, 0.11 %).
TEST(SessionPipeline, LargeDensityChangeSolvesTheSeamlessMapAgain) {
  Session fresh(read_mesh_file(test::mesh_path("block.obj")));
  ASSERT_NO_FATAL_FAILURE(run_completed(fresh, Job::Remesh, 8000, 40));
  Session session(read_mesh_file(test::mesh_path("block.obj")));
  ASSERT_NO_FATAL_FAILURE(run_completed(session, Job::Remesh, 500, 40));
  StageCounter counter;
  Progress counted = counter.progress();
  ASSERT_NO_FATAL_FAILURE(run_completed(session, Job::Remesh, 8000, 40, &counted));
  EXPECT_GT(counter.updates["cross_field"], 0);
  EXPECT_GT(counter.updates["seamless_map"], 0);
  EXPECT_EQ(session.report()["field"], fresh.report()["field"]);
  EXPECT_EQ(session.report()["seamless"]["edge_length"], fresh.report()["seamless"]["edge_length"]);
  ASSERT_NE(session.quad_result(), nullptr);
  ASSERT_NE(fresh.quad_result(), nullptr);
  EXPECT_EQ(session.quad_result()->num_quads(), fresh.quad_result()->num_quads());
  const PolygonMeshMetrics m = expect_valid_output("block", session, 40);
  EXPECT_LE(m.quad.hausdorff, 0.01);
}

// A dense input (face.obj, 51 712 triangles) is remeshed on a decimated working mesh; the quads
// lie on the input surface and a new density reuses the working mesh.
TEST(SessionPipeline, DenseMeshUsesAWorkingMeshAndKeepsItsSurface) {
  Session session(read_mesh_file(test::mesh_path("face.obj")));
  RemeshOptions options;
  options.target_faces = 500;
  session.set_options(options);
  Progress first;
  std::string message;
  ASSERT_EQ(run_job(session, Job::Remesh, first, &message), kCompleted) << message;
  const Json& w = session.report()["working_mesh"];
  EXPECT_EQ(w["decimated_components"], 1);
  EXPECT_EQ(w["input_faces"], 51712);
  EXPECT_LE(w["working_faces"].get<int>(), kMinWorkingFaces + 2);
  expect_valid_output("face", session, -1);
  // Every quad vertex on the input surface (the boundary included).
  const TriMesh& input = session.intake()->mesh;
  const TriangleBvh bvh(input);
  const QuadMesh& quads = *session.quad_result();
  double worst = 0;
  for (int v = 0; v < quads.num_vertices(); ++v)
    worst = std::max(worst, bvh.closest_point(quads.V.row(v).transpose()).squared_distance);
  EXPECT_LE(std::sqrt(worst), 1e-9 * input.bounding_box_diagonal());

  options.target_faces = 1500;
  expect_remesh_only_requantizes(session, options);
  expect_valid_output("face", session, -1);
}

// Grid UVs belong to the input triangles, so they use the full mesh even where a remesh of the same
// session used a decimated working mesh: a 102 400-triangle torus with radial noise. (Until
// 2026-11-29 this ran on face.obj, whose grid UVs took 340-400 s of the suite's time; the remesh half
// stays above. On the exact grid, without the noise, the remesh at 500 quads took 60 s: seamless
// map 42 s, integer-grid map 17 s, against 1.8 s with it.)
TEST(SessionPipeline, GridUvsOfADenseMeshUseTheWholeInput) {
  TriMesh torus = test::make_grid_torus(320, 160).mesh;
  for (int v = 0; v < torus.num_vertices(); ++v)  // off the exact grid, like a sculpt (radial noise)
    torus.V.row(v) *= 1 + 1e-3 * std::sin(37.0 * v) * std::sin(11.0 * v + 1);
  Session session(triangle_soup(torus));
  ASSERT_NO_FATAL_FAILURE(run_completed(session, Job::Remesh, 500, -1));
  EXPECT_EQ(session.report()["working_mesh"]["decimated_components"], 1);
  Progress progress;
  std::string message;
  ASSERT_EQ(run_job(session, Job::GridUV, progress, &message), kCompleted) << message;
  EXPECT_EQ(session.report()["working_mesh"]["decimated_components"], 0);
  EXPECT_EQ(session.report()["working_mesh"]["working_faces"], torus.num_faces());
  ASSERT_EQ(session.corner_uv().size(), static_cast<size_t>(torus.num_faces()) * 6);
  for (double c : session.corner_uv()) EXPECT_TRUE(std::isfinite(c));
}

TEST(SessionPipeline, GridUvJobGivesIntegerSeamsAndNoQuads) {
  Session session(read_mesh_file(test::mesh_path("bunny.off")));
  Progress progress;
  std::string message;
  ASSERT_EQ(run_job(session, Job::GridUV, progress, &message), kCompleted) << message;
  expect_attempts_follow_the_ladder("bunny", session.report());
  EXPECT_EQ(session.quad_result(), nullptr);
  const std::vector<double>& uv = session.corner_uv();
  ASSERT_EQ(uv.size(), static_cast<size_t>(session.input().num_faces()) * 6);
  // Across every seam the two sides' coordinates differ by a rotation by a multiple of 90 degrees
  // and an integer translation: corner coordinate differences along each edge agree up to rotation.
  const PolygonSoup& in = session.input();
  std::map<std::pair<int, int>, std::pair<int, int>> corner_of;  // (a, b) directed -> (face, k)
  for (int f = 0; f < in.num_faces(); ++f)
    for (int k = 0; k < 3; ++k)
      corner_of[{in.face_vertices[3 * f + k], in.face_vertices[3 * f + (k + 1) % 3]}] = {f, k};
  auto rotate = [](Vec2 p, int r) {
    for (int i = 0; i < r; ++i) p = Vec2(-p.y(), p.x());
    return p;
  };
  int seams = 0, checked = 0;
  for (const auto& [ab, fk] : corner_of) {
    auto it = corner_of.find({ab.second, ab.first});
    if (it == corner_of.end() || ab.first > ab.second) continue;
    auto at = [&](int f, int k) { return Vec2(uv[6 * f + 2 * (k % 3)], uv[6 * f + 2 * (k % 3) + 1]); };
    const auto [f, k] = fk;
    const auto [g, j] = it->second;
    // Vertex a is corner k of f and corner j+1 of g; vertex b is corner k+1 of f and corner j of g.
    const Vec2 pa = at(f, k), pb = at(f, k + 1), qa = at(g, j + 1), qb = at(g, j);
    int rotation = -1;
    for (int r = 0; r < 4 && rotation < 0; ++r)
      if ((rotate(pb - pa, r) - (qb - qa)).norm() < 1e-6) rotation = r;
    ASSERT_GE(rotation, 0) << "edge " << ab.first << "-" << ab.second << " is not seamless";
    const Vec2 t = qa - rotate(pa, rotation);
    EXPECT_LT((t - Vec2(std::round(t.x()), std::round(t.y()))).norm(), 1e-6) << "edge " << ab.first << "-" << ab.second;
    seams += (pa - qa).norm() + (pb - qb).norm() > 0;
    ++checked;
  }
  EXPECT_GT(checked, 10000);
  EXPECT_GT(seams, 0);
  EXPECT_EQ(static_cast<size_t>(seams), session.cut_edges().size());
}

// Input triangles intake removes (block's zero-area faces, needles and caps) still get grid UVs: the
// map of the nearest kept triangle at their corners, so a texture shows no stray (0, 0) corners.
TEST(SessionPipeline, GridUvsCoverTrianglesIntakeRemoved) {
  Session session(read_mesh_file(test::mesh_path("block.obj")));
  ASSERT_NO_FATAL_FAILURE(run_completed(session, Job::GridUV, 500));
  expect_attempts_follow_the_ladder("block", session.report());
  const PolygonSoup& in = session.input();
  std::vector<char> kept(in.num_faces(), 0);
  for (int f : session.intake()->input_face) kept[f] = 1;
  const std::vector<double>& uv = session.corner_uv();
  std::vector<std::vector<Vec2>> copies(in.num_vertices());  // uvs of each vertex in kept triangles
  for (int f = 0; f < in.num_faces(); ++f)
    if (kept[f])
      for (int k = 0; k < 3; ++k)
        copies[in.face_vertices[3 * f + k]].push_back(Vec2(uv[6 * f + 2 * k], uv[6 * f + 2 * k + 1]));
  int removed = 0, matched = 0;
  for (int f = 0; f < in.num_faces(); ++f) {
    for (int i = 0; i < 6; ++i) ASSERT_TRUE(std::isfinite(uv[6 * f + i])) << "face " << f;
    if (kept[f]) continue;
    ++removed;
    const Vec2 a(uv[6 * f], uv[6 * f + 1]), b(uv[6 * f + 2], uv[6 * f + 3]), c(uv[6 * f + 4], uv[6 * f + 5]);
    const Vec2 e = b - a, g = c - a;
    EXPECT_LT(std::abs(e.x() * g.y() - e.y() * g.x()), 1e-3) << "face " << f;  // as thin in uv as in 3D
    // Each corner lies where the kept triangles put the same input vertex, up to a transition (a
    // quarter turn and an integer translation: the triangle may take a chart across a seam), where
    // they still use it (a needle's collapsed corner is gone from them).
    for (int k = 0; k < 3; ++k) {
      const Vec2 p(uv[6 * f + 2 * k], uv[6 * f + 2 * k + 1]);
      double nearest = std::numeric_limits<double>::infinity();
      for (Vec2 q : copies[in.face_vertices[3 * f + k]])
        for (int r = 0; r < 4; ++r, q = Vec2(-q.y(), q.x())) {
          const Vec2 d = p - q;
          nearest = std::min(nearest, (d - Vec2(std::round(d.x()), std::round(d.y()))).norm());
        }
      if (std::isinf(nearest)) continue;
      EXPECT_LT(nearest, 1e-3) << "face " << f << " corner " << k;
      ++matched;
    }
  }
  // Intake removed some of them (collapses; others it kept by flipping an edge), never more than it repaired.
  int repaired = 0;
  for (const Json& r : session.report()["input"]["repairs"])
    if (r["kind"] == "zero_area_faces") repaired = r["count"].get<int>();
  EXPECT_GT(removed, 0);
  EXPECT_LE(removed, repaired);
  EXPECT_GT(matched, removed);
}

TEST(SessionPipeline, JointKeepsItsSharpEdgesAndFaceItsBoundary) {
  for (const auto& [name, sharp] : {std::pair<const char*, double>{"joint.obj", 40}, {"face.obj", -1}}) {
    Session session(read_mesh_file(test::mesh_path(name)));
    RemeshOptions options;
    options.sharp_angle_deg = sharp;
    options.target_faces = 2000;
    session.set_options(options);
    Progress progress;
    std::string message;
    ASSERT_EQ(run_job(session, Job::Remesh, progress, &message), kCompleted) << name << ": " << message;
    const PolygonMeshMetrics m = expect_valid_output(name, session, sharp);
    if (sharp > 0)
      EXPECT_GT(m.sharp_edges, 100) << name;
    else
      EXPECT_GT(m.quad.topology.boundary_edges, 0) << name;
  }
}

TEST(SessionPipeline, CancelInEveryStageKeepsTheSessionUsable) {
  Session session(read_mesh_file(test::mesh_path("bunny.off")));
  for (const char* stage : {"seamless_map", "tmesh", "quantization", "igm", "quad_extraction"}) {
    std::atomic<bool> cancel{false};
    Progress progress(
        [&](const std::string& s, double) {
          if (s == stage) cancel = true;
        },
        &cancel);
    std::string message;
    EXPECT_EQ(run_job(session, Job::Remesh, progress, &message), ErrorCode::Cancelled) << stage << ": " << message;
    EXPECT_EQ(session.quad_result(), nullptr);
    EXPECT_EQ(session.report()["status"], "error");
  }
  Progress progress;
  std::string message;
  ASSERT_EQ(run_job(session, Job::Remesh, progress, &message), kCompleted) << message;
  expect_valid_output("bunny", session, -1);
}

// A flat n x n square of unit cells, two triangles each: a disk whose cross field has no singularity
// inside (only the four corners).
PolygonSoup flat_square(int n) {
  std::vector<double> v;
  std::vector<int32_t> f;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) v.insert(v.end(), {double(i), double(j), 0.0});
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const int a = j * (n + 1) + i, b = a + 1, c = a + n + 2, d = a + n + 1;
      f.insert(f.end(), {a, b, c, a, c, d});
    }
  return soup_from_triangle_arrays(v.data(), (n + 1) * (n + 1), f.data(), 2 * n * n);
}

TEST(SessionPipeline, RoundQuantizerEitherSucceedsOrSaysWhy) {
  // The naive rounding baseline flips triangles around singularities on real meshes: then the job
  // fails with the reason. Without inner singularities (a flat square) rounding is valid. (A grid
  // torus does not do: its smoothest cross field has singularities.)
  int completed = 0, refused = 0;
  const std::pair<std::string, PolygonSoup> inputs[] = {{"flat square", flat_square(20)},
                                                        {"spot.obj", read_mesh_file(test::mesh_path("spot.obj"))},
                                                        {"joint.obj", read_mesh_file(test::mesh_path("joint.obj"))}};
  for (const auto& [name, soup] : inputs) {
    Session session(soup);
    RemeshOptions options;
    options.quantizer = Quantizer::Round;
    options.target_faces = 600;
    session.set_options(options);
    Progress progress;
    std::string message;
    const ErrorCode code = run_job(session, Job::Remesh, progress, &message);
    if (code == kCompleted) {
      expect_valid_output(name, session, -1);
      ++completed;
    } else {
      EXPECT_EQ(code, ErrorCode::StageFailed) << name << ": " << message;
      EXPECT_NE(message.find("round"), std::string::npos) << message;
      std::cout << name << ": " << message << "\n";
      ++refused;
    }
  }
  std::cout << "round quantizer: " << completed << " completed, " << refused << " refused\n";
  // Both outcomes occur: the flat square's rounding is valid, spot's and joint's are refused.
  EXPECT_GE(completed, 1);
  EXPECT_GE(refused, 1);
}

// Runs whose quads come from the T-mesh layout, because the global integer-grid map keeps a flipped
// or degenerate triangle, or a wound one-ring, after the untangle ("mesh@target", "@sharp" for
// features; measured on every run of these meshes). Every other run of the sweeps must take its quads
// from the integer-grid map, and these from the layout, so that a broken map extraction, or a map
// that starts working here, fails the test until this list is updated.
bool quads_expected_from_layout(const std::string& name, double sharp, double target) {
  // fandisk at 2 000 took the layout's quads until close singularity pairs were cancelled (2026-12-02).
  // With the repair's own interior-point solver (2026-12-05), camelhead at 500 takes the map's quads
  // and fertility at 500 the layout's (3 of the map's quads stay flipped; the layout's are valid).
  static const std::set<std::string> runs = {"armadillo.obj@500", "fertility.off@500", "stanford-bunny.obj@2000",
                                             "wingnut.obj@2000@40", "joint_rem_p.obj@500"};
  std::string run = name + "@" + std::to_string(static_cast<int>(target));
  if (sharp > 0) run += "@" + std::to_string(static_cast<int>(sharp));
  return runs.count(run) > 0;
}

// Runs whose source differs between machines (BLAS kernels chosen by the CPU change the solvers'
// last bits): mnf07 at 500 quads takes the map's quads (6 flipped) on one machine and the layout's
// (2 flipped after the untangle, the map keeping 6) on another, with the same binary (2026-11-29).
bool either_source(const std::string& name, double target) {
  return name == "mnf07HeadFem_rem_rem_p.obj" && target == 500;
}

// Known defect (docs/limitations.md): a quad that stays flipped against the surface after the
// untangle and the collapse: wingnut's at 2 000 quads lies across a crease, facing with the part's
// own triangles and against the input's (the same surface, triangulated otherwise: whether it
// faces with it is round-off). armadillo at 500 (3) and mnf07 at 500 (6) had flipped quads before
// the collapse (2026-12-06). Every other run: none.
int known_flipped_quads(const std::string& name, double sharp, double target) {
  if (name == "wingnut.obj" && sharp > 0 && target == 2000) return 1;
  return 0;
}

// One session per mesh, so the seamless map and T-mesh are computed once and re-quantized; prints a
// row per run. Returns the runs that failed ("mesh@target: message"); a failure must be a clean
// StageFailed error that leaves no result behind.
std::vector<std::string> sweep(const std::vector<std::pair<std::string, double>>& meshes, std::vector<double> targets) {
  std::cout << "mesh | sharp | target | quads | irregular | min scaled Jacobian | mean angle dev | Hausdorff | "
               "field..tmesh s | quantization s | igm s | extraction s | quads from"
            << std::endl;
  std::vector<std::string> failed;
  for (const auto& [name, sharp] : meshes) {
    Session session(read_mesh_file(test::mesh_path(name)));
    for (double target : targets) {
      set_target(session, target, sharp);
      Progress progress;
      std::string message;
      const ErrorCode code = run_job(session, Job::Remesh, progress, &message);
      if (code != kCompleted) {
        std::cout << name << " | " << sharp << " | " << target << " | FAILED: " << message << std::endl;
        EXPECT_EQ(code, ErrorCode::StageFailed) << name << ": " << message;
        EXPECT_EQ(session.quad_result(), nullptr) << name;
        failed.push_back(name + "@" + std::to_string(static_cast<int>(target)) + ": " + message);
        continue;
      }
      const PolygonMeshMetrics m = expect_valid_output(name, session, sharp, known_flipped_quads(name, sharp, target));
      expect_count_asked_for(name + "@" + std::to_string(static_cast<int>(target)), session.report(), target);
      // Within 1 % at 8 000 quads (block at 40 degrees came 1.21 % off on its own coarse triangles:
      // its quads now come from an isotropic remesh of them, 0.11 %).
      if (target >= 8000) EXPECT_LE(m.quad.hausdorff, 0.01) << name;
      const bool from_layout = session.report()["extraction"]["layout_components"].get<int>() > 0;
      if (!either_source(name, target))
        EXPECT_EQ(from_layout, quads_expected_from_layout(name, sharp, target))
            << name << "@" << target << ": quads from " << session.report()["extraction"]["components"][0]["path"];
      const Json& t = session.report()["timings_s"];
      auto sec = [&](const char* k) { return t.value(k, 0.0); };
      std::cout << name << " | " << sharp << " | " << target << " | " << m.quads << " | " << m.quad.irregular_vertices
                << " | " << m.quad.min_scaled_jacobian << " | " << m.quad.mean_angle_deviation << " | "
                << m.quad.hausdorff << " | "
                << sec("cross_field") + sec("cut_graph") + sec("seamless_map") + sec("tmesh") << " | "
                << sec("quantization") << " | " << sec("igm") << " | " << sec("quad_extraction") << " | "
                << session.report()["extraction"]["components"][0].value("path", "") << std::endl;
    }
  }
  return failed;
}

std::string joined(const std::vector<std::string>& lines) {
  std::string out;
  for (const std::string& l : lines) out += "\n  " + l;
  return out;
}

// Meshes that must become valid quad meshes at three densities (the CI set; every one of its runs
// must succeed).
TEST(SessionMeshes, OrganicMeshesBecomeValidQuadMeshesAtThreeDensities) {
  const std::vector<std::pair<std::string, double>> meshes = {{"spot.obj", -1},       {"bunny.off", -1},
                                                              {"torus.obj", -1},      {"kitten.obj", -1},
                                                              {"rocker-arm.obj", -1}, {"joint_rem_p.obj", -1}};
  const std::vector<std::string> failed = sweep(meshes, {500, 2000, 8000});
  EXPECT_TRUE(failed.empty()) << joined(failed);
}

// More shapes at 2000 quads (CAD with and without features, open, higher genus, scans): the integer-grid
// map's quads or, where that map keeps a flip, the T-mesh layout's; the output invariants hold.
TEST(SessionMeshes, MoreMeshesBecomeValidQuadMeshesAt2000) {
  const std::vector<std::pair<std::string, double>> meshes = {
      {"block.obj", -1},   {"fandisk.obj", -1}, {"fertility.off", -1},     {"beetle.off", -1},
      {"wingnut.obj", -1}, {"face.obj", -1},    {"decimated-max.obj", -1}, {"mnf07HeadFem_rem_rem_p.obj", -1},
      {"wingnut.obj", 40}, {"fandisk.obj", 40}, {"stanford-bunny.obj", -1}};
  const std::vector<std::string> failed = sweep(meshes, {2000});
  EXPECT_TRUE(failed.empty()) << joined(failed);
}

// Block with its sharp edges at 40 degrees: its needle and cap triangles (normals of rounding noise)
// used to add spurious sharp edges, 146 singularities and dozens of flipped, squeezed quads.
TEST(SessionMeshes, BlockKeepsItsSharpEdgesAt2000And8000) {
  const std::vector<std::string> failed = sweep({{"block.obj", 40}}, {2000, 8000});
  EXPECT_TRUE(failed.empty()) << joined(failed);
}

// Block's triangles are far larger than a quad at 2 000 and 8 000 quads, its top disc a fan of 32
// around one inner vertex inside a circular sharp rim. Every face of the fan follows its rim edge, so
// the fan's centre gets the disc's whole +4 quarter turns, and three move out to the rim. Chosen by
// residual alone they fell side by side, the map laid most of the rim on one straight isoline and
// the quads cut across it (5.4 %, 2.33 % and 1.21 % of the diagonal at 500, 2 000 and 8 000 quads;
// the last two were rescued on an isotropic remesh). Spread around the disc (stop 65), the part's
// own triangles give quads within 1 % at 500 quads and 0.5 % above, with no rescue.
TEST(SessionMeshes, ACoarseCadPartsFanCapIsQuaddedOnItsOwnTriangles) {
  for (double target : {500.0, 2000.0, 8000.0}) {
    Session session(read_mesh_file(test::mesh_path("block.obj")));
    run_completed(session, Job::Remesh, target, 40);
    const Json& report = session.report();
    EXPECT_FALSE(report.contains("rescued_components")) << target;
    EXPECT_EQ(report["working_mesh"]["remeshed_components"], 0) << target;
    EXPECT_LE(expect_valid_output("block.obj", session, 40, 0).quad.hausdorff, target < 1000 ? 0.01 : 0.005) << target;
  }
}

// CAD parts whose triangles are mostly needles, with their sharp edges. featuretype's seamless map
// starts with 126 of its 3 476 triangles flipped on them (repaired, 15 stayed and T-mesh tracing
// failed; before that the part was quadded by splitting them: 10 428 quads); it is not repaired
// there but rescued on an isotropic remesh of them at once, where the map is flip-free and its
// quads are valid and within 1 % (0.54 % measured). joint's map holds on its own 446 triangles,
// which it keeps. (featuretype at 2 000 keeps 1 flipped quad beside a hole narrower than a quad.)
TEST(SessionMeshes, NeedleCoveredCadPartsAreRemeshedWhenTheirMapFails) {
  for (const auto& [name, target] :
       std::vector<std::pair<std::string, double>>{{"featuretype.ply", 8000}, {"joint.obj", 2000}}) {
    Session session(read_mesh_file(test::mesh_path(name)));
    run_completed(session, Job::Remesh, target, 40);
    const Json& report = session.report();
    const bool remeshed = name == "featuretype.ply";
    EXPECT_EQ(report["working_mesh"]["remeshed_components"], remeshed ? 1 : 0) << name;
    EXPECT_EQ(report.contains("rescued_components"), remeshed) << name;
    if (!remeshed) {
      EXPECT_LE(expect_valid_output(name, session, 40, 0).quad.hausdorff, 0.01) << name;
      continue;
    }
    // A rescue: the stage reports are those of the failed run on its own triangles.
    const Json& rescue = report["rescued_components"][0];
    EXPECT_EQ(rescue["rescue"], "isotropic working mesh");
    EXPECT_EQ(rescue["stage"], "seamless_map");
    const std::string why = rescue["message"];
    const int triangles = report["input"]["faces"];
    const int bad_at_start = std::atoi(why.substr(why.find(": ") + 2).c_str());
    EXPECT_GT(bad_at_start, kMaxBadShareToRepairOnNeedles * triangles) << why;
    EXPECT_NE(why.find(" of " + std::to_string(triangles) +
                       " triangles flipped or degenerate on needle triangles across features, not repaired"),
              std::string::npos)
        << why;
    const QuadMesh* quads = session.quad_result();
    ASSERT_NE(quads, nullptr);
    EXPECT_EQ(quads->num_quads(), rescue["quads"].get<int64_t>());
    Progress progress;
    const PolygonMeshMetrics m = measure_polygon_mesh(test::polygon_soup(*quads), session.intake()->mesh, 40, progress);
    EXPECT_EQ(m.non_quads, 0);
    EXPECT_EQ(m.non_manifold_edges, 0);
    EXPECT_EQ(m.quad.topology.inconsistent_edges, 0);
    EXPECT_EQ(m.quad.topology.degenerate_quads, 0);
    EXPECT_EQ(m.quad.flipped_quads(), 0);
    EXPECT_EQ(m.euler_characteristic, m.reference_euler_characteristic);
    EXPECT_EQ(test::irregular_vertices_off_singularities(*quads), 0);
    EXPECT_GT(m.sharp_edge_coverage, 0.95);
    EXPECT_LE(m.quad.hausdorff, 0.01);
  }
}

// A CAD-style cylinder of needle fans with its rims as sharp edges: its map on its own needles is
// regular, but the quads cut across it (8.6 % of the diagonal at 2 000 quads, 12 % at 500); they
// are replaced by the quads of an isotropic remesh, within 1 % and valid.
TEST(SessionMeshes, QuadsFarOffANeedleCoveredPartComeFromARemesh) {
  for (double target : {500.0, 2000.0}) {
    Session session(test::polygon_soup(test::make_fan_cylinder(48, 1, 3)));
    run_completed(session, Job::Remesh, target, 40);
    const Json& report = session.report();
    ASSERT_TRUE(report.contains("rescued_components")) << target;
    EXPECT_EQ(report["rescued_components"][0]["rescue"], "isotropic working mesh");
    EXPECT_EQ(report["working_mesh"]["remeshed_components"], 1);
    const QuadMesh* quads = session.quad_result();
    ASSERT_NE(quads, nullptr);
    Progress progress;
    const PolygonMeshMetrics m = measure_polygon_mesh(test::polygon_soup(*quads), session.intake()->mesh, 40, progress);
    EXPECT_EQ(m.non_quads, 0);
    EXPECT_EQ(m.non_manifold_edges, 0);
    EXPECT_EQ(m.quad.topology.inconsistent_edges, 0);
    EXPECT_EQ(m.quad.flipped_quads(), 0);
    EXPECT_EQ(m.euler_characteristic, m.reference_euler_characteristic);
    EXPECT_GT(m.sharp_edge_coverage, 0.95);
    EXPECT_LE(m.quad.hausdorff, 0.01) << target;
  }
}

// cycloidal's pins with sharp edges: a needle cylinder whose caps are fans around a centre vertex.
// Every cap face follows its rim edge, so the field gives the centre the cap's whole +4 quarter
// turns, and three of them move out along spokes to the rim; spread around the cap, its map is
// regular. Chosen by their residual alone (equal on every spoke up to rounding) they fell side by
// side on seven of twelve such pins of cycloidal, whose maps then folded (28-36 of 96 triangles) and
// whose rescue gave quads with scaled Jacobians down to -0.98.
TEST(SessionMeshes, PinsWithFanCapsAreQuaddedOnTheirOwnTriangles) {
  for (int k = 0; k < 12; ++k) {
    const TriMesh pin = test::make_pin(24, 0.03125, 0.625, 0.37 * k, Vec3(0.3 + 0.11 * k, 1.1 - 0.07 * k, 0.883));
    Session session(test::polygon_soup(pin));
    run_completed(session, Job::Remesh, 20, 40);
    const std::string pin_k = "pin " + std::to_string(k);
    EXPECT_FALSE(session.report().contains("rescued_components")) << pin_k;
    EXPECT_EQ(session.report()["field"]["components"][0]["singularities"], 8) << pin_k;
    const PolygonMeshMetrics m = expect_valid_output(pin_k, session, 40);
    EXPECT_EQ(m.euler_characteristic, 2) << pin_k;
    EXPECT_GT(m.sharp_edge_coverage, 0.95) << pin_k;
    EXPECT_GT(m.quad.min_scaled_jacobian, 0.5) << pin_k;
  }
}

// dragon-genus1 (a noisy scan) at 500 quads. With its 125 close singularity pairs cancelled, the
// seamless map keeps one flipped triangle and one wound one-ring after the short repair that such a
// field gets (policy.h: bound_repair_where_pairs_were_cancelled). The pairs near them are kept
// (11 measured, 115 cancelled) and the map of that field is regular: the quads have 251 singular
// points to follow, not the 481 of the field without any pair cancelled (1 618 quads, 17 s;
// 2 776 quads, 33 s before).
TEST(SessionMeshes, NoisyScanKeepsOnlyThePairsNearItsMapsFolds) {
  Session session(read_mesh_file(test::mesh_path("dragon-genus1.obj")));
  run_completed(session, Job::Remesh, 500);
  const Json& field = session.report()["field"]["components"][0];
  EXPECT_GT(field["pairs_kept_near_folds"].get<int>(), 0);
  EXPECT_GT(field["close_pairs"].get<int>(), 10 * field["pairs_kept_near_folds"].get<int>());
  EXPECT_FALSE(field["close_pairs_kept"].get<bool>());
  const Json& seamless = session.report()["seamless"]["components"][0];
  EXPECT_EQ(seamless["flipped_triangles"].get<int>() + seamless["winding_defects"].get<int>(), 0);
  EXPECT_FALSE(session.report().contains("rescued_components"));
  expect_valid_output("dragon-genus1.obj", session, -1);
}

// dragon-genus1 (a noisy scan) at 2 000 quads. Its integer-grid map keeps flipped and degenerate
// triangles and wound one-rings, so the quads come from the T-mesh layout (about 2 400 quads: its
// 481 singular points allow no fewer near 2 000), some of them facing against the surface after the
// untangle (7 on 2026-12-06; 5 on one machine and 16 on another before: the untangle's outcome on
// this noisy scan turns on the last bits of the solvers' sums). The collapse (policy.h:
// collapse_folds) removes them: none stays flipped. Everything else a valid output promises holds.
TEST(SessionMeshes, NoisyScanHasItsFlippedQuadsCollapsed) {
  Session session(read_mesh_file(test::mesh_path("dragon-genus1.obj")));
  run_completed(session, Job::Remesh, 2000);
  const QuadMesh* quads = session.quad_result();
  ASSERT_NE(quads, nullptr);
  const Json& report = session.report();
  if (report.contains("rescued_components")) {  // its quads with cancelled pairs did not form a valid mesh
    const Json& rescued = report["rescued_components"][0];
    EXPECT_EQ(rescued["rescue"], "field without cancelled pairs");
    EXPECT_TRUE(report["field"]["components"][0]["close_pairs_kept"].get<bool>());
  } else {
    EXPECT_EQ(report["extraction"]["layout_components"].get<int>(), 1);
  }
  // The layout's quads, less those the collapse took (and the doublets it dissolved).
  ASSERT_TRUE(report["extraction"].contains("collapsed"));
  const Json& collapsed = report["extraction"]["collapsed"][0];
  EXPECT_GT(collapsed["flipped_before"].get<int>(), 0);
  EXPECT_EQ(collapsed["flipped_after"].get<int>(), 0);
  const int64_t made = report.contains("rescued_components") ? report["rescued_components"][0]["quads"].get<int64_t>()
                                                             : report["quantization"]["quads_expected"].get<int64_t>();
  EXPECT_LE(quads->num_quads(), made - collapsed["collapsed_quads"].get<int64_t>());
  EXPECT_GE(quads->num_quads(), made - 3 * collapsed["collapsed_quads"].get<int64_t>());
  Progress progress;
  const PolygonMeshMetrics m = measure_polygon_mesh(test::polygon_soup(*quads), session.intake()->mesh, -1, progress);
  std::cout << "dragon-genus1 @2000: " << m.quads << " quads, " << m.quad.flipped_quads() << " flipped, Hausdorff "
            << m.quad.hausdorff << std::endl;
  EXPECT_EQ(m.non_quads, 0);
  EXPECT_EQ(m.non_manifold_edges, 0);
  EXPECT_EQ(m.quad.topology.inconsistent_edges, 0);
  EXPECT_EQ(m.quad.topology.degenerate_quads, 0);
  EXPECT_EQ(m.euler_characteristic, m.reference_euler_characteristic);
  EXPECT_EQ(test::irregular_vertices_off_singularities(*quads), 0);
  EXPECT_EQ(m.quad.flipped_quads(), 0);
  EXPECT_EQ(report["quad"]["flipped_quads"].get<int>(), 0);
  EXPECT_LT(m.quad.hausdorff, 0.065);
}

// The flip rounds keep zero T-edges beside flipped layout quads at length 1, and each adds a row of
// quads. dragon-genus1 at 500 quads: the round that left 12 of 24 layout quads flipped gave 3 263
// quads where its layout allows 1 219 at least (measured 2026-12-07); the final quads had none
// flipped either way. A round is kept only while the quads stay within kMaxFlipRoundGrowth of those
// before the rounds; cow at 8 000 keeps its round (1 -> 0 flipped layout quads, same count).
TEST(SessionMeshes, FlipRoundsAddAtMostAQuarterOfTheQuads) {
  for (const auto& [name, target] :
       std::vector<std::pair<std::string, double>>{{"dragon-genus1.obj", 500}, {"cow.obj", 8000}}) {
    Session session(read_mesh_file(test::mesh_path(name)));
    run_completed(session, Job::Remesh, target);
    expect_valid_output(name, session, -1);
    const Json& quantization = session.report()["quantization"];
    int rounds = 0;
    for (const Json& c : quantization["components"]) {
      EXPECT_LE(c["quads_expected"].get<double>(), kMaxFlipRoundGrowth * c["quads_before_flip_rounds"].get<double>())
          << name;
      rounds += c["flip_rounds"].get<int>();
    }
    if (name == "cow.obj") EXPECT_GE(rounds, 1) << "cow at 8 000 keeps its flip round (measured 2026-12-07)";
    const Json& count = quantization["count"];
    if (count.contains("fewest_quads"))
      EXPECT_LE(session.quad_result()->num_quads(), kMaxFlipRoundGrowth * count["fewest_quads"].get<double>()) << name;
  }
}

// Runs whose quads used to fold against the surface (camelhead's thin ears, coarse limbs and heads)
// before the untangle step maximized the quads' worst corner areas: the output invariants hold,
// no quad flipped included.
TEST(SessionMeshes, ThinAndCoarsePartsComeOutUnfolded) {
  std::vector<std::string> failed = sweep({{"camelhead.off", -1}}, {500, 2000, 8000});
  const std::vector<std::string> more =
      sweep({{"armadillo.obj", -1}, {"fertility.off", -1}, {"mnf07HeadFem_rem_rem_p.obj", -1}}, {500});
  failed.insert(failed.end(), more.begin(), more.end());
  EXPECT_TRUE(failed.empty()) << joined(failed);
}

}  // namespace
}  // namespace qgp
// Session integration of the cross field and cut graph stages: report, caching, honest stop at
// the first stage that does not exist yet.
#include <gtest/gtest.h>

#include <atomic>
#include <set>
#include <string>

#include "core/error.h"
#include "intake/read_mesh_file.h"
#include "pipeline/session.h"
#include "test_support.h"

namespace qgp {
namespace {

// Records the progress of a remesh job and stops it when the seamless-map stage begins (the
// later stages have their own tests).
struct Recorder {
  int cross_field_updates = 0, cut_graph_updates = 0;
  double last_fraction = 0;
  bool fractions_in_range = true;
  std::atomic<bool> stop{false};
  Progress progress() {
    return Progress(
        [this](const std::string& stage, double fraction) {
          if (fraction < 0 || fraction > 1) fractions_in_range = false;
          if (stage == "cross_field" && fraction > 0) ++cross_field_updates;
          if (stage == "cut_graph" && fraction > 0) ++cut_graph_updates;
          if (stage == "seamless_map") stop = true;
          last_fraction = fraction;
        },
        &stop);
  }
};

// Runs a remesh job; kCompleted when it got through the field stages (stopped by the Recorder
// at the seamless map), else its error code.
constexpr ErrorCode kCompleted = static_cast<ErrorCode>(0);
ErrorCode run_remesh(Session& session, Progress& progress) {
  try {
    session.run(Job::Remesh, progress);
  } catch (const Error& e) {
    const bool at_seamless = std::string(e.what()).find("'seamless_map'") != std::string::npos;
    return e.code() == ErrorCode::Cancelled && at_seamless ? kCompleted : e.code();
  }
  return kCompleted;
}

TEST(FieldSession, ReportsTheFieldOfEveryComponent) {
  Session session(read_mesh_file(test::mesh_path("teapot.obj")));  // 4 components once welded, open
  Recorder recorder;
  Progress progress = recorder.progress();
  EXPECT_EQ(run_remesh(session, progress), kCompleted);
  const Json& report = session.report();
  EXPECT_TRUE(report["error"].is_object());  // stopped at the seamless map on purpose
  ASSERT_TRUE(report.contains("field"));
  const Json& field = report["field"];
  EXPECT_EQ(field["index_sum"], field["euler_characteristic"]);
  int chi = 0;
  for (const ComponentInfo& c : session.intake()->components) chi += c.euler_characteristic;
  EXPECT_EQ(field["euler_characteristic"], chi);
  ASSERT_EQ(field["components"].size(), session.components().size());
  int singularities = 0;
  for (const Json& c : field["components"]) {
    EXPECT_EQ(c["index_sum"], c["euler_characteristic"]);
    singularities += c["singularities"].get<int>();
  }
  EXPECT_EQ(field["singularities"], singularities);
  EXPECT_TRUE(report["timings_s"].contains("cross_field"));
  EXPECT_TRUE(report["timings_s"].contains("cut_graph"));
  EXPECT_GT(recorder.cross_field_updates, 0);
  EXPECT_GT(recorder.cut_graph_updates, 0);
  EXPECT_TRUE(recorder.fractions_in_range);
  for (const ComponentState& c : session.components()) {
    ASSERT_TRUE(c.field && c.cut);
    EXPECT_EQ(c.field->direction.size(), static_cast<size_t>(c.mesh.num_faces()));
  }
}

TEST(FieldSession, CachesFieldUntilFeaturesChange) {
  Session session(read_mesh_file(test::mesh_path("fandisk.obj")));
  Recorder first;
  Progress p1 = first.progress();
  EXPECT_EQ(run_remesh(session, p1), kCompleted);
  EXPECT_EQ(session.report()["field"]["feature_edges"], 0);

  // Only the density changes: neither stage runs again.
  RemeshOptions options = session.options();
  options.target_faces = 500;
  session.set_options(options);
  Recorder second;
  Progress p2 = second.progress();
  EXPECT_EQ(run_remesh(session, p2), kCompleted);
  EXPECT_EQ(second.cross_field_updates, 0);
  EXPECT_EQ(second.cut_graph_updates, 0);
  EXPECT_TRUE(session.report().contains("field"));

  // The sharp angle changes: both stages run with the dihedral features.
  options.sharp_angle_deg = 40;
  session.set_options(options);
  Recorder third;
  Progress p3 = third.progress();
  EXPECT_EQ(run_remesh(session, p3), kCompleted);
  EXPECT_GT(third.cross_field_updates, 0);
  EXPECT_GT(session.report()["field"]["feature_edges"].get<int>(), 600);
  EXPECT_EQ(session.report()["field"]["index_sum"], 2);

  // Caller features (input vertex pairs) are used as well.
  options.sharp_angle_deg = -1;
  const TriMesh& mesh = session.intake()->mesh;
  std::set<int> edges;  // the distinct edges of the first 30 halfedges
  for (int h = 0; h < 30; ++h) {
    options.feature_edges.push_back(
        {session.intake()->input_vertex[mesh.from(h)], session.intake()->input_vertex[mesh.to(h)]});
    edges.insert(mesh.edge_of[h]);
  }
  session.set_options(options);
  Recorder fourth;
  Progress p4 = fourth.progress();
  EXPECT_EQ(run_remesh(session, p4), kCompleted);
  EXPECT_GE(session.report()["field"]["feature_edges"].get<int>(), static_cast<int>(edges.size()));
}

TEST(FieldSession, CancelInsideTheFieldStagesThenRunAgain) {
  Session session(read_mesh_file(test::mesh_path("bunny.off")));
  for (const char* stage : {"cross_field", "cut_graph"}) {
    std::atomic<bool> cancel{false};
    Progress progress(
        [&](const std::string& s, double fraction) {
          if (s == stage && fraction > 0) cancel = true;
        },
        &cancel);
    EXPECT_EQ(run_remesh(session, progress), ErrorCode::Cancelled) << stage;
    EXPECT_EQ(session.report()["status"], "error");
  }
  // Nothing half-done is kept: the next run completes both stages.
  Recorder recorder;
  Progress progress = recorder.progress();
  EXPECT_EQ(run_remesh(session, progress), kCompleted);
  EXPECT_EQ(session.report()["field"]["index_sum"], 2);
}

}  // namespace
}  // namespace qgp

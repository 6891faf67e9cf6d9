#include "pipeline/session.h"

#include <cmath>

#include "core/error.h"
#include "core/timer.h"
#include "pipeline/split_faces.h"

namespace qgp {

Session::Session(PolygonSoup input) : input_(std::move(input)) {}
Session::~Session() = default;

void Session::set_options(const RemeshOptions& options) {
  if (options.target_faces > 0 && options.edge_length > 0)
    throw Error(ErrorCode::InvalidArgument, "give either a target face count or an edge length, not both");
  if (!std::isfinite(options.target_faces) || !std::isfinite(options.edge_length) ||
      !std::isfinite(options.sharp_angle_deg))
    throw Error(ErrorCode::InvalidArgument, "options must be finite numbers");
  if (options.sharp_angle_deg > 180)
    throw Error(ErrorCode::InvalidArgument, "sharp angle must be at most 180 degrees");
  for (const auto& e : options.feature_edges)
    if (e[0] < 0 || e[1] < 0 || e[0] >= input_.num_vertices() || e[1] >= input_.num_vertices() || e[0] == e[1])
      throw Error(ErrorCode::InvalidArgument, "feature edge (" + std::to_string(e[0]) + ", " +
                                                  std::to_string(e[1]) + ") is not a pair of distinct vertices of the mesh");
  if (options.drop_bad_components != options_.drop_bad_components) {
    intake_.reset();
    components_.clear();
  }
  if (options.feature_edges != options_.feature_edges || options.sharp_angle_deg != options_.sharp_angle_deg)
    components_.clear();
  options_ = options;
}

void Session::run(Job job, Progress& progress) {
  Timer total;
  report_ = Json::object();
  quads_.reset();
  quad_source_face_.clear();
  corner_uv_.clear();
  cut_edges_.clear();
  report_["status"] = "ok";
  report_["error"] = nullptr;
  report_["timings_s"] = Json::object();
  try {
    run_intake_stage(progress);
    if (job != Job::Intake) run_remesh_stages(job, progress);
    report_["timings_s"]["total"] = total.seconds();
  } catch (const Error& e) {
    report_["status"] = "error";
    report_["error"] = {{"code", error_code_name(e.code())}, {"message", e.what()}};
    report_["timings_s"]["total"] = total.seconds();
    throw;
  } catch (const std::bad_alloc&) {
    report_["status"] = "error";
    report_["error"] = {{"code", error_code_name(ErrorCode::Internal)}, {"message", "out of memory"}};
    throw Error(ErrorCode::Internal, "out of memory");
  } catch (const std::exception& e) {
    report_["status"] = "error";
    const std::string message = std::string("internal error: ") + e.what();
    report_["error"] = {{"code", error_code_name(ErrorCode::Internal)}, {"message", message}};
    throw Error(ErrorCode::Internal, message);
  }
}

void Session::run_intake_stage(Progress& progress) {
  Timer timer;
  if (!intake_) {
    IntakeOptions intake_options;
    intake_options.drop_bad_components = options_.drop_bad_components;
    intake_ = std::make_unique<IntakeResult>(run_intake(input_, intake_options, progress));
  }
  report_["input"] = intake_report(*intake_);
  report_["timings_s"]["intake"] = timer.seconds();
}

double Session::target_edge_length() const {
  if (options_.edge_length > 0) return options_.edge_length;
  const double faces = options_.target_faces > 0 ? options_.target_faces : RemeshOptions::kDefaultTargetFaces;
  double area = 0;
  const TriMesh& m = intake_->mesh;
  for (int f = 0; f < m.num_faces(); ++f) area += 0.5 * m.face_normal_unnormalized(f).norm();
  return std::sqrt(area / faces);
}

void Session::prepare_components() {
  if (!components_.empty()) return;
  int unmatched = 0;
  const std::vector<char> features = map_input_edges(*intake_, options_.feature_edges, &unmatched);
  components_.resize(intake_->components.size());
  int split = 0;
  for (size_t c = 0; c < components_.size(); ++c) {
    ComponentState& state = components_[c];
    state.mesh = extract_component(*intake_, static_cast<int>(c), &state.vertex_map, &state.face_map);
    std::vector<char> caller(state.mesh.num_edges(), 0);
    // Component edges map to intake edges through their halfedges' faces.
    for (int h = 0; h < state.mesh.num_halfedges(); ++h) {
      const int global_h = 3 * state.face_map[h / 3] + h % 3;
      if (features[intake_->mesh.edge_of[global_h]]) caller[state.mesh.edge_of[h]] = 1;
    }
    state.feature_edges = detect_feature_edges(state.mesh, caller, options_.sharp_angle_deg);
    split += split_overconstrained_faces(state.mesh, state.feature_edges, state.vertex_map, state.face_map);
  }
  split_faces_ = split;
  unmatched_features_ = unmatched;
}

void Session::report_component_preparation() {
  if (split_faces_ > 0)
    report_["input"]["repairs"].push_back({{"kind", "split_overconstrained_faces"}, {"count", split_faces_}});
  if (unmatched_features_ > 0)
    report_["input"]["warnings"].push_back(std::to_string(unmatched_features_) +
                                           " feature edge(s) are not edges of the repaired mesh and were ignored");
}

void Session::run_field_stages(Progress& progress) {
  // Each component gets a share of the stage's progress proportional to its face count.
  std::vector<double> share_end(components_.size());
  double faces = 0;
  for (size_t c = 0; c < components_.size(); ++c) share_end[c] = faces += components_[c].mesh.num_faces();
  auto set_share = [&](size_t c) {
    progress.set_range(c == 0 ? 0.0 : share_end[c - 1] / faces, share_end[c] / faces);
  };

  Timer field_timer;
  progress.begin_stage("cross_field");
  for (size_t c = 0; c < components_.size(); ++c) {
    ComponentState& state = components_[c];
    if (state.field) continue;
    set_share(c);
    CrossFieldOptions field_options;
    field_options.feature_edges = state.feature_edges;
    field_options.sharp_angle_deg = -1;  // dihedral features are already in feature_edges
    state.field = compute_cross_field(state.mesh, field_options, progress);
    state.cut.reset();
  }
  report_["timings_s"]["cross_field"] = field_timer.seconds();

  Timer cut_timer;
  progress.begin_stage("cut_graph");
  for (size_t c = 0; c < components_.size(); ++c) {
    ComponentState& state = components_[c];
    if (state.cut) continue;
    set_share(c);
    state.cut = compute_cut_graph(state.mesh, *state.field, progress);
  }
  report_["timings_s"]["cut_graph"] = cut_timer.seconds();

  // Report: totals plus one entry per component. index_sum is in full index units (quarter
  // turns / 4) so that it reads as the Euler characteristic.
  Json per_component = Json::array();
  int singularities = 0, index_quarters = 0, euler = 0, feature_edges = 0, cut_edges = 0, overconstrained = 0,
      collapsed = 0;
  for (const ComponentState& state : components_) {
    const CrossField& field = *state.field;
    int features = 0;
    for (char f : field.feature_edge) features += f;
    per_component.push_back({{"faces", state.mesh.num_faces()},
                             {"singularities", field.num_singularities},
                             {"index_sum", field.index_sum / 4},
                             {"euler_characteristic", field.euler_characteristic},
                             {"feature_edges", features},
                             {"overconstrained_faces", field.num_overconstrained_faces},
                             {"collapsed_sectors", field.num_collapsed_sectors},
                             {"cut_edges", state.cut->num_cut_edges}});
    singularities += field.num_singularities;
    index_quarters += field.index_sum;
    euler += field.euler_characteristic;
    feature_edges += features;
    cut_edges += state.cut->num_cut_edges;
    overconstrained += field.num_overconstrained_faces;
    collapsed += field.num_collapsed_sectors;
  }
  report_["field"] = {{"singularities", singularities},
                      {"index_sum", index_quarters / 4},
                      {"euler_characteristic", euler},
                      {"feature_edges", feature_edges},
                      {"overconstrained_faces", overconstrained},
                      {"collapsed_sectors", collapsed},
                      {"cut_edges", cut_edges},
                      {"components", std::move(per_component)}};
}

void Session::run_remesh_stages(Job job, Progress& progress) {
  (void)job;
  prepare_components();
  report_component_preparation();
  run_field_stages(progress);
  progress.begin_stage("seamless_map");
  throw Error(ErrorCode::NotBuilt, "stage 'seamless_map' is not built yet; no output was written");
}

}  // namespace qgp

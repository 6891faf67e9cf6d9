#include "pipeline/session.h"

#include <cmath>

#include "core/error.h"
#include "core/timer.h"

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
  for (size_t c = 0; c < components_.size(); ++c) {
    ComponentState& state = components_[c];
    state.mesh = extract_component(*intake_, static_cast<int>(c), &state.vertex_map, &state.face_map);
    state.feature_edges.assign(state.mesh.num_edges(), 0);
    // Component edges map to intake edges through their halfedges' faces.
    for (int h = 0; h < state.mesh.num_halfedges(); ++h) {
      const int global_h = 3 * state.face_map[h / 3] + h % 3;
      if (features[intake_->mesh.edge_of[global_h]]) state.feature_edges[state.mesh.edge_of[h]] = 1;
    }
  }
  if (unmatched > 0)
    report_["input"]["warnings"].push_back(std::to_string(unmatched) +
                                           " feature edge(s) are not edges of the repaired mesh and were ignored");
}

void Session::run_remesh_stages(Job job, Progress& progress) {
  (void)job;
  prepare_components();
  progress.begin_stage("cross_field");
  throw Error(ErrorCode::NotBuilt, "stage 'cross_field' is not built yet; no output was written");
}

}  // namespace qgp

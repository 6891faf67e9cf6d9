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
  if (options.drop_bad_components != options_.drop_bad_components) intake_.reset();
  options_ = options;
}

void Session::run(Job job, Progress& progress) {
  Timer total;
  report_ = Json::object();
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

void Session::run_remesh_stages(Job job, Progress& progress) {
  (void)job;
  progress.begin_stage("cross_field");
  throw Error(ErrorCode::NotBuilt, "stage 'cross_field' is not built yet; no output was written");
}

}  // namespace qgp

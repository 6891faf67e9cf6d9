// A Session owns the input mesh, the options and every stage's result, so that changing only
// the target density re-runs quantization and later stages, nothing before them.
#pragma once
#include <memory>

#include "core/json.h"
#include "core/progress.h"
#include "intake/intake.h"
#include "intake/polygon_soup.h"
#include "pipeline/options.h"

namespace qgp {

enum class Job { Intake, Remesh, GridUV };

class Session {
 public:
  explicit Session(PolygonSoup input);
  ~Session();

  // Validates and stores the options; stages whose inputs changed are invalidated.
  void set_options(const RemeshOptions& options);
  const RemeshOptions& options() const { return options_; }

  // Runs the job's stages (reusing cached ones). Throws Error on failure; the report describes
  // the outcome either way.
  void run(Job job, Progress& progress);

  const Json& report() const { return report_; }
  const IntakeResult* intake() const { return intake_.get(); }
  const PolygonSoup& input() const { return input_; }

 private:
  void run_intake_stage(Progress& progress);
  void run_remesh_stages(Job job, Progress& progress);

  PolygonSoup input_;
  RemeshOptions options_;
  std::unique_ptr<IntakeResult> intake_;
  Json report_;
};

}  // namespace qgp

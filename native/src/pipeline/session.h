// A Session owns the input mesh, the options and every stage's result, so that changing only
// the target density re-runs quantization and later stages, nothing before them.
#pragma once
#include <memory>
#include <optional>
#include <vector>

#include "core/json.h"
#include "core/progress.h"
#include "core/quad_mesh.h"
#include "cross_field/cross_field.h"
#include "cut_graph/cut_graph.h"
#include "igm/cell_map.h"
#include "igm/integer_grid_map.h"
#include "intake/intake.h"
#include "intake/polygon_soup.h"
#include "pipeline/options.h"
#include "quad_extraction/layout_quads.h"
#include "quad_extraction/untangle_quads.h"
#include "quad_extraction/quad_extraction.h"
#include "quantization/quantization.h"
#include "seamless_map/seamless_map.h"
#include "tmesh/tmesh.h"

namespace qgp {

enum class Job { Intake, Remesh, GridUV };

// One connected component on its way through the pipeline; later stages add their results here.
struct ComponentState {
  TriMesh mesh;                     // the component as its own mesh (the working mesh if decimated)
  std::vector<int> vertex_map;      // component vertex -> intake mesh vertex
  std::vector<int> face_map;        // component face -> intake mesh face (-1 when decimated)
  std::vector<char> feature_edges;  // #E of `mesh`: caller's and dihedral-angle feature edges
  // A dense component of a remesh job is decimated to a working resolution for the target; the
  // quads are projected back onto the full-resolution component kept here.
  std::optional<TriMesh> full_mesh;
  std::vector<int> full_face_map;        // full_mesh face -> intake mesh face
  std::vector<char> full_feature_edges;  // #E of full_mesh
  int working_face_budget = 0;           // the face budget `mesh` was made for (0: no limit)
  std::optional<CrossField> field;  // stage 1a (cached until features / sharp angle change)
  std::optional<CutGraph> cut;      // stage 1b
  std::optional<SeamlessMap> seamless;  // stage 1c: 1 uv unit = seamless_edge_length; a new density
  double seamless_edge_length = 0;      // only changes the quantization scale (up to kMaxSeamlessRescale)
  // Stage 2: the seamless map made exact (features and boundary on exact isolines) and its T-mesh.
  std::vector<char> isoline_edges;      // #E: feature and boundary edges kept as isolines
  std::optional<ExactParametrization> exact_seamless;
  std::optional<TMesh> tmesh;
  // Stage 3: integer T-edge lengths for quantization_scale (quads per seamless uv unit).
  std::optional<QuantizationResult> quantization;
  double quantization_scale = 0;
  int fold_rounds = 0;                  // re-quantizations that kept folding zero edges at 1
  int positive_edges = 0;               // T-edges kept at length >= 1 by them
  Quantizer quantizer = Quantizer::Greedy;
  // Stage 4: the integer-grid map (1 unit = 1 quad) and stage 5: its quads.
  std::optional<ExactParametrization> igm;
  IgmStats igm_stats;                   // of the greedy path (path "round" for the baseline)
  bool igm_escalated = false;           // computed with IgmOptions::escalate (grid UV jobs)
  // The fallback map on the mesh with the T-mesh inserted, when the global solve's map stays
  // flipped or wound and the fallback has no flipped triangle (cell_map_report says how it went;
  // null when it did not run).
  std::optional<CellMap> cell_map;
  Json cell_map_report;
  std::optional<QuadExtraction> quads;
  std::string quads_path;               // "integer-grid map" or "T-mesh layout (<why>)"
  LayoutQuadsStats layout_stats;        // when the quads come from the T-mesh layout
  UntangleStats untangle_stats;         // flipped quads unfolded after extraction
};

// A remesh job at a new density keeps a decimated working mesh until the density needs a budget
// more than this many times the one it was made for.
constexpr int kMaxWorkingBudgetGrowth = 4;
// ... and its seamless map until the target edge length is more than this many times shorter or
// longer than the one the map was solved for (rescaled further, the solver's tolerances no longer
// match the grid and results drift from a fresh run's).
constexpr double kMaxSeamlessRescale = 2;
constexpr int kMaxFoldRounds = 8;  // re-quantizations against a folding layout

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
  const std::vector<ComponentState>& components() const { return components_; }

  // Target quad edge length in model units, from the options and the total surface area.
  double target_edge_length() const;

  // Results of the last successful job (null / empty when there is none).
  // Quad mesh over all components; quad_source_face: per quad the input face it lies on.
  const QuadMesh* quad_result() const { return quads_ ? quads_.get() : nullptr; }
  const std::vector<int>& quad_source_face() const { return quad_source_face_; }
  // Integer-grid map per input triangle corner (#input faces x 3 x 2, 1 unit = 1 quad; NaN where
  // intake removed the face) and the cut edges as input vertex pairs.
  const std::vector<double>& corner_uv() const { return corner_uv_; }
  const std::vector<std::array<int, 2>>& cut_edges() const { return cut_edges_; }

 private:
  void run_intake_stage(Progress& progress);
  void prepare_components(Job job, Progress& progress);
  bool cached_components_fit(Job job) const;
  int component_face_budget(int component, double edge_length) const;  // working-mesh faces
  void report_component_preparation();
  void run_remesh_stages(Job job, Progress& progress);
  void run_field_stages(Progress& progress);
  void run_seamless_stage(Progress& progress);
  void run_tmesh_stage(Progress& progress);
  void run_quantization_stage(Progress& progress);
  void run_igm_stage(Job job, Progress& progress);
  // The fallback cell map of a component whose integer-grid map is not valid (paper §7.1.1).
  void run_cell_map(ComponentState& state, Progress& progress);
  void run_quad_stage(Progress& progress);
  // made_from: per input face, the (component, face) triangle made from it, or (-1, -1).
  void fill_missing_corner_uvs(const std::vector<std::pair<int, int>>& made_from);
  void collect_results(Job job, Progress& progress);
  // Runs body(c, state) for every component inside progress stage `stage`, each with its share
  // of the progress (by face count); records timings_s[stage]; a failure names the component.
  template <class Body>
  void for_each_component(const char* stage, Progress& progress, Body body);

  PolygonSoup input_;
  RemeshOptions options_;
  std::unique_ptr<IntakeResult> intake_;
  std::vector<ComponentState> components_;
  int split_faces_ = 0, unmatched_features_ = 0;
  Json report_;
  std::unique_ptr<QuadMesh> quads_;
  std::vector<int> quad_source_face_;
  std::vector<double> corner_uv_;
  std::vector<std::array<int, 2>> cut_edges_;
};

}  // namespace qgp

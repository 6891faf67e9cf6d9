// A Session owns the input mesh, the options and every component's stage results, so that a new
// target density re-runs quantization and later stages, nothing before them. It assembles: the
// stages compute (native/src/<stage>/), the policy decides (pipeline/policy.h), the report
// functions describe (pipeline/report.h).
#pragma once
#include <array>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/json.h"
#include "core/progress.h"
#include "core/quad_mesh.h"
#include "intake/intake.h"
#include "intake/polygon_soup.h"
#include "pipeline/component_state.h"
#include "pipeline/options.h"
#include "symmetry/symmetry.h"

namespace qgp {

class TriangleBvh;

class Session {
 public:
  explicit Session(PolygonSoup input);
  ~Session();

  // Validates and stores the options; components whose inputs changed are prepared again.
  void set_options(const RemeshOptions& options);
  const RemeshOptions& options() const { return options_; }

  // Runs the job's stages (reusing stored results whose inputs did not change). Throws Error on
  // failure; the report describes the outcome either way.
  void run(Job job, Progress& progress);

  const Json& report() const { return report_; }
  const IntakeResult* intake() const { return intake_.get(); }
  // The input face an intake face comes from, and the input vertex of an intake vertex (through the
  // half when symmetry is asked: -1 for a vertex the cut made).
  int input_face_of(int intake_face) const;
  int input_vertex_of(int intake_vertex) const;
  const PolygonSoup& input() const { return input_; }
  const std::vector<ComponentState>& components() const { return components_; }

  // Target quad edge length in model units, from the options and the total surface area.
  double target_edge_length() const;

  // Results of the last successful job (null / empty when there is none).
  // Quad mesh over all components; quad_source_face: per quad the input face it lies on.
  const QuadMesh* quad_result() const { return quads_ ? quads_.get() : nullptr; }
  const std::vector<int>& quad_source_face() const { return quad_source_face_; }
  // Components that could not be quadded (report: failed_components), kept as their repaired
  // triangles, and the non-orientable parts intake set aside (numbered after the components); null
  // when every part was quadded. V and F only (no connectivity); per triangle its input face and
  // component.
  const TriMesh* kept_triangles() const { return kept_triangles_.get(); }
  const std::vector<int>& kept_source_face() const { return kept_source_face_; }
  const std::vector<int>& kept_component() const { return kept_component_; }
  // Integer-grid map per input triangle corner (#input faces x 3 x 2, 1 unit = 1 quad; NaN where
  // intake removed the face) and the cut edges as input vertex pairs.
  const std::vector<double>& corner_uv() const { return corner_uv_; }
  const std::vector<std::array<int, 2>>& cut_edges() const { return cut_edges_; }

 private:
  // What intake reads: the input, or its positive half when symmetry is asked.
  const PolygonSoup& intake_input() const { return half_ ? half_->soup : input_; }
  // The quad count asked for the part intake reads (the whole count over the symmetric copies).
  double asked_quads() const;
  // The sizing field on the component's mesh (options adaptive and density), #F or empty.
  std::vector<double> component_face_sizes(const ComponentState& state) const;
  // The positive half options.symmetry asks for (null for none); throws when nothing is left.
  std::unique_ptr<HalfSoup> cut_half(const RemeshOptions& options) const;
  // Symmetry: quads_, quad_source_face_ and the kept triangles mirrored across the planes asked and
  // welded there; the reference for the quad figures mirrored alike (pipeline/session_symmetry.cpp).
  void mirror_results();
  void mirror_kept_triangles(const TriangleBvh& input_faces, const std::vector<int>& triangle_face);
  TriMesh mirrored_reference(const TriMesh& reference, std::vector<int>& component_of) const;
  void run_intake_stage(Progress& progress);
  void run_remesh_stages(Job job, Progress& progress);
  void prepare_components(Job job, Progress& progress);
  bool prepared_components_fit(Job job) const;
  // remesh: a needle-covered component with features runs on an isotropic remesh of itself.
  ComponentState prepare_component(int component, const std::vector<char>& features, Job job, bool remesh,
                                   Progress& progress);
  std::vector<char> intake_feature_edges();                            // the caller's feature edges on the intake mesh
  int component_face_budget(int component, double edge_length) const;  // working-mesh faces
  double intake_area() const;                                          // of the whole repaired mesh
  double component_area(int component) const;
  // Per component its share of the quad count asked, by area; zeros when an edge length was asked.
  std::vector<double> component_quad_targets() const;
  void add_preparation_repairs();
  // Runs body(state) for every component inside progress stage `stage`, each with its share of
  // the progress (by face count); records timings_s[stage]; a failure names the component.
  // A failure of the only component is kept too when the job rescues it.
  template <class Body>
  void for_each_component(Job job, const char* stage, Progress& progress, Body body);
  // Remesh jobs with the greedy quantizer rescue failed components (the round baseline's failures
  // are counted, not rescued).
  bool rescues_failed_components(Job job) const;
  // Per component the quads its rescue aims at: its share of the count asked, or, when an edge
  // length was asked, its area over the edge length squared.
  std::vector<double> rescue_quad_targets() const;
  // Every component a remesh stage failed on is rescued by policy.h's failed-part ladder: quadded
  // with the field without cancelled pairs, at a finer density, or by splitting its triangles;
  // throws when no component has quads.
  void rescue_failed_components(Job job, Progress& progress);
  // Components whose quads stay flipped are quadded at a finer density (policy.h: kFinerFlipShare)
  // or get their split triangles instead (kFlipRescueShare).
  void rescue_flipped_components(Progress& progress);
  // The last rung for flipped quads and slivers (policy.h: collapse_folds) on every quadded part;
  // the report's extraction.collapsed names the parts.
  void collapse_folded_components(Progress& progress);
  // A minor part whose quads keep a collapsed edge after that (policy.h: kFinerFlipShare) is quadded
  // again alone at the finer densities of kFinerEdgeFactors, its folds collapsed, until one leaves
  // none flipped or collapsed; it takes the one that leaves fewest, if fewer than its own.
  void refine_parts_with_collapsed_edges(Progress& progress);
  // The component's quads at the finer densities of kFinerEdgeFactors, at most max_quads of them:
  // the first valid ones, or while quads stay flipped in them, those of the finer density that
  // leaves fewest flipped; false if none gives such quads (state unchanged then).
  bool quad_at_finer_density(ComponentState& state, double target_quads, int64_t max_quads, Job job,
                             Progress& progress);
  // The field report's close_pairs_kept for the parts quad_without_cancelled_pairs rescued.
  void mark_fields_without_cancelled_pairs();
  // The component's quads at the density asked with the field without cancelled close pairs;
  // false if a stage failed.
  bool quad_without_cancelled_pairs(ComponentState& state, double target_quads, Job job, Progress& progress);
  // Parts on needle triangles whose quads lie far off their surface (policy.h:
  // remesh_may_bring_quads_closer) take the quads of an isotropic remesh where those lie closer.
  void remesh_parts_off_their_surface(Job job, Progress& progress);
  // Component c's quads on an isotropic remesh of its triangles (policy.h: retry_on_isotropic_remesh);
  // false (state unchanged) if the remesh does not apply or a stage failed.
  bool quad_on_isotropic_remesh(ComponentState& state, int c, double target_quads, Job job, Progress& progress);
  // The component's quads at the density asked with its field computed again (cancel_pairs: with
  // close +1/-1 pairs cancelled); false if a stage failed.
  bool quad_with_field(ComponentState& state, bool cancel_pairs, double target_quads, Job job, Progress& progress);
  // The component's quads alone at `factor` of the quad edge length asked; false if a stage failed.
  bool quad_at_edge_factor(ComponentState& state, double factor, double target_quads, Job job, Progress& progress);
  // A remesh component whose quads stay flipped, at the finer densities of kFinerEdgeFactors in
  // turn until one has none flipped: it takes the quads of the one with fewest flipped, if fewer
  // than its own (state unchanged otherwise).
  bool unflip_at_finer_density(ComponentState& state, double target_quads, Progress& progress);
  // The part's quads alone at the finer densities of kFinerEdgeFactors below its own, in turn (with
  // collapsed_edges, each with its folds collapsed), until one leaves no flipped quad (nor, with
  // collapsed_edges, one with a collapsed edge): the one that leaves fewest (flipped, then
  // collapsed), if fewer than its own; none otherwise.
  std::optional<ComponentState> quad_finer_with_fewer_defects(const ComponentState& state, double target_quads,
                                                              bool collapsed_edges, Progress& progress);
  void collect_grid_uvs();
  // made_from: per input face, the (component, face) triangle made from it, or (-1, -1).
  void fill_missing_corner_uvs(const std::vector<std::pair<int, int>>& made_from);
  void collect_quads(Progress& progress);
  // The failed components' triangles and the parts intake set aside (non-orientable).
  void collect_kept_triangles(const std::vector<int>& failed);
  void append_non_orientable_part(const NonOrientablePart& part, int component);
  // The quad figures (report "quad") of quads_, the quads of components `quadded`.
  Json measure_quads(const std::vector<int>& quadded, bool all_quadded, Progress& progress) const;
  void report_failed_components();
  // Report rescued_components, named in the quad count's note.
  void note_rescued_components(Json rescued);
  void throw_if_every_component_failed() const;
  void report_error(const std::string& code, const std::string& message);

  PolygonSoup input_;
  std::unique_ptr<HalfSoup> half_;  // the positive half intake reads, when symmetry is asked
  RemeshOptions options_;
  std::unique_ptr<IntakeResult> intake_;
  std::vector<ComponentState> components_;
  int split_faces_ = 0, unmatched_features_ = 0;
  Json report_;
  std::unique_ptr<QuadMesh> quads_;
  std::vector<int> quad_source_face_;
  std::unique_ptr<TriMesh> kept_triangles_;
  std::vector<int> kept_source_face_, kept_component_;
  std::vector<double> corner_uv_;
  std::vector<std::array<int, 2>> cut_edges_;
};

}  // namespace qgp

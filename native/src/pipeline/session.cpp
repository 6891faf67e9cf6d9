#include "pipeline/session.h"

#include <cmath>

#include <limits>
#include <set>

#include "core/error.h"
#include "core/sanitize_isolines.h"
#include "core/timer.h"
#include "igm/untangle_map.h"
#include "intake/working_mesh.h"
#include "pipeline/split_faces.h"
#include "quad_extraction/quad_metrics.h"
#include "quad_extraction/surface_projection.h"
#include "quantization/round_quantization.h"
#include "tmesh/tmesh_system.h"
#include "tmesh/trace_tmesh.h"

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
    report_["peak_memory_mb"] = peak_resident_mb();
  } catch (const Error& e) {
    report_["status"] = "error";
    report_["error"] = {{"code", error_code_name(e.code())}, {"message", e.what()}};
    report_["timings_s"]["total"] = total.seconds();
    report_["peak_memory_mb"] = peak_resident_mb();
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

int Session::component_face_budget(int component, double edge_length) const {
  double area = 0;
  const TriMesh& m = intake_->mesh;
  for (int f : intake_->components[component].faces) area += 0.5 * m.face_normal_unnormalized(f).norm();
  return working_face_budget(area / (edge_length * edge_length));
}

bool Session::cached_components_fit(Job job) const {
  if (components_.empty()) return false;
  const double edge_length = target_edge_length();
  for (size_t c = 0; c < components_.size(); ++c) {
    const ComponentState& state = components_[c];
    if (!state.full_mesh) continue;
    // Grid UVs belong to the input triangles. A new density reuses the working mesh (only
    // quantization and later stages run again) unless it needs a much finer one.
    if (job != Job::Remesh ||
        component_face_budget(static_cast<int>(c), edge_length) > kMaxWorkingBudgetGrowth * state.working_face_budget)
      return false;
  }
  return true;
}

void Session::prepare_components(Job job, Progress& progress) {
  if (cached_components_fit(job)) return;
  Timer timer;
  progress.begin_stage("working_mesh");
  components_.clear();
  int unmatched = 0;
  const std::vector<char> features = map_input_edges(*intake_, options_.feature_edges, &unmatched);
  const double edge_length = target_edge_length();
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
    if (job == Job::Remesh) {
      state.working_face_budget = component_face_budget(static_cast<int>(c), edge_length);
      WorkingMesh working = make_working_mesh(state.mesh, state.feature_edges, state.working_face_budget, progress);
      if (working.decimated) {
        for (int& v : working.vertex_of_input) v = state.vertex_map[v];
        state.full_mesh = std::move(state.mesh);
        state.full_face_map = std::move(state.face_map);
        state.full_feature_edges = std::move(state.feature_edges);
        state.mesh = std::move(working.mesh);
        state.vertex_map = std::move(working.vertex_of_input);
        state.face_map.assign(state.mesh.num_faces(), -1);
        state.feature_edges = std::move(working.feature_edges);
      }
    }
    split += split_overconstrained_faces(state.mesh, state.feature_edges, state.vertex_map, state.face_map);
    progress.update(static_cast<double>(c + 1) / components_.size());
  }
  split_faces_ = split;
  unmatched_features_ = unmatched;
  report_["timings_s"]["working_mesh"] = timer.seconds();
}

void Session::report_component_preparation() {
  int decimated = 0, input_faces = 0, working_faces = 0;
  for (const ComponentState& state : components_) {
    decimated += state.full_mesh.has_value();
    input_faces += state.full_mesh ? state.full_mesh->num_faces() : state.mesh.num_faces();
    working_faces += state.mesh.num_faces();
  }
  report_["working_mesh"] = {{"decimated_components", decimated},
                             {"input_faces", input_faces},
                             {"working_faces", working_faces},
                             {"faces_per_quad", kWorkingFacesPerQuad},
                             {"min_faces", kMinWorkingFaces}};
  if (split_faces_ > 0)
    report_["input"]["repairs"].push_back({{"kind", "split_overconstrained_faces"}, {"count", split_faces_}});
  if (unmatched_features_ > 0)
    report_["input"]["warnings"].push_back(std::to_string(unmatched_features_) +
                                           " feature edge(s) are not edges of the repaired mesh and were ignored");
}

template <class Body>
void Session::for_each_component(const char* stage, Progress& progress, Body body) {
  Timer timer;
  progress.begin_stage(stage);
  double faces = 0, done = 0;
  for (const ComponentState& state : components_) faces += state.mesh.num_faces();
  for (size_t c = 0; c < components_.size(); ++c) {
    ComponentState& state = components_[c];
    progress.set_range(done / faces, (done + state.mesh.num_faces()) / faces);
    done += state.mesh.num_faces();
    try {
      body(c, state);
    } catch (const Error& e) {
      if (components_.size() <= 1 || e.code() == ErrorCode::Cancelled) throw;
      throw Error(e.code(), "component " + std::to_string(c) + ": " + e.what());
    }
  }
  report_["timings_s"][stage] = timer.seconds();
}

void Session::run_field_stages(Progress& progress) {
  for_each_component("cross_field", progress, [&](size_t, ComponentState& state) {
    if (state.field) return;
    CrossFieldOptions field_options;
    field_options.feature_edges = state.feature_edges;
    field_options.sharp_angle_deg = -1;  // dihedral features are already in feature_edges
    state.field = compute_cross_field(state.mesh, field_options, progress);
    state.cut.reset();
  });
  for_each_component("cut_graph", progress, [&](size_t, ComponentState& state) {
    if (state.cut) return;
    state.cut = compute_cut_graph(state.mesh, *state.field, progress);
    state.seamless.reset();
  });

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
  prepare_components(job, progress);
  report_component_preparation();
  run_field_stages(progress);
  run_seamless_stage(progress);
  run_tmesh_stage(progress);
  run_quantization_stage(progress);
  run_igm_stage(job, progress);
  if (job == Job::Remesh) run_quad_stage(progress);
  collect_results(job, progress);
}


void Session::run_seamless_stage(Progress& progress) {
  const double edge_length = target_edge_length();
  for_each_component("seamless_map", progress, [&](size_t, ComponentState& state) {
    if (state.seamless) {
      const double rescale = state.seamless_edge_length / edge_length;
      if (std::max(rescale, 1 / rescale) <= kMaxSeamlessRescale * (1 + 1e-9)) return;  // re-quantized only
      state.seamless.reset();
    }
    SeamlessMapOptions options;
    options.edge_length = edge_length;
    state.seamless = compute_seamless_map(state.mesh, *state.field, *state.cut, options, progress);
    state.seamless_edge_length = edge_length;
    state.exact_seamless.reset();
    state.tmesh.reset();
    state.quantization.reset();
  });

  Json per_component = Json::array();
  int flipped = 0, degenerate = 0, iterations = 0;
  double residual = 0, energy = 0;
  for (const ComponentState& state : components_) {
    const SeamlessMapStats& s = state.seamless->stats;
    per_component.push_back({{"flipped_triangles", s.flipped_triangles},
                             {"degenerate_triangles", s.degenerate_triangles},
                             {"winding_defects", s.winding_defects},
                             {"max_transition_residual", s.max_transition_residual},
                             {"energy", s.energy},
                             {"ipopt_iterations", s.ipopt_iterations},
                             {"flipped_before_ipopt", s.flipped_before_ipopt},
                             {"isoline_edges", s.isoline_edges},
                             {"dropped_isolines", s.dropped_isolines},
                             {"repair_rounds", s.repair_rounds},
                             {"field_frame_solves", s.field_frame_solves},
                             {"min_area_ratio", s.min_area_ratio}});
    flipped += s.flipped_triangles;
    degenerate += s.degenerate_triangles;
    iterations += s.ipopt_iterations;
    residual = std::max(residual, s.max_transition_residual);
    energy += s.energy;
  }
  report_["seamless"] = {{"flipped_triangles", flipped},
                         {"degenerate_triangles", degenerate},
                         {"max_transition_residual", residual},
                         {"energy", energy},
                         {"ipopt_iterations", iterations},
                         {"edge_length", components_.empty() ? edge_length : components_[0].seamless_edge_length},
                         {"components", std::move(per_component)}};
  if (flipped + degenerate > 0)
    report_["seamless"]["warnings"].push_back(std::to_string(flipped) + " flipped and " + std::to_string(degenerate) +
                                              " degenerate triangle(s) remain in the seamless map");
}


void Session::run_tmesh_stage(Progress& progress) {
  Json per_component = Json::array();
  for_each_component("tmesh", progress, [&](size_t, ComponentState& state) {
    if (!state.tmesh) {
      state.quantization.reset();
      // Feature edges the seamless map left free (their isolines would collapse a triangle) are
      // not walls of the T-mesh.
      state.isoline_edges = state.feature_edges;
      for (int e : state.seamless->stats.dropped_isoline_edges) state.isoline_edges[e] = 0;
      const SanitizeResult exact = sanitize_with_isolines(
          state.mesh, state.seamless->param,
          isoline_constraints(state.mesh, state.seamless->param, state.isoline_edges, true), SanitizeOptions{});
      if (exact.unresolved_equations > 0)
        throw Error(ErrorCode::StageFailed, "T-mesh: " + std::to_string(exact.unresolved_equations) +
                                                " transition or isoline equation(s) of the seamless map cannot hold exactly");
      TraceOptions trace_options;
      trace_options.feature_edges = state.isoline_edges;
      state.tmesh = trace_tmesh(state.mesh, exact.param, trace_options, progress);
      state.exact_seamless = std::move(exact.param);
    }
    per_component.push_back(tmesh_report(*state.tmesh));
  });
  Json total = {{"nodes", 0}, {"edges", 0}, {"cells", 0}, {"singular_nodes", 0}};
  for (const Json& r : per_component)
    for (auto& [key, value] : total.items()) value = value.get<int64_t>() + r.value(key, int64_t(0));
  total["components"] = std::move(per_component);
  report_["tmesh"] = std::move(total);
}

namespace {

// Zero T-edges (x = 0) whose collapse folds the quad layout: those on the sides of the cells whose
// layout quads are not manifold, and of the cells up to `rings` cells away. Empty when the
// layout is a manifold quad mesh (the connectivity every map with this quantization gives).
std::vector<int> folding_zero_edges(const ComponentState& state, int rings) {
  Progress quiet;
  const TMesh& tm = *state.tmesh;
  const std::vector<int64_t>& x = state.quantization->x;
  const LayoutQuads layout = extract_layout_quads(state.mesh, *state.exact_seamless, tm, x, quiet, false);
  const std::vector<char> bad = non_manifold_quads(layout.quads);
  std::vector<char> in_region(tm.cells.size(), 0);
  std::vector<int> region;
  for (size_t q = 0; q < bad.size(); ++q)
    if (bad[q] && !in_region[layout.quad_cell[q]]) {
      in_region[layout.quad_cell[q]] = 1;
      region.push_back(layout.quad_cell[q]);
    }
  if (region.empty()) return {};
  for (int ring = 0, begin = 0; ring < rings; ++ring) {
    const int end = static_cast<int>(region.size());
    for (int i = begin; i < end; ++i)
      for (const auto& side : tm.cells[region[i]].sides)
        for (int e : side)
          for (int c : tm.edges[e].cells)
            if (c >= 0 && !in_region[c]) {
              in_region[c] = 1;
              region.push_back(c);
            }
    begin = end;
  }
  std::vector<int> edges;
  for (int c : region)
    for (const auto& side : tm.cells[c].sides)
      for (int e : side)
        if (x[e] == 0) edges.push_back(e);
  return edges;
}

}  // namespace

void Session::run_quantization_stage(Progress& progress) {
  const double edge_length = target_edge_length();
  Json per_component = Json::array();
  int64_t quads = 0;
  for_each_component("quantization", progress, [&](size_t, ComponentState& state) {
    const double scale = state.seamless_edge_length / edge_length;
    if (state.quantization && (state.quantization_scale != scale || state.quantizer != options_.quantizer))
      state.quantization.reset();
    if (!state.quantization) {
      state.igm.reset();
      state.quads.reset();
      QuantizationOptions options;
      options.scale = scale;
      if (options_.quantizer == Quantizer::Greedy) {
        state.quantization = quantize(*state.tmesh, options, progress);
        // Valid quantizations (singularities apart) can still collapse cells so that the layout
        // folds: a regular point between two quads only, two quads on both sides of one edge. Keep
        // the zero edges there (and in a widening ring around) at length 1 and quantize again.
        state.positive_edges = 0;
        state.fold_rounds = 0;
        for (int round = 0; round < kMaxFoldRounds; ++round) {
          const std::vector<int> edges = folding_zero_edges(state, round);
          if (edges.empty()) break;
          options.min_length.resize(state.tmesh->edges.size(), 0);
          for (int e : edges) options.min_length[e] = 1;
          state.quantization = quantize(*state.tmesh, options, progress);
          state.fold_rounds = round + 1;
        }
        for (int64_t m : options.min_length) state.positive_edges += static_cast<int>(m);
      } else {
        // The rounding baseline: its rounded map is the integer-grid map (when it is valid).
        options.method = QuantizationMethod::Round;
        const TraceFunction trace = [&state](const ExactParametrization& param, Progress& p) {
          TraceOptions trace_options;
          trace_options.feature_edges = state.isoline_edges;
          return trace_tmesh(state.mesh, param, trace_options, p);
        };
        RoundingResult rounded = quantize_by_rounding(state.mesh, state.seamless->param, state.isoline_edges,
                                                      *state.tmesh, options, trace, progress);
        if (!rounded.quantization.valid)
          throw Error(ErrorCode::StageFailed, "quantization (round): " + rounded.quantization.invalid_reason);
        state.quantization = std::move(rounded.quantization);
        state.igm = std::move(rounded.map.param);
        state.igm_stats = IgmStats{};
        state.igm_stats.path = "round";
        state.igm_stats.flipped_triangles = rounded.map.flipped_triangles;
        state.igm_stats.degenerate_triangles = rounded.map.degenerate_triangles;
        state.igm_stats.unresolved_equations = rounded.map.unresolved_equations;
      }
      state.quantization_scale = scale;
      state.quantizer = options_.quantizer;
    }
    quads += state.quantization->quads_expected;
    per_component.push_back(quantization_report(*state.quantization));
    per_component.back()["fold_rounds"] = state.fold_rounds;
    per_component.back()["kept_positive_edges"] = state.positive_edges;
  });
  report_["quantization"] = {{"method", quantizer_name(options_.quantizer)},
                             {"quads_expected", quads},
                             {"components", std::move(per_component)}};
}

void Session::run_igm_stage(Job job, Progress& progress) {
  Json per_component = Json::array();
  int flipped = 0, degenerate = 0, wound = 0, fallbacks = 0, cell_maps = 0;
  double residual = 0;
  // Quads have a fallback (the T-mesh layout), grid UVs do not: only they pay for the escalations.
  const bool escalate = job == Job::GridUV;
  for_each_component("igm", progress, [&](size_t, ComponentState& state) {
    const IgmStats& old = state.igm_stats;
    const bool irregular = old.flipped_triangles + old.degenerate_triangles + old.winding_defects > 0;
    if (state.igm && escalate && !state.igm_escalated && irregular && state.igm_stats.path != "round") state.igm.reset();
    if (!state.igm) {
      state.quads.reset();
      IgmOptions options;
      options.escalate = escalate;
      state.igm_escalated = escalate;
      options.edge_length = state.seamless_edge_length;
      IntegerGridMap map = compute_integer_grid_map(state.mesh, *state.field, *state.cut, *state.seamless,
                                                    *state.exact_seamless, *state.tmesh, *state.quantization,
                                                    options, progress);
      state.igm_stats = map.stats;
      state.igm = std::move(map.param);
      IgmStats& s = state.igm_stats;
      if (s.flipped_triangles + s.degenerate_triangles > 0) {
        const MapUntangleStats u = untangle_map(state.mesh, map.snapped_vertices, map.isolines, *state.igm, progress);
        s.untangled_vertices = u.moved_vertices;
        s.flipped_before_untangle = u.flipped_before;
        s.degenerate_before_untangle = u.degenerate_before;
        s.flipped_triangles = u.flipped_after;
        s.degenerate_triangles = u.degenerate_after;
        s.seconds += u.seconds;
        s.winding_defects = count_exact_winding_defects(state.mesh, *state.igm, cone_quarter_turns(state.mesh, *state.field));
      }
      state.cell_map.reset();
      state.cell_map_report = Json();
    }
    if (options_.fallback_uv_map && state.cell_map_report.is_null()) run_cell_map(state, progress);
    const IgmStats& s = state.igm_stats;
    flipped += s.flipped_triangles;
    degenerate += s.degenerate_triangles;
    wound += s.winding_defects;
    fallbacks += s.fallback_used;
    cell_maps += state.cell_map.has_value();
    residual = std::max(residual, s.max_integer_residual);
    per_component.push_back(igm_report(s));
    if (!state.cell_map_report.is_null()) per_component.back()["cell_map"] = state.cell_map_report;
  });
  report_["igm"] = {{"flipped_triangles", flipped},
                    {"degenerate_triangles", degenerate},
                    {"winding_defects", wound},
                    {"max_integer_residual", residual},
                    {"fallback_used", fallbacks + cell_maps > 0},
                    {"cell_map_components", cell_maps},
                    {"components", std::move(per_component)}};
}

void Session::run_cell_map(ComponentState& state, Progress& progress) {
  // Degenerate triangles alone do not call for it: its collapsed cells have many more.
  const IgmStats& s = state.igm_stats;
  if (s.flipped_triangles + s.winding_defects == 0) return;
  try {
    CellMapOptions options;
    options.cone_turns = cone_quarter_turns(state.mesh, *state.field);
    CellMap map = map_cells_to_rectangles(state.mesh, *state.tmesh, state.quantization->x, progress, options);
    state.cell_map_report = cell_map_stats_json(map.stats);
    const bool used = map.stats.flipped_triangles + map.stats.wound_vertices == 0;
    state.cell_map_report["used"] = used;
    if (used) state.cell_map = std::move(map);
  } catch (const Error& e) {
    if (e.code() != ErrorCode::StageFailed) throw;
    state.cell_map_report = {{"used", false}, {"failure", e.what()}};
  }
}

namespace {

// Why a quad mesh is not a consistently oriented 2-manifold with Euler characteristic `euler`
// ("" when it is).
std::string quad_mesh_defects(const QuadTopology& t, int euler) {
  std::string defects;
  auto add = [&](int count, const char* what) {
    if (count > 0) defects += (defects.empty() ? "" : "; ") + std::to_string(count) + " " + what;
  };
  add(t.non_manifold_edges, "non-manifold edge(s)");
  add(t.inconsistent_edges, "inconsistently oriented edge(s)");
  add(t.degenerate_quads, "degenerate quad(s)");
  if (defects.empty() && t.euler_characteristic != euler)
    defects = "Euler characteristic " + std::to_string(t.euler_characteristic) + " instead of " + std::to_string(euler);
  return defects;
}

}  // namespace

void Session::run_quad_stage(Progress& progress) {
  Json per_component = Json::array();
  for_each_component("quad_extraction", progress, [&](size_t c, ComponentState& state) {
    if (!state.quads) {
      const int euler = intake_->components[c].euler_characteristic;
      // Unfolds quads (on the working mesh, then, projected back, on the input surface).
      auto untangle = [&](QuadMesh& quads) {
        UntangleStats stats = untangle_flipped_quads(quads, state.mesh, state.field->feature_edge, progress);
        if (state.full_mesh) {
          project_to_surface(quads, *state.full_mesh, progress);
          quads.quad_face.resize(quads.num_quads());
          for (int q = 0; q < quads.num_quads(); ++q) quads.quad_face[q] = quads.vertex_face[quads.Q(q, 0)];
          const UntangleStats projected = untangle_flipped_quads(quads, *state.full_mesh, state.full_feature_edges, progress);
          stats.flipped_after = projected.flipped_after;
          stats.moved_vertices += projected.moved_vertices;
          stats.seconds += projected.seconds;
        }
        return stats;
      };
      // The integer-grid map's quads when the map is valid and they form a valid mesh.
      std::string why_not_igm;
      const IgmStats& igm = state.igm_stats;
      if (igm.flipped_triangles + igm.degenerate_triangles + igm.winding_defects > 0) {
        why_not_igm = std::to_string(igm.flipped_triangles) + " flipped and " + std::to_string(igm.degenerate_triangles) +
                      " degenerate triangle(s) and " + std::to_string(igm.winding_defects) +
                      " wound one-ring(s) in the integer-grid map";
      } else {
        try {
          QuadExtraction extraction = extract_quads(state.mesh, *state.igm, QuadExtractionOptions{}, progress);
          why_not_igm = quad_mesh_defects(quad_topology(extraction.quads), euler);
          if (why_not_igm.empty()) {
            state.untangle_stats = untangle(extraction.quads);
            state.quads = std::move(extraction);
            state.quads_path = "integer-grid map";
          }
        } catch (const Error& e) {
          if (e.code() != ErrorCode::StageFailed) throw;
          why_not_igm = e.what();
        }
      }
      // Otherwise, or if some of them stay flipped, the quads of the quantized T-mesh layout (kept
      // if they are valid and fewer stay flipped).
      if (!state.quads || state.untangle_stats.flipped_after > 0) {
        LayoutQuads layout =
            extract_layout_quads(state.mesh, *state.exact_seamless, *state.tmesh, state.quantization->x, progress);
        // Never hand out a broken mesh.
        const QuadTopology topology = quad_topology(layout.quads);
        const std::string defects = quad_mesh_defects(topology, euler);
        if (!defects.empty() && !state.quads) {
          // A manifold, oriented result of another topology: a hole or handle collapsed.
          const bool collapsed = topology.non_manifold_edges + topology.inconsistent_edges + topology.degenerate_quads == 0;
          throw Error(ErrorCode::StageFailed,
                      "quad extraction: the quads do not form a valid mesh (" + defects + "); no output was written" +
                          (collapsed ? ". A hole or handle of this part is narrower than one quad: try more quads" : ""));
        }
        if (defects.empty()) {
          QuadExtraction extraction;
          extraction.quads = std::move(layout.quads);
          extraction.stats.expected_quads = layout.stats.quads;
          extraction.stats.seconds = layout.stats.seconds;
          for (char s : extraction.quads.vertex_singular) extraction.stats.singular_vertices += s;
          const UntangleStats untangled = untangle(extraction.quads);
          if (!state.quads || untangled.flipped_after < state.untangle_stats.flipped_after) {
            if (state.quads)
              why_not_igm = std::to_string(state.untangle_stats.flipped_after) + " of the integer-grid map's quads stay flipped";
            state.quads = std::move(extraction);
            state.quads_path = "T-mesh layout (" + why_not_igm + ")";
            state.layout_stats = layout.stats;
            state.untangle_stats = untangled;
          }
        }
      }
    }
    Json stats = quad_extraction_stats_json(state.quads->stats);
    stats["path"] = state.quads_path;
    if (state.quads_path.rfind("T-mesh", 0) == 0) stats["layout"] = layout_quads_stats_json(state.layout_stats);
    const UntangleStats& u = state.untangle_stats;
    stats["untangle"] = {{"flipped_before", u.flipped_before}, {"flipped_after", u.flipped_after},
                         {"moved_vertices", u.moved_vertices}, {"seconds", u.seconds}};
    per_component.push_back(std::move(stats));
  });
  int from_layout = 0;
  for (const ComponentState& state : components_) from_layout += state.quads_path.rfind("T-mesh", 0) == 0;
  report_["extraction"] = {{"layout_components", from_layout}, {"components", std::move(per_component)}};
  if (from_layout > 0) {
    report_["igm"]["fallback_used"] = true;
    report_["igm"]["fallback"] = "quads of the T-mesh layout in " + std::to_string(from_layout) + " component(s)";
  }
}

void Session::fill_missing_corner_uvs(const std::vector<std::pair<int, int>>& made_from) {
  // Corners the per-vertex matching left NaN: those of input triangles intake removed (zero-area,
  // needles, caps), and those whose input vertex a needle's collapse merged away. They get the map of
  // the triangle made from their input triangle, else of the one nearest its centroid, extended
  // affinely: one chart, a (nearly) degenerate uv triangle where the 3D one is. Triangles of
  // components remeshed on a decimated working mesh stay NaN (their map is not on these triangles).
  std::vector<std::unique_ptr<TriangleBvh>> bvh(components_.size());
  std::vector<char> kept(input_.num_faces(), 0);
  for (int f : intake_->input_face) kept[f] = 1;
  for (int f = 0; f < input_.num_faces(); ++f) {
    if (input_.face_size(f) != 3) continue;
    bool missing = false;
    for (int i = 0; i < 6; ++i) missing = missing || std::isnan(corner_uv_[6 * f + i]);
    if (!missing || (kept[f] && made_from[f].first < 0)) continue;
    Vec3 corner[3], centroid = Vec3::Zero();
    for (int j = 0; j < 3; ++j) centroid += corner[j] = input_.positions[input_.face_vertices[input_.face_start[f] + j]];
    centroid /= 3;
    auto [component, t] = made_from[f];
    if (component < 0) {
      double nearest = std::numeric_limits<double>::infinity();
      for (size_t c = 0; c < components_.size(); ++c) {
        if (components_[c].full_mesh || !components_[c].igm) continue;
        if (!bvh[c]) bvh[c] = std::make_unique<TriangleBvh>(components_[c].mesh);
        const TriangleBvh::Hit h = bvh[c]->closest_point(centroid);
        if (h.triangle >= 0 && h.squared_distance < nearest)
          nearest = h.squared_distance, component = static_cast<int>(c), t = h.triangle;
      }
      if (component < 0) continue;
    }
    const ComponentState& state = components_[component];
    const Vec3 a = state.mesh.position(state.mesh.F(t, 0));
    const Vec3 e1 = state.mesh.position(state.mesh.F(t, 1)) - a, e2 = state.mesh.position(state.mesh.F(t, 2)) - a;
    const double d11 = e1.dot(e1), d12 = e1.dot(e2), d22 = e2.dot(e2), det = d11 * d22 - d12 * d12;
    if (!(det > 0)) continue;
    Vec2 w[3];
    for (int k = 0; k < 3; ++k)
      w[k] = Vec2(state.igm->to_double(state.igm->uv[3 * t + k][0]), state.igm->to_double(state.igm->uv[3 * t + k][1]));
    for (int j = 0; j < 3; ++j) {
      if (!std::isnan(corner_uv_[6 * f + 2 * j]) && !std::isnan(corner_uv_[6 * f + 2 * j + 1])) continue;
      // Barycentric coordinates of the corner projected onto the triangle's plane (may be outside).
      const Vec3 r = corner[j] - a;
      const double s1 = (d22 * r.dot(e1) - d12 * r.dot(e2)) / det, s2 = (d11 * r.dot(e2) - d12 * r.dot(e1)) / det;
      const Vec2 p = w[0] + s1 * (w[1] - w[0]) + s2 * (w[2] - w[0]);
      corner_uv_[6 * f + 2 * j] = p.x();
      corner_uv_[6 * f + 2 * j + 1] = p.y();
    }
  }
}

void Session::collect_results(Job job, Progress& progress) {
  const TriMesh& intake_mesh = intake_->mesh;
  // Per-corner integer-grid UVs of the input triangles: corners are matched by input vertex (faces
  // split by the pipeline share their corners with the input triangle).
  corner_uv_.assign(static_cast<size_t>(input_.num_faces()) * 6, std::numeric_limits<double>::quiet_NaN());
  std::set<std::array<int, 2>> cuts;
  std::vector<std::pair<int, int>> made_from(input_.num_faces(), {-1, -1});  // (component, face)
  for (size_t c = 0; c < components_.size(); ++c) {
    const ComponentState& state = components_[c];
    if (state.full_mesh) continue;  // the map lives on the working mesh, not on the input triangles
    const ExactParametrization& igm = *state.igm;
    auto input_vertex = [&](int v) {
      const int iv = state.vertex_map[v];
      return iv < 0 ? -1 : intake_->input_vertex[iv];
    };
    for (int f = 0; f < state.mesh.num_faces(); ++f) {
      const int input_face = intake_->input_face[state.face_map[f]];
      made_from[input_face] = {static_cast<int>(c), f};
      if (input_.face_size(input_face) != 3) continue;
      for (int k = 0; k < 3; ++k) {
        const int iv = input_vertex(state.mesh.F(f, k));
        for (int j = 0; j < 3; ++j)
          if (iv >= 0 && input_.face_vertices[input_.face_start[input_face] + j] == iv) {
            corner_uv_[6 * input_face + 2 * j] = igm.to_double(igm.uv[3 * f + k][0]);
            corner_uv_[6 * input_face + 2 * j + 1] = igm.to_double(igm.uv[3 * f + k][1]);
          }
      }
    }
    // Seams: interior edges whose two sides disagree in the map.
    for (int e = 0; e < state.mesh.num_edges(); ++e) {
      const int h = state.mesh.edge_halfedge[e], o = state.mesh.opposite[h];
      if (o < 0) continue;
      const int a = state.mesh.F(h / 3, h % 3), b = state.mesh.F(h / 3, (h + 1) % 3);
      const bool same = igm.uv[h] == igm.uv[3 * (o / 3) + (o + 1) % 3] &&
                        igm.uv[3 * (h / 3) + (h + 1) % 3] == igm.uv[o];
      const int ia = input_vertex(a), ib = input_vertex(b);
      if (!same && ia >= 0 && ib >= 0) cuts.insert({std::min(ia, ib), std::max(ia, ib)});
    }
  }
  cut_edges_.assign(cuts.begin(), cuts.end());
  fill_missing_corner_uvs(made_from);
  if (job != Job::Remesh) return;

  Timer timer;
  progress.begin_stage("metrics");
  quads_ = std::make_unique<QuadMesh>();
  for (size_t c = 0; c < components_.size(); ++c) {
    const ComponentState& state = components_[c];
    append_quad_mesh(*quads_, state.quads->quads, static_cast<int>(c));
    for (int q = 0; q < state.quads->quads.num_quads(); ++q) {
      const int f = state.quads->quads.quad_face.empty() ? -1 : state.quads->quads.quad_face[q];
      const std::vector<int>& face_map = state.full_mesh ? state.full_face_map : state.face_map;
      quad_source_face_.push_back(f < 0 ? -1 : intake_->input_face[face_map[f]]);
    }
  }
  QuadMetricsOptions metric_options;
  metric_options.hausdorff_samples = 20000;
  const QuadMetrics metrics = compute_quad_metrics(*quads_, intake_mesh, metric_options, progress);
  report_["quad"] = quad_report_json(metrics);
  report_["timings_s"]["metrics"] = timer.seconds();
}

}  // namespace qgp

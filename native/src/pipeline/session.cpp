#include "pipeline/session.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <set>
#include <utility>

#include "core/blas_kernels.h"
#include "core/error.h"
#include "core/timer.h"
#include "intake/working_mesh.h"
#include "metrics/quad_metrics.h"
#include "pipeline/component_stages.h"
#include "pipeline/policy.h"
#include "pipeline/report.h"
#include "pipeline/split_faces.h"
#include "quad_extraction/surface_projection.h"
#include "sizing/sizing.h"

namespace qgp {
namespace {

// Per quad of `part`, the intake face under its centre: the face of the component's surface (its
// full mesh when it has a working mesh) closest to the mean of its corners; -1 where none
// is known. A quad's material and face attributes come from that face: the face under a corner
// (where extraction started the quad) can lie a quad's half-diagonal away, across a material split.
std::vector<int> intake_faces_under_quad_centres(const QuadMesh& part, const ComponentState& state) {
  const bool full = state.full_mesh.has_value();
  const std::vector<int>& face_map = full ? state.full_face_map : state.face_map;
  std::vector<int> faces =
      triangles_under_centres<4>(part.V, part.Q, TriangleBvh(full ? *state.full_mesh : state.mesh));
  for (int& f : faces) f = f >= 0 && f < static_cast<int>(face_map.size()) ? face_map[f] : -1;
  return faces;
}

// The larger of the two sampled Hausdorff distances between a part's quads and its surface.
double quads_distance(const QuadMesh& quads, const TriMesh& surface, Progress& progress) {
  constexpr int kSamples = 20000;
  const std::array<double, 2> d = hausdorff_distances(quads, surface, TriangleBvh(surface), kSamples, 1, progress);
  return std::max(d[0], d[1]);
}

}  // namespace

Session::Session(PolygonSoup input) : input_(std::move(input)) {}
Session::~Session() = default;

void Session::set_options(const RemeshOptions& options) {
  if (options.target_faces > 0 && options.edge_length > 0)
    throw Error(ErrorCode::InvalidArgument, "give either a target face count or an edge length, not both");
  if (!std::isfinite(options.target_faces) || !std::isfinite(options.edge_length) ||
      !std::isfinite(options.sharp_angle_deg))
    throw Error(ErrorCode::InvalidArgument, "options must be finite numbers");
  if (!(options.adaptive >= 0 && options.adaptive <= 1))
    throw Error(ErrorCode::InvalidArgument, "adaptive size must be a number from 0 (uniform) to 1");
  if (!options.density.empty() && static_cast<int>(options.density.size()) != input_.num_vertices())
    throw Error(ErrorCode::InvalidArgument, "the density has " + std::to_string(options.density.size()) +
                                                " values for " + std::to_string(input_.num_vertices()) +
                                                " vertices: give one per vertex");
  for (size_t v = 0; v < options.density.size(); ++v)
    if (!(options.density[v] > 0) || !std::isfinite(options.density[v]))
      throw Error(ErrorCode::InvalidArgument,
                  "the density of vertex " + std::to_string(v) + " is not a positive number");
  if (!(options.weld_tolerance >= 0) || !std::isfinite(options.weld_tolerance))
    throw Error(ErrorCode::InvalidArgument, "the weld tolerance must be a finite number >= 0");
  if (options.sharp_angle_deg > 180) throw Error(ErrorCode::InvalidArgument, "sharp angle must be at most 180 degrees");
  for (const auto& e : options.feature_edges)
    if (e[0] < 0 || e[1] < 0 || e[0] >= input_.num_vertices() || e[1] >= input_.num_vertices() || e[0] == e[1])
      throw Error(ErrorCode::InvalidArgument, "feature edge (" + std::to_string(e[0]) + ", " + std::to_string(e[1]) +
                                                  ") is not a pair of distinct vertices of the mesh");
  const bool half_changed = options.symmetry != options_.symmetry || options.feature_edges != options_.feature_edges ||
                            options.density != options_.density;
  std::unique_ptr<HalfSoup> half = half_changed ? cut_half(options) : nullptr;
  if (options.drop_bad_components != options_.drop_bad_components ||
      options.weld_tolerance != options_.weld_tolerance ||
      options.refuse_non_manifold != options_.refuse_non_manifold || options.symmetry != options_.symmetry) {
    intake_.reset();
    components_.clear();
  }
  if (options.feature_edges != options_.feature_edges || options.sharp_angle_deg != options_.sharp_angle_deg)
    components_.clear();
  if (half_changed) half_ = std::move(half);
  options_ = options;
}

std::unique_ptr<HalfSoup> Session::cut_half(const RemeshOptions& options) const {
  if (!options.symmetry.any()) return nullptr;
  Eigen::AlignedBox3d box;
  for (const Vec3& p : input_.positions) box.extend(p);
  const double snap = input_.positions.empty() ? 0.0 : kSymmetrySnapTolerance * box.diagonal().norm();
  auto half = std::make_unique<HalfSoup>(
      cut_to_positive_half(input_, options.feature_edges, options.symmetry, snap, options.density));
  if (half->soup.num_faces() == 0 && input_.num_faces() > 0) {
    std::string planes;
    for (char axis : options.symmetry.name()) planes += std::string(planes.empty() ? "" : ", ") + axis + " = 0";
    throw Error(ErrorCode::InvalidArgument,
                "symmetry " + options.symmetry.name() + ": no face of the mesh is on the positive side of " + planes +
                    "; the planes are the object's own (its origin and axes): move the origin onto the symmetry "
                    "plane, or mirror about another axis");
  }
  return half;
}

int Session::input_face_of(int intake_face) const {
  const int f = intake_->input_face[intake_face];
  return half_ ? half_->input_face[f] : f;
}

std::vector<double> Session::component_face_sizes(const ComponentState& state) const {
  SizingOptions sizing;
  sizing.adaptive = options_.adaptive;
  const std::vector<double>& density = half_ ? half_->vertex_values : options_.density;
  if (!density.empty()) {
    sizing.vertex_density.assign(state.mesh.num_vertices(), 1.0);
    for (int v = 0; v < state.mesh.num_vertices(); ++v) {
      const int intake_vertex = state.vertex_map[v];  // -1 for a vertex splitting a face
      if (intake_vertex >= 0) sizing.vertex_density[v] = density[intake_->input_vertex[intake_vertex]];
    }
  }
  return face_sizes(state.mesh, state.feature_edges, sizing);
}

int Session::input_vertex_of(int intake_vertex) const {
  const int v = intake_->input_vertex[intake_vertex];
  return half_ ? half_->input_vertex[v] : v;
}

double Session::asked_quads() const {
  const double faces = options_.target_faces > 0 ? options_.target_faces : RemeshOptions::kDefaultTargetFaces;
  return faces / options_.symmetry.copies();
}

void Session::run(Job job, Progress& progress) {
  Timer total;
  report_ = Json::object();
  quads_.reset();
  quad_source_face_.clear();
  kept_triangles_.reset();
  kept_source_face_.clear();
  kept_component_.clear();
  corner_uv_.clear();
  cut_edges_.clear();
  report_["status"] = "ok";
  report_["error"] = nullptr;
  report_["timings_s"] = Json::object();
  try {
    if (job == Job::GridUV && half_)
      throw Error(ErrorCode::InvalidArgument,
                  "symmetry applies to quad remeshing: integer-grid UVs are made on the whole input's triangles");
    run_intake_stage(progress);
    if (job != Job::Intake) run_remesh_stages(job, progress);
    report_["timings_s"]["total"] = total.seconds();
    report_["peak_memory_mb"] = peak_resident_mb();
    report_["blas_kernels"] = blas_kernels();
  } catch (const Error& e) {
    report_error(error_code_name(e.code()), e.what());
    report_["timings_s"]["total"] = total.seconds();
    report_["peak_memory_mb"] = peak_resident_mb();
    throw;
  } catch (const std::bad_alloc&) {
    report_error(error_code_name(ErrorCode::Internal), "out of memory");
    throw Error(ErrorCode::Internal, "out of memory");
  } catch (const std::exception& e) {
    const std::string message = std::string("internal error: ") + e.what();
    report_error(error_code_name(ErrorCode::Internal), message);
    throw Error(ErrorCode::Internal, message);
  }
}

void Session::report_error(const std::string& code, const std::string& message) {
  report_["status"] = "error";
  report_["error"] = {{"code", code}, {"message", message}};
}

void Session::run_intake_stage(Progress& progress) {
  Timer timer;
  if (!intake_) {
    IntakeOptions intake_options;
    intake_options.drop_bad_components = options_.drop_bad_components;
    intake_options.refuse_non_manifold = options_.refuse_non_manifold;
    intake_options.weld_tolerance = options_.weld_tolerance;
    intake_ = std::make_unique<IntakeResult>(run_intake(intake_input(), intake_options, progress));
  }
  report_["input"] = *intake_;
  report_["timings_s"]["intake"] = timer.seconds();
}

double Session::target_edge_length() const {
  if (options_.edge_length > 0) return options_.edge_length;
  return std::sqrt(intake_area() / asked_quads());
}

double Session::intake_area() const {
  double area = 0;
  const TriMesh& m = intake_->mesh;
  for (int f = 0; f < m.num_faces(); ++f) area += 0.5 * m.face_normal_unnormalized(f).norm();
  return area;
}

double Session::component_area(int component) const {
  double area = 0;
  const TriMesh& m = intake_->mesh;
  for (int f : intake_->components[component].faces) area += 0.5 * m.face_normal_unnormalized(f).norm();
  return area;
}

int Session::component_face_budget(int component, double edge_length) const {
  return working_face_budget(component_area(component) / (edge_length * edge_length));
}

std::vector<double> Session::component_quad_targets() const {
  const int n = static_cast<int>(intake_->components.size());
  std::vector<double> targets(n, 0.0);
  if (options_.edge_length > 0) return targets;
  const double faces = asked_quads();
  double total = 0;
  for (int c = 0; c < n; ++c) total += targets[c] = component_area(c);
  for (double& t : targets) t = total > 0 ? faces * t / total : 0.0;
  return targets;
}

bool Session::prepared_components_fit(Job job) const {
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

ComponentState Session::prepare_component(int c, const std::vector<char>& features, Job job, bool remesh,
                                          Progress& progress) {
  ComponentState state;
  state.mesh = extract_component(*intake_, c, &state.vertex_map, &state.face_map);
  state.euler_characteristic = intake_->components[c].euler_characteristic;
  std::vector<char> caller(state.mesh.num_edges(), 0);
  // Component edges map to intake edges through their halfedges' faces.
  for (int h = 0; h < state.mesh.num_halfedges(); ++h) {
    const int global_h = 3 * state.face_map[h / 3] + h % 3;
    if (features[intake_->mesh.edge_of[global_h]]) caller[state.mesh.edge_of[h]] = 1;
  }
  state.feature_edges = detect_feature_edges(state.mesh, caller, options_.sharp_angle_deg);
  if (job == Job::Remesh) {
    const double edge_length = target_edge_length(), area = component_area(c);
    state.working_face_budget = component_face_budget(c, edge_length);
    const int remesh_faces = remesh ? remesh_face_budget(area / (edge_length * edge_length), area / intake_area(),
                                                         remesh_faces_per_quad(state.mesh, state.feature_edges))
                                    : 0;
    WorkingMesh working =
        make_working_mesh(state.mesh, state.feature_edges, state.working_face_budget, remesh_faces, progress);
    if (working.replaces_input()) {
      for (int& v : working.vertex_of_input) v = state.vertex_map[v];
      state.full_mesh = std::move(state.mesh);
      state.full_face_map = std::move(state.face_map);
      state.full_feature_edges = std::move(state.feature_edges);
      state.remeshed = working.remeshed;
      state.mesh = std::move(working.mesh);
      state.vertex_map = std::move(working.vertex_of_input);
      state.face_map.assign(state.mesh.num_faces(), -1);
      state.feature_edges = std::move(working.feature_edges);
    }
  }
  split_faces_ += split_overconstrained_faces(state.mesh, state.feature_edges, state.vertex_map, state.face_map);
  state.tip_vertices = sharp_tip_vertices(state.mesh);
  return state;
}

std::vector<char> Session::intake_feature_edges() {
  return map_input_edges(*intake_, half_ ? half_->feature_edges : options_.feature_edges, &unmatched_features_);
}

void Session::prepare_components(Job job, Progress& progress) {
  if (prepared_components_fit(job)) return;
  Timer timer;
  progress.begin_stage("working_mesh");
  components_.clear();
  split_faces_ = 0;
  const std::vector<char> features = intake_feature_edges();
  const int n = static_cast<int>(intake_->components.size());
  for (int c = 0; c < n; ++c) {
    components_.push_back(prepare_component(c, features, job, false, progress));
    progress.update(static_cast<double>(c + 1) / n);
  }
  report_["timings_s"]["working_mesh"] = timer.seconds();
}

void Session::add_preparation_repairs() {
  if (split_faces_ > 0)
    report_["input"]["repairs"].push_back({{"kind", "split_overconstrained_faces"}, {"count", split_faces_}});
  if (unmatched_features_ > 0)
    report_["input"]["warnings"].push_back(std::to_string(unmatched_features_) +
                                           " feature edge(s) are not edges of the repaired mesh and were ignored");
}

// A stage failure of one component: the others go on, and the component is rescued (`rescues` a
// StageFailed: rescue_failed_components) or kept as its triangles. A cancel, a bad option, or a
// failure of the only component that is not rescued ends the job.
bool part_failure_is_kept(const Error& e, size_t num_components, bool rescues) {
  if (e.code() == ErrorCode::Cancelled || e.code() == ErrorCode::InvalidArgument) return false;
  return num_components > 1 || (rescues && e.code() == ErrorCode::StageFailed);
}

template <class Body>
void Session::for_each_component(Job job, const char* stage, Progress& progress, Body body) {
  Timer timer;
  progress.begin_stage(stage);
  double faces = 0, done = 0;
  for (const ComponentState& state : components_) faces += state.mesh.num_faces();
  for (size_t c = 0; c < components_.size(); ++c) {
    ComponentState& state = components_[c];
    progress.set_range(done / faces, (done + state.mesh.num_faces()) / faces);
    done += state.mesh.num_faces();
    if (state.failure) continue;
    try {
      body(state);
    } catch (const Error& e) {
      if (!part_failure_is_kept(e, components_.size(), rescues_failed_components(job))) {
        if (components_.size() <= 1 || e.code() == ErrorCode::Cancelled) throw;
        throw Error(e.code(), "component " + std::to_string(c) + ": " + e.what());
      }
      state.failure = PartFailure{stage, e.code(), e.what()};
    }
  }
  report_["timings_s"][stage] = timer.seconds();
  if (!rescues_failed_components(job)) throw_if_every_component_failed();
}

namespace {
// Errors a rescue rung may end with (the next rung is tried): not a cancel or a bad option.
void rethrow_unless_rung_failed(const Error& e) {
  if (e.code() == ErrorCode::Cancelled || e.code() == ErrorCode::InvalidArgument) throw e;
}
}  // namespace

std::vector<double> Session::rescue_quad_targets() const {
  std::vector<double> targets = component_quad_targets();
  const double edge_length = target_edge_length();
  for (size_t c = 0; c < targets.size(); ++c)
    if (targets[c] <= 0) targets[c] = component_area(static_cast<int>(c)) / (edge_length * edge_length);
  return targets;
}

bool Session::rescues_failed_components(Job job) const {
  return job == Job::Remesh && options_.quantizer == Quantizer::Greedy;
}

bool Session::quad_at_edge_factor(ComponentState& state, double factor, double target_quads, Job job,
                                  Progress& progress) {
  const double edge_length = target_edge_length() * factor;
  try {
    update_seamless_map(state, edge_length, component_face_sizes(state), progress);
    update_tmesh(state, progress);
    update_quantization(state, edge_length, target_quads / (factor * factor), options_.quantizer, progress);
    update_integer_grid_map(state, job, progress);
    update_quads(state, progress);
    return true;
  } catch (const Error& e) {
    rethrow_unless_rung_failed(e);
    return false;
  }
}

bool Session::quad_with_field(ComponentState& state, bool cancel_pairs, double target_quads, Job job,
                              Progress& progress) {
  try {
    update_cross_field(state, target_edge_length(), cancel_pairs, progress);
    update_cut_graph(state, progress);
  } catch (const Error& e) {
    rethrow_unless_rung_failed(e);
    return false;
  }
  return quad_at_edge_factor(state, 1, target_quads, job, progress);
}

bool Session::quad_on_isotropic_remesh(ComponentState& state, int c, double target_quads, Job job, Progress& progress) {
  ComponentState remeshed = prepare_component(c, intake_feature_edges(), job, true, progress);
  if (!remeshed.remeshed || !quad_with_field(remeshed, true, target_quads, job, progress)) return false;
  remeshed.failure = state.failure;  // why its own triangles gave no quads
  remeshed.rescued_on_remesh = true;
  state = std::move(remeshed);
  return true;
}

bool Session::quad_without_cancelled_pairs(ComponentState& state, double target_quads, Job job, Progress& progress) {
  if (!quad_with_field(state, false, target_quads, job, progress)) return false;
  state.without_cancelled_pairs = true;
  return true;
}

bool Session::quad_at_finer_density(ComponentState& state, double target_quads, int64_t max_quads, Job job,
                                    Progress& progress) {
  std::optional<ComponentState> best;
  for (const double factor : kFinerEdgeFactors) {
    ComponentState finer = state;
    if (!quad_at_edge_factor(finer, factor, target_quads, job, progress)) continue;
    if (finer.quads->extraction.quads.num_quads() > max_quads) break;  // finer ones have more
    finer.finer_edge_factor = factor;
    if (!best || finer.quads->untangle.flipped_after < best->quads->untangle.flipped_after) best = std::move(finer);
    if (best->quads->untangle.flipped_after == 0) break;
  }
  if (!best) return false;
  state = std::move(*best);
  return true;
}

bool Session::unflip_at_finer_density(ComponentState& state, double target_quads, Progress& progress) {
  const int flipped = state.quads->untangle.flipped_after;
  std::optional<ComponentState> best = quad_finer_with_fewer_defects(state, target_quads, false, progress);
  if (!best) return false;
  best->failure = PartFailure{"quad_extraction", ErrorCode::StageFailed,
                              std::to_string(flipped) +
                                  " quad(s) stayed flipped against the surface at the density "
                                  "asked (it folds within them)"};
  state = std::move(*best);
  return true;
}

namespace {
// Flipped quads, then (with_collapsed) quads with a collapsed edge, of the quads in use: fewer is
// better.
std::pair<int, int> quad_defects(const ComponentState& state, bool with_collapsed) {
  const QuadChoice& choice = state.quad_choice();
  return {choice.untangle.flipped_after, with_collapsed ? quads_with_a_collapsed_edge(choice.extraction.quads) : 0};
}
}  // namespace

std::optional<ComponentState> Session::quad_finer_with_fewer_defects(const ComponentState& state, double target_quads,
                                                                     bool collapsed_edges, Progress& progress) {
  std::pair<int, int> fewest = quad_defects(state, collapsed_edges);
  std::optional<ComponentState> best;
  for (const double factor : kFinerEdgeFactors) {
    if (factor >= state.finer_edge_factor) continue;
    ComponentState finer = state;
    finer.collapsed_quads.reset();
    if (!quad_at_edge_factor(finer, factor, target_quads, Job::Remesh, progress)) continue;
    if (collapsed_edges) finer.collapsed_quads = collapse_folds(finer, finer.quad_choice(), progress);
    const std::pair<int, int> left = quad_defects(finer, collapsed_edges);
    if (!(left < fewest)) continue;
    fewest = left;
    finer.finer_edge_factor = factor;
    best = std::move(finer);
    if (left == std::make_pair(0, 0)) break;
  }
  return best;
}

void Session::rescue_failed_components(Job job, Progress& progress) {
  Timer timer;
  progress.begin_stage("rescue");
  const std::vector<double> targets = rescue_quad_targets();
  for (size_t c = 0; c < components_.size(); ++c) {
    ComponentState& state = components_[c];
    if (!state.failure || state.failure->code != ErrorCode::StageFailed) continue;  // e.g. a degenerate part
    const double target = targets[c];
    if (retry_on_isotropic_remesh(state, job) &&
        quad_on_isotropic_remesh(state, static_cast<int>(c), target, job, progress))
      continue;
    if (retry_without_cancelled_pairs(state) && quad_without_cancelled_pairs(state, target, job, progress)) continue;
    try {
      state.split_quads = quads_of_split_triangles(state, target, progress);
    } catch (const Error& e) {
      rethrow_unless_rung_failed(e);
      state.failure->message += "; " + std::string(e.what());
    }
    const int64_t most =
        state.split_quads ? state.split_quads->extraction.quads.num_quads() : std::numeric_limits<int64_t>::max();
    if (finer_density_may_help(state.failure->stage) && quad_at_finer_density(state, target, most, job, progress))
      state.split_quads.reset();
  }
  report_["timings_s"]["rescue"] = timer.seconds();
  throw_if_every_component_failed();
}

void Session::remesh_parts_off_their_surface(Job job, Progress& progress) {
  const double limit = kMaxQuadDistanceInEdges * target_edge_length();
  const std::vector<double> targets = rescue_quad_targets();
  for (size_t c = 0; c < components_.size(); ++c) {
    ComponentState& state = components_[c];
    if (!remesh_may_bring_quads_closer(state, job, target_edge_length())) continue;
    const double distance = quads_distance(state.quads->extraction.quads, state.mesh, progress);
    if (distance <= limit) continue;
    ComponentState own = state;
    state.failure = PartFailure{"quad_extraction", ErrorCode::StageFailed,
                                "its quads lie up to " + std::to_string(distance) +
                                    " off its surface (more than half a quad edge) on its own triangles"};
    if (!quad_on_isotropic_remesh(state, static_cast<int>(c), targets[c], job, progress) ||
        quads_distance(state.quads->extraction.quads, *state.full_mesh, progress) >= distance)
      state = std::move(own);
  }
}

void Session::rescue_flipped_components(Progress& progress) {
  Timer timer;
  const std::vector<double> targets = rescue_quad_targets();
  double budget = 0, quads_made = 0;
  for (const ComponentState& state : components_)
    if (state.quadded()) quads_made += state.quad_choice().extraction.quads.num_quads();
  budget = kFlipRescueShare * quads_made;
  for (size_t c = 0; c < components_.size(); ++c) {
    ComponentState& state = components_[c];
    if (!state.failure && state.quads->untangle.flipped_after > 0 &&
        state.quads->extraction.quads.num_quads() <= kFinerFlipShare * quads_made)
      unflip_at_finer_density(state, targets[c], progress);
  }
  for (size_t c = 0; c < components_.size(); ++c) {
    ComponentState& state = components_[c];
    // Also a part that the finer density left with fewer flipped quads, but some.
    if (!state.quadded() || state.split_quads || state.quads->untangle.flipped_after == 0 ||
        state.mesh.num_faces() > kFlipRescueMaxTriangles)
      continue;
    const double target = targets[c];
    if (std::min(3.0 * std::ceil(target / 3), 3.0 * state.mesh.num_faces()) > budget) continue;  // too large
    std::optional<QuadChoice> split;
    try {
      split = quads_of_split_triangles(state, target, progress, budget);
    } catch (const Error& e) {
      rethrow_unless_rung_failed(e);
      continue;
    }
    const int quads = split->extraction.quads.num_quads();
    if (split->untangle.flipped_after > 0 || quads > budget) continue;
    budget -= quads;
    if (!state.failure)
      state.failure = PartFailure{"quad_extraction", ErrorCode::StageFailed,
                                  std::to_string(state.quads->untangle.flipped_after) +
                                      " quad(s) stay flipped against the surface (it folds within them)"};
    state.finer_edge_factor = 1;  // the split triangles replace the finer density's quads
    state.split_quads = std::move(split);
  }
  Json& rescue_seconds = report_["timings_s"]["rescue"];
  rescue_seconds = rescue_seconds.get<double>() + timer.seconds();  // after rescue_failed_components'
}

void Session::collapse_folded_components(Progress& progress) {
  Timer timer;
  Json collapsed = Json::array();
  for (size_t c = 0; c < components_.size(); ++c) {
    ComponentState& state = components_[c];
    if (!state.quadded()) continue;
    const QuadChoice& choice = state.quad_choice();
    std::optional<QuadChoice> folded = collapse_folds(state, choice, progress);
    if (!folded) continue;
    collapsed.push_back({{"component", c},
                         {"collapsed_quads", folded->untangle.collapsed_quads},
                         {"removed_quads", choice.extraction.quads.num_quads() - folded->extraction.quads.num_quads()},
                         {"flipped_before", choice.untangle.flipped_after},
                         {"flipped_after", folded->untangle.flipped_after},
                         {"collapsed_edge_quads_before", folded->untangle.collapsed_before},
                         {"collapsed_edge_quads_after", folded->untangle.collapsed_after}});
    state.collapsed_quads = std::move(folded);
  }
  if (!collapsed.empty()) report_["extraction"]["collapsed"] = std::move(collapsed);
  Json& rescue_seconds = report_["timings_s"]["rescue"];
  rescue_seconds = rescue_seconds.get<double>() + timer.seconds();
}

void Session::refine_parts_with_collapsed_edges(Progress& progress) {
  Timer timer;
  const std::vector<double> targets = rescue_quad_targets();
  double quads_made = 0;
  for (const ComponentState& state : components_)
    if (state.quadded()) quads_made += state.quad_choice().extraction.quads.num_quads();
  for (size_t c = 0; c < components_.size(); ++c) {
    ComponentState& state = components_[c];
    if (!state.quadded() || state.split_quads ||
        state.quad_choice().extraction.quads.num_quads() > kFinerFlipShare * quads_made)
      continue;
    const int collapsed = quads_with_a_collapsed_edge(state.quad_choice().extraction.quads);
    if (collapsed == 0) continue;
    std::optional<ComponentState> best = quad_finer_with_fewer_defects(state, targets[c], true, progress);
    if (!best) continue;
    if (!best->failure)
      best->failure = PartFailure{"quad_extraction", ErrorCode::StageFailed,
                                  std::to_string(collapsed) +
                                      " quad(s) kept a collapsed edge at the density asked (its quads fold "
                                      "onto each other)"};
    state = std::move(*best);
  }
  Json& rescue_seconds = report_["timings_s"]["rescue"];
  rescue_seconds = rescue_seconds.get<double>() + timer.seconds();
}

void Session::mark_fields_without_cancelled_pairs() {
  Json& per_component = report_["field"]["components"];
  for (size_t c = 0; c < components_.size(); ++c)
    if (components_[c].without_cancelled_pairs) per_component[c]["close_pairs_kept"] = true;
}

void Session::throw_if_every_component_failed() const {
  if (components_.empty()) throw Error(ErrorCode::InvalidMesh, "no part of the mesh is left to remesh");
  for (const ComponentState& state : components_)
    if (state.quadded()) return;
  const PartFailure& first = *components_.front().failure;
  throw Error(first.code, "component 0: " + first.message + " (and every other component failed as well)");
}

void Session::run_remesh_stages(Job job, Progress& progress) {
  prepare_components(job, progress);
  for (ComponentState& state : components_) {
    state.failure.reset();
    state.split_quads.reset();
    state.collapsed_quads.reset();
    state.finer_edge_factor = 1;
    state.without_cancelled_pairs = false;
    state.rescued_on_remesh = false;
  }
  report_["working_mesh"] = working_mesh_report(components_);
  add_preparation_repairs();
  const double edge_length = target_edge_length();
  for_each_component(job, "cross_field", progress,
                     [&](ComponentState& s) { update_cross_field(s, edge_length, true, progress); });
  for_each_component(job, "cut_graph", progress, [&](ComponentState& s) { update_cut_graph(s, progress); });
  report_["field"] = field_report(components_);
  for_each_component(job, "seamless_map", progress, [&](ComponentState& s) {
    const bool remesh_follows = remesh_follows_a_folded_start(s, job, rescues_failed_components(job));
    update_seamless_map(s, edge_length, component_face_sizes(s), progress, remesh_follows);
    if (seamless_map_folds_where_pairs_were_cancelled(s) && keep_pairs_near_folds(s, progress)) {
      update_cut_graph(s, progress);
      update_seamless_map(s, edge_length, component_face_sizes(s), progress, remesh_follows);
    }
    if (!seamless_map_folds_where_pairs_were_cancelled(s)) return;
    update_cross_field(s, edge_length, false, progress);
    update_cut_graph(s, progress);
    update_seamless_map(s, edge_length, component_face_sizes(s), progress, remesh_follows);
  });
  report_["field"] = field_report(components_);  // again: a component may have fallen back
  report_["seamless"] = seamless_report(components_, edge_length);
  for_each_component(job, "tmesh", progress, [&](ComponentState& s) { update_tmesh(s, progress); });
  report_["tmesh"] = tmesh_report(components_);
  const std::vector<double> quad_targets = component_quad_targets();
  for_each_component(job, "quantization", progress, [&](ComponentState& s) {
    update_quantization(s, edge_length, quad_targets[&s - components_.data()], options_.quantizer, progress);
  });
  report_["quantization"] = quantization_report(components_, options_.quantizer, options_.symmetry.copies());
  for_each_component(job, "igm", progress, [&](ComponentState& s) {
    update_integer_grid_map(s, job, progress);
    if (options_.fallback_uv_map) update_cell_map(s, progress);
  });
  report_["igm"] = igm_report(components_);
  if (job == Job::Remesh) {
    for_each_component(job, "quad_extraction", progress, [&](ComponentState& s) { update_quads(s, progress); });
    report_["extraction"] = extraction_report(components_, report_["igm"]);
    if (rescues_failed_components(job)) {
      rescue_failed_components(job, progress);
      remesh_parts_off_their_surface(job, progress);
      rescue_flipped_components(progress);
      collapse_folded_components(progress);
      refine_parts_with_collapsed_edges(progress);
      mark_fields_without_cancelled_pairs();
      report_["working_mesh"] = working_mesh_report(components_);  // with the parts rescued on a remesh
    }
  }
  if (!half_) collect_grid_uvs();  // the map of the input's own triangles (a half has other triangles)
  if (job == Job::Remesh) collect_quads(progress);
  report_failed_components();
}

void Session::note_rescued_components(Json rescued) {
  int64_t quads = 0;
  for (const Json& s : rescued) quads += s["quads"].get<int64_t>();
  Json& count = report_["quantization"]["count"];
  std::string made;  // the count asked (not the quantization's, 0 when no part got that far)
  if (!(options_.edge_length > 0))
    made = std::to_string(std::lround(asked_quads() * options_.symmetry.copies())) + " quads asked, " +
           std::to_string(report_["quad"].value("faces", 0)) + " made: ";
  count["note"] = made + std::to_string(rescued.size()) +
                  " part(s) rescued (their layouts gave no valid quads, or flipped ones) with " +
                  std::to_string(quads) +
                  " quads, on an isotropic remesh of their triangles, with the field without cancelled "
                  "singularity pairs, at a finer density or by splitting their triangles (report: rescued_components)";
  report_["rescued_components"] = std::move(rescued);
}

namespace {
const char* rescue_name(const ComponentState& state) {
  if (state.rescued_on_remesh) return "isotropic working mesh";
  if (state.split_quads) return "split triangles";
  return state.finer_edge_factor < 1 ? "finer density" : "field without cancelled pairs";
}
}  // namespace

void Session::report_failed_components() {
  Json failed = Json::array(), rescued = Json::array();
  for (size_t c = 0; c < components_.size(); ++c) {
    const std::optional<PartFailure>& failure = components_[c].failure;
    if (!failure) continue;
    if (components_[c].quadded()) {
      const ComponentState& state = components_[c];
      rescued.push_back({{"component", c},
                         {"triangles", intake_->components[c].faces.size()},
                         {"quads", state.quad_choice().extraction.quads.num_quads()},
                         {"rescue", rescue_name(state)},
                         {"edge_length_factor", state.finer_edge_factor},
                         {"stage", failure->stage},
                         {"code", error_code_name(failure->code)},
                         {"message", failure->message}});
      continue;
    }
    failed.push_back({{"component", c},
                      {"triangles", intake_->components[c].faces.size()},
                      {"stage", failure->stage},
                      {"code", error_code_name(failure->code)},
                      {"message", failure->message}});
  }
  // Non-orientable parts, set aside at intake, follow the intake's components in numbering.
  for (size_t k = 0; k < intake_->non_orientable_parts.size(); ++k)
    failed.push_back({{"component", components_.size() + k},
                      {"triangles", intake_->non_orientable_parts[k].triangles.size()},
                      {"stage", "intake"},
                      {"code", error_code_name(ErrorCode::InvalidMesh)},
                      {"message", "non-orientable (a surface without two sides has no quad mesh)"}});
  if (!rescued.empty()) note_rescued_components(std::move(rescued));
  if (failed.empty()) return;
  report_["status"] = "partial";
  report_["failed_components"] = std::move(failed);
}

void Session::fill_missing_corner_uvs(const std::vector<std::pair<int, int>>& made_from) {
  // Corners the per-vertex matching left NaN: those of input triangles intake removed (zero-area,
  // needles, caps), and those whose input vertex a needle's collapse merged away. They get the map of
  // the triangle made from their input triangle, else of the one nearest its centroid, extended
  // affinely: one chart, a (nearly) degenerate uv triangle where the 3D one is. Triangles of
  // components remeshed on a working mesh stay NaN (their map is not on these triangles).
  std::vector<std::unique_ptr<TriangleBvh>> bvh(components_.size());
  std::vector<char> kept(input_.num_faces(), 0), failed(input_.num_faces(), 0);
  for (int f : intake_->input_face) kept[f] = 1;
  for (size_t c = 0; c < components_.size(); ++c)
    if (components_[c].failure)
      for (int f : intake_->components[c].faces) failed[intake_->input_face[f]] = 1;
  for (const NonOrientablePart& part : intake_->non_orientable_parts)
    for (int f : part.input_face) failed[f] = 1;
  for (int f = 0; f < input_.num_faces(); ++f) {
    if (input_.face_size(f) != 3) continue;
    bool missing = false;
    for (int i = 0; i < 6; ++i) missing = missing || std::isnan(corner_uv_[6 * f + i]);
    if (!missing || failed[f] || (kept[f] && made_from[f].first < 0)) continue;
    Vec3 corner[3], centroid = Vec3::Zero();
    for (int j = 0; j < 3; ++j)
      centroid += corner[j] = input_.positions[input_.face_vertices[input_.face_start[f] + j]];
    centroid /= 3;
    auto [component, t] = made_from[f];
    if (component < 0) {
      double nearest = std::numeric_limits<double>::infinity();
      for (size_t c = 0; c < components_.size(); ++c) {
        if (components_[c].full_mesh || components_[c].failure || !components_[c].igm.has_value()) continue;
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
      w[k] = Vec2(state.igm->map.to_double(state.igm->map.uv[3 * t + k][0]),
                  state.igm->map.to_double(state.igm->map.uv[3 * t + k][1]));
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

void Session::collect_grid_uvs() {
  // Per-corner integer-grid UVs of the input triangles: corners are matched by input vertex (faces
  // split by the pipeline share their corners with the input triangle).
  corner_uv_.assign(static_cast<size_t>(input_.num_faces()) * 6, std::numeric_limits<double>::quiet_NaN());
  std::set<std::array<int, 2>> cuts;
  std::vector<std::pair<int, int>> made_from(input_.num_faces(), {-1, -1});  // (component, face)
  for (size_t c = 0; c < components_.size(); ++c) {
    const ComponentState& state = components_[c];
    if (state.full_mesh || state.failure) continue;  // no map on the input triangles
    const ExactParametrization& igm = state.igm->map;
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
          if (iv >= 0 && intake_->weld_target[input_.face_vertices[input_.face_start[input_face] + j]] == iv) {
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
      const bool same =
          igm.uv[h] == igm.uv[3 * (o / 3) + (o + 1) % 3] && igm.uv[3 * (h / 3) + (h + 1) % 3] == igm.uv[o];
      const int ia = input_vertex(a), ib = input_vertex(b);
      if (!same && ia >= 0 && ib >= 0) cuts.insert({std::min(ia, ib), std::max(ia, ib)});
    }
  }
  cut_edges_.assign(cuts.begin(), cuts.end());
  fill_missing_corner_uvs(made_from);
}

void Session::collect_quads(Progress& progress) {
  Timer timer;
  progress.begin_stage("metrics");
  quads_ = std::make_unique<QuadMesh>();
  std::vector<int> quadded, failed;
  for (size_t c = 0; c < components_.size(); ++c) {
    const ComponentState& state = components_[c];
    (state.quadded() ? quadded : failed).push_back(static_cast<int>(c));
    if (!state.quadded()) continue;
    const QuadMesh& part = state.quad_choice().extraction.quads;
    append_quad_mesh(*quads_, part, static_cast<int>(c));
    if (half_) continue;  // mirror_results finds every quad's face on the whole input
    for (const int f : intake_faces_under_quad_centres(part, state))
      quad_source_face_.push_back(f < 0 ? -1 : input_face_of(f));
  }
  collect_kept_triangles(failed);
  if (half_) mirror_results();
  report_["quad"] = measure_quads(quadded, failed.empty(), progress);
  report_["timings_s"]["metrics"] = timer.seconds();
}

Json Session::measure_quads(const std::vector<int>& quadded, bool all_quadded, Progress& progress) const {
  // Measured against the components the quads stand for (kept ones are their own triangles), each
  // quad's flip against its own component (not a part it passes through).
  QuadMetricsOptions options;
  options.hausdorff_samples = 20000;
  std::vector<int> component_of(intake_->mesh.num_faces(), -1);
  for (size_t c = 0; c < intake_->components.size(); ++c)
    for (int f : intake_->components[c].faces) component_of[f] = static_cast<int>(c);
  if (all_quadded && !half_) {
    options.reference_component = std::move(component_of);
    return compute_quad_metrics(*quads_, intake_->mesh, options, progress);
  }
  std::vector<int> face_map;
  TriMesh reference = extract_components(*intake_, quadded, nullptr, &face_map);
  for (int f : face_map) options.reference_component.push_back(component_of[f]);
  if (half_) reference = mirrored_reference(reference, options.reference_component);
  return compute_quad_metrics(*quads_, reference, options, progress);
}

void Session::collect_kept_triangles(const std::vector<int>& failed) {
  kept_triangles_.reset();
  kept_source_face_.clear();
  kept_component_.clear();
  if (failed.empty() && intake_->non_orientable_parts.empty()) return;
  std::vector<int> face_map;
  const TriMesh failed_parts = extract_components(*intake_, failed, nullptr, &face_map);
  kept_triangles_ = std::make_unique<TriMesh>();  // V and F only: a non-orientable part has no halfedges
  kept_triangles_->V = failed_parts.V;
  kept_triangles_->F = failed_parts.F;
  for (int f : face_map) kept_source_face_.push_back(input_face_of(f));
  for (int c : failed) kept_component_.insert(kept_component_.end(), intake_->components[c].faces.size(), c);
  for (size_t k = 0; k < intake_->non_orientable_parts.size(); ++k)
    append_non_orientable_part(intake_->non_orientable_parts[k], static_cast<int>(components_.size() + k));
}

void Session::append_non_orientable_part(const NonOrientablePart& part, int component) {
  TriMesh& kept = *kept_triangles_;
  const int base = kept.num_vertices(), first = kept.num_faces();
  kept.V.conservativeResize(base + static_cast<int>(part.positions.size()), 3);
  for (size_t v = 0; v < part.positions.size(); ++v) kept.V.row(base + v) = part.positions[v].transpose();
  kept.F.conservativeResize(first + static_cast<int>(part.triangles.size()), 3);
  for (size_t t = 0; t < part.triangles.size(); ++t)
    for (int j = 0; j < 3; ++j) kept.F(first + t, j) = base + part.triangles[t][j];
  for (int f : part.input_face) kept_source_face_.push_back(half_ ? half_->input_face[f] : f);
  kept_component_.insert(kept_component_.end(), part.triangles.size(), component);
}

}  // namespace qgp

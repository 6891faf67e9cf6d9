#include "seamless_map/seamless_map.h"

#include <cmath>
#include <memory>
#include <string>

#include "core/error.h"
#include "seamless_map/parametrization_problem.h"

namespace qgp {

IsolineSelection select_isolines(const TriMesh& mesh, const CrossField& field, const CutGraph& cut) {
  const int ne = mesh.num_edges(), nf = mesh.num_faces();
  const bool have_sectors = static_cast<int>(cut.edge_sector.size()) == 3 * nf;
  // Axis and misalignment (radians) of each feature/boundary halfedge in its face's chart.
  auto axis_of = [&](int h, double* deviation) {
    const int f = TriMesh::face(h);
    const Vec3 n = mesh.face_normal_unnormalized(f).normalized();
    const Vec3 fu = (cut.frame_u[f] - cut.frame_u[f].dot(n) * n).normalized();
    const Vec3 d = mesh.edge_vector(h);
    const double angle = std::atan2(d.dot(n.cross(fu)), d.dot(fu));
    int q = have_sectors && cut.edge_sector[h] >= 0 ? cut.edge_sector[h]
                                                    : static_cast<int>(std::lround(angle / (M_PI / 2)));
    q = ((q % 4) + 4) % 4;
    double dev = angle - q * M_PI / 2;
    dev = std::remainder(dev, 2 * M_PI);
    if (deviation) *deviation = std::abs(dev);
    return q % 2 == 0 ? 1 : 0;  // q even: the edge runs along u, so v is constant
  };
  std::vector<char> iso(ne, 0);
  for (int e = 0; e < ne; ++e)
    iso[e] = mesh.is_boundary_edge(e) || (!field.feature_edge.empty() && field.feature_edge[e]);
  IsolineSelection out;
  // A triangle cannot have two isoline edges of one axis (its three corners would share that
  // coordinate): drop the worse aligned edge of such a pair (e.g. the third feature edge of a
  // triangle with three).
  for (bool changed = true; changed;) {
    changed = false;
    for (int f = 0; f < nf; ++f) {
      int worst = -1;
      double worst_dev = -1;
      int count[2] = {0, 0};
      for (int k = 0; k < 3; ++k) {
        const int h = 3 * f + k;
        if (!iso[mesh.edge_of[h]]) continue;
        ++count[axis_of(h, nullptr)];
      }
      if (count[0] < 2 && count[1] < 2) continue;
      for (int k = 0; k < 3; ++k) {
        const int h = 3 * f + k;
        if (!iso[mesh.edge_of[h]]) continue;
        double dev = 0;
        const int a = axis_of(h, &dev);
        if (count[a] >= 2 && dev > worst_dev) worst = h, worst_dev = dev;
      }
      iso[mesh.edge_of[worst]] = 0;
      out.dropped.push_back(mesh.edge_of[worst]);
      changed = true;
    }
  }
  for (int e = 0; e < ne; ++e) {
    if (!iso[e]) continue;
    const int h = mesh.edge_halfedge[e];
    Isoline line;
    line.halfedge = h;
    line.axis = axis_of(h, &line.misalignment);
    out.isolines.push_back(line);
  }
  return out;
}

namespace {

// The corners of param's flipped and degenerate triangles and the vertices wound off their cone
// (ascending, each once).
std::vector<int> bad_vertices(const TriMesh& mesh, const Parametrization& param,
                              const ParametrizationProblem& problem) {
  std::vector<char> bad(mesh.num_vertices(), 0);
  const std::vector<double> area = parametric_areas(param);
  for (int f = 0; f < mesh.num_faces(); ++f)
    if (!(area[f] > 0))
      for (int k = 0; k < 3; ++k) bad[mesh.F(f, k)] = 1;
  for (int v : problem.wound_vertices(param)) bad[v] = 1;
  std::vector<int> vertices;
  for (int v = 0; v < mesh.num_vertices(); ++v)
    if (bad[v]) vertices.push_back(v);
  return vertices;
}

}  // namespace

SeamlessMap compute_seamless_map(const TriMesh& mesh, const CrossField& field, const CutGraph& cut,
                                 const SeamlessMapOptions& options, Progress& progress) {
  progress.check_cancel();
  const int nf = mesh.num_faces(), ne = mesh.num_edges();
  if (static_cast<int>(cut.rotation.size()) != 3 * nf || static_cast<int>(cut.frame_u.size()) != nf ||
      static_cast<int>(cut.is_cut.size()) != ne)
    throw Error(ErrorCode::Internal, "seamless map: the cut graph does not match the mesh");
  if (!field.feature_edge.empty() && static_cast<int>(field.feature_edge.size()) != ne)
    throw Error(ErrorCode::Internal, "seamless map: the feature edges do not match the mesh");
  if (!(options.edge_length > 0) || !std::isfinite(options.edge_length))
    throw Error(ErrorCode::InvalidArgument, "seamless map: the target edge length must be positive");

  // Isoline constraints that alone collapse a triangle (e.g. a sliver between two nearly collinear
  // feature edges that the field maps to orthogonal isolines) are dropped, the worst aligned
  // edge of each such triangle first, until no triangle is forced degenerate.
  IsolineSelection iso = select_isolines(mesh, field, cut);
  std::unique_ptr<ParametrizationProblem> problem;
  for (int attempt = 0;; ++attempt) {
    problem = std::make_unique<ParametrizationProblem>(mesh, cut.rotation, cut.is_cut, cut.frame_u, options.edge_length,
                                                       options.face_size);
    for (const Isoline& line : iso.isolines) problem->add_isoline(line.halfedge, line.axis);
    const std::vector<int> forced = problem->forced_degenerate_faces(progress);
    if (forced.empty() || attempt == 8) break;
    std::vector<int> isoline_of_edge(ne, -1);
    for (size_t i = 0; i < iso.isolines.size(); ++i)
      isoline_of_edge[mesh.edge_of[iso.isolines[i].halfedge]] = static_cast<int>(i);
    std::vector<char> drop(iso.isolines.size(), 0);
    bool any = false;
    for (int f : forced) {
      int worst = -1;
      for (int k = 0; k < 3; ++k) {
        const int i = isoline_of_edge[mesh.edge_of[3 * f + k]];
        if (i >= 0 && (worst < 0 || iso.isolines[i].misalignment > iso.isolines[worst].misalignment)) worst = i;
      }
      if (worst >= 0 && !drop[worst]) drop[worst] = 1, any = true;
    }
    if (!any) break;
    std::vector<Isoline> kept;
    for (size_t i = 0; i < iso.isolines.size(); ++i) {
      if (drop[i])
        iso.dropped.push_back(mesh.edge_of[iso.isolines[i].halfedge]);
      else
        kept.push_back(iso.isolines[i]);
    }
    iso.isolines.swap(kept);
  }
  const int isolines = static_cast<int>(iso.isolines.size());

  // The field's cone angles, for the map's winding check.
  if (!field.vertex_index.empty()) problem->set_cone_angles(cone_quarter_turns(mesh, field));
  ParametrizationSolveOptions solve_options;
  solve_options.regularity = options.regularity ? RegularityMode::Repair : RegularityMode::Off;
  solve_options.max_repair_rounds = options.max_repair_rounds;
  solve_options.region_stagnation_rounds = options.region_stagnation_rounds;
  solve_options.count_stagnation_rounds = options.count_stagnation_rounds;
  solve_options.winding_repair = options.winding_repair;
  solve_options.field_frame_solve = options.field_frame_solve;
  solve_options.move_shared_coordinates = options.move_shared_coordinates;
  solve_options.max_bad_share_to_repair = options.max_bad_share_to_repair;
  ParametrizationSolution solution = problem->solve(solve_options, progress);

  SeamlessMap out;
  out.param = std::move(solution.param);
  out.face_size = options.face_size;
  const ParametrizationSolveStats& s = solution.stats;
  SeamlessMapStats& st = out.stats;
  st.flipped_triangles = s.flipped;
  st.degenerate_triangles = s.degenerate;
  st.winding_defects = s.winding_defects;
  if (st.flipped_triangles + st.degenerate_triangles + st.winding_defects > 0)
    out.bad_vertices = bad_vertices(mesh, out.param, *problem);
  st.max_transition_residual = max_transition_residual(mesh, out.param);
  st.energy = s.energy;
  st.ipopt_iterations = s.ipopt_iterations;
  st.flipped_before_ipopt = s.flipped_initial;
  st.degenerate_before_ipopt = s.degenerate_initial;
  st.forced_degenerate = s.forced_degenerate;
  st.isoline_edges = isolines;
  st.dropped_isolines = static_cast<int>(iso.dropped.size());
  st.dropped_isoline_edges = iso.dropped;
  st.ipopt_solves = s.ipopt_solves;
  st.qp_by_ipopt = s.qp_by_ipopt;
  st.repair_rounds = s.repair_rounds;
  st.field_frame_solves = s.field_frame_solves;
  st.moved_shared_coordinates = s.moved_shared_coordinates;
  st.repair_declined = s.repair_declined;
  st.max_region_faces = s.max_region_faces;
  st.repair_bad_faces = s.bad_after_round;
  st.repair_seconds = s.seconds_of_round;
  st.min_area_ratio = s.min_area_ratio;
  st.seconds_cholesky = s.seconds_cholesky;
  st.seconds_ipopt = s.seconds_ipopt;
  return out;
}

}  // namespace qgp

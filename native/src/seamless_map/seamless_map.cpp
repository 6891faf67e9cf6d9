#include "seamless_map/seamless_map.h"

#include <cmath>
#include <string>

#include "core/error.h"
#include "seamless_map/parametrization_problem.h"

namespace qgp {

int isoline_axis(const TriMesh& mesh, const Vec3& frame_u, int h) {
  const int f = TriMesh::face(h);
  const Vec3 n = mesh.face_normal_unnormalized(f).normalized();
  const Vec3 fu = (frame_u - frame_u.dot(n) * n).normalized();
  const Vec3 fv = n.cross(fu);
  const Vec3 d = mesh.edge_vector(h);
  // An edge running along u has constant v.
  return std::abs(d.dot(fu)) >= std::abs(d.dot(fv)) ? 1 : 0;
}

SeamlessMap compute_seamless_map(const TriMesh& mesh, const CrossField& field, const CutGraph& cut,
                                 const SeamlessMapOptions& options, Progress& progress) {
  progress.begin_stage("seamless_map");
  const int nf = mesh.num_faces(), ne = mesh.num_edges();
  if (static_cast<int>(cut.rotation.size()) != 3 * nf || static_cast<int>(cut.frame_u.size()) != nf ||
      static_cast<int>(cut.is_cut.size()) != ne)
    throw Error(ErrorCode::Internal, "seamless map: the cut graph does not match the mesh");
  if (!field.feature_edge.empty() && static_cast<int>(field.feature_edge.size()) != ne)
    throw Error(ErrorCode::Internal, "seamless map: the feature edges do not match the mesh");
  if (!(options.edge_length > 0) || !std::isfinite(options.edge_length))
    throw Error(ErrorCode::InvalidArgument, "seamless map: the target edge length must be positive");

  ParametrizationProblem problem(mesh, cut.rotation, cut.is_cut, cut.frame_u, options.edge_length);
  int isolines = 0;
  for (int e = 0; e < ne; ++e) {
    const bool feature = !field.feature_edge.empty() && field.feature_edge[e];
    if (!feature && !mesh.is_boundary_edge(e)) continue;
    const int h = mesh.edge_halfedge[e];
    problem.add_isoline(h, isoline_axis(mesh, cut.frame_u[TriMesh::face(h)], h));
    ++isolines;
  }

  ParametrizationSolveOptions solve_options;
  solve_options.regularity = options.regularity ? RegularityMode::Repair : RegularityMode::Off;
  ParametrizationSolution solution = problem.solve(solve_options, progress);

  SeamlessMap out;
  out.param = std::move(solution.param);
  const ParametrizationSolveStats& s = solution.stats;
  SeamlessMapStats& st = out.stats;
  st.flipped_triangles = s.flipped;
  st.degenerate_triangles = s.degenerate;
  st.max_transition_residual = max_transition_residual(mesh, out.param);
  st.energy = s.energy;
  st.ipopt_iterations = s.ipopt_iterations;
  st.flipped_before_ipopt = s.flipped_initial;
  st.degenerate_before_ipopt = s.degenerate_initial;
  st.forced_degenerate = s.forced_degenerate;
  st.isoline_edges = isolines;
  st.ipopt_solves = s.ipopt_solves;
  st.regions_grown = std::max(0, s.repair_rounds - 1);
  st.max_region_faces = s.max_region_faces;
  st.min_area_ratio = s.min_area_ratio;
  st.seconds_cholesky = s.seconds_cholesky;
  st.seconds_ipopt = s.seconds_ipopt;
  return out;
}

}  // namespace qgp

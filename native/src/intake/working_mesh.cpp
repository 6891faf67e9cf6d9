#include "intake/working_mesh.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <optional>

#include "core/error.h"
#include "intake/edge_collapse.h"
#include "intake/isotropic_remesh.h"

namespace qgp {

namespace {

// Same Euler characteristic and number of boundary loops.
bool same_topology(const TriMesh& input, const TriMesh& working) {
  const int chi_in = input.num_vertices() - input.num_edges() + input.num_faces();
  const int chi_out = working.num_vertices() - working.num_edges() + working.num_faces();
  return chi_in == chi_out && count_boundary_loops(input) == count_boundary_loops(working);
}

// About max_faces equilateral triangles over the mesh's area.
std::optional<WorkingMesh> remeshed_working_mesh(const TriMesh& mesh, const std::vector<char>& feature_edges,
                                                 int max_faces) {
  double area = 0;
  for (int f = 0; f < mesh.num_faces(); ++f) area += 0.5 * mesh.face_normal_unnormalized(f).norm();
  IsotropicRemeshOptions options;
  options.edge_length = std::sqrt(area / (max_faces * std::sqrt(3.0) / 4));
  std::optional<RemeshedSurface> remeshed = remesh_isotropic(mesh, feature_edges, options);
  if (!remeshed) return std::nullopt;
  WorkingMesh result;
  result.mesh = std::move(remeshed->mesh);
  result.feature_edges = std::move(remeshed->feature_edges);
  result.vertex_of_input = std::move(remeshed->nearest_input_vertex);
  result.remeshed = true;
  return result;
}

bool has_feature_edges(const std::vector<char>& feature_edges) {
  return std::find(feature_edges.begin(), feature_edges.end(), 1) != feature_edges.end();
}

}  // namespace

int working_face_budget(double target_quads) {
  const double budget = kWorkingFacesPerQuad * (target_quads > 0 ? target_quads : 0.0);  // NaN: none
  return static_cast<int>(std::min(std::max(budget, double(kMinWorkingFaces)), 1e9));
}

bool has_needles_across_features(const TriMesh& mesh, const std::vector<char>& feature_edges) {
  return has_feature_edges(feature_edges) && needle_area_share(mesh) > kRemeshAboveNeedleShare;
}

bool has_coarse_triangles_across_features(const TriMesh& mesh, const std::vector<char>& feature_edges,
                                          double edge_length) {
  return has_feature_edges(feature_edges) &&
         coarse_area_share(mesh, kCoarseEdgeInQuads * edge_length) > kRemeshAboveNeedleShare;
}

double remesh_faces_per_quad(const TriMesh& mesh, const std::vector<char>& feature_edges) {
  return has_needles_across_features(mesh, feature_edges) ? kWorkingFacesPerQuad : kCoarseRemeshFacesPerQuad;
}

int remesh_face_budget(double target_quads, double area_share, double faces_per_quad) {
  const double faces = std::max(faces_per_quad * target_quads, kMinWorkingFaces * area_share);
  return static_cast<int>(std::min(std::max(faces, 1.0), 1e9));  // NaN: 1
}

WorkingMesh make_working_mesh(const TriMesh& mesh, const std::vector<char>& feature_edges, int max_faces,
                              int remesh_faces, Progress& progress) {
  if (remesh_faces > 0)
    if (std::optional<WorkingMesh> remeshed = remeshed_working_mesh(mesh, feature_edges, remesh_faces))
      return *remeshed;
  auto keep_input = [&] {
    WorkingMesh copy;
    copy.mesh = mesh;
    copy.vertex_of_input.resize(mesh.num_vertices());
    std::iota(copy.vertex_of_input.begin(), copy.vertex_of_input.end(), 0);
    copy.feature_edges = feature_edges;
    return copy;
  };
  if (mesh.num_faces() <= kDecimateAboveBudget * max_faces) return keep_input();

  // Feature and boundary edges stay: their vertices never move or go.
  std::vector<char> locked(mesh.num_vertices(), 0);
  for (int e = 0; e < mesh.num_edges(); ++e)
    if (feature_edges[e] || mesh.is_boundary_edge(e)) {
      const int h = mesh.edge_halfedge[e];
      locked[mesh.from(h)] = locked[mesh.to(h)] = 1;
    }
  EdgeCollapseOptions options;
  options.max_faces = max_faces;
  const FaceMatrix faces = collapse_edges(mesh, locked, options, progress);
  if (faces.rows() == mesh.num_faces()) return keep_input();  // every vertex locked (or no legal collapse)

  // The kept vertices, in input order, with their input positions.
  WorkingMesh result;
  std::vector<char> kept(mesh.num_vertices(), 0);
  for (int i = 0; i < faces.size(); ++i) kept[faces.data()[i]] = 1;
  std::vector<int> working_index(mesh.num_vertices(), -1);
  for (int v = 0; v < mesh.num_vertices(); ++v)
    if (kept[v]) {
      working_index[v] = static_cast<int>(result.vertex_of_input.size());
      result.vertex_of_input.push_back(v);
    }
  result.mesh.V.resize(static_cast<int>(result.vertex_of_input.size()), 3);
  for (int v = 0; v < result.mesh.num_vertices(); ++v) result.mesh.V.row(v) = mesh.V.row(result.vertex_of_input[v]);
  result.mesh.F = faces;
  for (int i = 0; i < result.mesh.F.size(); ++i) result.mesh.F.data()[i] = working_index[result.mesh.F.data()[i]];
  try {
    build_connectivity(result.mesh);
  } catch (const Error&) {
    return keep_input();
  }
  if (!same_topology(mesh, result.mesh)) return keep_input();

  // Feature edges between locked vertices survive every collapse.
  std::map<std::pair<int, int>, int> input_edge;
  for (int e = 0; e < mesh.num_edges(); ++e)
    if (feature_edges[e]) {
      const int h = mesh.edge_halfedge[e];
      input_edge[std::minmax(mesh.from(h), mesh.to(h))] = e;
    }
  result.feature_edges.assign(result.mesh.num_edges(), 0);
  int carried = 0;
  for (int e = 0; e < result.mesh.num_edges(); ++e) {
    const int h = result.mesh.edge_halfedge[e];
    const auto key =
        std::minmax(result.vertex_of_input[result.mesh.from(h)], result.vertex_of_input[result.mesh.to(h)]);
    if (input_edge.count(key)) {
      result.feature_edges[e] = 1;
      ++carried;
    }
  }
  if (carried != static_cast<int>(input_edge.size())) return keep_input();
  result.decimated = true;
  return result;
}

}  // namespace qgp

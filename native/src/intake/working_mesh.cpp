#include "intake/working_mesh.h"

#include <algorithm>
#include <map>
#include <numeric>

#include "core/error.h"
#include "intake/edge_collapse.h"

namespace qgp {

namespace {

// Same Euler characteristic and number of boundary loops.
bool same_topology(const TriMesh& input, const TriMesh& working) {
  const int chi_in = input.num_vertices() - input.num_edges() + input.num_faces();
  const int chi_out = working.num_vertices() - working.num_edges() + working.num_faces();
  return chi_in == chi_out && count_boundary_loops(input) == count_boundary_loops(working);
}

}  // namespace

int working_face_budget(double target_quads) {
  const double budget = kWorkingFacesPerQuad * (target_quads > 0 ? target_quads : 0.0);  // NaN: none
  return static_cast<int>(std::min(std::max(budget, double(kMinWorkingFaces)), 1e9));
}

WorkingMesh make_working_mesh(const TriMesh& mesh, const std::vector<char>& feature_edges, int max_faces,
                              Progress& progress) {
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

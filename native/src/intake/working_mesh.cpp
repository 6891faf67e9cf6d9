#include "intake/working_mesh.h"

#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Tools/Decimater/DecimaterT.hh>
#include <OpenMesh/Tools/Decimater/ModAspectRatioT.hh>
#include <OpenMesh/Tools/Decimater/ModNormalFlippingT.hh>
#include <OpenMesh/Tools/Decimater/ModQuadricT.hh>
#include <algorithm>
#include <map>
#include <numeric>

#include "core/error.h"

namespace qgp {

namespace {

// Double precision: kept vertices keep their input coordinates bit for bit.
struct DoubleTraits : OpenMesh::DefaultTraits {
  using Point = OpenMesh::Vec3d;
  using Normal = OpenMesh::Vec3d;
};
using OmMesh = OpenMesh::TriMesh_ArrayKernelT<DoubleTraits>;

// Same Euler characteristic and number of boundary loops.
bool same_topology(const TriMesh& input, const TriMesh& working) {
  const int chi_in = input.num_vertices() - input.num_edges() + input.num_faces();
  const int chi_out = working.num_vertices() - working.num_edges() + working.num_faces();
  return chi_in == chi_out && count_boundary_loops(input) == count_boundary_loops(working);
}

}  // namespace

int working_face_budget(double target_quads) {
  const double budget = kWorkingFacesPerQuad * std::max(target_quads, 0.0);
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

  OmMesh om;
  om.request_vertex_status();
  om.request_edge_status();
  om.request_face_status();
  om.request_face_normals();
  OpenMesh::VPropHandleT<int> input_index;
  om.add_property(input_index);
  std::vector<OmMesh::VertexHandle> handles(mesh.num_vertices());
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    handles[v] = om.add_vertex(OmMesh::Point(mesh.V(v, 0), mesh.V(v, 1), mesh.V(v, 2)));
    om.property(input_index, handles[v]) = v;
  }
  for (int f = 0; f < mesh.num_faces(); ++f)
    if (!om.add_face(handles[mesh.F(f, 0)], handles[mesh.F(f, 1)], handles[mesh.F(f, 2)]).is_valid())
      return keep_input();  // cannot happen on a manifold, oriented component
  om.update_face_normals();
  // Feature and boundary edges stay: their vertices never move or go.
  for (int e = 0; e < mesh.num_edges(); ++e)
    if (feature_edges[e] || mesh.is_boundary_edge(e)) {
      const int h = mesh.edge_halfedge[e];
      om.status(handles[mesh.from(h)]).set_locked(true);
      om.status(handles[mesh.to(h)]).set_locked(true);
    }
  progress.check_cancel();

  OpenMesh::Decimater::DecimaterT<OmMesh> decimater(om);
  OpenMesh::Decimater::ModQuadricT<OmMesh>::Handle quadric;
  OpenMesh::Decimater::ModNormalFlippingT<OmMesh>::Handle normal_flipping;
  OpenMesh::Decimater::ModAspectRatioT<OmMesh>::Handle aspect_ratio;
  decimater.add(quadric);
  decimater.add(normal_flipping);
  decimater.add(aspect_ratio);
  decimater.module(quadric).unset_max_err();
  decimater.module(normal_flipping).set_max_normal_deviation(60.0);
  decimater.module(aspect_ratio).set_binary(true);
  decimater.module(aspect_ratio).set_aspect_ratio(5.0);
  if (!decimater.initialize()) return keep_input();
  const size_t collapses = decimater.decimate_to_faces(0, static_cast<size_t>(max_faces));
  progress.check_cancel();
  if (collapses == 0) return keep_input();  // every vertex locked (or no legal collapse)
  om.garbage_collection();

  // Back to a TriMesh (OpenMesh keeps the orientation of every face).
  WorkingMesh result;
  result.mesh.V.resize(static_cast<int>(om.n_vertices()), 3);
  result.vertex_of_input.resize(om.n_vertices());
  for (const auto vh : om.vertices()) {
    const int v = vh.idx();
    result.vertex_of_input[v] = om.property(input_index, vh);
    result.mesh.V.row(v) = mesh.V.row(result.vertex_of_input[v]);
  }
  result.mesh.F.resize(static_cast<int>(om.n_faces()), 3);
  for (const auto fh : om.faces()) {
    int k = 0;
    for (const auto vh : om.fv_ccw_range(fh)) result.mesh.F(fh.idx(), k++) = vh.idx();
  }
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

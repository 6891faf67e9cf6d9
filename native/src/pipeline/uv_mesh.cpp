#include "pipeline/uv_mesh.h"

#include "core/error.h"
#include "pipeline/policy.h"

namespace qgp {

bool available_uv_map(const Session& session, UvMapKind* kind) {
  if (session.intake() == nullptr || session.components().empty()) return false;
  bool igm = true, seamless = true, any = false;
  for (const ComponentState& c : session.components()) {
    if (c.failure) continue;  // kept as triangles: not in the uv mesh
    any = true;
    igm = igm && c.igm_is_current();
    seamless = seamless && c.seamless_is_current();
  }
  if (kind) *kind = igm ? UvMapKind::IntegerGrid : UvMapKind::Seamless;
  return any && (igm || seamless);
}

UvMesh compose_uv_mesh(const Session& session, UvMapKind kind) {
  UvMapKind available = UvMapKind::Seamless;
  if (!available_uv_map(session, &available) || (kind == UvMapKind::IntegerGrid && available != kind))
    throw Error(ErrorCode::NotReady, kind == UvMapKind::IntegerGrid
                                         ? "no integer-grid map: run a grid-UV or remesh job first"
                                         : "no seamless map: run a grid-UV or remesh job first");
  const IntakeResult& intake = *session.intake();
  const bool grid = kind == UvMapKind::IntegerGrid;
  auto refined = [&](const ComponentState& c) { return grid && cell_map_in_use(c) != nullptr; };
  auto mesh_of = [&](const ComponentState& c) -> const TriMesh& {
    return refined(c) ? cell_map_in_use(c)->mesh : c.mesh;
  };

  UvMesh out;
  int num_vertices = intake.mesh.num_vertices(), num_faces = 0;
  for (const ComponentState& c : session.components()) {
    if (c.failure) continue;
    for (int v : c.vertex_map) num_vertices += v < 0;
    num_vertices += mesh_of(c).num_vertices() - c.mesh.num_vertices();
    num_faces += mesh_of(c).num_faces();
    out.refined_components += refined(c);
  }
  out.mesh.V.resize(num_vertices, 3);
  out.mesh.V.topRows(intake.mesh.num_vertices()) = intake.mesh.V;
  out.mesh.F.resize(num_faces, 3);
  out.uv.resize(3 * static_cast<Eigen::Index>(num_faces), 2);
  out.source_face.assign(num_faces, -1);
  int next_vertex = intake.mesh.num_vertices(), face = 0;
  for (const ComponentState& c : session.components()) {
    if (c.failure) continue;
    const TriMesh& mesh = mesh_of(c);
    std::vector<int> id(mesh.num_vertices());
    for (int v = 0; v < mesh.num_vertices(); ++v) {
      id[v] = v < c.mesh.num_vertices() && c.vertex_map[v] >= 0 ? c.vertex_map[v] : next_vertex++;
      out.mesh.V.row(id[v]) = mesh.V.row(v);
    }
    for (int f = 0; f < mesh.num_faces(); ++f, ++face) {
      const int component_face = refined(c) ? cell_map_in_use(c)->source_face[f] : f;
      const int intake_face = component_face >= 0 ? c.face_map[component_face] : -1;
      out.source_face[face] = intake_face >= 0 ? intake.input_face[intake_face] : -1;
      for (int k = 0; k < 3; ++k) {
        out.mesh.F(face, k) = id[mesh.F(f, k)];
        if (refined(c))
          out.uv.row(3 * face + k) = cell_map_in_use(c)->corner_uv[3 * f + k].transpose();
        else if (grid)
          for (int a = 0; a < 2; ++a) out.uv(3 * face + k, a) = c.igm->map.to_double(c.igm->map.uv[3 * f + k][a]);
        else
          out.uv.row(3 * face + k) = c.seamless->param.uv.row(3 * f + k);
      }
    }
  }
  return out;
}

}  // namespace qgp

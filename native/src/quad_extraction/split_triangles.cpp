#include "quad_extraction/split_triangles.h"

namespace qgp {
namespace {

void mark_irregular_vertices(const TriMesh& mesh, QuadMesh& quads) {
  std::vector<int> valence(quads.num_vertices(), 0);
  std::vector<char> boundary(quads.num_vertices(), 0);
  for (int q = 0; q < quads.num_quads(); ++q)
    for (int k = 0; k < 4; ++k) ++valence[quads.Q(q, k)];
  for (int e = 0; e < mesh.num_edges(); ++e) {
    if (!mesh.is_boundary_edge(e)) continue;
    const int h = mesh.edge_halfedge[e];
    boundary[mesh.from(h)] = boundary[mesh.to(h)] = boundary[mesh.num_vertices() + e] = 1;
  }
  quads.vertex_singular.assign(quads.num_vertices(), 0);
  for (int v = 0; v < quads.num_vertices(); ++v) quads.vertex_singular[v] = valence[v] != (boundary[v] ? 2 : 4);
}

}  // namespace

QuadMesh split_triangles_into_quads(const TriMesh& mesh) {
  const int nv = mesh.num_vertices(), ne = mesh.num_edges(), nf = mesh.num_faces();
  QuadMesh quads;
  quads.V.resize(nv + ne + nf, 3);
  quads.vertex_face.assign(nv + ne + nf, -1);
  quads.V.topRows(nv) = mesh.V;
  for (int e = 0; e < ne; ++e) {
    const int h = mesh.edge_halfedge[e];
    quads.V.row(nv + e) = 0.5 * (mesh.V.row(mesh.from(h)) + mesh.V.row(mesh.to(h)));
    quads.vertex_face[nv + e] = TriMesh::face(h);
  }
  quads.Q.resize(3 * nf, 4);
  for (int f = 0; f < nf; ++f) {
    const int centre = nv + ne + f;
    quads.V.row(centre) = (mesh.V.row(mesh.F(f, 0)) + mesh.V.row(mesh.F(f, 1)) + mesh.V.row(mesh.F(f, 2))) / 3.0;
    quads.vertex_face[centre] = f;
    for (int k = 0; k < 3; ++k) {
      const int h = 3 * f + k;  // from corner k to corner k+1
      const int before = nv + mesh.edge_of[TriMesh::prev(h)], after = nv + mesh.edge_of[h];
      quads.Q.row(3 * f + k) << mesh.F(f, k), after, centre, before;
      quads.vertex_face[mesh.F(f, k)] = f;
    }
  }
  mark_irregular_vertices(mesh, quads);
  return quads;
}

}  // namespace qgp

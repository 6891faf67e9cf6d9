#include "pipeline/split_faces.h"

#include <algorithm>
#include <array>
#include <cstdint>
#include <unordered_set>

namespace qgp {

int split_overconstrained_faces(TriMesh& mesh, std::vector<char>& feature_edges, std::vector<int>& vertex_map,
                                std::vector<int>& face_map) {
  auto constrained = [&](int h) { return mesh.opposite[h] < 0 || feature_edges[mesh.edge_of[h]]; };
  std::vector<int> split;
  for (int f = 0; f < mesh.num_faces(); ++f)
    if (constrained(3 * f) && constrained(3 * f + 1) && constrained(3 * f + 2)) split.push_back(f);
  if (split.empty()) return 0;

  auto key = [](int a, int b) {
    return static_cast<uint64_t>(std::min(a, b)) << 32 | static_cast<uint32_t>(std::max(a, b));
  };
  std::unordered_set<uint64_t> feature_pairs;
  for (int e = 0; e < mesh.num_edges(); ++e)
    if (feature_edges[e]) feature_pairs.insert(key(mesh.from(mesh.edge_halfedge[e]), mesh.to(mesh.edge_halfedge[e])));

  const int nv = mesh.num_vertices(), nf = mesh.num_faces(), ns = static_cast<int>(split.size());
  TriMesh out;
  out.V.resize(nv + ns, 3);
  out.V.topRows(nv) = mesh.V;
  out.F.resize(nf + 2 * ns, 3);
  out.F.topRows(nf) = mesh.F;
  for (int i = 0; i < ns; ++i) {
    const int f = split[i], m = nv + i;
    const std::array<int, 3> t{mesh.F(f, 0), mesh.F(f, 1), mesh.F(f, 2)};
    out.V.row(m) = (mesh.V.row(t[0]) + mesh.V.row(t[1]) + mesh.V.row(t[2])) / 3.0;
    out.F.row(f) << t[0], t[1], m;
    out.F.row(nf + 2 * i) << t[1], t[2], m;
    out.F.row(nf + 2 * i + 1) << t[2], t[0], m;
    vertex_map.push_back(-1);
    face_map.push_back(face_map[f]);
    face_map.push_back(face_map[f]);
  }
  build_connectivity(out);
  feature_edges.assign(out.num_edges(), 0);
  for (int e = 0; e < out.num_edges(); ++e)
    if (feature_pairs.count(key(out.from(out.edge_halfedge[e]), out.to(out.edge_halfedge[e])))) feature_edges[e] = 1;
  mesh = std::move(out);
  return ns;
}

}  // namespace qgp

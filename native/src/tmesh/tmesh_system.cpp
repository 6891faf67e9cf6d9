#include "tmesh/tmesh_system.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>

#include "core/error.h"

namespace qgp {

TMeshCellSystem tmesh_cell_system(const TMesh& tmesh) {
  const int nc = static_cast<int>(tmesh.cells.size()), ne = static_cast<int>(tmesh.edges.size());
  std::vector<Eigen::Triplet<int>> triplets;
  for (int c = 0; c < nc; ++c) {
    const TMeshCell& cell = tmesh.cells[c];
    if (!cell.four_sided) continue;
    for (int s = 0; s < 4; ++s)
      for (int e : cell.sides[s]) triplets.emplace_back(2 * c + s % 2, e, s < 2 ? 1 : -1);
  }
  TMeshCellSystem sys;
  sys.A.resize(2 * nc, ne);
  sys.A.setFromTriplets(triplets.begin(), triplets.end());  // duplicates are summed
  sys.A.prune(0);
  sys.ideal_lengths.resize(ne);
  for (int e = 0; e < ne; ++e) sys.ideal_lengths[e] = tmesh.edges[e].length;
  return sys;
}

TMeshCheck check_tmesh(const TMesh& tmesh) {
  TMeshCheck check;
  for (const TMeshNode& n : tmesh.nodes) {
    check.singular_nodes += n.singular();
    check.t_junctions += n.kind == TMeshNode::Kind::TJunction;
  }
  for (const TMeshCell& cell : tmesh.cells) {
    if (!cell.four_sided) {
      ++check.cells_not_four_sided;
      continue;
    }
    for (int pair = 0; pair < 2; ++pair) {
      double a = 0, b = 0;
      for (int e : cell.sides[pair]) a += tmesh.edges[e].length;
      for (int e : cell.sides[pair + 2]) b += tmesh.edges[e].length;
      const double scale = std::max(a, b);
      if (scale > 0)
        check.max_cell_equation_residual = std::max(check.max_cell_equation_residual, std::fabs(a - b) / scale);
    }
  }
  const TMeshCellSystem sys = tmesh_cell_system(tmesh);
  for (int r = 0; r < sys.A.outerSize(); ++r)
    for (Eigen::SparseMatrix<int, Eigen::RowMajor>::InnerIterator it(sys.A, r); it; ++it)
      check.max_abs_coefficient = std::max(check.max_abs_coefficient, std::abs(it.value()));
  for (const TMeshEdge& e : tmesh.edges) {
    const int sides = (e.cells[0] >= 0) + (e.cells[1] >= 0);
    if (sides < 1 || (!e.on_feature && sides < 2)) ++check.edges_without_cells;
  }
  return check;
}

void to_json(Json& j, const TMesh& tmesh) {
  const TMeshCheck check = check_tmesh(tmesh);
  j = Json::object();
  j["nodes"] = tmesh.nodes.size();
  j["edges"] = tmesh.edges.size();
  j["cells"] = tmesh.cells.size();
  j["singular_nodes"] = check.singular_nodes;
  j["t_junctions"] = check.t_junctions;
  j["euler_characteristic"] = tmesh.euler_characteristic();
  j["cells_not_four_sided"] = check.cells_not_four_sided;
  j["max_cell_equation_residual"] = check.max_cell_equation_residual;
  j["trace_seconds"] = tmesh.stats.trace_seconds;
  j["motorcycles"] = tmesh.stats.motorcycles;
  j["head_on"] = tmesh.stats.head_on;
  j["crossings"] = tmesh.stats.crossings;
  j["virtual_corners"] = tmesh.stats.virtual_corners;
  j["seeds"] = tmesh.stats.seeds;
  j["steps"] = tmesh.stats.steps;
  j["walls_not_isolines"] = tmesh.stats.walls_not_isolines;
}

void write_layout_obj(std::ostream& out, const TriMesh& mesh, const TMesh& tmesh, long long& vertex_offset) {
  out.precision(17);
  // Nodes first, so that edges can end at the node points.
  const long long node_base = vertex_offset + 1;
  for (const TMeshNode& n : tmesh.nodes) {
    const Vec3 p = n.point.position(mesh);
    out << "v " << p.x() << ' ' << p.y() << ' ' << p.z() << '\n';
  }
  vertex_offset += static_cast<long long>(tmesh.nodes.size());
  if (!tmesh.nodes.empty()) {
    out << "p";
    for (size_t i = 0; i < tmesh.nodes.size(); ++i) out << ' ' << node_base + static_cast<long long>(i);
    out << '\n';
  }
  for (const TMeshEdge& e : tmesh.edges) {
    // Interior points of the path (consecutive duplicates at changes of face are skipped).
    std::vector<long long> ids{node_base + e.from};
    Vec3 last = tmesh.nodes[e.from].point.position(mesh);
    for (size_t k = 1; k + 1 < e.trace.size(); ++k) {
      const Vec3 p = e.trace[k].position(mesh);
      if ((p - last).norm() == 0) continue;
      out << "v " << p.x() << ' ' << p.y() << ' ' << p.z() << '\n';
      ids.push_back(++vertex_offset);
      last = p;
    }
    ids.push_back(node_base + e.to);
    out << "l";
    for (long long id : ids) out << ' ' << id;
    out << '\n';
  }
}

void write_layout_obj(const std::string& path, const std::vector<const TriMesh*>& meshes,
                      const std::vector<const TMesh*>& tmeshes) {
  std::ofstream out(path);
  if (!out) throw Error(ErrorCode::UnreadableFile, "cannot write layout file '" + path + "'");
  out << "# Quantized Retopo T-mesh layout: nodes as points, edges as polylines\n";
  long long offset = 0;
  for (size_t c = 0; c < meshes.size() && c < tmeshes.size(); ++c) {
    out << "o tmesh_" << c << '\n';
    write_layout_obj(out, *meshes[c], *tmeshes[c], offset);
  }
  if (!out) throw Error(ErrorCode::UnreadableFile, "writing layout file '" + path + "' failed");
}

}  // namespace qgp

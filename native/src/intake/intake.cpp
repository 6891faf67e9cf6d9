#include "intake/intake.h"

#include <algorithm>
#include <cstdint>
#include <numeric>
#include <sstream>
#include <unordered_map>

#include "core/error.h"
#include "intake/repair.h"

namespace qgp {
namespace {

std::string point_text(const Vec3& p) {
  std::ostringstream s;
  s << "(" << p.x() << ", " << p.y() << ", " << p.z() << ")";
  return s.str();
}

// Drops the given edge-connected components, or refuses the mesh when dropping is not allowed.
void drop_or_refuse(TriangleSoup& soup, const std::vector<int>& bad_components, const std::string& what,
                    bool allow_drop, IntakeResult& result, const std::string& repair_kind) {
  int num_components = 0;
  const std::vector<int> component = edge_connected_components(soup, &num_components);
  std::vector<char> bad(num_components, 0);
  for (int c : bad_components) bad[c] = 1;
  if (!allow_drop)
    throw Error(ErrorCode::InvalidMesh,
                what + "; the mesh is refused (repair it, or allow dropping the affected parts)");
  RepairLocations where;
  std::vector<char> keep(soup.triangles.size()), located(num_components, 0);
  for (size_t t = 0; t < keep.size(); ++t) {
    keep[t] = !bad[component[t]];
    if (bad[component[t]] && !located[component[t]]) {
      located[component[t]] = 1;
      where.add(soup.input_vertex[soup.triangles[t][0]]);
    }
  }
  keep_triangles(soup, keep);
  result.repairs.push_back({repair_kind, static_cast<int>(bad_components.size()), where.input_vertices});
  result.warnings.push_back(what + "; " + std::to_string(bad_components.size()) +
                            " affected component(s) were dropped");
  if (soup.triangles.empty()) throw Error(ErrorCode::InvalidMesh, what + "; no usable component is left");
}

// Records a repair that happened (count > 0) with where it happened.
void note_repair(IntakeResult& result, const char* kind, int count, const RepairLocations& where) {
  if (count > 0) result.repairs.push_back({kind, count, where.input_vertices});
}

// Runs one repair step that reports its locations and notes it.
template <class Step>
void run_repair(IntakeResult& result, const char* kind, Step step) {
  RepairLocations where;
  const int count = step(&where);
  note_repair(result, kind, count, where);
}

// The refusal (or, with drop_bad_components, the dropping) of components with non-manifold edges.
void refuse_nonmanifold_edges(TriangleSoup& soup, const std::vector<std::array<int, 2>>& nonmanifold,
                              const IntakeOptions& options, IntakeResult& result) {
  int num_components = 0;
  const std::vector<int> component = edge_connected_components(soup, &num_components);
  std::unordered_map<uint64_t, char> is_bad_edge;
  for (auto e : nonmanifold) is_bad_edge[static_cast<uint64_t>(e[0]) << 32 | static_cast<uint32_t>(e[1])] = 1;
  std::vector<char> bad(num_components, 0);
  for (size_t t = 0; t < soup.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      int a = soup.triangles[t][k], b = soup.triangles[t][(k + 1) % 3];
      if (a > b) std::swap(a, b);
      if (is_bad_edge.count(static_cast<uint64_t>(a) << 32 | static_cast<uint32_t>(b))) bad[component[t]] = 1;
    }
  std::vector<int> bad_list;
  for (int c = 0; c < num_components; ++c)
    if (bad[c]) bad_list.push_back(c);
  const auto& first = nonmanifold.front();
  drop_or_refuse(soup, bad_list,
                 std::to_string(nonmanifold.size()) +
                     " non-manifold edge(s) (shared by more than two faces), the first between input vertices " +
                     std::to_string(soup.input_vertex[first[0]]) + " and " +
                     std::to_string(soup.input_vertex[first[1]]) + " at " + point_text(soup.positions[first[0]]),
                 options.drop_bad_components, result, "dropped_nonmanifold_components");
}

// Cuts non-manifold edges into sheets, or refuses them when the options say so.
void repair_nonmanifold_edges(TriangleSoup& soup, const IntakeOptions& options, IntakeResult& result) {
  if (options.refuse_non_manifold) {
    const auto nonmanifold = find_nonmanifold_edges(soup);
    if (!nonmanifold.empty()) refuse_nonmanifold_edges(soup, nonmanifold, options, result);
    return;
  }
  run_repair(result, "cut_nonmanifold_edges", [&](RepairLocations* w) { return cut_nonmanifold_edges(soup, w); });
}

// Welding of boundary vertices and the triangles it collapses.
void weld(TriangleSoup& soup, const IntakeOptions& options, IntakeResult& result) {
  result.weld_target.resize(result.input_vertices);
  std::iota(result.weld_target.begin(), result.weld_target.end(), 0);
  run_repair(result, "welded_vertices", [&](RepairLocations* w) {
    return weld_boundary_vertices(soup, options.weld_tolerance, &result.weld_target, w);
  });
  run_repair(result, "collapsed_faces", [&](RepairLocations* w) { return remove_collapsed_triangles(soup, w); });
}

// Moves the given edge-connected components out of the soup into result.non_orientable_parts;
// refuses the mesh when nothing else is left (a lone Möbius strip has no quads to give).
void set_aside_non_orientable(TriangleSoup& soup, const std::vector<int>& parts, const std::string& what,
                              IntakeResult& result) {
  int num_components = 0;
  const std::vector<int> component = edge_connected_components(soup, &num_components);
  std::vector<int> part_of(num_components, -1);
  for (size_t k = 0; k < parts.size(); ++k) part_of[parts[k]] = static_cast<int>(k);
  std::vector<NonOrientablePart> set_aside(parts.size());
  std::vector<std::vector<int>> new_index(parts.size());  // per part: soup vertex -> part vertex
  std::vector<char> keep(soup.triangles.size(), 1);
  RepairLocations where;
  std::vector<int> input_order(soup.triangles.size());  // the parts keep the input's face order
  std::iota(input_order.begin(), input_order.end(), 0);
  std::stable_sort(input_order.begin(), input_order.end(),
                   [&](int a, int b) { return soup.input_face[a] < soup.input_face[b]; });
  for (int t : input_order) {
    const int k = part_of[component[t]];
    if (k < 0) continue;
    keep[t] = 0;
    NonOrientablePart& part = set_aside[k];
    if (part.triangles.empty()) where.add(soup.input_vertex[soup.triangles[t][0]]);
    std::vector<int>& index = new_index[k];
    if (index.empty()) index.assign(soup.positions.size(), -1);
    std::array<int, 3> triangle;
    for (int j = 0; j < 3; ++j) {
      int& v = index[soup.triangles[t][j]];
      if (v < 0) {
        v = static_cast<int>(part.positions.size());
        part.positions.push_back(soup.positions[soup.triangles[t][j]]);
      }
      triangle[j] = v;
    }
    part.triangles.push_back(triangle);
    part.input_face.push_back(soup.input_face[t]);
  }
  if (std::find(keep.begin(), keep.end(), 1) == keep.end())
    throw Error(ErrorCode::InvalidMesh, what +
                                            " and nothing else; the mesh is refused (a surface without two sides "
                                            "has no quad mesh; repair it)");
  keep_triangles(soup, keep);
  result.non_orientable_parts = std::move(set_aside);
  result.repairs.push_back({"kept_nonorientable_components", static_cast<int>(parts.size()), where.input_vertices});
  result.warnings.push_back(what + "; kept as their triangles (a surface without two sides has no quad mesh)");
}

// Orientation, non-orientable parts, non-manifold vertices and zero-area faces.
void repair_orientation_and_shape(TriangleSoup& soup, const IntakeOptions& options, IntakeResult& result) {
  std::vector<int> non_orientable;
  run_repair(result, "inconsistent_orientation",
             [&](RepairLocations* w) { return orient_consistently(soup, &non_orientable, w); });
  if (!non_orientable.empty()) {
    const std::string what = std::to_string(non_orientable.size()) + " non-orientable component(s)";
    if (options.drop_bad_components)
      drop_or_refuse(soup, non_orientable, what, true, result, "dropped_nonorientable_components");
    else
      set_aside_non_orientable(soup, non_orientable, what, result);
  }
  run_repair(result, "nonmanifold_vertices", [&](RepairLocations* w) { return split_nonmanifold_vertices(soup, w); });
  int unrepaired = 0;
  run_repair(result, "zero_area_faces", [&](RepairLocations* w) {
    return repair_zero_area_faces(soup, options.zero_area, options.flatness, &unrepaired, w);
  });
  if (unrepaired > 0)
    result.warnings.push_back(std::to_string(unrepaired) + " zero-area face(s) could not be repaired");
  remove_unreferenced_vertices(soup);  // vertices orphaned by collapses
}

// The repaired soup as the result's mesh, with connectivity.
void build_result_mesh(TriangleSoup& soup, IntakeResult& result) {
  TriMesh& mesh = result.mesh;
  mesh.V.resize(static_cast<int>(soup.positions.size()), 3);
  for (size_t v = 0; v < soup.positions.size(); ++v) mesh.V.row(v) = soup.positions[v].transpose();
  mesh.F.resize(static_cast<int>(soup.triangles.size()), 3);
  for (size_t t = 0; t < soup.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) mesh.F(t, k) = soup.triangles[t][k];
  result.input_vertex = std::move(soup.input_vertex);
  result.input_face = std::move(soup.input_face);
  try {
    build_connectivity(mesh);
  } catch (const Error& e) {  // the repair steps above guarantee a manifold; this is a bug
    throw Error(ErrorCode::Internal, std::string("intake left a non-manifold mesh: ") + e.what());
  }
}

void classify_components(IntakeResult& result) {
  const TriMesh& mesh = result.mesh;
  std::vector<int> comp(mesh.num_faces(), -1);
  std::vector<int> stack;
  for (int seed = 0; seed < mesh.num_faces(); ++seed) {
    if (comp[seed] >= 0) continue;
    const int id = static_cast<int>(result.components.size());
    result.components.emplace_back();
    comp[seed] = id;
    stack.push_back(seed);
    while (!stack.empty()) {
      const int f = stack.back();
      stack.pop_back();
      result.components[id].faces.push_back(f);
      for (int k = 0; k < 3; ++k) {
        const int o = mesh.opposite[3 * f + k];
        if (o >= 0 && comp[o / 3] < 0) {
          comp[o / 3] = id;
          stack.push_back(o / 3);
        }
      }
    }
  }
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    const int h = mesh.vertex_halfedge[v];
    if (h >= 0) ++result.components[comp[h / 3]].num_vertices;
  }
  for (int e = 0; e < mesh.num_edges(); ++e) ++result.components[comp[mesh.edge_halfedge[e] / 3]].num_edges;
  std::vector<char> seen(mesh.num_halfedges(), 0);
  for (int h = 0; h < mesh.num_halfedges(); ++h) {
    if (mesh.opposite[h] >= 0 || seen[h]) continue;
    ++result.components[comp[h / 3]].boundary_loops;
    for (int c = h; c >= 0 && !seen[c]; c = mesh.vertex_halfedge[mesh.to(c)]) seen[c] = 1;
  }
  for (ComponentInfo& c : result.components) {
    c.num_faces = static_cast<int>(c.faces.size());
    std::sort(c.faces.begin(), c.faces.end());
    c.euler_characteristic = c.num_vertices - c.num_edges + c.num_faces;
    c.genus = (2 - c.euler_characteristic - c.boundary_loops) / 2;
  }
}

// Starts each triangle of a part set aside at the corner nearest to its input face's first corner,
// as the input had it (intake's canonical order starts it at its lowest vertex).
void restore_input_corners(const PolygonSoup& input, NonOrientablePart& part) {
  for (size_t t = 0; t < part.triangles.size(); ++t) {
    std::array<int, 3>& triangle = part.triangles[t];
    const Vec3& first = input.positions[input.face_vertices[input.face_start[part.input_face[t]]]];
    int nearest = 0;
    for (int j = 1; j < 3; ++j)
      if ((part.positions[triangle[j]] - first).squaredNorm() <
          (part.positions[triangle[nearest]] - first).squaredNorm())
        nearest = j;
    std::rotate(triangle.begin(), triangle.begin() + nearest, triangle.end());
  }
}

}  // namespace

IntakeResult run_intake(const PolygonSoup& input, const IntakeOptions& options, Progress& progress) {
  progress.begin_stage("intake");
  IntakeResult result;
  result.input_vertices = input.num_vertices();
  result.input_faces = input.num_faces();
  validate_soup(input);

  TriangleSoup soup;
  run_repair(result, "triangulated_polygons", [&](RepairLocations* w) { return triangulate_polygons(input, soup, w); });
  run_repair(result, "unreferenced_vertices",
             [&](RepairLocations* w) { return remove_unreferenced_vertices(soup, w); });
  weld(soup, options, result);
  sort_triangles_canonically(soup);  // the repairs below then do not depend on the input's face order
  run_repair(result, "duplicate_faces", [&](RepairLocations* w) { return remove_duplicate_faces(soup, w); });
  progress.update(0.2);
  repair_nonmanifold_edges(soup, options, result);
  progress.update(0.35);
  repair_orientation_and_shape(soup, options, result);
  if (soup.triangles.empty() && result.non_orientable_parts.empty())
    throw Error(ErrorCode::InvalidMesh, "every face of the mesh has zero area (all " +
                                            std::to_string(input.num_faces()) +
                                            " were removed): no surface is left to remesh");
  progress.update(0.7);
  sort_triangles_canonically(soup);  // again: the repairs split vertices and reorient triangles
  for (NonOrientablePart& part : result.non_orientable_parts) restore_input_corners(input, part);
  build_result_mesh(soup, result);
  classify_components(result);
  progress.update(1.0);
  return result;
}

void to_json(Json& input, const IntakeResult& r) {
  input["vertices"] = r.mesh.num_vertices();
  input["faces"] = r.mesh.num_faces();
  input["input_vertices"] = r.input_vertices;
  input["input_faces"] = r.input_faces;
  input["components"] = r.components.size();
  Json loops = Json::array(), genus = Json::array(), chi = Json::array(), faces = Json::array();
  for (const ComponentInfo& c : r.components) {
    loops.push_back(c.boundary_loops);
    genus.push_back(c.genus);
    chi.push_back(c.euler_characteristic);
    faces.push_back(c.num_faces);
  }
  input["boundary_loops"] = loops;
  input["genus"] = genus;
  input["euler_characteristic"] = chi;
  input["component_faces"] = faces;
  Json repairs = Json::array();
  for (const Repair& rep : r.repairs)
    repairs.push_back({{"kind", rep.kind}, {"count", rep.count}, {"input_vertices", rep.input_vertices}});
  input["repairs"] = repairs;
  input["warnings"] = r.warnings;
}

std::vector<char> map_input_edges(const IntakeResult& intake, const std::vector<std::array<int, 2>>& input_pairs,
                                  int* unmatched) {
  const TriMesh& mesh = intake.mesh;
  auto key = [](int a, int b) {
    return static_cast<uint64_t>(std::min(a, b)) << 32 | static_cast<uint32_t>(std::max(a, b));
  };
  std::unordered_multimap<uint64_t, int> by_input;
  by_input.reserve(mesh.num_edges());
  for (int e = 0; e < mesh.num_edges(); ++e) {
    const int h = mesh.edge_halfedge[e];
    by_input.emplace(key(intake.input_vertex[mesh.from(h)], intake.input_vertex[mesh.to(h)]), e);
  }
  std::vector<char> marked(mesh.num_edges(), 0);
  int missing = 0;
  for (const auto& p : input_pairs) {
    const auto welded = [&](int v) {
      return v >= 0 && v < static_cast<int>(intake.weld_target.size()) ? intake.weld_target[v] : v;
    };
    auto range = by_input.equal_range(key(welded(p[0]), welded(p[1])));
    if (range.first == range.second) ++missing;
    for (auto it = range.first; it != range.second; ++it) marked[it->second] = 1;
  }
  if (unmatched) *unmatched = missing;
  return marked;
}

TriMesh extract_component(const IntakeResult& intake, int component, std::vector<int>* vertex_map,
                          std::vector<int>* face_map) {
  return extract_components(intake, {component}, vertex_map, face_map);
}

TriMesh extract_components(const IntakeResult& intake, const std::vector<int>& components, std::vector<int>* vertex_map,
                           std::vector<int>* face_map) {
  std::vector<int> faces;
  for (int c : components)
    faces.insert(faces.end(), intake.components.at(c).faces.begin(), intake.components.at(c).faces.end());
  std::vector<int> local(intake.mesh.num_vertices(), -1), to_global;
  TriMesh m;
  m.F.resize(static_cast<int>(faces.size()), 3);
  for (size_t i = 0; i < faces.size(); ++i)
    for (int k = 0; k < 3; ++k) {
      const int v = intake.mesh.F(faces[i], k);
      if (local[v] < 0) {
        local[v] = static_cast<int>(to_global.size());
        to_global.push_back(v);
      }
      m.F(static_cast<int>(i), k) = local[v];
    }
  m.V.resize(static_cast<int>(to_global.size()), 3);
  for (size_t v = 0; v < to_global.size(); ++v) m.V.row(v) = intake.mesh.V.row(to_global[v]);
  build_connectivity(m);
  if (vertex_map) *vertex_map = std::move(to_global);
  if (face_map) *face_map = std::move(faces);
  return m;
}

}  // namespace qgp

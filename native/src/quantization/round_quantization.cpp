#include "quantization/round_quantization.h"

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <cmath>
#include <limits>

#include "core/error.h"
#include "core/timer.h"

namespace qgp {

namespace {

// (R^r w)[a] = sign * w[index] for a quarter rotation r.
struct RotatedComponent {
  int index;
  double sign;
};
RotatedComponent rotated_component(int r, int a) {
  switch (((r % 4) + 4) % 4) {
    case 0: return {a, 1.0};
    case 1: return a == 0 ? RotatedComponent{1, -1.0} : RotatedComponent{0, 1.0};
    case 2: return {a, -1.0};
    default: return a == 0 ? RotatedComponent{1, 1.0} : RotatedComponent{0, -1.0};
  }
}

Eigen::Matrix2d rotation_matrix(int r) {
  Eigen::Matrix2d m;
  switch (((r % 4) + 4) % 4) {
    case 0: m << 1, 0, 0, 1; break;
    case 1: m << 0, -1, 1, 0; break;
    case 2: m << -1, 0, 0, -1; break;
    default: m << 0, 1, -1, 0; break;
  }
  return m;
}

}  // namespace

std::vector<char> independent_vertices(const TriMesh& mesh, const Parametrization& param, const TMesh& tmesh) {
  std::vector<char> snap(mesh.num_vertices(), 0);
  std::vector<int> holonomy(mesh.num_vertices(), 0);
  for (int h = 0; h < mesh.num_halfedges(); ++h)
    if (mesh.opposite[h] >= 0) holonomy[mesh.to(h)] += param.rotation[h];
  for (int v = 0; v < mesh.num_vertices(); ++v)
    if (holonomy[v] % 4 != 0 && !is_boundary_vertex(mesh, v)) snap[v] = 1;
  for (const TMeshNode& n : tmesh.nodes) {
    const bool independent = n.singular() || n.kind == TMeshNode::Kind::FeatureCorner ||
                             n.kind == TMeshNode::Kind::BoundaryNode || n.kind == TMeshNode::Kind::Seed;
    if (independent && n.mesh_vertex >= 0 && n.mesh_vertex < mesh.num_vertices()) snap[n.mesh_vertex] = 1;
  }
  return snap;
}

namespace {

// Sanitization options of the rounding: integer snapping of snap_vertices, and feature and
// boundary edges as isolines (the coordinate that is constant along each, per corner).
SanitizeOptions isoline_snap_options(const TriMesh& mesh, const Parametrization& scaled,
                                     const std::vector<char>& feature_edges, const std::vector<char>& snap_vertices,
                                     int fraction_bits) {
  const int nc = 3 * mesh.num_faces();
  SanitizeOptions options;
  options.fraction_bits = fraction_bits;
  options.snap_bits = 0;
  options.snap_vertex = snap_vertices;
  options.snap_corner_axes.assign(nc, 0);
  for (int h = 0; h < nc; ++h) {
    const int e = mesh.edge_of[h];
    if (mesh.opposite[h] >= 0 && (feature_edges.empty() || !feature_edges[e])) continue;
    const int f = h / 3, a = h % 3, b = (h % 3 + 1) % 3;
    const Vec2 d = scaled.corner(f, b) - scaled.corner(f, a);
    const uint8_t bit = std::abs(d.x()) <= std::abs(d.y()) ? 1 : 2;
    options.snap_corner_axes[3 * f + a] |= bit;
    options.snap_corner_axes[3 * f + b] |= bit;
  }
  return options;
}

// One (u,v) unknown per vertex in the chart of a reference corner; corner c of vertex v has value
// R_c W_v + t_c with the exact transitions of the rounded map.
struct VertexCharts {
  std::vector<int> corner_rotation;       // 3#F: r of R_c
  std::vector<IVec2> corner_translation;  // 3#F: t_c (grid units)
  std::vector<int> reference;             // #V: reference corner, -1 for an isolated vertex
};

// The chart of every corner relative to its vertex's reference corner, from s1's transitions.
VertexCharts vertex_charts(const TriMesh& mesh, const ExactParametrization& s1) {
  const int nv = mesh.num_vertices(), nc = 3 * mesh.num_faces();
  VertexCharts charts;
  charts.corner_rotation.assign(nc, 0);
  charts.corner_translation.assign(nc, IVec2{0, 0});
  charts.reference.assign(nv, -1);
  for (int v = 0; v < nv; ++v) {
    const std::vector<int> out = outgoing_halfedges(mesh, v);
    if (out.empty()) continue;
    charts.reference[v] = out[0];  // halfedge h starts at corner h of its face
    for (size_t i = 0; i + 1 < out.size(); ++i) {
      const int p = TriMesh::prev(out[i]);  // crossed going counter-clockwise
      const int r = s1.rotation[p];
      const IVec2 t = rotate_quarter(charts.corner_translation[out[i]], r);
      charts.corner_rotation[out[i + 1]] = (charts.corner_rotation[out[i]] + r) % 4;
      charts.corner_translation[out[i + 1]] = {t[0] + s1.translation[p][0], t[1] + s1.translation[p][1]};
    }
  }
  return charts;
}

// The 2#V vertex unknowns of the re-solve: which are fixed, and the values of the fixed ones.
struct FixedValues {
  std::vector<char> fixed;
  std::vector<double> value;
};

// Fixes isolated vertices, the snapped vertices and the snapped axes of corners at their rounded
// values in s1 (unit: parameter units per grid unit).
FixedValues rounded_fixed_values(const TriMesh& mesh, const ExactParametrization& s1, const VertexCharts& charts,
                                 const std::vector<char>& snap_vertices, const std::vector<uint8_t>& snap_corner_axes,
                                 double unit) {
  const int nv = mesh.num_vertices(), nc = 3 * mesh.num_faces();
  FixedValues fv{std::vector<char>(2 * nv, 0), std::vector<double>(2 * nv, 0)};
  std::vector<char>& fixed = fv.fixed;
  std::vector<double>& value = fv.value;
  for (int v = 0; v < nv; ++v) {
    if (charts.reference[v] < 0) {  // isolated vertex
      fixed[2 * v] = fixed[2 * v + 1] = 1;
      continue;
    }
    if (!snap_vertices[v]) continue;
    const IVec2 p = s1.uv[charts.reference[v]];
    fixed[2 * v] = fixed[2 * v + 1] = 1;
    value[2 * v] = p[0] * unit, value[2 * v + 1] = p[1] * unit;
  }
  for (int c = 0; c < nc; ++c)
    for (int a = 0; a < 2; ++a) {
      if (!((snap_corner_axes[c] >> a) & 1)) continue;
      const int v = mesh.F(c / 3, c % 3);
      const RotatedComponent rc = rotated_component(charts.corner_rotation[c], a);
      fixed[2 * v + rc.index] = 1;
      value[2 * v + rc.index] = rc.sign * static_cast<double>(s1.uv[c][a] - charts.corner_translation[c][a]) * unit;
    }
  return fv;
}

// Pins the first vertex of every component without a fully fixed vertex where it is in s1.
void pin_floating_components(const TriMesh& mesh, const ExactParametrization& s1, const VertexCharts& charts,
                             double unit, FixedValues& fv) {
  // A component without any fixed vertex would float: pin its first vertex where it is.
  const int nv = mesh.num_vertices(), nf = mesh.num_faces();
  std::vector<int> parent(nv);
  for (int v = 0; v < nv; ++v) parent[v] = v;
  auto find = [&](int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (int f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) parent[find(mesh.F(f, k))] = find(mesh.F(f, (k + 1) % 3));
  std::vector<char> anchored(nv, 0);
  for (int v = 0; v < nv; ++v)
    if (fv.fixed[2 * v] && fv.fixed[2 * v + 1]) anchored[find(v)] = 1;
  for (int v = 0; v < nv; ++v)
    if (!anchored[find(v)] && charts.reference[v] >= 0) {
      anchored[find(v)] = 1;
      const IVec2 p = s1.uv[charts.reference[v]];
      fv.fixed[2 * v] = fv.fixed[2 * v + 1] = 1;
      fv.value[2 * v] = p[0] * unit, fv.value[2 * v + 1] = p[1] * unit;
    }
}

// Normal equations of the least-squares re-solve, restricted to the free unknowns.
struct ReducedSystem {
  std::vector<int> free_index;  // 2#V: row/column of each free unknown, -1 for fixed ones
  int nfree = 0;
  std::vector<Eigen::Triplet<double>> triplets;
  Eigen::VectorXd rhs;
};

// Assembles the deviation of the map from the continuous map's per-triangle edge vectors
// (cotangent weights), the fixed unknowns moved to the right-hand side.
ReducedSystem assemble_reduced_system(const TriMesh& mesh, const Parametrization& scaled, const VertexCharts& charts,
                                      const FixedValues& fv, double unit) {
  const int nv = mesh.num_vertices(), nf = mesh.num_faces();
  ReducedSystem sys;
  sys.free_index.assign(2 * nv, -1);
  for (int i = 0; i < 2 * nv; ++i)
    if (!fv.fixed[i]) sys.free_index[i] = sys.nfree++;
  const std::vector<int>& free_index = sys.free_index;
  Eigen::VectorXd& rhs = sys.rhs;
  rhs = Eigen::VectorXd::Zero(sys.nfree);
  auto add = [&](int row, int col, double a) {
    if (free_index[row] < 0) return;
    if (free_index[col] >= 0)
      sys.triplets.emplace_back(free_index[row], free_index[col], a);
    else
      rhs[free_index[row]] -= a * fv.value[col];
  };
  for (int f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) {
      const int i = (k + 1) % 3, j = (k + 2) % 3;
      const Vec3 a = mesh.position(mesh.F(f, i)) - mesh.position(mesh.F(f, k));
      const Vec3 b = mesh.position(mesh.F(f, j)) - mesh.position(mesh.F(f, k));
      const double cross = a.cross(b).norm();
      if (!(cross > 0)) continue;
      const double w = 0.5 * a.dot(b) / cross;
      const int ci = 3 * f + i, cj = 3 * f + j;
      const int vi = mesh.F(f, i), vj = mesh.F(f, j);
      const Eigen::Matrix2d Ri = rotation_matrix(charts.corner_rotation[ci]);
      const Eigen::Matrix2d Rj = rotation_matrix(charts.corner_rotation[cj]);
      const Vec2 target = scaled.corner(f, i) - scaled.corner(f, j);
      const Vec2 b0 = Vec2(charts.corner_translation[ci][0] - charts.corner_translation[cj][0],
                           charts.corner_translation[ci][1] - charts.corner_translation[cj][1]) *
                          unit -
                      target;
      // E += w |Ri Wi - Rj Wj + b0|^2: gradient rows of Wi and Wj.
      const Eigen::Matrix2d cross_block = -Ri.transpose() * Rj;
      const Vec2 gi = Ri.transpose() * b0, gj = -Rj.transpose() * b0;
      for (int r = 0; r < 2; ++r) {
        add(2 * vi + r, 2 * vi + r, w);
        add(2 * vj + r, 2 * vj + r, w);
        for (int s = 0; s < 2; ++s) {
          add(2 * vi + r, 2 * vj + s, w * cross_block(r, s));
          add(2 * vj + r, 2 * vi + s, w * cross_block(s, r));
        }
        if (free_index[2 * vi + r] >= 0) rhs[free_index[2 * vi + r]] -= w * gi[r];
        if (free_index[2 * vj + r] >= 0) rhs[free_index[2 * vj + r]] -= w * gj[r];
      }
    }
  return sys;
}

// All 2#V vertex unknowns: the fixed values, and the least-squares solution for the free ones.
std::vector<double> solve_with_fixed_values(const TriMesh& mesh, const Parametrization& scaled,
                                            const VertexCharts& charts, const FixedValues& fv, double unit) {
  const int nv = mesh.num_vertices();
  const ReducedSystem sys = assemble_reduced_system(mesh, scaled, charts, fv, unit);
  std::vector<double> solution(fv.value);
  if (sys.nfree > 0) {
    Eigen::SparseMatrix<double> H(sys.nfree, sys.nfree);
    H.setFromTriplets(sys.triplets.begin(), sys.triplets.end());
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(H);
    if (solver.info() != Eigen::Success)
      throw Error(ErrorCode::StageFailed, "rounding: the re-solve with fixed integer variables is singular");
    const Eigen::VectorXd x = solver.solve(sys.rhs);
    for (int i = 0; i < 2 * nv; ++i)
      if (sys.free_index[i] >= 0) solution[i] = x[sys.free_index[i]];
  }
  return solution;
}

// The continuous map of the vertex values (corner c: R_c W_v + t_c) with s1's transitions.
Parametrization map_of_vertex_values(const TriMesh& mesh, const ExactParametrization& s1, const VertexCharts& charts,
                                     const std::vector<double>& solution, double unit) {
  const int nc = 3 * mesh.num_faces();
  Parametrization resolved;
  resolved.uv.resize(nc, 2);
  for (int c = 0; c < nc; ++c) {
    const int v = mesh.F(c / 3, c % 3);
    const Vec2 p = rotation_matrix(charts.corner_rotation[c]) * Vec2(solution[2 * v], solution[2 * v + 1]) +
                   Vec2(charts.corner_translation[c][0], charts.corner_translation[c][1]) * unit;
    resolved.uv.row(c) = p.transpose();
  }
  resolved.rotation = s1.rotation;
  resolved.is_cut = s1.is_cut;
  return resolved;
}

// The result: the exact map, its flipped / degenerate triangles and its largest change.
RoundedMap rounded_map(const ExactParametrization& exact_map, const Parametrization& scaled,
                       const std::vector<char>& snap_vertices, int unresolved_equations) {
  const int nc = static_cast<int>(exact_map.uv.size()), nf = nc / 3;
  RoundedMap out;
  out.param = exact_map;
  out.snapped_vertices = snap_vertices;
  out.unresolved_equations = unresolved_equations;
  for (int f = 0; f < nf; ++f) {
    const int o = orient2d_exact(out.param.uv[3 * f], out.param.uv[3 * f + 1], out.param.uv[3 * f + 2]);
    out.flipped_triangles += o < 0;
    out.degenerate_triangles += o == 0;
  }
  for (int c = 0; c < nc; ++c)
    for (int a = 0; a < 2; ++a)
      out.max_change = std::max(out.max_change, std::abs(out.param.to_double(out.param.uv[c][a]) - scaled.uv(c, a)));
  return out;
}

}  // namespace

RoundedMap round_parametrization(const TriMesh& mesh, const Parametrization& param,
                                 const std::vector<char>& feature_edges, const std::vector<char>& snap_vertices,
                                 double scale, int fraction_bits) {
  const int nv = mesh.num_vertices(), nf = mesh.num_faces(), nc = 3 * nf;
  if (param.uv.rows() != nc || static_cast<int>(param.rotation.size()) != nc ||
      static_cast<int>(snap_vertices.size()) != nv ||
      (!feature_edges.empty() && static_cast<int>(feature_edges.size()) != mesh.num_edges()))
    throw Error(ErrorCode::InvalidArgument,
                "rounding: parametrization, features or vertex flags do not match the mesh");
  if (!(scale > 0) || !std::isfinite(scale)) throw Error(ErrorCode::InvalidArgument, "rounding: invalid scale");

  Parametrization scaled = param;
  scaled.uv *= scale;
  const SanitizeOptions options = isoline_snap_options(mesh, scaled, feature_edges, snap_vertices, fraction_bits);

  // 1. Round the independent variables, derive the dependent ones exactly.
  const SanitizeResult rounded = sanitize_parametrization(mesh, scaled, options);
  const ExactParametrization& s1 = rounded.param;
  const double unit = std::ldexp(1.0, -fraction_bits);

  // 2. Solve again with them fixed. Unknowns: one (u,v) per vertex in the chart of a reference
  // corner; corner c of vertex v has value R_c W_v + t_c with the exact transitions of s1.
  const VertexCharts charts = vertex_charts(mesh, s1);
  FixedValues fixed = rounded_fixed_values(mesh, s1, charts, snap_vertices, options.snap_corner_axes, unit);
  pin_floating_components(mesh, s1, charts, unit, fixed);
  const std::vector<double> solution = solve_with_fixed_values(mesh, scaled, charts, fixed, unit);
  const Parametrization resolved = map_of_vertex_values(mesh, s1, charts, solution, unit);

  // 3. Exact form (the fixed values are integers already; sanitization keeps them).
  const SanitizeResult exact = sanitize_parametrization(mesh, resolved, options);
  return rounded_map(exact.param, scaled, snap_vertices, rounded.unresolved_equations + exact.unresolved_equations);
}

RoundingResult quantize_by_rounding(const TriMesh& mesh, const Parametrization& param,
                                    const std::vector<char>& feature_edges, const TMesh& tmesh,
                                    const QuantizationOptions& options, const TraceFunction& trace,
                                    Progress& progress) {
  Timer timer;
  RoundingResult out;
  QuantizationResult& r = out.quantization;
  r.quantizer = Quantizer::Round;
  r.scale = options.scale;
  r.objective = std::numeric_limits<double>::quiet_NaN();
  progress.update(0);
  auto finish = [&](const std::string& reason) {
    r.valid = reason.empty();
    r.invalid_reason = reason;
    r.seconds = timer.seconds();
    return std::move(out);
  };

  out.map = round_parametrization(mesh, param, feature_edges, independent_vertices(mesh, param, tmesh), options.scale);
  progress.update(0.3);
  if (out.map.unresolved_equations > 0)
    return finish("rounding: " + std::to_string(out.map.unresolved_equations) + " transition equation(s) unresolved");
  try {
    out.tmesh = trace(out.map.param, progress);
  } catch (const Error& e) {
    if (e.code() == ErrorCode::Cancelled) throw;
    return finish(std::string("the rounded map cannot be traced (") + std::to_string(out.map.flipped_triangles) +
                  " flipped, " + std::to_string(out.map.degenerate_triangles) + " degenerate triangles): " + e.what());
  }
  progress.update(0.8);
  r.x.resize(out.tmesh.edges.size());
  for (size_t e = 0; e < out.tmesh.edges.size(); ++e) {
    const double length = out.tmesh.edges[e].length;
    if (length != std::round(length))
      return finish("the rounded map's T-edge " + std::to_string(e) + " has non-integer length " +
                    std::to_string(length));
    r.x[e] = static_cast<int64_t>(length);
  }
  r.zero_edges = static_cast<int>(std::count(r.x.begin(), r.x.end(), 0));
  r.quads_expected = quantization_quads(out.tmesh, r.x);
  r.consistency_residual = quantization_consistency_residual(out.tmesh, r.x);
  if (r.consistency_residual != 0) return finish("the rounded map's T-mesh violates its cell equations");
  QuantizationValidity validity;
  try {
    validity = check_quantization_validity(out.tmesh, r.x);
  } catch (const Error& e) {
    return finish(std::string("the rounded map's T-mesh is malformed: ") + e.what());
  }
  ++r.validity_checks;
  progress.update(1);
  return finish(validity.valid ? "" : validity.reason);
}

}  // namespace qgp

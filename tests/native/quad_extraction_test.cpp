// Quad extraction from integer-grid maps (quad_extraction/): synthetic IGMs of known quad count
// (cubes, tori, planar patches, open cubes, glued sectors with singularities of any valence),
// perturbed and re-triangulated variants, coarse and fine maps, robustness on broken maps, the
// metrics and the projection onto a finer surface.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <random>
#include <set>
#include <thread>

#include <Eigen/Sparse>

#include "core/error.h"
#include "core/parallel.h"
#include "core/timer.h"
#include "cross_field/cross_field.h"
#include "igm/integer_grid_map.h"
#include "igm/untangle_map.h"
#include "metrics/quad_metrics.h"
#include "quad_extraction/collapse_quads.h"
#include "quad_extraction/quad_extraction.h"
#include "quad_extraction/surface_projection.h"
#include "quad_extraction/untangle_quads.h"
#include "test_support.h"

namespace qgp {
namespace {

using test::SyntheticParametrized;

// ---------------------------------------------------------------------------------------------
// Synthetic maps.

// Cone angle of every vertex in quarter turns, measured in the (double) parametrization.
std::vector<int> cone_quarter_turns(const TriMesh& mesh, const Parametrization& param) {
  std::vector<double> angle(mesh.num_vertices(), 0);
  for (int f = 0; f < mesh.num_faces(); ++f)
    for (int k = 0; k < 3; ++k) {
      const Vec2 a = param.corner(f, (k + 1) % 3) - param.corner(f, k);
      const Vec2 b = param.corner(f, (k + 2) % 3) - param.corner(f, k);
      angle[mesh.F(f, k)] += std::atan2(a.x() * b.y() - a.y() * b.x(), a.dot(b));
    }
  std::vector<int> turns(mesh.num_vertices());
  for (int v = 0; v < mesh.num_vertices(); ++v) turns[v] = static_cast<int>(std::lround(angle[v] / (M_PI / 2)));
  return turns;
}

bool is_singular(const TriMesh& mesh, const std::vector<int>& turns, int v) {
  return turns[v] != (is_boundary_vertex(mesh, v) ? 2 : 4);
}

// Sanitizes a synthetic seamless map into an exact IGM: singular vertices snapped to integers,
// boundary corners snapped onto their isolines.
ExactParametrization to_igm(const TriMesh& mesh, const Parametrization& param, int fraction_bits = 20) {
  SanitizeOptions options;
  options.fraction_bits = fraction_bits;
  const std::vector<int> turns = cone_quarter_turns(mesh, param);
  options.snap_vertex.assign(mesh.num_vertices(), 0);
  for (int v = 0; v < mesh.num_vertices(); ++v) options.snap_vertex[v] = is_singular(mesh, turns, v);
  options.snap_corner_axes.assign(mesh.num_halfedges(), 0);
  for (int h = 0; h < mesh.num_halfedges(); ++h) {
    if (mesh.opposite[h] >= 0) continue;
    const Vec2 d = param.corner(h / 3, (h % 3 + 1) % 3) - param.corner(h / 3, h % 3);
    const uint8_t axis = d.x() == 0 ? 1 : d.y() == 0 ? 2 : 0;  // the coordinate that is constant
    options.snap_corner_axes[h] |= axis;                       // corner of from(h)
    options.snap_corner_axes[TriMesh::next(h)] |= axis;        // corner of to(h)
  }
  const SanitizeResult r = sanitize_parametrization(mesh, param, options);
  EXPECT_EQ(r.unresolved_equations, 0);
  EXPECT_EQ(exact_transition_residual(mesh, r.param), 0);
  return r.param;
}

SyntheticParametrized scaled(SyntheticParametrized s, double factor) {
  s.param.uv *= factor;
  return s;
}

// Moves every non-singular vertex randomly inside its 1-ring in the parametrization (boundary
// vertices along their boundary isoline), consistently in every chart, keeping it flip-free.
void perturb_vertices(SyntheticParametrized& s, double amount, unsigned seed) {
  const TriMesh& mesh = s.mesh;
  Parametrization& p = s.param;
  const std::vector<int> turns = cone_quarter_turns(mesh, p);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uniform(-1, 1);
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    if (is_singular(mesh, turns, v)) continue;
    const std::vector<int> fan = outgoing_halfedges(mesh, v);
    double room = 1e300;  // distance to the nearest opposite edge line, the same in every chart
    for (int h : fan) {
      const int f = h / 3, k = h % 3;
      const Vec2 x = p.corner(f, k), a = p.corner(f, (k + 1) % 3), b = p.corner(f, (k + 2) % 3);
      const Vec2 e = b - a, d = x - a;
      room = std::min(room, std::abs(e.x() * d.y() - e.y() * d.x()) / e.norm());
    }
    Vec2 delta(uniform(rng), uniform(rng));
    if (is_boundary_vertex(mesh, v)) {
      const int h = fan.front();
      const Vec2 along = p.corner(h / 3, (h % 3 + 1) % 3) - p.corner(h / 3, h % 3);
      delta = along.x() == 0 ? Vec2(0, delta.y()) : Vec2(delta.x(), 0);
    }
    delta *= amount * room / std::max(1.0, delta.norm());
    for (int h : fan) {
      p.uv.row(h) += delta.transpose();
      const int cross = TriMesh::prev(h);
      if (mesh.opposite[cross] >= 0) delta = rotate_quarter(delta, p.rotation[cross]);
    }
  }
}

// Torus whose vertex lattice has spacing `step` in the parametrization (step 1/2: integer isolines
// run along every other edge row and through vertices; step 2 or 3: several quads per triangle),
// with a random diagonal in every cell and a random centre vertex in some cells.
SyntheticParametrized make_random_torus(int nu, int nv, double step, double split_probability, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uniform(0, 1);
  std::vector<Vec3> positions;
  auto torus_point = [&](double a, double b) {
    const double A = 2 * M_PI * a / nu, B = 2 * M_PI * b / nv;
    return Vec3((3 + std::cos(B)) * std::cos(A), (3 + std::cos(B)) * std::sin(A), std::sin(B));
  };
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) positions.push_back(torus_point(i, j));
  auto id = [&](int i, int j) { return (i % nu) * nv + (j % nv); };
  std::vector<std::array<int, 3>> tris;
  std::vector<std::array<Vec2, 3>> uvs;
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      const int c[4] = {id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)};
      const Vec2 q[4] = {Vec2(i, j) * step, Vec2(i + 1, j) * step, Vec2(i + 1, j + 1) * step, Vec2(i, j + 1) * step};
      if (uniform(rng) < split_probability) {
        const int m = static_cast<int>(positions.size());
        positions.push_back(torus_point(i + 0.5, j + 0.5));
        const Vec2 qm = Vec2(i + 0.5, j + 0.5) * step;
        for (int k = 0; k < 4; ++k)
          tris.push_back({c[k], c[(k + 1) % 4], m}), uvs.push_back({q[k], q[(k + 1) % 4], qm});
      } else if (uniform(rng) < 0.5) {
        tris.push_back({c[0], c[1], c[2]}), uvs.push_back({q[0], q[1], q[2]});
        tris.push_back({c[0], c[2], c[3]}), uvs.push_back({q[0], q[2], q[3]});
      } else {
        tris.push_back({c[0], c[1], c[3]}), uvs.push_back({q[0], q[1], q[3]});
        tris.push_back({c[1], c[2], c[3]}), uvs.push_back({q[1], q[2], q[3]});
      }
    }
  SyntheticParametrized out;
  out.mesh.V.resize(static_cast<int>(positions.size()), 3);
  for (size_t v = 0; v < positions.size(); ++v) out.mesh.V.row(v) = positions[v].transpose();
  out.mesh.F.resize(static_cast<int>(tris.size()), 3);
  out.param.uv.resize(3 * static_cast<int>(tris.size()), 2);
  for (size_t t = 0; t < tris.size(); ++t)
    for (int k = 0; k < 3; ++k) out.mesh.F(t, k) = tris[t][k], out.param.uv.row(3 * t + k) = uvs[t][k].transpose();
  build_connectivity(out.mesh);
  test::infer_rotations(out.mesh, out.param);
  return out;
}

// k quadrant sectors [0,n]^2 glued around a centre vertex: sector i's edge {u = 0} is sector
// i+1's edge {v = 0}. The centre is a singularity of valence k; the outer corners are boundary
// corners of valence 2. Embedded in the plane by scaling the polar angle.
SyntheticParametrized make_glued_sectors(int k, int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::map<std::array<int, 3>, int> vertex_id;
  std::vector<Vec3> positions;
  auto vid = [&](int s, int u, int v) {
    if (u == 0 && v == 0)
      s = 0;
    else if (u == 0)
      s = (s + 1) % k, u = v, v = 0;
    auto it = vertex_id.emplace(std::array<int, 3>{s, u, v}, static_cast<int>(positions.size())).first;
    if (it->second == static_cast<int>(positions.size())) {
      const double theta = (s + std::atan2(double(v), double(u)) / (M_PI / 2)) * 2 * M_PI / k;
      const double r = std::hypot(double(u), double(v));
      positions.push_back(Vec3(r * std::cos(theta), r * std::sin(theta), 0));
    }
    return it->second;
  };
  std::vector<std::array<int, 3>> tris;
  std::vector<std::array<Vec2, 3>> uvs;
  for (int s = 0; s < k; ++s)
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) {
        const int c[4] = {vid(s, i, j), vid(s, i + 1, j), vid(s, i + 1, j + 1), vid(s, i, j + 1)};
        const Vec2 q[4] = {Vec2(i, j), Vec2(i + 1, j), Vec2(i + 1, j + 1), Vec2(i, j + 1)};
        if (rng() % 2) {
          tris.push_back({c[0], c[1], c[2]}), uvs.push_back({q[0], q[1], q[2]});
          tris.push_back({c[0], c[2], c[3]}), uvs.push_back({q[0], q[2], q[3]});
        } else {
          tris.push_back({c[0], c[1], c[3]}), uvs.push_back({q[0], q[1], q[3]});
          tris.push_back({c[1], c[2], c[3]}), uvs.push_back({q[1], q[2], q[3]});
        }
      }
  SyntheticParametrized out;
  out.mesh.V.resize(static_cast<int>(positions.size()), 3);
  for (size_t v = 0; v < positions.size(); ++v) out.mesh.V.row(v) = positions[v].transpose();
  out.mesh.F.resize(static_cast<int>(tris.size()), 3);
  out.param.uv.resize(3 * static_cast<int>(tris.size()), 2);
  for (size_t t = 0; t < tris.size(); ++t)
    for (int c = 0; c < 3; ++c) out.mesh.F(t, c) = tris[t][c], out.param.uv.row(3 * t + c) = uvs[t][c].transpose();
  build_connectivity(out.mesh);
  test::infer_rotations(out.mesh, out.param);
  return out;
}

// Keeps only the faces for which keep(f) holds (vertices re-indexed, charts kept).
SyntheticParametrized keep_faces(const SyntheticParametrized& s, const std::function<bool(int)>& keep) {
  std::vector<int> new_id(s.mesh.num_vertices(), -1);
  std::vector<int> faces;
  for (int f = 0; f < s.mesh.num_faces(); ++f)
    if (keep(f)) faces.push_back(f);
  int nv = 0;
  for (int f : faces)
    for (int k = 0; k < 3; ++k)
      if (new_id[s.mesh.F(f, k)] < 0) new_id[s.mesh.F(f, k)] = nv++;
  SyntheticParametrized out;
  out.mesh.V.resize(nv, 3);
  for (int v = 0; v < s.mesh.num_vertices(); ++v)
    if (new_id[v] >= 0) out.mesh.V.row(new_id[v]) = s.mesh.V.row(v);
  out.mesh.F.resize(static_cast<int>(faces.size()), 3);
  out.param.uv.resize(3 * static_cast<int>(faces.size()), 2);
  for (size_t i = 0; i < faces.size(); ++i)
    for (int k = 0; k < 3; ++k) {
      out.mesh.F(i, k) = new_id[s.mesh.F(faces[i], k)];
      out.param.uv.row(3 * i + k) = s.param.uv.row(3 * faces[i] + k);
    }
  build_connectivity(out.mesh);
  test::infer_rotations(out.mesh, out.param);
  return out;
}

// Planar w x h rectangle (lattice step `step` in the parametrization), random diagonals.
SyntheticParametrized make_rectangle(int w, int h, double step, unsigned seed) {
  // A torus lattice cut open: keep all cells but do not wrap (build it directly).
  std::mt19937 rng(seed);
  SyntheticParametrized out;
  out.mesh.V.resize((w + 1) * (h + 1), 3);
  auto id = [&](int i, int j) { return i * (h + 1) + j; };
  for (int i = 0; i <= w; ++i)
    for (int j = 0; j <= h; ++j) out.mesh.V.row(id(i, j)) << i * step, j * step, 0;
  out.mesh.F.resize(2 * w * h, 3);
  out.param.uv.resize(6 * w * h, 2);
  int t = 0;
  for (int i = 0; i < w; ++i)
    for (int j = 0; j < h; ++j) {
      const int c[4][2] = {{i, j}, {i + 1, j}, {i + 1, j + 1}, {i, j + 1}};
      const int pick[2][2][3] = {{{0, 1, 2}, {0, 2, 3}}, {{0, 1, 3}, {1, 2, 3}}};
      const int variant = rng() % 2;
      for (const auto& tri : pick[variant]) {
        for (int k = 0; k < 3; ++k) {
          out.mesh.F(t, k) = id(c[tri[k]][0], c[tri[k]][1]);
          out.param.uv.row(3 * t + k) << c[tri[k]][0] * step, c[tri[k]][1] * step;
        }
        ++t;
      }
    }
  build_connectivity(out.mesh);
  test::infer_rotations(out.mesh, out.param);
  return out;
}

// ---------------------------------------------------------------------------------------------
// Invariants of an extraction.

int euler_characteristic(const TriMesh& mesh) { return mesh.num_vertices() - mesh.num_edges() + mesh.num_faces(); }

// Extracts and asserts every invariant; returns the extraction.
QuadExtraction extract_and_check(const std::string& label, const TriMesh& mesh, const ExactParametrization& igm,
                                 int64_t expected_quads, bool check_flips = true) {
  SCOPED_TRACE(label);
  Progress progress;
  QuadExtraction r;
  try {
    r = extract_quads(mesh, igm, QuadExtractionOptions{}, progress);
  } catch (const Error& e) {
    ADD_FAILURE() << "extraction threw: " << e.what();
    return r;
  }
  const QuadMesh& q = r.quads;
  const QuadExtractionStats& s = r.stats;
  EXPECT_EQ(s.flipped_triangles + s.degenerate_triangles + s.failed_traces + s.inconsistent_segments + s.non_quad_faces,
            0);
  // Quad count = parametric area = the construction's expected count.
  EXPECT_TRUE(s.area_is_integral);
  EXPECT_EQ(s.expected_quads, expected_quads);
  EXPECT_EQ(q.num_quads(), expected_quads);
  // Topology: every face a quad (by type), edge-manifold, consistently oriented, same Euler
  // characteristic as the input.
  const QuadTopology t = quad_topology(q);
  EXPECT_EQ(t.non_manifold_edges, 0);
  EXPECT_EQ(t.inconsistent_edges, 0);
  EXPECT_EQ(t.degenerate_quads, 0);
  EXPECT_EQ(t.unreferenced_vertices, 0);
  EXPECT_EQ(t.euler_characteristic, euler_characteristic(mesh));
  // Boundary: quad boundary edges = parametric length of the mesh boundary.
  int64_t boundary_length = 0;
  for (int h = 0; h < mesh.num_halfedges(); ++h)
    if (mesh.opposite[h] < 0) {
      const IVec2 a = igm.uv[h], b = igm.uv[TriMesh::next(h)];
      boundary_length += std::llabs(b[0] - a[0]) + std::llabs(b[1] - a[1]);
    }
  EXPECT_EQ(boundary_length % igm.one(), 0);
  EXPECT_EQ(t.boundary_edges, boundary_length / igm.one());
  // Irregular vertices exactly at the singular mesh vertices, with the valence of their cone.
  const std::vector<int> turns = cone_quarter_turns(mesh, igm.to_double());
  std::map<std::array<double, 3>, int> singular_at;  // position -> mesh vertex
  for (int v = 0; v < mesh.num_vertices(); ++v)
    if (is_singular(mesh, turns, v)) singular_at[{mesh.V(v, 0), mesh.V(v, 1), mesh.V(v, 2)}] = v;
  int found = 0;
  for (int v = 0; v < q.num_vertices(); ++v) {
    const bool irregular = t.valence[v] != (t.on_boundary[v] ? 3 : 4);
    EXPECT_EQ(bool(q.vertex_singular[v]), irregular) << "quad vertex " << v;
    auto it = singular_at.find({q.V(v, 0), q.V(v, 1), q.V(v, 2)});
    if (!irregular && it == singular_at.end()) continue;
    if (it == singular_at.end()) {
      ADD_FAILURE() << "irregular quad vertex " << v << " (valence " << t.valence[v] << ") is no singularity";
      continue;
    }
    ++found;
    const int mv = it->second;
    EXPECT_EQ(t.valence[v], turns[mv] + (is_boundary_vertex(mesh, mv) ? 1 : 0)) << "at mesh vertex " << mv;
  }
  EXPECT_EQ(found, static_cast<int>(singular_at.size()));
  // No quad flipped against the input's normals.
  QuadMetricsOptions mo;
  mo.hausdorff = false;
  const QuadMetrics m = compute_quad_metrics(q, mesh, mo, progress);
  if (check_flips) EXPECT_EQ(m.flipped_quads(), 0);
  EXPECT_EQ(m.irregular_vertices, s.singular_vertices);
  return r;
}

// ---------------------------------------------------------------------------------------------

TEST(QuadExtraction, ScaledCubesGiveExactQuadCounts) {
  for (int n : {1, 2, 3, 5})
    for (int k : {1, 2, 3, 7}) {
      const auto cube = scaled(test::make_grid_cube(n), k);
      const auto r = extract_and_check("cube n=" + std::to_string(n) + " k=" + std::to_string(k), cube.mesh,
                                       to_igm(cube.mesh, cube.param), 6 * n * n * k * k);
      EXPECT_EQ(r.stats.singular_vertices, 8);
    }
}

TEST(QuadExtraction, CubeQuadsLieOnTheCube) {
  const auto cube = scaled(test::make_grid_cube(4), 3);
  Progress progress;
  const auto r = extract_quads(cube.mesh, to_igm(cube.mesh, cube.param), QuadExtractionOptions{}, progress);
  const QuadMetrics m = compute_quad_metrics(r.quads, cube.mesh, QuadMetricsOptions{}, progress);
  EXPECT_LT(m.hausdorff, 1e-9);
  EXPECT_NEAR(m.min_scaled_jacobian, 1, 1e-9);
  EXPECT_NEAR(m.mean_angle_deviation, 0, 1e-6);
  EXPECT_NEAR(m.p95_angle_deviation, 0, 1e-6);
  EXPECT_EQ(m.irregular_vertices, 8);
  // Grid vertices sit on the lattice of spacing 1/3.
  std::map<std::array<long, 3>, int> at;
  for (int v = 0; v < r.quads.num_vertices(); ++v) {
    std::array<long, 3> key;
    for (int a = 0; a < 3; ++a) {
      EXPECT_NEAR(r.quads.V(v, a) * 3, std::round(r.quads.V(v, a) * 3), 1e-9);
      key[a] = std::lround(r.quads.V(v, a) * 3);
    }
    EXPECT_TRUE(at.emplace(key, v).second) << "two quad vertices at one point";
  }
  // The cube's sharp edges (features on integer isolines) are covered by quad edges.
  std::set<std::pair<int, int>> quad_edges;
  for (int q = 0; q < r.quads.num_quads(); ++q)
    for (int k = 0; k < 4; ++k) {
      const int a = r.quads.Q(q, k), b = r.quads.Q(q, (k + 1) % 4);
      quad_edges.insert({std::min(a, b), std::max(a, b)});
    }
  int covered = 0;
  for (const auto& [key, v] : at)
    for (int axis = 0; axis < 3; ++axis) {
      // Points on a cube edge along `axis`: the other two coordinates are 0 or 12.
      const int o1 = (axis + 1) % 3, o2 = (axis + 2) % 3;
      if ((key[o1] != 0 && key[o1] != 12) || (key[o2] != 0 && key[o2] != 12) || key[axis] == 12) continue;
      std::array<long, 3> next = key;
      ++next[axis];
      auto it = at.find(next);
      ASSERT_NE(it, at.end());
      EXPECT_TRUE(quad_edges.count({std::min(v, it->second), std::max(v, it->second)}));
      ++covered;
    }
  EXPECT_EQ(covered, 12 * 12);
}

// The untangle tests' input: the quads of a 4 x 4 x 4 cube (3 quads per grid unit), its sharp edges
// at 40 degrees and a closest-point tree.
struct CubeQuads {
  SyntheticParametrized cube = scaled(test::make_grid_cube(4), 3);
  Progress progress;
  QuadMesh quads = extract_quads(cube.mesh, to_igm(cube.mesh, cube.param), QuadExtractionOptions{}, progress).quads;
  std::vector<char> sharp = detect_feature_edges(cube.mesh, {}, 40);
  TriangleBvh bvh{cube.mesh};
};

// Folded cube quads (free vertices pushed across their neighbours) are unfolded; vertices on the
// cube's sharp edges stay there (here nothing needs them to move), the connectivity stays.
TEST(UntangleQuads, FoldedCubeQuadsAreUnfoldedWithoutMovingFeatureVertices) {
  CubeQuads input;
  auto& [cube, progress, quads, sharp, bvh] = input;
  auto on_cube_edge = [&input](int v) {  // (C++17 lambdas cannot capture structured bindings)
    const auto& V = input.quads.V;
    int extreme = 0;
    for (int a = 0; a < 3; ++a) extreme += std::abs(V(v, a)) < 1e-9 || std::abs(V(v, a) - 4) < 1e-9;
    return extreme >= 2;
  };
  // Push a few face-interior vertices past the opposite corner of one of their quads (staying on
  // their cube face).
  std::mt19937 rng(5);
  int folded = 0;
  for (int v = 0; v < quads.num_vertices() && folded < 6; ++v) {
    if (on_cube_edge(v) || rng() % 9 != 0) continue;
    for (int q = 0; q < quads.num_quads(); ++q)
      for (int k = 0; k < 4; ++k)
        if (quads.Q(q, k) == v) {
          const int w = quads.Q(q, (k + 2) % 4);
          const Vec3 moved = quads.V.row(w).transpose() + 0.4 * (quads.V.row(w) - quads.V.row(v)).transpose();
          const TriangleBvh::Hit hit = bvh.closest_point(moved);
          if (on_cube_edge(w) || (hit.point - moved).norm() > 1e-9) continue;
          quads.V.row(v) = hit.point.transpose();
          quads.vertex_face[v] = hit.triangle;
          ++folded;
          q = quads.num_quads();
          break;
        }
  }
  ASSERT_GE(folded, 3);
  const QuadMesh folded_quads = quads;
  // The metrics name exactly the flipped quads, in order.
  const QuadMetrics folded_metrics = compute_quad_metrics(folded_quads, cube.mesh, QuadMetricsOptions{}, progress);
  std::vector<int> flipped_ids;
  for (int q = 0; q < folded_quads.num_quads(); ++q) {
    Vec3 p[4];
    for (int k = 0; k < 4; ++k) p[k] = folded_quads.V.row(folded_quads.Q(q, k)).transpose();
    if (quad_is_flipped(p, cube.mesh, bvh)) flipped_ids.push_back(q);
  }
  EXPECT_FALSE(flipped_ids.empty());
  EXPECT_EQ(folded_metrics.flipped_quad_ids, flipped_ids);
  EXPECT_EQ(folded_metrics.flipped_quads(), static_cast<int>(flipped_ids.size()));
  EXPECT_EQ(Json(folded_metrics)["flipped_quad_ids"].get<std::vector<int>>(), flipped_ids);
  const UntangleStats stats = untangle_flipped_quads(quads, cube.mesh, sharp, progress);
  EXPECT_EQ(stats.flipped_before, static_cast<int>(flipped_ids.size()));
  EXPECT_EQ(stats.flipped_after, 0);
  const QuadMetrics untangled_metrics = compute_quad_metrics(quads, cube.mesh, QuadMetricsOptions{}, progress);
  EXPECT_EQ(untangled_metrics.flipped_quads(), 0);
  EXPECT_TRUE(untangled_metrics.flipped_quad_ids.empty());
  EXPECT_EQ(quads.Q, folded_quads.Q);
  for (int v = 0; v < quads.num_vertices(); ++v) {
    if (on_cube_edge(v)) EXPECT_EQ(quads.V.row(v), folded_quads.V.row(v)) << v;
    EXPECT_LT(bvh.closest_point(quads.V.row(v).transpose()).squared_distance, 1e-18) << v;
  }
  // Nothing flipped: nothing moves.
  QuadMesh clean = extract_quads(cube.mesh, to_igm(cube.mesh, cube.param), QuadExtractionOptions{}, progress).quads;
  const QuadMesh copy = clean;
  EXPECT_EQ(untangle_flipped_quads(clean, cube.mesh, sharp, progress).moved_vertices, 0);
  EXPECT_EQ(clean.V, copy.V);
}

// A vertex on a sharp edge pushed past its neighbour along that edge (folding the quads of both
// cube faces) slides back along the edge; it never leaves the edge, and the cube's corners stay.
TEST(UntangleQuads, VertexOnASharpEdgeSlidesBackAlongIt) {
  CubeQuads input;
  auto& [cube, progress, quads, sharp, bvh] = input;
  auto extreme_axes = [&](const QuadMesh& q, int v) {
    std::vector<int> axes;
    for (int a = 0; a < 3; ++a)
      if (std::abs(q.V(v, a)) < 1e-9 || std::abs(q.V(v, a) - 4) < 1e-9) axes.push_back(a);
    return axes;
  };
  // v and w: neighbours on the same cube edge, neither a corner; v goes two edge lengths past w,
  // still on the edge.
  int v = -1;
  Vec3 past = Vec3::Zero();
  for (int q = 0; q < quads.num_quads() && v < 0; ++q)
    for (int k = 0; k < 4 && v < 0; ++k) {
      const int a = quads.Q(q, k), b = quads.Q(q, (k + 1) % 4);
      if (extreme_axes(quads, a).size() != 2 || extreme_axes(quads, a) != extreme_axes(quads, b)) continue;
      past = quads.V.row(b).transpose() + 2 * (quads.V.row(b) - quads.V.row(a)).transpose();
      const std::vector<int> axes = extreme_axes(quads, a);
      bool inside_edge = true;
      for (int axis = 0; axis < 3; ++axis)
        if (std::find(axes.begin(), axes.end(), axis) == axes.end())
          inside_edge = inside_edge && past[axis] > 0.5 && past[axis] < 3.5;
      if (inside_edge) v = a;
    }
  ASSERT_GE(v, 0);
  const TriangleBvh::Hit hit = bvh.closest_point(past);
  ASSERT_LT((hit.point - past).norm(), 1e-9);
  quads.V.row(v) = hit.point.transpose();
  quads.vertex_face[v] = hit.triangle;
  const QuadMesh folded = quads;
  const UntangleStats stats = untangle_flipped_quads(quads, cube.mesh, sharp, progress);
  EXPECT_GE(stats.flipped_before, 1);
  EXPECT_EQ(stats.flipped_after, 0);
  EXPECT_EQ(compute_quad_metrics(quads, cube.mesh, QuadMetricsOptions{}, progress).flipped_quads(), 0);
  EXPECT_NE(quads.V.row(v), folded.V.row(v));
  EXPECT_EQ(extreme_axes(quads, v), extreme_axes(folded, v));
  for (int u = 0; u < quads.num_vertices(); ++u) {
    if (extreme_axes(folded, u).size() == 3) EXPECT_EQ(quads.V.row(u), folded.V.row(u)) << u;
    if (extreme_axes(folded, u).size() == 2) EXPECT_EQ(extreme_axes(quads, u), extreme_axes(folded, u)) << u;
    EXPECT_LT(bvh.closest_point(quads.V.row(u).transpose()).squared_distance, 1e-18) << u;
  }
}

// The collapse's invariants on cube quads: only quads, a consistently oriented closed manifold of
// Euler characteristic 2, every vertex on the cube, none flipped and no sliver left.
void expect_valid_cube_quads(const QuadMesh& quads, const CubeQuads& input) {
  Progress progress;
  const QuadTopology t = quad_topology(quads);
  EXPECT_EQ(t.non_manifold_edges + t.inconsistent_edges + t.degenerate_quads + t.unreferenced_vertices, 0);
  EXPECT_EQ(t.boundary_edges, 0);
  EXPECT_EQ(t.euler_characteristic, 2);
  const QuadMetrics metrics = compute_quad_metrics(quads, input.cube.mesh, QuadMetricsOptions{}, progress);
  EXPECT_EQ(metrics.flipped_quads(), 0);
  EXPECT_EQ(metrics.collapsed_edge_quads(), 0);
  EXPECT_EQ(test::count_slivers(quads), 0);
  EXPECT_EQ(test::irregular_vertices_off_singularities(quads), 0);
  for (int v = 0; v < quads.num_vertices(); ++v)
    EXPECT_LT(input.bvh.closest_point(quads.V.row(v).transpose()).squared_distance, 1e-18) << v;
}

// Vertex `v` moved, on its cube face, to `share` of the way to the corner opposite it in its quad q.
void squeeze_quad(CubeQuads& input, int q, int k, double share) {
  QuadMesh& quads = input.quads;
  const int v = quads.Q(q, k), w = quads.Q(q, (k + 2) % 4);
  const Vec3 target = quads.V.row(v).transpose() + share * (quads.V.row(w) - quads.V.row(v)).transpose();
  const TriangleBvh::Hit hit = input.bvh.closest_point(target);
  quads.V.row(v) = hit.point.transpose();
  quads.vertex_face[v] = hit.triangle;
}

// A quad squeezed to a sliver (one free corner moved 95 % of the way to the opposite one) is
// collapsed: one quad and one vertex fewer, the vertices on the cube's sharp edges where they were.
TEST(CollapseFoldedQuads, SliverOnACubeFaceIsCollapsed) {
  CubeQuads input;
  QuadMesh& quads = input.quads;
  const QuadTopology before = quad_topology(quads);
  auto on_cube_edge = [&](const QuadMesh& m, int v) {
    int extreme = 0;
    for (int a = 0; a < 3; ++a) extreme += std::abs(m.V(v, a)) < 1e-9 || std::abs(m.V(v, a) - 4) < 1e-9;
    return extreme >= 2;
  };
  // A quad in the middle of a face: all four corners inside it (valence 4).
  int q = 0;
  for (; q < quads.num_quads(); ++q) {
    bool inner = true;
    for (int k = 0; k < 4; ++k)
      inner = inner && !on_cube_edge(quads, quads.Q(q, k)) && before.valence[quads.Q(q, k)] == 4;
    if (inner) break;
  }
  ASSERT_LT(q, quads.num_quads());
  squeeze_quad(input, q, 0, 0.95);
  ASSERT_EQ(test::count_slivers(quads), 1);
  std::vector<Vec3> edge_points;
  for (int v = 0; v < quads.num_vertices(); ++v)
    if (on_cube_edge(quads, v)) edge_points.push_back(quads.V.row(v).transpose());
  const QuadMesh squeezed = quads;
  const UntangleStats stats = collapse_folded_quads(quads, input.cube.mesh, input.sharp, input.progress);
  EXPECT_EQ(stats.collapsed_quads, 1);
  EXPECT_EQ(quads.num_quads(), squeezed.num_quads() - 1);
  EXPECT_EQ(quads.num_vertices(), squeezed.num_vertices() - 1);
  expect_valid_cube_quads(quads, input);
  std::vector<Vec3> edge_points_after;
  for (int v = 0; v < quads.num_vertices(); ++v)
    if (on_cube_edge(quads, v)) edge_points_after.push_back(quads.V.row(v).transpose());
  EXPECT_EQ(edge_points_after, edge_points);
  // Nothing folded: nothing changes.
  QuadMesh clean = CubeQuads{}.quads;
  const QuadMesh copy = clean;
  EXPECT_EQ(collapse_folded_quads(clean, input.cube.mesh, input.sharp, input.progress).collapsed_quads, 0);
  EXPECT_EQ(clean.Q, copy.Q);
  EXPECT_EQ(clean.V, copy.V);
}

// Without sharp edges every cube vertex is free. A quad at a cube corner squeezed along its diagonal
// between the two cube-edge vertices (the corner of valence 3 beside them): both diagonals remove
// the sliver, so the shorter goes; the two cube-edge vertices merge, the corner is left with two
// quads and is dissolved (two quads and two vertices fewer), and the result is valid.
TEST(CollapseFoldedQuads, SliverBesideAValence3CornerDissolvesIt) {
  CubeQuads input;
  QuadMesh& quads = input.quads;
  const QuadTopology before = quad_topology(quads);
  int q = 0, k = 0;
  for (; q < quads.num_quads(); ++q) {
    for (k = 0; k < 4 && before.valence[quads.Q(q, (k + 1) % 4)] != 3; ++k) {
    }
    if (k < 4) break;
  }
  ASSERT_LT(q, quads.num_quads());
  // Corner k + 1 has valence 3: corners k and k + 2 are the cube-edge vertices; squeeze k toward k + 2.
  squeeze_quad(input, q, k, 0.95);
  ASSERT_EQ(test::count_slivers(quads), 1);
  const QuadMesh squeezed = quads;
  const std::vector<char> no_features;
  const UntangleStats stats = collapse_folded_quads(quads, input.cube.mesh, no_features, input.progress);
  EXPECT_EQ(stats.collapsed_quads, 1);
  const int removed = squeezed.num_quads() - quads.num_quads();
  EXPECT_EQ(removed, 2);
  EXPECT_EQ(squeezed.num_vertices() - quads.num_vertices(), removed);
  expect_valid_cube_quads(quads, input);
}

// How many faces of the cube [0, 4]^3 vertex v lies on (1: a face, 2: an edge, 3: a corner).
int cube_sides(const QuadMesh& quads, int v) {
  int sides = 0;
  for (int a = 0; a < 3; ++a) sides += std::abs(quads.V(v, a)) < 1e-9 || std::abs(quads.V(v, a) - 4) < 1e-9;
  return sides;
}

// The quads of `quads` with an edge between v and w, ascending.
std::vector<int> quads_on_edge(const QuadMesh& quads, int v, int w) {
  std::vector<int> found;
  for (int q = 0; q < quads.num_quads(); ++q)
    for (int k = 0; k < 4; ++k) {
      const int a = quads.Q(q, k), b = quads.Q(q, (k + 1) % 4);
      if ((a == v && b == w) || (a == w && b == v)) found.push_back(q);
    }
  return found;
}

// A free vertex moved onto its neighbour on a cube face: the two quads on their edge have a
// collapsed edge (triangles to the eye) and nothing is flipped. The metrics name those two quads;
// the untangle of flipped quads leaves them; the collapse's first untangle moves the two corners
// apart without changing the connectivity.
TEST(CollapseFoldedQuads, CollapsedEdgeOnACubeFaceIsMovedApart) {
  CubeQuads input;
  QuadMesh& quads = input.quads;
  const QuadTopology topology = quad_topology(quads);
  auto inner = [&](int v) { return cube_sides(quads, v) == 1 && topology.valence[v] == 4; };
  int v = -1, w = -1;
  for (int q = 0; q < quads.num_quads() && v < 0; ++q)
    if (inner(quads.Q(q, 0)) && inner(quads.Q(q, 1))) v = quads.Q(q, 0), w = quads.Q(q, 1);
  ASSERT_GE(v, 0);
  quads.V.row(v) = quads.V.row(w);
  quads.vertex_face[v] = quads.vertex_face[w];
  const std::vector<int> collapsed = quads_on_edge(quads, v, w);
  ASSERT_EQ(collapsed.size(), 2u);
  for (int q = 0; q < quads.num_quads(); ++q)
    EXPECT_EQ(quad_has_collapsed_edge(quads, q), q == collapsed[0] || q == collapsed[1]) << q;
  const QuadMetrics metrics = compute_quad_metrics(quads, input.cube.mesh, QuadMetricsOptions{}, input.progress);
  EXPECT_EQ(metrics.flipped_quads(), 0);
  EXPECT_EQ(metrics.collapsed_edge_quad_ids, collapsed);
  EXPECT_EQ(Json(metrics)["collapsed_edge_quads"], 2);
  const QuadMesh moved = quads;
  QuadMesh untangled = quads;
  EXPECT_EQ(untangle_flipped_quads(untangled, input.cube.mesh, input.sharp, input.progress).moved_vertices, 0);
  EXPECT_EQ(untangled.V, moved.V);
  const UntangleStats stats = collapse_folded_quads(quads, input.cube.mesh, input.sharp, input.progress);
  EXPECT_EQ(stats.collapsed_before, 2);
  EXPECT_EQ(stats.collapsed_after, 0);
  EXPECT_EQ(stats.collapsed_quads, 0);
  EXPECT_GE(stats.moved_vertices, 1);
  EXPECT_EQ(quads.Q, moved.Q);
  expect_valid_cube_quads(quads, input);
}

// A quad vertex on a sharp cube edge moved onto the cube corner beside it, where another quad
// vertex stays: neither could move (vertices at corners stay), so one of the two leaves the corner
// along a cube edge. The corner keeps a vertex, every vertex on a cube edge stays on one, and no
// edge stays collapsed.
TEST(CollapseFoldedQuads, TwoVerticesOnACubeCornerAreMovedApart) {
  CubeQuads input;
  QuadMesh& quads = input.quads;
  int corner = -1, v = -1;
  for (int q = 0; q < quads.num_quads() && v < 0; ++q)
    for (int k = 0; k < 4 && v < 0; ++k)
      if (cube_sides(quads, quads.Q(q, k)) == 3 && cube_sides(quads, quads.Q(q, (k + 1) % 4)) == 2)
        corner = quads.Q(q, k), v = quads.Q(q, (k + 1) % 4);
  ASSERT_GE(v, 0);
  std::vector<int> axes_before(quads.num_vertices());
  for (int u = 0; u < quads.num_vertices(); ++u) axes_before[u] = cube_sides(quads, u);
  const Vec3 corner_point = quads.V.row(corner).transpose();
  quads.V.row(v) = quads.V.row(corner);
  quads.vertex_face[v] = quads.vertex_face[corner];
  ASSERT_EQ(quads_on_edge(quads, v, corner).size(), 2u);
  const QuadMesh moved = quads;
  const UntangleStats stats = collapse_folded_quads(quads, input.cube.mesh, input.sharp, input.progress);
  EXPECT_EQ(stats.collapsed_before, 2);
  EXPECT_EQ(stats.collapsed_after, 0);
  EXPECT_EQ(quads.Q, moved.Q);
  expect_valid_cube_quads(quads, input);
  EXPECT_TRUE(quads.V.row(corner).transpose() == corner_point || quads.V.row(v).transpose() == corner_point);
  for (int u = 0; u < quads.num_vertices(); ++u) EXPECT_GE(cube_sides(quads, u), std::min(2, axes_before[u])) << u;
}

// Moves vertex v of an exact map by delta, given in the chart of its outgoing halfedge h0, in every
// chart it appears in (rotated across each transition); v must be interior.
void move_exact_vertex(const TriMesh& mesh, ExactParametrization& map, int h0, IVec2 delta) {
  std::vector<int> fan = outgoing_halfedges(mesh, mesh.from(h0));
  std::rotate(fan.begin(), std::find(fan.begin(), fan.end(), h0), fan.end());
  for (int h : fan) {
    map.uv[h] = {map.uv[h][0] + delta[0], map.uv[h][1] + delta[1]};
    delta = rotate_quarter(delta, map.rotation[TriMesh::prev(h)]);
  }
}

// An exact cube map with vertices pushed 1.5 edges towards a neighbour, consistently in every
// chart: vertices off the cut, vertices on the cut (the cube's edges) and, where the cube's edges
// are isolines, vertices pushed along them. The untangle unfolds every triangle and keeps the
// transitions exact, the singular corners in place, the isolines, every vertex's angle sum and the
// parametric area, and the map gives its quads again.
class UntangleMapFolds : public ::testing::TestWithParam<bool> {};

TEST_P(UntangleMapFolds, AreUnfoldedAndEverythingElseKept) {
  const bool cube_edges_are_isolines = GetParam();
  const auto cube = scaled(test::make_grid_cube(4), 3);
  const TriMesh& mesh = cube.mesh;
  ExactParametrization igm = to_igm(mesh, cube.param);
  const std::vector<int> cones = exact_angle_sums(mesh, igm);
  bool integral = false;
  const int64_t area = exact_parametric_area(igm, &integral);
  // The cube's edges: both ends on the same two faces of the cube ([0, 4]^3).
  auto cube_faces = [&](int v) {
    std::vector<int> faces;
    for (int a = 0; a < 3; ++a)
      for (double side : {0.0, 4.0})
        if (std::abs(mesh.V(v, a) - side) < 1e-9) faces.push_back(2 * a + (side > 0));
    return faces;
  };
  std::vector<char> on_cube_edge(mesh.num_edges(), 0);
  for (int e = 0; e < mesh.num_edges(); ++e) {
    const int h = mesh.edge_halfedge[e];
    const std::vector<int> a = cube_faces(mesh.from(h)), b = cube_faces(mesh.to(h));
    on_cube_edge[e] = a.size() >= 2 && b.size() >= 2 && (a == b || a.size() == 3 || b.size() == 3);
  }
  std::vector<IsolineConstraint> isolines;
  if (cube_edges_are_isolines) isolines = isoline_constraints(mesh, igm.to_double(), on_cube_edge, false);
  // Fold vertices that share no triangle: off the cut, on the cut, and along a cube edge.
  enum Kind { OffCut, OnCut, AlongCubeEdge };
  std::vector<char> on_cut(mesh.num_vertices(), 0), touched(mesh.num_vertices(), 0);
  for (int h = 0; h < mesh.num_halfedges(); ++h)
    if (igm.is_cut[mesh.edge_of[h]]) on_cut[mesh.from(h)] = on_cut[mesh.to(h)] = 1;
  std::map<Kind, int> folded;
  for (int h = 0; h < mesh.num_halfedges(); ++h) {
    const int v = mesh.from(h), w = mesh.to(h);
    if (cube_faces(v).size() == 3 || touched[v]) continue;
    const Kind kind = !on_cut[v]                                                 ? OffCut
                      : on_cube_edge[mesh.edge_of[h]] && cube_edges_are_isolines ? AlongCubeEdge
                                                                                 : OnCut;
    if (folded[kind] >= 2 || (kind == OnCut && cube_edges_are_isolines)) continue;
    bool near = false;
    for (int g : outgoing_halfedges(mesh, v))
      for (int j = 0; j < 3; ++j) near = near || touched[mesh.F(g / 3, j)];
    if (near) continue;
    const IVec2 p = igm.uv[h], q = igm.uv[TriMesh::next(h)];
    move_exact_vertex(mesh, igm, h, {(q[0] - p[0]) * 3 / 2, (q[1] - p[1]) * 3 / 2});
    touched[v] = touched[w] = 1;
    ++folded[kind];
  }
  ASSERT_EQ(folded[OffCut], 2);
  ASSERT_EQ(folded[cube_edges_are_isolines ? AlongCubeEdge : OnCut], 2);
  ASSERT_EQ(exact_transition_residual(mesh, igm), 0);
  const ExactParametrization before = igm;
  int flipped = 0, degenerate = 0;
  count_exact_irregular(igm, &flipped, &degenerate);
  ASSERT_GT(flipped, 0);
  EXPECT_GT(count_exact_winding_defects(mesh, igm, cones), 0);  // a folded vertex has no full turn
  Progress progress;
  const MapUntangleStats stats = untangle_map(mesh, {}, isolines, igm, progress);
  EXPECT_EQ(stats.flipped_before, flipped);
  EXPECT_EQ(stats.flipped_after, 0);
  EXPECT_EQ(stats.degenerate_after, 0);
  EXPECT_GE(stats.moved_vertices, 4);
  count_exact_irregular(igm, &flipped, &degenerate);
  EXPECT_EQ(flipped + degenerate, 0);
  EXPECT_EQ(exact_transition_residual(mesh, igm), 0);
  EXPECT_EQ(exact_parametric_area(igm, &integral), area);
  EXPECT_TRUE(integral);
  EXPECT_EQ(igm.rotation, before.rotation);
  EXPECT_EQ(igm.translation, before.translation);
  EXPECT_EQ(igm.is_cut, before.is_cut);
  for (int c = 0; c < 3 * mesh.num_faces(); ++c)
    if (cube_faces(mesh.F(c / 3, c % 3)).size() == 3) EXPECT_EQ(igm.uv[c], before.uv[c]) << c;
  for (const IsolineConstraint& iso : isolines) {
    const int h = iso.halfedge;
    EXPECT_EQ(igm.uv[h][iso.axis], before.uv[h][iso.axis]) << h;
    EXPECT_EQ(igm.uv[TriMesh::next(h)][iso.axis], before.uv[TriMesh::next(h)][iso.axis]) << h;
  }
  EXPECT_EQ(exact_angle_sums(mesh, igm), cones);  // no cone appeared or moved
  EXPECT_EQ(count_exact_winding_defects(mesh, igm, cones), 0);
  extract_and_check("untangled cube", mesh, igm, 6 * 4 * 4 * 3 * 3);
}

INSTANTIATE_TEST_SUITE_P(UntangleMap, UntangleMapFolds, ::testing::Bool(),
                         [](const auto& info) { return info.param ? "CubeEdgesAreIsolines" : "NoIsolines"; });

QuadMesh quads_of(const std::vector<std::array<int, 4>>& faces, int num_vertices) {
  QuadMesh q;
  q.V = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>::Zero(num_vertices, 3);
  q.Q.resize(static_cast<int>(faces.size()), 4);
  for (size_t i = 0; i < faces.size(); ++i)
    for (int k = 0; k < 4; ++k) q.Q(static_cast<int>(i), k) = faces[i][k];
  return q;
}

TEST(NonManifoldQuads, FlagsEveryQuadOfABadEdgeOrCorner) {
  // Two quads side by side: fine.
  EXPECT_EQ(non_manifold_quads(quads_of({{0, 1, 4, 3}, {1, 2, 5, 4}}, 6)), std::vector<char>({0, 0}));
  // A third quad on edge 1-4, and one running 1 -> 4 like the first: all of them flagged.
  EXPECT_EQ(non_manifold_quads(quads_of({{0, 1, 4, 3}, {1, 2, 5, 4}, {4, 1, 6, 7}, {8, 9, 10, 11}}, 12)),
            std::vector<char>({1, 1, 1, 0}));
  EXPECT_EQ(non_manifold_quads(quads_of({{0, 1, 4, 3}, {2, 1, 4, 5}}, 6)), std::vector<char>({1, 1}));
  // A repeated corner, next to each other or across.
  EXPECT_EQ(non_manifold_quads(quads_of({{0, 1, 1, 3}, {4, 5, 6, 7}}, 8)), std::vector<char>({1, 0}));
  EXPECT_EQ(non_manifold_quads(quads_of({{0, 1, 0, 3}, {4, 5, 6, 7}}, 8)), std::vector<char>({1, 0}));
  // A pillow of two quads glued along all four edges is a closed 2-manifold.
  EXPECT_EQ(non_manifold_quads(quads_of({{0, 1, 4, 3}, {1, 0, 3, 4}}, 5)), std::vector<char>({0, 0}));
}

TEST(QuadExtraction, Tori) {
  for (int k : {1, 2, 5}) {
    const auto torus = scaled(test::make_grid_torus(12, 8), k);
    extract_and_check("torus k=" + std::to_string(k), torus.mesh, to_igm(torus.mesh, torus.param), 96 * k * k);
  }
}

TEST(QuadExtraction, CoarseMapsWithManyTrianglesPerQuad) {
  // Cube sides of 8 x 8 cells mapped onto 2 x 2 quads (32 triangles per quad).
  const auto cube = scaled(test::make_grid_cube(8), 0.25);
  extract_and_check("coarse cube", cube.mesh, to_igm(cube.mesh, cube.param), 24);
  const auto cube1 = scaled(test::make_grid_cube(6), 1.0 / 6);
  extract_and_check("one quad per side", cube1.mesh, to_igm(cube1.mesh, cube1.param), 6);
  // 4 x 3 quads (with fewer than 3 quads around, two quads share two edges between the same
  // vertices, which the vertex-pair topology check cannot tell apart).
  const auto torus = scaled(test::make_grid_torus(16, 12), 0.25);
  extract_and_check("coarse torus", torus.mesh, to_igm(torus.mesh, torus.param), 12);
  auto perturbed = scaled(test::make_grid_cube(8), 0.25);
  perturb_vertices(perturbed, 0.45, 5);
  extract_and_check("coarse perturbed cube", perturbed.mesh, to_igm(perturbed.mesh, perturbed.param), 24);
}

TEST(QuadExtraction, PerturbedCubesAndTori) {
  for (unsigned seed = 1; seed <= 6; ++seed) {
    auto cube = scaled(test::make_grid_cube(3 + seed % 3), 1 + seed % 3);
    const int n = 3 + seed % 3, k = 1 + seed % 3;
    perturb_vertices(cube, 0.45, seed);
    extract_and_check("perturbed cube seed " + std::to_string(seed), cube.mesh, to_igm(cube.mesh, cube.param),
                      6 * n * n * k * k);
    auto torus = scaled(test::make_grid_torus(10, 6), seed % 2 ? 1 : 0.5);
    perturb_vertices(torus, 0.45, 100 + seed);
    extract_and_check("perturbed torus seed " + std::to_string(seed), torus.mesh, to_igm(torus.mesh, torus.param),
                      seed % 2 ? 60 : 15);
  }
}

TEST(QuadExtraction, RetriangulatedGridsWithIsolinesThroughVerticesAndAlongEdges) {
  for (unsigned seed = 1; seed <= 4; ++seed) {
    // Half steps: isolines along every other edge row, through vertices and cell centres.
    const auto half = make_random_torus(12, 8, 0.5, 0.3, seed);
    extract_and_check("half-step torus", half.mesh, to_igm(half.mesh, half.param), 24);
    // Unit steps: every edge row is an isoline; centres are half-integer.
    const auto unit = make_random_torus(10, 6, 1, 0.4, 10 + seed);
    extract_and_check("unit-step torus", unit.mesh, to_igm(unit.mesh, unit.param), 60);
    // Fine maps: 3 x 3 quads per cell, centre vertices on integer points.
    const auto fine = make_random_torus(8, 6, 3, 0.5, 20 + seed);
    extract_and_check("fine torus", fine.mesh, to_igm(fine.mesh, fine.param), 8 * 6 * 9);
  }
}

TEST(QuadExtraction, FineMapsWithManyQuadsPerTriangle) {
  const auto cube = scaled(test::make_grid_cube(1), 40);  // 12 triangles, 9600 quads
  extract_and_check("fine cube", cube.mesh, to_igm(cube.mesh, cube.param), 6 * 1600);
  auto torus = scaled(test::make_grid_torus(6, 4), 9);
  perturb_vertices(torus, 0.45, 77);
  extract_and_check("fine perturbed torus", torus.mesh, to_igm(torus.mesh, torus.param), 24 * 81);
}

TEST(QuadExtraction, PlanarRectanglesKeepTheirBoundary) {
  for (unsigned seed = 1; seed <= 3; ++seed) {
    const auto rect = make_rectangle(6, 4, 1, seed);
    auto r = extract_and_check("rectangle", rect.mesh, to_igm(rect.mesh, rect.param), 24);
    EXPECT_EQ(r.stats.singular_vertices, 4);  // the four corners, valence 2
    auto fine = make_rectangle(4, 2, 3, seed);
    perturb_vertices(fine, 0.4, seed);
    extract_and_check("fine rectangle", fine.mesh, to_igm(fine.mesh, fine.param), 72);
    auto coarse = make_rectangle(8, 12, 0.5, seed);
    perturb_vertices(coarse, 0.45, seed + 7);
    extract_and_check("coarse rectangle", coarse.mesh, to_igm(coarse.mesh, coarse.param), 24);
  }
}

TEST(QuadExtraction, CubeWithOneSideRemoved) {
  for (int k : {1, 2}) {
    const int n = 4;
    const auto cube = scaled(test::make_grid_cube(n), k);
    auto open = keep_faces(cube, [&](int f) {
      for (int c = 0; c < 3; ++c)
        if (cube.mesh.V(cube.mesh.F(f, c), 2) != n) return true;
      return false;
    });
    EXPECT_EQ(count_boundary_loops(open.mesh), 1);
    auto r = extract_and_check("open cube", open.mesh, to_igm(open.mesh, open.param), 5 * n * n * k * k);
    EXPECT_EQ(r.stats.singular_vertices, 4);  // the bottom corners; the rim corners are regular
    perturb_vertices(open, 0.45, 3 + k);
    extract_and_check("perturbed open cube", open.mesh, to_igm(open.mesh, open.param), 5 * n * n * k * k);
  }
}

TEST(QuadExtraction, SingularitiesOfAnyValenceFromGluedSectors) {
  for (int k : {3, 5, 6, 8}) {
    auto sectors = make_glued_sectors(k, 3, k);
    auto r =
        extract_and_check("sectors k=" + std::to_string(k), sectors.mesh, to_igm(sectors.mesh, sectors.param), 9 * k);
    EXPECT_EQ(r.stats.singular_vertices, 1 + k);  // the centre and the outer corners
    auto s2 = scaled(make_glued_sectors(k, 2, 50 + k), 2);
    perturb_vertices(s2, 0.45, k);
    extract_and_check("perturbed sectors", s2.mesh, to_igm(s2.mesh, s2.param), 16 * k);
  }
}

// ---------------------------------------------------------------------------------------------
// Real meshes: Tutte embeddings of discs onto integer rectangles are flip-free integer-grid maps
// (four boundary corners as the only singularities) with every kind of local density.

// The mesh as a disc: itself if it has one boundary loop, else without the faces of vertex v0's star.
TriMesh real_disc(const TriMesh& mesh, int v0) {
  if (count_boundary_loops(mesh) == 1) return mesh;
  SyntheticParametrized s;
  s.mesh = mesh;
  s.param.uv.setZero(3 * mesh.num_faces(), 2);
  return keep_faces(s, [&](int f) { return mesh.F(f, 0) != v0 && mesh.F(f, 1) != v0 && mesh.F(f, 2) != v0; }).mesh;
}

// Uniform-weight Tutte embedding onto [0,w] x [0,h], boundary by arc length, corners at quartiles.
SyntheticParametrized tutte_rectangle(const TriMesh& disc, int w, int h) {
  std::vector<int> loop;
  int start = -1;
  for (int hh = 0; hh < disc.num_halfedges() && start < 0; ++hh)
    if (disc.opposite[hh] < 0) start = hh;
  for (int hh = start; loop.empty() || hh != start; hh = disc.vertex_halfedge[disc.to(hh)]) {
    loop.push_back(disc.from(hh));
    if (loop.size() > static_cast<size_t>(disc.num_vertices())) throw std::runtime_error("boundary walk");
  }
  const int nb = static_cast<int>(loop.size());
  std::vector<double> arc(nb + 1, 0);
  for (int i = 0; i < nb; ++i)
    arc[i + 1] = arc[i] + (disc.position(loop[(i + 1) % nb]) - disc.position(loop[i])).norm();
  int corner[5];
  for (int c = 0; c < 4; ++c)
    corner[c] = static_cast<int>(std::lower_bound(arc.begin(), arc.end(), arc[nb] * c / 4) - arc.begin());
  corner[4] = nb;
  for (int c = 0; c < 4; ++c)
    if (corner[c + 1] <= corner[c]) throw std::runtime_error("tutte_rectangle: a side without boundary edges");
  const Vec2 rect[5] = {{0, 0}, {double(w), 0}, {double(w), double(h)}, {0, double(h)}, {0, 0}};
  std::vector<Vec2> uv(disc.num_vertices(), Vec2::Zero());
  std::vector<int> unknown(disc.num_vertices(), -1);
  std::vector<char> fixed(disc.num_vertices(), 0);
  for (int c = 0; c < 4; ++c)
    for (int i = corner[c]; i < corner[c + 1]; ++i) {
      const double t = (arc[i] - arc[corner[c]]) / (arc[corner[c + 1]] - arc[corner[c]]);
      uv[loop[i]] = rect[c] + t * (rect[c + 1] - rect[c]);
      fixed[loop[i]] = 1;
    }
  int n = 0;
  for (int v = 0; v < disc.num_vertices(); ++v)
    if (!fixed[v]) unknown[v] = n++;
  std::vector<Eigen::Triplet<double>> triplets;
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(n, 2);
  for (int v = 0; v < disc.num_vertices(); ++v) {
    if (fixed[v]) continue;
    const std::vector<int> out = outgoing_halfedges(disc, v);
    triplets.emplace_back(unknown[v], unknown[v], double(out.size()));
    for (int hh : out) {
      const int u = disc.to(hh);
      if (fixed[u])
        rhs.row(unknown[v]) += uv[u].transpose();
      else
        triplets.emplace_back(unknown[v], unknown[u], -1.0);
    }
  }
  Eigen::SparseMatrix<double> L(n, n);
  L.setFromTriplets(triplets.begin(), triplets.end());
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(L);
  const Eigen::MatrixXd x = solver.solve(rhs);
  for (int v = 0; v < disc.num_vertices(); ++v)
    if (!fixed[v]) uv[v] = x.row(unknown[v]).transpose();
  SyntheticParametrized out;
  out.mesh = disc;
  out.param.uv.resize(3 * disc.num_faces(), 2);
  for (int f = 0; f < disc.num_faces(); ++f)
    for (int k = 0; k < 3; ++k) out.param.uv.row(3 * f + k) = uv[disc.F(f, k)].transpose();
  test::infer_rotations(out.mesh, out.param);
  return out;
}

TEST(QuadExtraction, TutteRectanglesOnRealMeshes) {
  for (const std::string name :
       {"spot.obj", "bunny.off", "fandisk.obj", "wingnut.obj", "decimated-max.obj", "camelhead.off", "face.obj"}) {
    const TriMesh mesh = test::component_mesh(test::load_mesh(name), 0);
    for (const auto& size : {std::array<int, 2>{25, 20}, std::array<int, 2>{50, 40}}) {
      // A closed mesh is opened at a vertex star; a star whose Tutte map has an ear triangle (three
      // boundary vertices on one rectangle side, hence degenerate), or whose boundary cannot give each
      // rectangle side an edge, is replaced by the next one.
      bool done = false;
      for (int v0 = 0, tries = 0; v0 < mesh.num_vertices() && tries < 5 && !done; ++v0) {
        if (outgoing_halfedges(mesh, v0).size() < 6) continue;  // each rectangle side needs an edge
        ++tries;
        const TriMesh disc = real_disc(mesh, v0);
        ASSERT_EQ(count_boundary_loops(disc), 1) << name;
        ASSERT_EQ(euler_characteristic(disc), 1) << name;
        SyntheticParametrized tutte;
        try {
          tutte = tutte_rectangle(disc, size[0], size[1]);
        } catch (const std::runtime_error&) {
          continue;  // "a side without boundary edges"
        }
        const ExactParametrization igm = to_igm(tutte.mesh, tutte.param, 40);
        int flipped = 0;
        for (int f = 0; f < disc.num_faces(); ++f)
          flipped += orient2d_exact(igm.uv[3 * f], igm.uv[3 * f + 1], igm.uv[3 * f + 2]) <= 0;
        if (flipped > 0) continue;
        done = true;
        Timer timer;
        const auto r = extract_and_check(name + " " + std::to_string(size[0]) + "x" + std::to_string(size[1]),
                                         tutte.mesh, igm, size[0] * size[1], false);
        std::printf("%-18s %6d triangles %5d quads: %7lld triangle steps, extract+check %.3f s\n", name.c_str(),
                    disc.num_faces(), r.quads.num_quads(), static_cast<long long>(r.stats.triangle_steps),
                    timer.seconds());
      }
      EXPECT_TRUE(done) << name << ": no flip-free Tutte map";
    }
  }
}

// The integer-grid map of a quad mesh: each triangle of `tri` is split into three quads (corner,
// edge midpoints, centre), each quad into two triangles (random diagonal) whose chart is the square
// [0,k]^2. Singularities of every valence sit at the original vertices (valence = number of
// triangles there) and at the face centres (valence 3); genus and boundaries are the input's.
struct QuadMeshMap {
  SyntheticParametrized map;
  int64_t quads = 0;
};
QuadMeshMap quad_mesh_map(const TriMesh& tri, int k, unsigned seed) {
  std::mt19937 rng(seed);
  const int nv = tri.num_vertices(), ne = tri.num_edges(), nf = tri.num_faces();
  auto mid = [&](int h) { return nv + tri.edge_of[h]; };
  auto centre = [&](int f) { return nv + ne + f; };
  QuadMeshMap out;
  TriMesh& mesh = out.map.mesh;
  mesh.V.resize(nv + ne + nf, 3);
  for (int v = 0; v < nv; ++v) mesh.V.row(v) = tri.V.row(v);
  for (int e = 0; e < ne; ++e) {
    const int h = tri.edge_halfedge[e];
    mesh.V.row(nv + e) = 0.5 * (tri.V.row(tri.from(h)) + tri.V.row(tri.to(h)));
  }
  for (int f = 0; f < nf; ++f)
    mesh.V.row(centre(f)) = (tri.V.row(tri.F(f, 0)) + tri.V.row(tri.F(f, 1)) + tri.V.row(tri.F(f, 2))) / 3;
  mesh.F.resize(6 * nf, 3);
  out.map.param.uv.resize(18 * nf, 2);
  const Vec2 square[4] = {{0, 0}, {double(k), 0}, {double(k), double(k)}, {0, double(k)}};
  int t = 0;
  for (int f = 0; f < nf; ++f)
    for (int c = 0; c < 3; ++c) {
      const int h = 3 * f + c, hp = TriMesh::prev(h);
      const int quad[4] = {tri.from(h), mid(h), centre(f), mid(hp)};  // counter-clockwise
      const int d = rng() % 2;                                        // diagonal 0-2 or 1-3
      const int split[2][2][3] = {{{0, 1, 2}, {0, 2, 3}}, {{0, 1, 3}, {1, 2, 3}}};
      for (const auto& tr : split[d]) {
        for (int j = 0; j < 3; ++j) {
          mesh.F(t, j) = quad[tr[j]];
          out.map.param.uv.row(3 * t + j) = square[tr[j]].transpose();
        }
        ++t;
      }
    }
  build_connectivity(mesh);
  test::infer_rotations(mesh, out.map.param);
  out.quads = int64_t(3) * nf * k * k;
  return out;
}

TEST(QuadExtraction, QuadMeshMapsOfRealMeshesWithSingularitiesOfEveryValence) {
  struct Case {
    std::string name;
    int max_k;
    bool smooth;
  };
  // k = 1: the map of the quad mesh itself; k = 2: refined and perturbed. On CAD meshes the
  // perturbation moves isolines off the sharp edges, so quads may fold over them: flips are
  // asserted on the smooth meshes only there.
  const Case cases[] = {{"joint.obj", 2, false},    {"spot.obj", 2, true},     {"torus.obj", 2, true},
                        {"fertility.off", 2, true}, {"wingnut.obj", 2, false}, {"camelhead.off", 1, true}};
  for (const Case& c : cases) {
    const std::string& name = c.name;
    const TriMesh tri = test::component_mesh(test::load_mesh(name), 0);
    for (int k = 1; k <= c.max_k; ++k) {
      QuadMeshMap qm = quad_mesh_map(tri, k, k);
      if (k == 2) perturb_vertices(qm.map, 0.45, 17);
      const ExactParametrization igm = to_igm(qm.map.mesh, qm.map.param, 24);
      Timer timer;
      const auto r =
          extract_and_check(name + " k=" + std::to_string(k), qm.map.mesh, igm, qm.quads, k == 1 || c.smooth);
      int max_valence = 0;
      const QuadTopology topo = quad_topology(r.quads);
      for (int v = 0; v < r.quads.num_vertices(); ++v) max_valence = std::max(max_valence, topo.valence[v]);
      std::printf("%-14s k=%d %6d triangles %6d quads %5d singular (max valence %d), extract+check %.3f s\n",
                  name.c_str(), k, qm.map.mesh.num_faces(), r.quads.num_quads(), r.stats.singular_vertices, max_valence,
                  timer.seconds());
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Robustness: broken maps never crash or hang.

TEST(QuadExtraction, FlippedTriangleIsReportedNotCrashed) {
  auto torus = test::make_grid_torus(8, 6);
  ExactParametrization igm = to_igm(torus.mesh, torus.param);
  // Push one vertex across its ring (consistently in all corners, so transitions still hold).
  const int v = 20;
  for (int h : outgoing_halfedges(torus.mesh, v)) igm.uv[h][0] += 3 * igm.one() / 2;
  Progress progress;
  try {
    extract_quads(torus.mesh, igm, QuadExtractionOptions{}, progress);
    ADD_FAILURE() << "a flipped map was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::StageFailed);
    EXPECT_NE(std::string(e.what()).find("flipped"), std::string::npos);
  }
  QuadExtractionOptions lenient;
  lenient.allow_defects = true;
  const auto r = extract_quads(torus.mesh, igm, lenient, progress);
  EXPECT_GT(r.stats.flipped_triangles, 0);
  EXPECT_LT(r.quads.num_quads(), 48);
  for (int qd = 0; qd < r.quads.num_quads(); ++qd)
    for (int c = 0; c < 4; ++c) EXPECT_LT(r.quads.Q(qd, c), r.quads.num_vertices());
}

TEST(QuadExtraction, NonIntegerSingularityIsReported) {
  auto cube = test::make_grid_cube(3);
  // Shift the whole map by half a unit: the corners leave the integer points.
  cube.param.uv.array() += 0.5;
  SanitizeOptions so;
  so.fraction_bits = 16;
  ExactParametrization igm = sanitize_parametrization(cube.mesh, cube.param, so).param;
  Progress progress;
  QuadExtractionOptions lenient;
  lenient.allow_defects = true;
  QuadExtraction r;
  try {
    r = extract_quads(cube.mesh, igm, lenient, progress);
  } catch (const Error& e) {
    // Translations may have become non-integral: refused with a clear message.
    EXPECT_EQ(e.code(), ErrorCode::InvalidArgument) << e.what();
    return;
  }
  EXPECT_GT(r.stats.failed_traces + r.stats.non_quad_faces + r.stats.inconsistent_segments, 0);
  EXPECT_THROW(extract_quads(cube.mesh, igm, QuadExtractionOptions{}, progress), Error);
}

TEST(QuadExtraction, RandomGarbageMapsNeverCrash) {
  std::mt19937 rng(9);
  for (int trial = 0; trial < 20; ++trial) {
    auto torus = test::make_grid_torus(6, 5);
    ExactParametrization igm = to_igm(torus.mesh, torus.param, 8);
    // Random consistent vertex moves of up to two units (flips and wild maps included).
    std::uniform_int_distribution<int64_t> move(-2 * igm.one(), 2 * igm.one());
    for (int v = 0; v < torus.mesh.num_vertices(); ++v) {
      if (rng() % 3) continue;
      IVec2 d{move(rng), move(rng)};
      for (int h : outgoing_halfedges(torus.mesh, v)) {
        igm.uv[h][0] += d[0], igm.uv[h][1] += d[1];
        const int cross = TriMesh::prev(h);
        d = rotate_quarter(d, igm.rotation[cross]);
      }
    }
    ASSERT_EQ(exact_transition_residual(torus.mesh, igm), 0);
    Progress progress;
    QuadExtractionOptions lenient;
    lenient.allow_defects = true;
    const auto r = extract_quads(torus.mesh, igm, lenient, progress);
    for (int qd = 0; qd < r.quads.num_quads(); ++qd)
      for (int c = 0; c < 4; ++c) ASSERT_LT(r.quads.Q(qd, c), r.quads.num_vertices());
    EXPECT_THROW(extract_quads(torus.mesh, igm, QuadExtractionOptions{}, progress), Error);
  }
}

TEST(QuadExtraction, MalformedInputIsRefused) {
  auto torus = test::make_grid_torus(6, 4);
  ExactParametrization igm = to_igm(torus.mesh, torus.param);
  Progress progress;
  ExactParametrization short_igm = igm;
  short_igm.uv.pop_back();
  EXPECT_THROW(extract_quads(torus.mesh, short_igm, QuadExtractionOptions{}, progress), Error);
  ExactParametrization bad_translation = igm;
  for (int h = 0; h < torus.mesh.num_halfedges(); ++h)
    if (bad_translation.translation[h][0] != 0) {
      bad_translation.translation[h][0] += 1;
      break;
    }
  EXPECT_THROW(extract_quads(torus.mesh, bad_translation, QuadExtractionOptions{}, progress), Error);
}

TEST(QuadExtraction, HugeMapsAreRefusedQuickly) {
  const auto cube = scaled(test::make_grid_cube(2), 100000);  // 2.4e11 quads
  Progress progress;
  Timer timer;
  EXPECT_THROW(extract_quads(cube.mesh, to_igm(cube.mesh, cube.param, 4), QuadExtractionOptions{}, progress), Error);
  const auto small = scaled(test::make_grid_cube(3), 3);
  QuadExtractionOptions limited;
  limited.max_quads = 100;
  try {
    extract_quads(small.mesh, to_igm(small.mesh, small.param), limited, progress);
    ADD_FAILURE() << "the quad limit was ignored";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::StageFailed);
    EXPECT_NE(std::string(e.what()).find("486"), std::string::npos) << e.what();
  }
}

TEST(QuadExtraction, CancelStopsTheExtraction) {
  const auto cube = scaled(test::make_grid_cube(2), 20);
  const ExactParametrization igm = to_igm(cube.mesh, cube.param);
  std::atomic<bool> cancel{true};
  Progress progress(nullptr, &cancel);
  try {
    extract_quads(cube.mesh, igm, QuadExtractionOptions{}, progress);
    ADD_FAILURE() << "not cancelled";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::Cancelled);
  }
}

// ---------------------------------------------------------------------------------------------
// Projection, metrics, report.

TEST(QuadExtraction, ProjectionOntoAFinerSurface) {
  // Working mesh: a coarse torus; original: a fine torus of the same shape.
  auto coarse = scaled(test::make_grid_torus(12, 8), 2);
  const auto fine = test::make_grid_torus(96, 64);
  Progress progress;
  auto r = extract_quads(coarse.mesh, to_igm(coarse.mesh, coarse.param), QuadExtractionOptions{}, progress);
  QuadMetricsOptions mo;
  mo.hausdorff_samples = 20000;
  const QuadMetrics before = compute_quad_metrics(r.quads, fine.mesh, mo, progress);
  project_to_surface(r.quads, fine.mesh, progress);
  const QuadMetrics after = compute_quad_metrics(r.quads, fine.mesh, mo, progress);
  const TriangleBvh bvh(fine.mesh);
  for (int v = 0; v < r.quads.num_vertices(); ++v) {
    EXPECT_LT(bvh.closest_point(r.quads.V.row(v).transpose()).squared_distance, 1e-20);
    EXPECT_GE(r.quads.vertex_face[v], 0);
  }
  EXPECT_LT(after.hausdorff_quads_to_mesh, before.hausdorff_quads_to_mesh);
  EXPECT_EQ(after.flipped_quads(), 0);
  std::printf("torus 384 quads projected: Hausdorff %.5f -> %.5f of the diagonal\n", before.hausdorff, after.hausdorff);
}

TEST(QuadExtraction, ClosestPointMatchesBruteForce) {
  const auto torus = test::make_grid_torus(20, 12);
  const TriangleBvh bvh(torus.mesh);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-5, 5);
  for (int i = 0; i < 300; ++i) {
    const Vec3 p(u(rng), u(rng), u(rng) / 2);
    double best = 1e300;
    for (int f = 0; f < torus.mesh.num_faces(); ++f) {
      const Vec3 q =
          closest_point_on_triangle(p, torus.mesh.position(torus.mesh.F(f, 0)), torus.mesh.position(torus.mesh.F(f, 1)),
                                    torus.mesh.position(torus.mesh.F(f, 2)));
      best = std::min(best, (q - p).squaredNorm());
    }
    const TriangleBvh::Hit hit = bvh.closest_point(p);
    EXPECT_NEAR(hit.squared_distance, best, 1e-12);
    // The hit names the caller's triangle (the tree keeps its own order of them).
    ASSERT_GE(hit.triangle, 0);
    const Vec3 on_hit = closest_point_on_triangle(p, torus.mesh.position(torus.mesh.F(hit.triangle, 0)),
                                                  torus.mesh.position(torus.mesh.F(hit.triangle, 1)),
                                                  torus.mesh.position(torus.mesh.F(hit.triangle, 2)));
    EXPECT_EQ(on_hit, hit.point);
  }
}

TEST(QuadExtraction, MetricsAndReport) {
  auto torus = scaled(test::make_grid_torus(12, 8), 2);
  perturb_vertices(torus, 0.45, 4);
  Progress progress;
  const auto r = extract_quads(torus.mesh, to_igm(torus.mesh, torus.param), QuadExtractionOptions{}, progress);
  const QuadMetrics m = compute_quad_metrics(r.quads, torus.mesh, QuadMetricsOptions{}, progress);
  EXPECT_GT(m.min_scaled_jacobian, 0);
  EXPECT_LT(m.min_scaled_jacobian, 1);
  EXPECT_GT(m.mean_angle_deviation, 0);
  EXPECT_GE(m.p95_angle_deviation, m.mean_angle_deviation * 0.5);
  EXPECT_LT(m.hausdorff, 0.05);
  const Json j = m;
  EXPECT_EQ(j["faces"].get<int>(), 384);
  EXPECT_EQ(j["vertices"].get<int>(), 384);
  EXPECT_EQ(j["irregular_vertices"].get<int>(), 0);
  for (const char* key :
       {"min_scaled_jacobian", "mean_angle_deviation_deg", "p95_angle_deviation_deg", "flipped_quads", "hausdorff"})
    EXPECT_TRUE(j.contains(key)) << key;
  const Json s = r.stats;
  EXPECT_EQ(s["expected_quads"].get<int64_t>(), 384);
}

TEST(QuadExtraction, AppendMergesComponents) {
  const auto cube = scaled(test::make_grid_cube(2), 2);
  const auto torus = test::make_grid_torus(8, 6);
  Progress progress;
  const auto a = extract_quads(cube.mesh, to_igm(cube.mesh, cube.param), QuadExtractionOptions{}, progress);
  const auto b = extract_quads(torus.mesh, to_igm(torus.mesh, torus.param), QuadExtractionOptions{}, progress);
  QuadMesh all;
  append_quad_mesh(all, a.quads, 0);
  append_quad_mesh(all, b.quads, 1);
  ASSERT_EQ(all.num_quads(), a.quads.num_quads() + b.quads.num_quads());
  ASSERT_EQ(all.num_vertices(), a.quads.num_vertices() + b.quads.num_vertices());
  EXPECT_EQ(all.component.front(), 0);
  EXPECT_EQ(all.component.back(), 1);
  EXPECT_EQ(all.vertex_singular.size(), static_cast<size_t>(all.num_vertices()));
  const QuadTopology t = quad_topology(all);
  EXPECT_EQ(t.euler_characteristic, 2 + 0);  // sphere + torus
  EXPECT_EQ(t.non_manifold_edges + t.inconsistent_edges + t.unreferenced_vertices, 0);
  EXPECT_EQ(all.Q(all.num_quads() - 1, 0), b.quads.Q(b.quads.num_quads() - 1, 0) + a.quads.num_vertices());
}

// Prints figures for ~100k quads (no timing assertion).
TEST(QuadExtraction, BenchmarkHundredThousandQuads) {
  struct Case {
    std::string name;
    SyntheticParametrized s;
    int64_t quads;
  };
  std::vector<Case> cases;
  cases.push_back({"cube n=130 (1 quad per 2 triangles)", test::make_grid_cube(130), 6 * 130 * 130});
  cases.push_back({"cube n=20 k=7 (24 quads per triangle)", scaled(test::make_grid_cube(20), 7), 6 * 400 * 49});
  auto torus = scaled(test::make_grid_torus(160, 80), 3);
  perturb_vertices(torus, 0.45, 1);
  cases.push_back({"perturbed torus 160x80 k=3", torus, 160 * 80 * 9});
  for (auto& c : cases) {
    const ExactParametrization igm = to_igm(c.s.mesh, c.s.param);
    Progress progress;
    Timer timer;
    const auto r = extract_quads(c.s.mesh, igm, QuadExtractionOptions{}, progress);
    const double seconds = timer.seconds();
    EXPECT_EQ(r.quads.num_quads(), c.quads);
    Timer metrics_timer;
    const QuadMetrics m = compute_quad_metrics(r.quads, c.s.mesh, QuadMetricsOptions{}, progress);
    std::printf("%-40s %7d triangles %7d quads  extraction %.3f s  metrics %.3f s  hausdorff %.2e\n", c.name.c_str(),
                c.s.mesh.num_faces(), r.quads.num_quads(), seconds, metrics_timer.seconds(), m.hausdorff);
  }
}

// Two parts 0.01 apart facing each other (a thin shell's two sides, or interpenetrating parts): a
// quad of the lower part lying just above its own surface is closer to the upper part, whose
// normal points the other way. Judged against its own part it is not flipped; against the whole
// surface it would be.
TEST(QuadMetrics, AQuadIsJudgedAgainstItsOwnPart) {
  TriMesh two;
  two.V.resize(8, 3);
  two.V << 0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0,         // part 0 at z = 0, normal +z
      0, 0, 0.05, 1, 0, 0.05, 1, 1, 0.05, 0, 1, 0.05;  // part 1 at z = 0.05, normal -z
  two.F.resize(4, 3);
  two.F << 0, 1, 2, 0, 2, 3, 4, 6, 5, 4, 7, 6;
  build_connectivity(two);
  QuadMesh quad;
  quad.V.resize(4, 3);
  quad.V << 0.2, 0.2, 0.03, 0.8, 0.2, 0.03, 0.8, 0.8, 0.03, 0.2, 0.8, 0.03;  // normal +z, nearer part 1
  quad.Q.resize(1, 4);
  quad.Q << 0, 1, 2, 3;
  quad.component = {0};
  Progress progress;
  QuadMetricsOptions options;
  options.hausdorff = false;
  EXPECT_EQ(compute_quad_metrics(quad, two, options, progress).flipped_quads(), 1);  // one surface
  options.reference_component = {0, 0, 1, 1};
  EXPECT_EQ(compute_quad_metrics(quad, two, options, progress).flipped_quads(), 0);  // its own part
  quad.component = {1};  // claimed by the part facing -z, it is flipped
  EXPECT_EQ(compute_quad_metrics(quad, two, options, progress).flipped_quads(), 1);
}

// Two solids in face contact leave two coincident sheets facing opposite ways, tessellated
// differently (cycloidal's rings and pins): a quad on them faces with one of them and is not
// flipped, either way it faces. On one sheet alone, the quad facing against it is.
TEST(QuadMetrics, CoincidentSheetsFacingOppositeWaysFlipNoQuad) {
  TriMesh sheets;
  sheets.V.resize(9, 3);
  sheets.V << 0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0,                      // sheet up: two triangles
      0, 0, 1e-9, 1, 0, 1e-9, 1, 1, 1e-9, 0, 1, 1e-9, 0.5, 0.5, 1e-9;  // sheet down: a fan of four
  sheets.F.resize(6, 3);
  sheets.F << 0, 1, 2, 0, 2, 3, 4, 8, 5, 5, 8, 6, 6, 8, 7, 7, 8, 4;
  build_connectivity(sheets);
  const TriangleBvh bvh(sheets);
  Vec3 up[4] = {{0.2, 0.2, 0}, {0.8, 0.2, 0}, {0.8, 0.8, 0}, {0.2, 0.8, 0}};
  Vec3 down[4] = {up[0], up[3], up[2], up[1]};
  EXPECT_FALSE(quad_is_flipped(up, sheets, bvh));
  EXPECT_FALSE(quad_is_flipped(down, sheets, bvh));
  const Vec3 x(0.3, 0.6, 1e-3);
  EXPECT_GT(sheets.face_normal_unnormalized(bvh.closest_point_facing(x, Vec3::UnitZ(), 1e-3).triangle).z(), 0);
  EXPECT_LT(sheets.face_normal_unnormalized(bvh.closest_point_facing(x, -Vec3::UnitZ(), 1e-3).triangle).z(), 0);

  TriMesh one;
  one.V = sheets.V.topRows(4);
  one.F = sheets.F.topRows(2);
  build_connectivity(one);
  const TriangleBvh one_bvh(one);
  EXPECT_FALSE(quad_is_flipped(up, one, one_bvh));
  EXPECT_TRUE(quad_is_flipped(down, one, one_bvh));
}

// Across a crease the closest point lies on the shared edge, as close to both triangles: the
// facing query keeps the closest one there (a crease is no second sheet), so a quad folded over a
// crease stays flipped. A sheet folded back onto itself is two sheets. Elsewhere it is the closest
// point within the tolerance, facing with the normal asked where any such is.
TEST(QuadExtraction, ClosestPointFacingSwitchesOnlyToASheetFacingTheOtherWay) {
  TriMesh crease;
  crease.V.resize(4, 3);
  crease.V << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1;  // the faces z = 0 and y = 0 meeting along x
  crease.F.resize(2, 3);
  crease.F << 0, 2, 1, 0, 1, 3;
  build_connectivity(crease);
  const TriangleBvh bvh(crease);
  const Vec3 outside(0.3, -0.1, -0.1);  // nearest the shared edge
  const TriangleBvh::Hit closest = bvh.closest_point(outside);
  for (const Vec3& n : {Vec3(0, 0, 1), Vec3(0, 0, -1), Vec3(0, 1, 0), Vec3(0, -1, 0)})
    EXPECT_EQ(bvh.closest_point_facing(outside, n, 0.5).triangle, closest.triangle);

  TriMesh fold = crease;  // the second face folded over onto the first: the same triangle, facing +z
  fold.V.row(3) << 0, 1, 0;
  build_connectivity(fold);
  const TriangleBvh fold_bvh(fold);
  const Vec3 above(0.3, 0.3, 1e-3);  // as close to both sheets
  EXPECT_EQ(fold_bvh.closest_point_facing(above, Vec3(0, 0, 1), 0.1).triangle, 1);
  EXPECT_EQ(fold_bvh.closest_point_facing(above, Vec3(0, 0, -1), 0.1).triangle, 0);

  const auto torus = test::make_grid_torus(20, 12);
  const TriangleBvh torus_bvh(torus.mesh);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-5, 5);
  for (int i = 0; i < 200; ++i) {
    const Vec3 p(u(rng), u(rng), u(rng) / 2), n = Vec3(u(rng), u(rng), u(rng)).normalized();
    const double tolerance = 0.05;
    const TriangleBvh::Hit best = torus_bvh.closest_point(p), facing = torus_bvh.closest_point_facing(p, n, tolerance);
    ASSERT_GE(facing.triangle, 0);
    EXPECT_LE(std::sqrt(facing.squared_distance), std::sqrt(best.squared_distance) + tolerance + 1e-12);
    if (facing.triangle != best.triangle) EXPECT_GT(torus.mesh.face_normal_unnormalized(facing.triangle).dot(n), 0);
  }
}

// The report's count takes, at a point as close to both sides of a crease, the side facing with the
// quad (OnCrease::FacingSide): a quad lying on one side and reaching past the crease (beside a
// concave feature curve) is not flipped, whichever of the two triangles comes first; the same quad
// turned over is. The pipeline's rule (KeepClosest) keeps the triangle found first.
TEST(QuadExtraction, AQuadPastACreaseFacesWithTheSideItLiesOnInTheReport) {
  for (const bool swapped : {false, true}) {
    TriMesh crease;
    crease.V.resize(4, 3);
    crease.V << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1;  // z = 0 (normal -z) and y = 0 (normal -y)
    crease.F.resize(2, 3);
    if (swapped) {
      crease.F << 0, 1, 3, 0, 2, 1;
    } else {
      crease.F << 0, 2, 1, 0, 1, 3;
    }
    build_connectivity(crease);
    const TriangleBvh bvh(crease);
    const int z0 = swapped ? 1 : 0, y0 = swapped ? 0 : 1;
    const Vec3 outside(0.3, -0.1, -0.1);  // as close to both: the closest point is on the crease
    EXPECT_EQ(bvh.closest_point_facing(outside, -Vec3::UnitZ(), 0.5, OnCrease::FacingSide).triangle, z0);
    EXPECT_EQ(bvh.closest_point_facing(outside, -Vec3::UnitY(), 0.5, OnCrease::FacingSide).triangle, y0);
    const int closest = bvh.closest_point(outside).triangle;
    EXPECT_EQ(bvh.closest_point_facing(outside, Vec3::UnitZ(), 0.5, OnCrease::FacingSide).triangle, closest);

    // In the plane z = 0, just past the crease (y < 0): normal -z, as triangle z0's.
    const Vec3 past[4] = {{0.2, -0.3, 0}, {0.2, -0.02, 0}, {0.8, -0.02, 0}, {0.8, -0.3, 0}};
    const Vec3 over[4] = {past[0], past[3], past[2], past[1]};
    ASSERT_LT((past[2] - past[0]).cross(past[3] - past[1]).z(), 0);
    EXPECT_FALSE(quad_is_flipped(past, crease, bvh, OnCrease::FacingSide)) << "swapped " << swapped;
    EXPECT_TRUE(quad_is_flipped(over, crease, bvh, OnCrease::FacingSide)) << "swapped " << swapped;
    EXPECT_TRUE(quad_is_flipped(over, crease, bvh, OnCrease::KeepClosest)) << "swapped " << swapped;
  }
}

// The Hausdorff distance's samples are shared out among threads (core/parallel.h): every chunk
// runs once, whatever the threads, and an exception of the calling thread's chunk (a cancel) leaves
// only after the other threads have finished theirs.
TEST(Parallel, EveryChunkRunsOnceAndTheThreadsAreJoinedBeforeAnExceptionLeaves) {
  EXPECT_EQ(threads_for(100, 1000), 1);
  EXPECT_EQ(threads_for(1e9, 1, 3), 3);
  EXPECT_EQ(threads_for(1e9, 1, 64), 8);
  for (int chunks : {1, 2, 5}) {
    std::vector<std::atomic<int>> runs(chunks);
    run_chunks(chunks, [&](int t) { ++runs[t]; });
    for (int t = 0; t < chunks; ++t) EXPECT_EQ(runs[t], 1) << chunks << " chunks, chunk " << t;
  }
  std::vector<std::atomic<int>> finished(4);
  try {
    run_chunks(4, [&](int t) {
      if (t == 0) throw Error(ErrorCode::Cancelled, "cancelled");
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
      ++finished[t];
    });
    ADD_FAILURE() << "the exception of chunk 0 was lost";
  } catch (const Error&) {
    for (int t = 1; t < 4; ++t) EXPECT_EQ(finished[t], 1) << "chunk " << t << " had not finished";
  }
}

}  // namespace
}  // namespace qgp

#include "test_support.h"

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <sstream>
#include <stdexcept>

#include "core/error.h"
#include "core/progress.h"
#include "intake/read_mesh_file.h"
#include "metrics/quad_metrics.h"

namespace qgp::test {

std::string mesh_path(const std::string& name) { return std::string(QGP_MESH_DIR) + "/" + name; }

std::vector<std::string> all_mesh_files() {
  std::vector<std::string> names;
  for (const auto& entry : std::filesystem::directory_iterator(QGP_MESH_DIR)) {
    const std::string ext = entry.path().extension().string();
    if (ext == ".obj" || ext == ".off" || ext == ".ply") names.push_back(entry.path().filename().string());
  }
  std::sort(names.begin(), names.end());
  return names;
}

std::vector<std::string> accepted_mesh_files() {
  // Non-manifold edges (truck, cycloidal) are cut into sheets by default: every file is accepted.
  return all_mesh_files();
}

std::vector<std::string> manifold_mesh_files() {
  // QGP_TEST_MESHES=a.obj,b.off restricts the sweeps to those meshes (for investigating one).
  if (const char* only = std::getenv("QGP_TEST_MESHES")) {
    std::vector<std::string> names;
    std::stringstream list(only);
    for (std::string name; std::getline(list, name, ',');)
      if (!name.empty()) names.push_back(name);
    return names;
  }
  return {
      "armadillo.obj",     "beetle.off",        "block.obj",       "bunny.off",          "camelhead.off",
      "decimated-max.obj", "dragon-genus1.obj", "face.obj",        "fandisk.obj",        "fertility.off",
      "igea.ply",          "joint.obj",         "joint_rem_p.obj", "kitten.obj",         "mnf07HeadFem_rem_rem_p.obj",
      "nefertiti.obj",     "rocker-arm.obj",    "spot.obj",        "stanford-bunny.obj", "torus.obj",
      "wingnut.obj"};
}

std::vector<std::string> quick_mesh_files() {
  return {"spot.obj",    "bunny.off", "torus.obj",     "fertility.off",
          "fandisk.obj", "joint.obj", "camelhead.off", "wingnut.obj"};
}

IntakeResult load_mesh(const std::string& name) {
  Progress progress;
  return run_intake(read_mesh_file(mesh_path(name)), IntakeOptions{}, progress);
}

PolygonSoup moebius_strip(const Vec3& centre) {
  PolygonSoup s;
  const int n = 8;
  for (int i = 0; i < n; ++i) {
    const double t = 2 * M_PI * i / n;
    for (int side : {-1, 1}) {
      const double w = 0.3 * side;
      s.positions.push_back(centre + Vec3((2 + w * std::cos(t / 2)) * std::cos(t),
                                          (2 + w * std::cos(t / 2)) * std::sin(t), w * std::sin(t / 2)));
    }
  }
  for (int i = 0; i < n; ++i) {
    const int a = 2 * i, b = 2 * i + 1;
    int c = 2 * ((i + 1) % n), d = c + 1;
    if (i == n - 1) std::swap(c, d);  // the half twist
    const int t0[3] = {a, c, b}, t1[3] = {b, c, d};
    s.add_face(t0, 3);
    s.add_face(t1, 3);
  }
  return s;
}

TriMesh component_mesh(const IntakeResult& intake, int component) { return extract_component(intake, component); }

void infer_rotations(const TriMesh& mesh, Parametrization& param) {
  param.rotation.assign(mesh.num_halfedges(), 0);
  param.is_cut.assign(mesh.num_edges(), 0);
  for (int h = 0; h < mesh.num_halfedges(); ++h) {
    const int o = mesh.opposite[h];
    if (o < 0) continue;
    const Vec2 df = param.corner(h / 3, (h % 3 + 1) % 3) - param.corner(h / 3, h % 3);
    const Vec2 dg = param.corner(o / 3, o % 3) - param.corner(o / 3, (o % 3 + 1) % 3);
    int found = -1;
    for (int r = 0; r < 4 && found < 0; ++r)
      if ((rotate_quarter(df, r) - dg).norm() < 1e-9 * (1 + df.norm())) found = r;
    if (found < 0) throw std::runtime_error("infer_rotations: edge matches no quarter turn");
    param.rotation[h] = static_cast<int8_t>(found);
    const Vec2 pf = param.corner(h / 3, h % 3), pg = param.corner(o / 3, (o % 3 + 1) % 3);
    if (found != 0 || (pg - pf).norm() > 1e-12) param.is_cut[mesh.edge_of[h]] = 1;
  }
}

SyntheticParametrized make_grid_cube(int n) {
  // Side frames (a, b) with a x b = outward normal.
  struct Side {
    Vec3 origin, a, b;
  };
  const double N = n;
  const Side sides[6] = {{{0, 0, N}, Vec3::UnitX(), Vec3::UnitY()}, {{0, 0, 0}, Vec3::UnitY(), Vec3::UnitX()},
                         {{N, 0, 0}, Vec3::UnitY(), Vec3::UnitZ()}, {{0, 0, 0}, Vec3::UnitZ(), Vec3::UnitY()},
                         {{0, N, 0}, Vec3::UnitZ(), Vec3::UnitX()}, {{0, 0, 0}, Vec3::UnitX(), Vec3::UnitZ()}};
  std::map<std::array<long, 3>, int> vertex_id;
  std::vector<Vec3> positions;
  std::vector<std::array<int, 3>> tris;
  std::vector<std::array<Vec2, 3>> uvs;
  auto vid = [&](const Vec3& p) {
    const std::array<long, 3> key{std::lround(p.x()), std::lround(p.y()), std::lround(p.z())};
    auto it = vertex_id.emplace(key, static_cast<int>(positions.size())).first;
    if (it->second == static_cast<int>(positions.size())) positions.push_back(p);
    return it->second;
  };
  for (const Side& s : sides)
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) {
        const Vec2 q[4] = {{double(i), double(j)},
                           {double(i + 1), double(j)},
                           {double(i + 1), double(j + 1)},
                           {double(i), double(j + 1)}};
        int id[4];
        for (int k = 0; k < 4; ++k) id[k] = vid(s.origin + q[k].x() * s.a + q[k].y() * s.b);
        // Alternate the diagonal so no vertex is special.
        if ((i + j) % 2 == 0) {
          tris.push_back({id[0], id[1], id[2]}), uvs.push_back({q[0], q[1], q[2]});
          tris.push_back({id[0], id[2], id[3]}), uvs.push_back({q[0], q[2], q[3]});
        } else {
          tris.push_back({id[0], id[1], id[3]}), uvs.push_back({q[0], q[1], q[3]});
          tris.push_back({id[1], id[2], id[3]}), uvs.push_back({q[1], q[2], q[3]});
        }
      }
  SyntheticParametrized out;
  out.mesh.V.resize(static_cast<int>(positions.size()), 3);
  for (size_t v = 0; v < positions.size(); ++v) out.mesh.V.row(v) = positions[v].transpose();
  out.mesh.F.resize(static_cast<int>(tris.size()), 3);
  out.param.uv.resize(3 * static_cast<int>(tris.size()), 2);
  for (size_t t = 0; t < tris.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      out.mesh.F(t, k) = tris[t][k];
      out.param.uv.row(3 * t + k) = uvs[t][k].transpose();
    }
  build_connectivity(out.mesh);
  infer_rotations(out.mesh, out.param);
  return out;
}

SyntheticParametrized make_grid_torus(int nu, int nv, double major_radius, double minor_radius) {
  SyntheticParametrized out;
  auto id = [&](int i, int j) { return ((i % nu + nu) % nu) * nv + ((j % nv + nv) % nv); };
  out.mesh.V.resize(nu * nv, 3);
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      const double a = 2 * M_PI * i / nu, b = 2 * M_PI * j / nv;
      out.mesh.V.row(id(i, j)) << (major_radius + minor_radius * std::cos(b)) * std::cos(a),
          (major_radius + minor_radius * std::cos(b)) * std::sin(a), minor_radius * std::sin(b);
    }
  out.mesh.F.resize(2 * nu * nv, 3);
  out.param.uv.resize(6 * nu * nv, 2);
  int t = 0;
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      const int corners[2][3][2] = {{{i, j}, {i + 1, j}, {i + 1, j + 1}}, {{i, j}, {i + 1, j + 1}, {i, j + 1}}};
      for (const auto& tri : corners) {
        for (int k = 0; k < 3; ++k) {
          out.mesh.F(t, k) = id(tri[k][0], tri[k][1]);
          out.param.uv.row(3 * t + k) << tri[k][0], tri[k][1];
        }
        ++t;
      }
    }
  build_connectivity(out.mesh);
  infer_rotations(out.mesh, out.param);
  return out;
}

std::string run_until_stage(Session& session, const std::string& stage) {
  std::atomic<bool> cancel{false};
  Progress progress([&](const std::string& begun, double) { cancel = cancel || begun == stage; }, &cancel);
  try {
    session.run(Job::Remesh, progress);
  } catch (const Error& e) {
    if (e.code() == ErrorCode::Cancelled && cancel) return "";
    return e.what();
  }
  return "stage '" + stage + "' did not start";
}

std::unique_ptr<Session> remeshed_session(const std::string& name, double target, double sharp_angle) {
  auto session = std::make_unique<Session>(read_mesh_file(mesh_path(name)));
  RemeshOptions options;
  options.target_faces = target;
  options.sharp_angle_deg = sharp_angle;
  session->set_options(options);
  Progress progress;
  session->run(Job::Remesh, progress);
  return session;
}

namespace {

// The sides of a cylinder whose rims are vertices 0..segments-1 (z = 0) and segments..2*segments-1
// (z = height): each side a quad cut into two needles from rim to rim.
std::vector<std::array<int, 3>> cylinder_sides(int segments) {
  std::vector<std::array<int, 3>> faces;
  for (int i = 0; i < segments; ++i) {
    const int j = (i + 1) % segments;
    faces.push_back({i, j, segments + j});
    faces.push_back({i, segments + j, segments + i});
  }
  return faces;
}

void set_faces(TriMesh& mesh, const std::vector<std::array<int, 3>>& faces) {
  mesh.F.resize(static_cast<int>(faces.size()), 3);
  for (size_t f = 0; f < faces.size(); ++f) mesh.F.row(static_cast<int>(f)) << faces[f][0], faces[f][1], faces[f][2];
  build_connectivity(mesh);
}

}  // namespace

TriMesh make_fan_cylinder(int segments, double radius, double height) {
  TriMesh mesh;
  mesh.V.resize(2 * segments, 3);
  for (int i = 0; i < segments; ++i) {
    const double a = 2 * M_PI * i / segments;
    mesh.V.row(i) << radius * std::cos(a), radius * std::sin(a), 0;
    mesh.V.row(segments + i) << radius * std::cos(a), radius * std::sin(a), height;
  }
  std::vector<std::array<int, 3>> faces = cylinder_sides(segments);
  for (int i = 1; i + 1 < segments; ++i) {
    faces.push_back({0, i + 1, i});                               // bottom, facing -z
    faces.push_back({segments, segments + i, segments + i + 1});  // top, facing +z
  }
  set_faces(mesh, faces);
  return mesh;
}

TriMesh make_pin(int segments, double radius, double height, double turn, const Vec3& at) {
  const int bottom = 2 * segments, top = 2 * segments + 1;
  TriMesh mesh;
  mesh.V.resize(2 * segments + 2, 3);
  mesh.V.topRows(2 * segments) = make_fan_cylinder(segments, radius, height).V;
  mesh.V.row(bottom) << 0, 0, 0;
  mesh.V.row(top) << 0, 0, height;
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    const double x = mesh.V(v, 0), y = mesh.V(v, 1);
    const Vec3 p =
        at + Vec3(x * std::cos(turn) - y * std::sin(turn), x * std::sin(turn) + y * std::cos(turn), mesh.V(v, 2));
    for (int k = 0; k < 3; ++k) mesh.V(v, k) = static_cast<float>(p[k]);
  }
  std::vector<std::array<int, 3>> faces = cylinder_sides(segments);
  for (int i = 0; i < segments; ++i) {
    const int j = (i + 1) % segments;
    faces.push_back({bottom, j, i});                     // facing -z
    faces.push_back({top, segments + i, segments + j});  // facing +z
  }
  set_faces(mesh, faces);
  return mesh;
}

std::string identifier(std::string text) {
  for (char& c : text)
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  return text;
}

PolygonSoup polygon_soup(const TriMesh& mesh) {
  PolygonSoup soup;
  for (int v = 0; v < mesh.num_vertices(); ++v) soup.positions.push_back(mesh.position(v));
  for (int f = 0; f < mesh.num_faces(); ++f) soup.add_face(mesh.F.row(f).data(), 3);
  return soup;
}

PolygonSoup polygon_soup(const QuadMesh& quads) {
  PolygonSoup soup;
  for (int v = 0; v < quads.num_vertices(); ++v) soup.positions.push_back(quads.V.row(v).transpose());
  for (int q = 0; q < quads.num_quads(); ++q) soup.add_face(quads.Q.row(q).data(), 4);
  return soup;
}

int irregular_vertices_off_singularities(const QuadMesh& quads) {
  const QuadTopology topology = quad_topology(quads);
  int count = 0;
  for (int v = 0; v < quads.num_vertices(); ++v) {
    const bool irregular = topology.on_boundary[v] ? topology.valence[v] != 3 : topology.valence[v] != 4;
    count += irregular && !quads.vertex_singular[v];
  }
  return count;
}

int count_slivers(const QuadMesh& quads) {
  int count = 0;
  for (int q = 0; q < quads.num_quads(); ++q) {
    const double a = (quads.V.row(quads.Q(q, 0)) - quads.V.row(quads.Q(q, 2))).norm();
    const double b = (quads.V.row(quads.Q(q, 1)) - quads.V.row(quads.Q(q, 3))).norm();
    count += 10 * std::min(a, b) < std::max(a, b);
  }
  return count;
}

}  // namespace qgp::test

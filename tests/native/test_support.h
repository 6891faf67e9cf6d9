// Shared helpers for the GoogleTest suites: the shared mesh set and small synthetic meshes with
// known seamless parametrizations.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "core/mesh.h"
#include "core/parametrization.h"
#include "core/quad_mesh.h"
#include "intake/intake.h"
#include "intake/polygon_soup.h"
#include "pipeline/session.h"

namespace qgp::test {

// Path of a file in ../shared/meshes.
std::string mesh_path(const std::string& name);

// Every mesh file of the shared set (27 files).
std::vector<std::string> all_mesh_files();
// The meshes intake accepts with its default options (all: non-manifold edges are cut).
std::vector<std::string> accepted_mesh_files();
// The manifold meshes of the shared set's README (one clean component each).
std::vector<std::string> manifold_mesh_files();
// A representative subset of manifold meshes that is quick to process (for slower stages).
std::vector<std::string> quick_mesh_files();

// Reads and repairs a shared mesh (throws on failure).
IntakeResult load_mesh(const std::string& name);

// A Möbius strip of 8 quads (16 triangles), width 0.6 around a circle of radius 2 centred at
// `centre`: non-orientable.
PolygonSoup moebius_strip(const Vec3& centre = Vec3::Zero());

// A single connected component of an intake result as its own mesh.
TriMesh component_mesh(const IntakeResult& intake, int component);

// Axis-aligned cube [0,n]^3, each side split into n x n squares of two triangles, with the
// seamless parametrization whose chart on each side is that side's own coordinates (the eight
// corners are singularities of index +1).
struct SyntheticParametrized {
  TriMesh mesh;
  Parametrization param;
};
SyntheticParametrized make_grid_cube(int n);

// Torus with nu x nv quads (split into triangles), parametrized by (i, j) grid coordinates with
// translations (nu, 0) and (0, nv) across the two cut loops; no singularities.
SyntheticParametrized make_grid_torus(int nu, int nv, double major_radius = 3, double minor_radius = 1);

// Fills rotation[] (and is_cut) from per-corner uvs: the quarter turn that maps each edge's
// vector in one chart to the other. Throws if an edge matches no rotation.
void infer_rotations(const TriMesh& mesh, Parametrization& param);

// Runs the session's remesh job until `stage` begins (cancelling it there); returns the error
// message of a failure before that stage, "" when every earlier stage completed.
std::string run_until_stage(Session& session, const std::string& stage);

// A shared mesh remeshed to about `target` quads (sharp_angle < 0: no sharp edges as features).
std::unique_ptr<Session> remeshed_session(const std::string& name, double target, double sharp_angle = -1);

// The quads as a polygon soup (for measure_polygon_mesh).
// `text` with every character but letters and digits replaced by '_' (a GoogleTest parameter name).
std::string identifier(std::string text);
PolygonSoup polygon_soup(const QuadMesh& quads);
PolygonSoup polygon_soup(const TriMesh& mesh);
// A closed cylinder as CAD exports it: each side a quad cut into two needles from cap to cap, each
// cap a fan from one rim vertex (needles again). Its rims are feature curves. Connectivity built.
TriMesh make_fan_cylinder(int segments, double radius, double height);
// A pin as CAD exports it (cycloidal's 96-triangle pins): the sides as in make_fan_cylinder, each
// cap a fan around a centre vertex. Turned by `turn` radians about its axis, moved to `at`, and its
// coordinates rounded to float precision (as a binary PLY stores them). Connectivity built.
TriMesh make_pin(int segments, double radius, double height, double turn, const Vec3& at);

// Irregular quad vertices (valence != 4 inside, != 3 on the boundary) not flagged vertex_singular.
int irregular_vertices_off_singularities(const QuadMesh& quads);
// Quads whose shorter diagonal is under 1/10 of the longer (nearly degenerate).
int count_slivers(const QuadMesh& quads);

}  // namespace qgp::test

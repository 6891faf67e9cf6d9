// Mesh intake: validate a polygon soup, repair what is safely repairable (reporting each repair
// with a count), split it into connected components and classify them.
#pragma once
#include <array>
#include <string>
#include <vector>

#include "core/json.h"
#include "core/mesh.h"
#include "core/progress.h"
#include "intake/polygon_soup.h"

namespace qgp {

struct IntakeOptions {
  // Boundary vertices closer than weld_tolerance * (bounding-box diagonal) are merged (exporters
  // split meshes at UV seams and hard normals); 0 turns welding off.
  double weld_tolerance = 1e-6;
  // Non-manifold edges (more than two faces) are cut into sheets; true refuses the mesh instead
  // (Error InvalidMesh naming the first such edge).
  bool refuse_non_manifold = false;
  // Parts that cannot be repaired: true drops them (non-orientable parts, and non-manifold ones
  // when refuse_non_manifold), keeps the rest and says so in the report. false refuses the mesh
  // (Error InvalidMesh) for non-manifold parts, and sets non-orientable parts aside as their
  // triangles (IntakeResult::non_orientable_parts) unless nothing else is left.
  bool drop_bad_components = false;
  // A face is zero-area when area <= zero_area * diag^2 (diag: bounding-box diagonal)
  // or 2*area <= flatness * (longest edge)^2: needles and caps this thin have a normal that is
  // rounding noise, which would make their edges look sharp (244 faces of block.obj).
  double zero_area = 1e-12;
  double flatness = 1e-4;
};

struct Repair {
  std::string kind;  // welded_vertices, cut_nonmanifold_edges, duplicate_faces, zero_area_faces, ...
  int count = 0;
  std::vector<int> input_vertices;  // where: the first few (<= 10) input vertices it happened at
};

struct ComponentInfo {
  std::vector<int> faces;  // faces of IntakeResult::mesh in this component
  int num_vertices = 0, num_edges = 0, num_faces = 0;
  int boundary_loops = 0;
  int euler_characteristic = 0;  // V - E + F
  int genus = 0;                 // (2 - chi - boundary_loops) / 2
  bool closed() const { return boundary_loops == 0; }
};

// A part that cannot be given one consistent side (a Möbius strip, a Klein bottle): it cannot be
// quadded, so it is kept apart as its input triangles, in their input orientation.
struct NonOrientablePart {
  std::vector<Vec3> positions;
  std::vector<std::array<int, 3>> triangles;
  std::vector<int> input_face;  // per triangle: the input face it came from
};

struct IntakeResult {
  TriMesh mesh;                   // repaired, oriented, manifold; connectivity built
  std::vector<int> input_vertex;  // per mesh vertex: its index in the input soup
  std::vector<int> input_face;    // per mesh face: the input face (polygon) it came from
  std::vector<int> weld_target;   // per input vertex: the input vertex it was welded into (or itself)
  std::vector<ComponentInfo> components;
  std::vector<NonOrientablePart> non_orientable_parts;  // not in mesh (nor in components)
  std::vector<Repair> repairs;                          // only repairs that happened (count > 0)
  std::vector<std::string> warnings;
  int input_vertices = 0, input_faces = 0;
};

// Throws Error(InvalidMesh) naming what is wrong when the input is unusable.
IntakeResult run_intake(const PolygonSoup& soup, const IntakeOptions& options, Progress& progress);

// The "input" object of the JSON report.
void to_json(Json& j, const IntakeResult& result);

// Marks the mesh edges whose endpoints are the given input vertex pairs (welded vertices stand for
// the vertex they were welded into). Pairs that match no
// edge (not adjacent in the input, or removed by a repair) are counted in *unmatched.
std::vector<char> map_input_edges(const IntakeResult& intake, const std::vector<std::array<int, 2>>& input_pairs,
                                  int* unmatched);

// One connected component as its own mesh (connectivity built). vertex_map / face_map (optional)
// receive, per component vertex / face, the index in intake.mesh.
TriMesh extract_component(const IntakeResult& intake, int component, std::vector<int>* vertex_map = nullptr,
                          std::vector<int>* face_map = nullptr);
// Several components (in the given order) as one mesh, likewise.
TriMesh extract_components(const IntakeResult& intake, const std::vector<int>& components,
                           std::vector<int>* vertex_map = nullptr, std::vector<int>* face_map = nullptr);

}  // namespace qgp

// Validity and quality figures of a quad mesh, measured against the triangle surface it
// approximates: topology (manifoldness, orientation, Euler characteristic, valences), element
// quality (scaled Jacobian, angle deviation), flips against the surface normals, and the two-sided
// Hausdorff distance.
#pragma once
#include <array>
#include <cstdint>
#include <random>
#include <vector>

#include "core/json.h"
#include "core/mesh.h"
#include "core/progress.h"
#include "core/quad_mesh.h"
#include "quad_extraction/surface_projection.h"

namespace qgp {

struct QuadTopology {
  int vertices = 0, edges = 0, faces = 0;
  int boundary_edges = 0;      // edges with one quad
  int non_manifold_edges = 0;  // edges with more than two quads
  int inconsistent_edges = 0;  // edges two quads traverse in the same direction
  int degenerate_quads = 0;    // quads repeating a vertex
  int unreferenced_vertices = 0;
  int euler_characteristic = 0;   // V - E + F
  std::vector<int> valence;       // #V: number of edges at each vertex
  std::vector<char> on_boundary;  // #V: touches a boundary edge
  int irregular_interior = 0;     // interior vertices of valence != 4
  int irregular_boundary = 0;     // boundary vertices of valence != 3
};

QuadTopology quad_topology(const QuadMesh& quads);

// #Q flags: the quads behind quad_topology's defect counts (a repeated corner, or an edge shared by
// more than two quads or run twice in one direction).
std::vector<char> non_manifold_quads(const QuadMesh& quads);

struct QuadMetricsOptions {
  bool hausdorff = true;           // sample the two-sided Hausdorff distance
  int hausdorff_samples = 100000;  // random surface samples per direction (plus all vertices)
  uint32_t seed = 1;
  // Per reference face, the part it belongs to (empty: one part). With it and QuadMesh::component,
  // a quad's flip is judged against its own part's surface only, not a part it passes close to
  // (interpenetrating parts: teeth in a jaw, a strap through a buckle).
  std::vector<int> reference_component;
};

struct QuadMetrics {
  QuadTopology topology;
  int irregular_vertices = 0;         // irregular_interior + irregular_boundary
  double min_scaled_jacobian = 1;     // over all quad corners, w.r.t. the quad's own normal
  double mean_angle_deviation = 0;    // degrees, |corner angle - 90| over all corners
  double p95_angle_deviation = 0;     // degrees, 95th percentile
  std::vector<int> flipped_quad_ids;  // ascending: quads whose normal (of the diagonals) points against
                                      // the mean reference normal at the closest points of five
                                      // interior points (quad_reference_normal, OnCrease::FacingSide)
  int flipped_quads() const { return static_cast<int>(flipped_quad_ids.size()); }
  std::vector<int> collapsed_edge_quad_ids;  // ascending: quads with a collapsed edge (quad_has_collapsed_edge)
  int collapsed_edge_quads() const { return static_cast<int>(collapsed_edge_quad_ids.size()); }
  double hausdorff = 0;  // max of the two directions, relative to the bbox diagonal
  double hausdorff_quads_to_mesh = 0;
  double hausdorff_mesh_to_quads = 0;
};

// Sum of the unit normals of `reference` at the closest points of five interior points of the
// bilinear quad p[0..3] (not normalized; zero if the reference is empty). Where another sheet of
// the reference lies as close (within kCoincidentSheets times the quad's longer diagonal), facing
// the opposite way (two solids in face contact, a sheet folded back onto itself), the point on the
// sheet facing with the quad counts (TriangleBvh::closest_point_facing): the quad faces with one of
// them. Of the 208 quads of cycloidal with sharp edges at 2 000 quads judged flipped before, 201 lay
// on such sheets of the input within 0.5 % of the quad (163 within 0.1 %), facing with one of them.
constexpr double kCoincidentSheets = 5e-3;
// A point as close to both sides of a crease (its closest point lies on the crease) takes the side
// facing with the quad in the report's count (OnCrease::FacingSide): a quad overhanging a concave
// feature curve faces with the surface it lies on (wingnut with sharp edges at 2 000 quads: one quad
// counted flipped, its normal 0.999 along its side's, by which of two tied triangles came first).
// The pipeline's rounds keep the closest triangle found (KeepClosest): stricter, and its choices
// between quantizations and untangles were tuned on it (applied there, the report's rule changed the
// quads of 26 of the 99 sweep runs; cow and ogre at 8 000 quads went over 1 % Hausdorff).
using OnCrease = TriangleBvh::OnCrease;
Vec3 quad_reference_normal(const Vec3 p[4], const TriMesh& reference, const TriangleBvh& reference_bvh,
                           OnCrease on_crease = OnCrease::KeepClosest);

// Quad p[0..3] (counter-clockwise) is flipped: its normal (of the diagonals) points against the
// summed normals of `reference` at the closest points of five interior points.
bool quad_is_flipped(const Vec3 p[4], const TriMesh& reference, const TriangleBvh& reference_bvh,
                     OnCrease on_crease = OnCrease::KeepClosest);
// The same for quad q of `quads`.
bool quad_is_flipped(const QuadMesh& quads, int q, const TriMesh& reference, const TriangleBvh& reference_bvh,
                     OnCrease on_crease = OnCrease::KeepClosest);

// A quad edge no longer than this share of the quad's mean edge length is collapsed: its two corners
// lie on one point to the eye, and the quad looks like a triangle. Moving vertices one by one and
// projecting them onto the surface can draw two neighbours onto one point (a slide along a feature
// curve that stopped on a corner another quad vertex holds); 23 of the 99 runs of the shared
// meshes' sweep had such quads, 287 in all (stop 63).
constexpr double kCollapsedEdgeShare = 1e-3;
// Quad p[0..3] has an edge no longer than kCollapsedEdgeShare of its mean edge length.
bool quad_has_collapsed_edge(const Vec3 p[4]);
// The same for quad q of `quads`.
bool quad_has_collapsed_edge(const QuadMesh& quads, int q);
// The quads of `quads` with a collapsed edge.
int quads_with_a_collapsed_edge(const QuadMesh& quads);

// reference: the triangle surface the quads approximate (normals for flips, Hausdorff distance).
QuadMetrics compute_quad_metrics(const QuadMesh& quads, const TriMesh& reference, const QuadMetricsOptions& options,
                                 Progress& progress);

// Area-weighted random points on a triangle soup (count of them), plus every vertex.
std::vector<Vec3> sample_surface(const std::vector<Vec3>& V, const std::vector<std::array<int, 3>>& T, int count,
                                 std::mt19937& rng);
// The sampled two-sided Hausdorff distance between the quads (each split into two triangles) and
// `reference`, in model units: {quads to reference, reference to quads}. samples: random points per
// direction, plus every vertex; the same seed gives the same figures.
std::array<double, 2> hausdorff_distances(const QuadMesh& quads, const TriMesh& reference,
                                          const TriangleBvh& reference_bvh, int samples, uint32_t seed,
                                          Progress& progress);
// Largest distance from the samples to the surface.
double max_distance(const std::vector<Vec3>& samples, const TriangleBvh& target, Progress& progress);

// The report object `quad`: {faces, vertices, irregular_vertices, ...metrics}.
void to_json(Json& j, const QuadMetrics& metrics);

}  // namespace qgp

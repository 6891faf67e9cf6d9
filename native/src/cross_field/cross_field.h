// Stage 1a: smoothest 4-RoSy cross field, hard-aligned to features and boundaries.
//
// Method: Knoeppel et al. 2013 power field. Every face f has a frame (e1 = unit vector of its
// halfedge 3f, e2 = n x e1) and the cross is the complex number z_f = exp(4i theta_f). The
// field minimizes sum_e w_e |z_g - rho_fg z_f|^2 (rho_fg: transport across the shared edge,
// w_e = 3|e|^2 / (2 (A_f + A_g))). Faces next to a feature or boundary edge are fixed (hard
// constraints) and the rest solves one sparse Hermitian system (CHOLMOD); without any constraint
// the field is the smallest eigenvector (inverse iteration, mass = face areas).
// The transport is the Levi-Civita connection of a proxy surface whose face normals are the true
// ones diffused over 1 % of the bounding-box diagonal (never across feature or boundary edges):
// scan noise then does not spawn singularity pairs. Directions move between the true and the proxy
// tangent planes by the minimal rotation between the normals. Everything downstream (matchings,
// indices, sectors) is measured on the true faces.
//
// Constrained faces ("feature" below means caller feature, dihedral feature or boundary edge):
//   - one feature edge: the cross contains the edge direction exactly;
//   - two feature edges (they meet at a corner of angle beta): in a parametrization both edges
//     must become isolines and the corner cannot collapse, so they are mapped to orthogonal
//     isolines. The cross is the symmetric compromise: each edge is off its axis by
//     |45deg - beta/2| (exact alignment with both when beta = 90deg);
//   - three feature edges: the pair whose corner angle is closest to 90deg is handled as above
//     (lowest corner on ties); the third edge is not aligned (no triangle has three isolines:
//     counted in num_overconstrained_faces; splitting such faces is the remedy);
//   - acute sectors: around a vertex, the faces between two consecutive feature/boundary edges
//     whose angles sum to beta < 45deg (two faces or more) would map to zero quarter turns; all
//     of them get the same symmetric compromise (first edge 45deg - beta/2 off its axis, last
//     edge 45deg + beta/2), so the sector maps to one quarter turn. A face in several acute
//     sectors takes the sharpest; the rules above take precedence.
//
// Charts: face f's chart has +u = direction[f] and +v = n_f x direction[f]. A tangent vector at
// angle phi in the chart has coordinates (cos phi, sin phi).
#pragma once
#include <cstdint>
#include <vector>

#include "core/mesh.h"
#include "core/progress.h"

namespace qgp {

struct CrossFieldOptions {
  std::vector<char> feature_edges;   // #E: caller's feature edges (Blender marked sharp); may be empty
  double sharp_angle_deg = -1;       // edges with a larger dihedral angle (angle between the two
                                     // face normals) are features; < 0: off
  double cancel_pairs_within = 0;    // pairs of singularities of index +1 and -1 off features joined
                                     // by ordinary edges no longer than this (model units) are
                                     // cancelled (0: none)
  std::vector<int> keep_pairs_near;  // vertices near which no such pair is cancelled (where a
                                     // seamless map with them folded)
};

struct CrossField {
  std::vector<Vec3> direction;         // #F: unit tangent vector, one of the four cross directions
  std::vector<int8_t> matching;        // 3#F: quarter turns r(h), same convention as
                                       // Parametrization::rotation (chart of face(h) -> chart of the
                                       // opposite face when each face's +u axis is direction[f]):
                                       // the edge vector in the opposite chart is R^r times the edge
                                       // vector in face(h)'s chart up to a residual rotation:
                                       // across ordinary edges r is the nearest quarter turn
                                       // (residual <= 45deg); across feature edges r keeps both
                                       // sides' isoline sectors (see edge_sector; residual <=
                                       // 90deg). 0 on boundary halfedges;
                                       // matching[opposite] = (4 - matching[h]) % 4.
  std::vector<int> vertex_index;       // #V: singularity index in quarter turns (4 - valence of the
                                       // quad-mesh vertex: +1 at a cube corner) = (angle defect -
                                       // sum of the residual rotations left by the matchings
                                       // around the vertex) / 90deg, an exact integer. Boundary
                                       // vertices use the boundary version of Poincare-Hopf (2 -
                                       // number of quads at the vertex: +1 at a 90deg corner):
                                       // (pi - angle sum - residuals + how far the two boundary
                                       // edges are off their isolines) / 90deg. Interior vertices:
                                       // index = sum of the matchings around them, mod 4.
  std::vector<char> feature_edge;      // #E: feature edges in use (caller + dihedral); boundaries
                                       // are features too but are not flagged here
  std::vector<char> constrained_face;  // #F: how the direction was fixed: 0 free (smoothest),
                                       // 1 aligned to its one feature edge, 2 compromise of its
                                       // two (three) feature edges, 3 compromise of an acute
                                       // sector at one of its vertices (see above)
  std::vector<int8_t> edge_sector;     // 3#F: for halfedges of feature and boundary edges, the
                                       // isoline sector q: the halfedge vector runs along R^q(+u)
                                       // of face(h)'s chart (q even: the edge runs along u, so v
                                       // is constant on it; q odd: u is constant); the nearest
                                       // axis in face(h) (off by at most 45deg; up to 90deg
                                       // where a collapsed sector was resolved). Consistent
                                       // across interior feature edges:
                                       //   q(opposite) = (q(h) + matching[h] + 2) % 4.
                                       // -1 on all other halfedges.
  int num_overconstrained_faces = 0;   // faces with three feature/boundary edges: no triangle can
                                       // have all three on isolines (the seamless map must give
                                       // one up or the face must be split)
  int num_collapsed_sectors = 0;       // sectors between consecutive feature/boundary edges around
                                       // a vertex that map to no quarter turn (or, one face wide,
                                       // not to exactly one): the seamless map must degenerate
                                       // there. Only around over-constrained faces on the shared
                                       // meshes (plus 2 on cow.obj at 40deg).
  int num_resolved_sectors = 0;        // quarter turns moved into sectors that would have
                                       // collapsed (or interior vertices of index > +1) from a
                                       // neighbour: one matching (|residual| < 135deg) or one
                                       // edge_sector (|rho| < 90deg) per move (see
                                       // resolve_collapsed_sectors in cross_field.cpp)
  int num_close_pairs = 0;             // pairs cancelled by cancel_pairs_within
  int num_pairs_kept_near_folds = 0;   // pairs within it left uncancelled near keep_pairs_near
  int num_cancelled_pairs = 0;         // a closed torus's fields that no seamless map follows
  int num_untwisted_loops = 0;         // without folds, made admissible (see
                                       // compute_cross_field): its one pair of singularities of
                                       // index +1 and -1 cancelled; its handle loops around which
                                       // a field without singularities turns untwisted
  int num_turned_matchings = 0;        // matchings the pair cancellations and untwists turned by
                                       // a quarter turn (counted per turn), each off the nearest
                                       // quarter turn until the field is smoothed
  int num_singularities = 0;           // vertices with vertex_index != 0
  int index_sum = 0;                   // sum of vertex_index (quarter turns) = 4 * chi
  int euler_characteristic = 0;        // of the mesh
};

// Feature edges (#E flags): the caller's plus those whose dihedral angle exceeds sharp_angle_deg
// (off when < 0). Boundary edges are implicit features and are not flagged.
std::vector<char> detect_feature_edges(const TriMesh& mesh, const std::vector<char>& caller_features,
                                       double sharp_angle_deg);

// mesh: one connected, oriented, manifold component (connectivity built).
// Throws Error(InvalidArgument) if options.feature_edges is neither empty nor #E long,
// Error(InvalidMesh) on a face without a normal, Error(StageFailed) if the solver fails.
CrossField compute_cross_field(const TriMesh& mesh, const CrossFieldOptions& options, Progress& progress);

// d (a tangent of face f) rotated by k quarter turns counter-clockwise about f's unit normal.
Vec3 rotate_in_face(const TriMesh& mesh, int f, const Vec3& d, int k);

// Cone angle of every vertex in quarter turns that a parametrization following the field has:
// 4 - index inside, 2 - index on the boundary. #V.
std::vector<int> cone_quarter_turns(const TriMesh& mesh, const CrossField& field);

// Angle (radians, in (-pi, pi]) of the vector of halfedge h in the chart of face(h) whose +u axis
// is u_axis (a unit tangent of that face).
double chart_angle(const TriMesh& mesh, int h, const Vec3& u_axis);

}  // namespace qgp

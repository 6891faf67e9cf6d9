// Stage 1a: smoothest 4-RoSy cross field, hard-aligned to features and boundaries.
#pragma once
#include <cstdint>
#include <vector>

#include "core/mesh.h"
#include "core/progress.h"

namespace qgp {

struct CrossFieldOptions {
  std::vector<char> feature_edges;  // #E: caller's feature edges (Blender marked sharp); may be empty
  double sharp_angle_deg = -1;      // edges with a larger dihedral angle are features; < 0: off
};

struct CrossField {
  std::vector<Vec3> direction;        // #F: unit tangent vector, one of the four cross directions
  std::vector<int8_t> matching;       // 3#F: quarter turns r(h), same convention as
                                      // Parametrization::rotation (chart of face(h) -> chart of the
                                      // opposite face when each face's +u axis is direction[f])
  std::vector<int> vertex_index;      // #V: singularity index in quarter turns (4 - valence of the
                                      // quad-mesh vertex: +1 at a cube corner); boundary vertices
                                      // use the boundary version of Poincare-Hopf
  std::vector<char> feature_edge;     // #E: feature edges in use (caller + dihedral); boundaries
                                      // are features too but are not flagged here
  std::vector<char> constrained_face; // #F: faces whose direction was fixed by a feature/boundary
  int num_singularities = 0;          // vertices with vertex_index != 0
  int index_sum = 0;                  // sum of vertex_index (quarter turns) = 4 * chi
  int euler_characteristic = 0;       // of the mesh
};

// mesh: one connected, oriented, manifold component (connectivity built).
CrossField compute_cross_field(const TriMesh& mesh, const CrossFieldOptions& options, Progress& progress);

}  // namespace qgp

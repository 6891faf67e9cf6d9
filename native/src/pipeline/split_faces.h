// Component preparation: faces whose three edges are all feature or boundary edges cannot have
// all their sides on parameter isolines (the map would have to collapse them), so they are split
// at their centroid before the field is computed.
#pragma once
#include <vector>

#include "core/mesh.h"

namespace qgp {

// feature_edges: #E flags (boundary edges count as features implicitly). vertex_map / face_map:
// per vertex / face of `mesh` an index in another mesh; new centroids get -1, the three parts of
// a split face keep its entry. All four are updated. Returns the number of faces split.
int split_overconstrained_faces(TriMesh& mesh, std::vector<char>& feature_edges, std::vector<int>& vertex_map,
                                std::vector<int>& face_map);

}  // namespace qgp

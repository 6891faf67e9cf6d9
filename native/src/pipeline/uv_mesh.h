// The map of a finished session as a triangle mesh of its own, with per-corner texture
// coordinates: what `qgp --uv-out` writes and the add-on's refined grid-UV copy shows.
#pragma once
#include <vector>

#include <Eigen/Core>

#include "core/mesh.h"
#include "pipeline/session.h"

namespace qgp {

enum class UvMapKind {
  IntegerGrid,  // the integer-grid map, 1 uv unit = 1 quad
  Seamless,     // the continuous seamless map before quantization, 1 uv unit = seamless_edge_length
};

struct UvMesh {
  // The repaired input mesh (faces split by the pipeline included; a decimated component's working
  // mesh). A component whose integer-grid map fell back to the cell map has the T-mesh inserted:
  // its extra vertices follow the intake's. V and F only (no connectivity).
  TriMesh mesh;
  Eigen::Matrix<double, Eigen::Dynamic, 2, Eigen::RowMajor> uv;  // 3#F x 2, per corner
  std::vector<int> source_face;  // #F: the input face (polygon) each triangle lies in, -1 if unknown
  int refined_components = 0;    // components written with the T-mesh inserted
};

// Which map every component of the session has (components that failed and are kept as triangles
// aside: they are not in the uv mesh): IntegerGrid if all have one, else Seamless if all
// have that; false if neither (e.g. after an intake-only job).
bool available_uv_map(const Session& session, UvMapKind* kind);

// Throws Error(NotReady) if the session has no such map for every component.
UvMesh compose_uv_mesh(const Session& session, UvMapKind kind);

}  // namespace qgp

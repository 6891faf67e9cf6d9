// The T-mesh layout (motorcycle graph) of a finished session as line segments: what
// `qgp --layout-out` writes as OBJ polylines and the add-on's Show Layout draws.
#pragma once
#include <array>
#include <vector>

#include "core/mesh.h"
#include "pipeline/session.h"

namespace qgp {

struct LayoutLines {
  std::vector<Vec3> points;                  // on the surface of each component's working mesh
  std::vector<std::array<int, 2>> segments;  // pairs of indices into points
};

// Whether every component (but those kept as triangles) has a T-mesh traced on its current
// seamless map, and at least one does.
bool has_layout(const Session& session);

// The T-mesh edges of every component (but those kept as triangles) as segments over their nodes
// and the points of their paths (consecutive duplicates skipped, as write_layout_obj does), with
// symmetry mirrored across its planes like the quads. Throws Error(NotReady) if has_layout is false.
LayoutLines compose_layout_lines(const Session& session);

}  // namespace qgp

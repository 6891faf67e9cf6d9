#include "pipeline/layout_lines.h"

#include "core/error.h"
#include "tmesh/tmesh_system.h"

namespace qgp {

bool has_layout(const Session& session) {
  bool complete = false;
  for (const auto& c : session.components()) {
    if (c.failure) continue;
    if (!c.seamless_is_current() || !c.traced.computed_from(c.seamless.id())) return false;
    complete = true;
  }
  return complete;
}

namespace {

// Appends one edge's path: from its start node over the interior points of its trace to its end node.
void append_edge(LayoutLines& lines, const TriMesh& mesh, const TMesh& tmesh, const TMeshEdge& e, int node_base) {
  int previous = node_base + e.from;
  Vec3 last = tmesh.nodes[e.from].point.position(mesh);
  for (size_t k = 1; k + 1 < e.trace.size(); ++k) {
    const Vec3 p = e.trace[k].position(mesh);
    if ((p - last).norm() == 0) continue;
    lines.points.push_back(p);
    const int current = static_cast<int>(lines.points.size()) - 1;
    lines.segments.push_back({previous, current});
    previous = current;
    last = p;
  }
  lines.segments.push_back({previous, node_base + e.to});
}

void append_tmesh(LayoutLines& lines, const TriMesh& mesh, const TMesh& tmesh) {
  const int node_base = static_cast<int>(lines.points.size());
  for (const TMeshNode& n : tmesh.nodes) lines.points.push_back(n.point.position(mesh));
  for (const TMeshEdge& e : tmesh.edges) append_edge(lines, mesh, tmesh, e, node_base);
}

// The lines mirrored across each plane of the symmetry asked (the layout is the positive half's).
void append_mirror_images(LayoutLines& lines, const SymmetryAxes& axes) {
  for (int axis = 0; axis < 3; ++axis) {
    if (!axes.axis[axis]) continue;
    const int n = static_cast<int>(lines.points.size()), m = static_cast<int>(lines.segments.size());
    for (int i = 0; i < n; ++i) {
      Vec3 image = lines.points[i];
      image[axis] = -image[axis];
      lines.points.push_back(image);
    }
    for (int s = 0; s < m; ++s) lines.segments.push_back({lines.segments[s][0] + n, lines.segments[s][1] + n});
  }
}

}  // namespace

LayoutLines compose_layout_lines(const Session& session) {
  if (!has_layout(session)) throw Error(ErrorCode::NotReady, "no quad layout: run a remesh or grid-UV job first");
  LayoutLines lines;
  for (const auto& c : session.components())
    if (!c.failure) append_tmesh(lines, c.mesh, c.traced->tmesh);
  append_mirror_images(lines, session.options().symmetry);
  return lines;
}

}  // namespace qgp

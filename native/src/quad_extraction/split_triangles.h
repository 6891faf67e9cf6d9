// The smallest valid quad mesh of any triangle mesh's topology: every triangle split into three
// quads through its edge midpoints and its centroid (Catmull-Clark's first step on triangles).
//
// The quads keep the triangles' orientation, every triangle edge (as two quad edges, so feature and
// boundary curves stay exactly where they were), the Euler characteristic and the boundary loops;
// each quad is planar and convex inside its triangle. The pipeline's last rung for a part whose
// layout cannot give quads (policy.h: quads_of_split_triangles).
#pragma once
#include "core/mesh.h"
#include "core/quad_mesh.h"

namespace qgp {

// mesh: connectivity built. Vertices: the mesh's own (same indices), then one per edge (#V + e),
// then one per face (#V + #E + f). Quads: 3 per face, counter-clockwise like the face, quad 3f + k
// at corner k of face f. vertex_face holds a face of `mesh` under each vertex; vertex_singular marks
// the vertices whose valence is not 4 inside (3 on the boundary).
QuadMesh split_triangles_into_quads(const TriMesh& mesh);

}  // namespace qgp

"""numpy conversions between Blender mesh data and the native arrays (no `import bpy`).

Functions take Blender mesh objects only through their foreach_get/foreach_set API, so the
arithmetic here is testable without Blender.
"""
import numpy as np


def mesh_arrays(mesh):
    """Vertices (n,3) float64, triangles (m,3) int32 and the loop of each triangle corner (m,3)
    int32, from a bpy Mesh (triangulated through its loop triangles; n-gons stay intact)."""
    mesh.calc_loop_triangles()
    n = len(mesh.vertices)
    co = np.empty(3 * n, np.float32)
    mesh.vertices.foreach_get("co", co)
    m = len(mesh.loop_triangles)
    tris = np.empty(3 * m, np.int32)
    mesh.loop_triangles.foreach_get("vertices", tris)
    loops = np.empty(3 * m, np.int32)
    mesh.loop_triangles.foreach_get("loops", loops)
    return co.reshape(-1, 3).astype(np.float64), tris.reshape(-1, 3), loops.reshape(-1, 3)


def edge_vertex_pairs(mesh, flags):
    """Vertex pairs (k,2) int32 of the edges whose boolean flag (array of len(mesh.edges)) is set."""
    e = np.empty(2 * len(mesh.edges), np.int32)
    mesh.edges.foreach_get("vertices", e)
    e = e.reshape(-1, 2)
    return np.ascontiguousarray(e[np.asarray(flags, bool)])

"""numpy conversions between Blender mesh data and the native arrays (no `import bpy`).

Functions take Blender mesh objects only through their foreach_get/foreach_set API, so the
arithmetic here is testable without Blender.
"""
import numpy as np


def mesh_arrays(mesh):
    """Vertices (n,3) float64, triangles (m,3) int32, the loop of each triangle corner (m,3) int32
    and the polygon of each triangle (m,) int32, from a bpy Mesh: its quads split by split_quads,
    other polygons through Blender's loop triangles (n-gons stay intact); triangles by polygon."""
    mesh.calc_loop_triangles()
    n = len(mesh.vertices)
    co = np.empty(3 * n, np.float32)
    mesh.vertices.foreach_get("co", co)
    vertices = co.reshape(-1, 3).astype(np.float64)
    m = len(mesh.loop_triangles)
    tris, loops, polys = np.empty(3 * m, np.int32), np.empty(3 * m, np.int32), np.empty(m, np.int32)
    mesh.loop_triangles.foreach_get("vertices", tris)
    mesh.loop_triangles.foreach_get("loops", loops)
    mesh.loop_triangles.foreach_get("polygon_index", polys)
    sizes, starts = np.empty(len(mesh.polygons), np.int32), np.empty(len(mesh.polygons), np.int32)
    mesh.polygons.foreach_get("loop_total", sizes)
    mesh.polygons.foreach_get("loop_start", starts)
    loop_vertex = np.empty(len(mesh.loops), np.int32)
    mesh.loops.foreach_get("vertex_index", loop_vertex)
    quads = np.flatnonzero(sizes == 4)
    quad_loops = (starts[quads][:, None] + np.arange(4)).astype(np.int32)
    quad_tris, quad_tri_loops = split_quads(vertices, loop_vertex[quad_loops], quad_loops)
    other = sizes[polys] != 4
    triangles = np.concatenate([tris.reshape(-1, 3)[other], quad_tris])
    triangle_loops = np.concatenate([loops.reshape(-1, 3)[other], quad_tri_loops])
    triangle_polygon = np.concatenate([polys[other], np.repeat(quads, 2)]).astype(np.int32)
    order = np.argsort(triangle_polygon, kind="stable")
    return vertices, triangles[order], triangle_loops[order], triangle_polygon[order]


def split_quads(vertices, quad_vertices, quad_loops):
    """Two triangles (2k,3) and their loops (2k,3) per quad (k,4): along the diagonal from the quad's
    lowest vertex unless its two triangles face apart (a concave quad), else along the other one.
    Blender splits a quad from its first loop, and gives a new mesh's loops from another start from
    run to run (a UV sphere's): the same quads must give the same triangles, whatever their start."""
    first = np.argmin(quad_vertices, axis=1)
    corners = (first[:, None] + np.arange(4)) % 4
    v = np.take_along_axis(quad_vertices, corners, axis=1)
    loops = np.take_along_axis(quad_loops, corners, axis=1)
    p = vertices[v]
    n1 = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    n2 = np.cross(p[:, 2] - p[:, 0], p[:, 3] - p[:, 0])
    from_lowest = np.einsum("ij,ij->i", n1, n2) >= 0
    pick = np.where(from_lowest[:, None, None], [[0, 1, 2], [0, 2, 3]], [[1, 2, 3], [1, 3, 0]])  # (k,2,3)
    rows = np.arange(len(v))[:, None, None]
    return v[rows, pick].reshape(-1, 3).astype(np.int32), loops[rows, pick].reshape(-1, 3).astype(np.int32)


def edge_vertex_pairs(mesh, flags):
    """Vertex pairs (k,2) int32 of the edges whose boolean flag (array of len(mesh.edges)) is set."""
    e = np.empty(2 * len(mesh.edges), np.int32)
    mesh.edges.foreach_get("vertices", e)
    e = e.reshape(-1, 2)
    return np.ascontiguousarray(e[np.asarray(flags, bool)])


def _rotate_quarter(p, r):
    for _ in range(r % 4):
        p = np.array([-p[1], p[0]])
    return p


def loop_uvs_from_triangles(corner_uv, triangles, triangle_loops, triangle_polygon, num_loops):
    """Per-loop UVs (num_loops, 2) from per-triangle-corner integer-grid UVs (t, 3, 2).

    A polygon split into several triangles may have them in different charts (a seam along an
    inner diagonal); their corners are brought into the chart of the polygon's first triangle
    through the transition across each shared diagonal (a quarter-turn rotation plus a
    translation, recovered from the two shared corners), so every loop of a polygon is in one chart."""
    loop_uv = np.full((num_loops, 2), np.nan)
    by_polygon = {}
    for t, p in enumerate(triangle_polygon.tolist()):
        by_polygon.setdefault(p, []).append(t)
    for tris in by_polygon.values():
        if len(tris) == 1:
            t = tris[0]
            loop_uv[triangle_loops[t]] = corner_uv[t]
            continue
        placed = {tris[0]: corner_uv[tris[0]].copy()}
        pending = list(tris[1:])
        while pending:
            progressed = False
            for t in list(pending):
                for s, uv_s in placed.items():
                    shared = [v for v in triangles[t] if v in triangles[s]]
                    if len(shared) != 2:
                        continue
                    ks = [list(triangles[s]).index(v) for v in shared]
                    kt = [list(triangles[t]).index(v) for v in shared]
                    ds = uv_s[ks[1]] - uv_s[ks[0]]
                    dt = corner_uv[t][kt[1]] - corner_uv[t][kt[0]]
                    r = min(range(4), key=lambda r: np.abs(_rotate_quarter(dt, r) - ds).sum())
                    shift = uv_s[ks[0]] - _rotate_quarter(corner_uv[t][kt[0]], r)
                    placed[t] = np.array([_rotate_quarter(c, r) + shift for c in corner_uv[t]])
                    pending.remove(t)
                    progressed = True
                    break
            if not progressed:  # triangles of the polygon that share no edge: keep their own chart
                for t in pending:
                    placed[t] = corner_uv[t].copy()
                pending = []
        for t, uv in placed.items():
            loop_uv[triangle_loops[t]] = uv
    return loop_uv


def uv_seam_edges(mesh, uv_layer, tolerance=0.0):
    """Flag per edge (len(mesh.edges) bool): set where the polygons on its two sides disagree in UV
    (by more than `tolerance` in a coordinate) at one of its ends, i.e. the edges along which the
    UV islands are cut apart. Boundary edges (one polygon) are never set."""
    num_loops = len(mesh.loops)
    uv = np.empty(2 * num_loops, np.float32)
    uv_layer.data.foreach_get("uv", uv)
    uv = uv.reshape(-1, 2).astype(np.float64)
    loop_vertex = np.empty(num_loops, np.int32)
    loop_edge = np.empty(num_loops, np.int32)
    mesh.loops.foreach_get("vertex_index", loop_vertex)
    mesh.loops.foreach_get("edge_index", loop_edge)
    loop_start = np.empty(len(mesh.polygons), np.int32)
    loop_total = np.empty(len(mesh.polygons), np.int32)
    mesh.polygons.foreach_get("loop_start", loop_start)
    mesh.polygons.foreach_get("loop_total", loop_total)
    # A loop's edge runs from its vertex to the vertex of the polygon's next loop.
    following = np.arange(1, num_loops + 1, dtype=np.int64)
    following[loop_start + loop_total - 1] = loop_start
    # Each side of an edge gives the UV of both ends: (edge, vertex, uv) twice per loop.
    edge = np.concatenate([loop_edge, loop_edge])
    vertex = np.concatenate([loop_vertex, loop_vertex[following]])
    corner = np.concatenate([uv, uv[following]])
    order = np.lexsort((vertex, edge))
    edge, vertex, corner = edge[order], vertex[order], corner[order]
    same_end = (edge[1:] == edge[:-1]) & (vertex[1:] == vertex[:-1])
    apart = same_end & (np.abs(corner[1:] - corner[:-1]).max(axis=1) > tolerance)
    flags = np.zeros(len(mesh.edges), bool)
    flags[edge[1:][apart]] = True
    return flags


def loop_polygons(loop_start, loop_total):
    """The polygon of every loop (num_loops,) int32, from each polygon's loop_start and loop_total
    (each polygon's loops are the block loop_start .. loop_start + loop_total)."""
    loop_start = np.asarray(loop_start, np.int64)
    loop_total = np.asarray(loop_total, np.int64)
    order = np.argsort(loop_start, kind="stable")
    return np.repeat(order, loop_total[order]).astype(np.int32)


def edges_between_differing_faces(loop_edge, loop_polygon, polygon_value, num_edges):
    """Flag per edge (num_edges bool): set where the polygons around the edge do not all have the
    same `polygon_value` (a material index, a face set): the boundaries between such regions.
    Boundary edges (one polygon) are never set; non-manifold edges are set if any two differ."""
    flags = np.zeros(num_edges, bool)
    if num_edges == 0 or len(loop_edge) == 0:
        return flags
    values = np.asarray(polygon_value, np.int64)[np.asarray(loop_polygon, np.int64)]
    lowest = np.full(num_edges, np.iinfo(np.int64).max)
    highest = np.full(num_edges, np.iinfo(np.int64).min)
    np.minimum.at(lowest, loop_edge, values)
    np.maximum.at(highest, loop_edge, values)
    used = np.zeros(num_edges, bool)
    used[loop_edge] = True
    return used & (lowest != highest)

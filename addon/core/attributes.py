"""Carrying a source mesh's attributes over to the quad mesh made from it (no `import bpy`).

Every new vertex is projected onto the source (the Blender glue finds the nearest source triangle
and the point on it); point and corner values are interpolated there with barycentric weights,
face values come from the source polygon under each new face. All arrays are numpy; the glue
reads and writes Blender data through foreach_get/foreach_set.
"""
import numpy as np

# Types carried over, and the foreach_get/foreach_set key of their values with its width.
VALUE_KEYS = {
    "FLOAT": ("value", 1), "INT": ("value", 1), "BOOLEAN": ("value", 1),
    "FLOAT_VECTOR": ("vector", 3), "FLOAT2": ("vector", 2),
    "FLOAT_COLOR": ("color", 4), "BYTE_COLOR": ("color", 4),
}
# Values that cannot be blended: the value of the nearest source vertex is taken instead.
DISCRETE_TYPES = {"INT", "BOOLEAN"}
COLOR_TYPES = {"FLOAT_COLOR", "BYTE_COLOR"}
# Attributes Blender keeps itself (geometry, selection, shading, creases, materials): a new mesh
# gets its own, and materials are set per face separately.
BUILTIN_NAMES = {"position", "material_index", "sharp_face", "sharp_edge", "crease", "crease_vert",
                 "crease_edge", "bevel_weight_vert", "bevel_weight_edge", "normal", "shade_smooth",
                 "sculpt_face_set", "uv_seam"}


def is_carried(name, domain, data_type, uv_names=()):
    """Whether an attribute goes over to the quad mesh: a user attribute (not internal, i.e. not
    starting with '.', not one Blender keeps itself, not a UV map) of a carried type on points or
    faces; colours also on face corners."""
    if name.startswith(".") or name in BUILTIN_NAMES or name in uv_names or data_type not in VALUE_KEYS:
        return False
    return domain in ("POINT", "FACE") or (domain == "CORNER" and data_type in COLOR_TYPES)


def painted_density(weights, factor):
    """The linear quad density per vertex from painted weights in [0, 1] (clamped): `factor` where the
    weight is 1, 1 (the target) where it is 0, geometric in between."""
    return np.power(float(factor), np.clip(np.asarray(weights, np.float64), 0.0, 1.0))


def luminance(rgb):
    """Rec. 709 luminance of colours (n, 3+), the painted weight of a colour attribute."""
    rgb = np.asarray(rgb, np.float64)
    return rgb[:, 0] * 0.2126 + rgb[:, 1] * 0.7152 + rgb[:, 2] * 0.0722


def barycentric_weights(points, a, b, c):
    """Barycentric weights (n,3) of `points` (n,3) in the triangles (a, b, c) (each (n,3)), of the
    point's projection onto the triangle's plane, clamped into the triangle (negative weights set
    to 0, the rest scaled to sum 1). A degenerate triangle gives its corners equal weights."""
    points, a, b, c = (np.asarray(x, np.float64) for x in (points, a, b, c))
    e0, e1, d = b - a, c - a, points - a
    d00 = np.einsum("ij,ij->i", e0, e0)
    d01 = np.einsum("ij,ij->i", e0, e1)
    d11 = np.einsum("ij,ij->i", e1, e1)
    d20 = np.einsum("ij,ij->i", d, e0)
    d21 = np.einsum("ij,ij->i", d, e1)
    denominator = d00 * d11 - d01 * d01
    scale = np.maximum(d00 * d11, 1e-300)
    good = denominator > 1e-12 * scale
    safe = np.where(good, denominator, 1.0)
    v = (d11 * d20 - d01 * d21) / safe
    w = (d00 * d21 - d01 * d20) / safe
    weights = np.stack([1.0 - v - w, v, w], axis=1)
    weights[~good] = 1.0 / 3.0
    weights = np.clip(weights, 0.0, None)
    return weights / weights.sum(axis=1, keepdims=True)


def blend(corner_values, weights, discrete=False):
    """Values at points from the values at their triangle's three corners (n,3[,k]) and the
    barycentric weights (n,3): the weighted sum, or for `discrete` values the corner of the largest
    weight."""
    corner_values = np.asarray(corner_values)
    if discrete:
        return corner_values[np.arange(len(weights)), np.argmax(weights, axis=1)]
    w = weights.reshape(weights.shape + (1,) * (corner_values.ndim - 2))
    return (corner_values * w).sum(axis=1)


def point_values(values, triangles, triangle, weights, discrete=False):
    """Point-domain values (one per source vertex) at the projected points: `triangle` (n,) is each
    point's source triangle (rows of `triangles`), `weights` (n,3) its barycentric weights."""
    return blend(np.asarray(values)[np.asarray(triangles)[triangle]], weights, discrete)


def corner_values(values, triangle_loops, triangle, weights, discrete=False):
    """Corner-domain values (one per source loop) at the projected points, interpolated between the
    loops of the point's source triangle (`triangle_loops`: the loop of each triangle corner)."""
    return blend(np.asarray(values)[np.asarray(triangle_loops)[triangle]], weights, discrete)


def face_values(values, triangle_polygon, face_triangle):
    """Face-domain values (one per source polygon) for new faces: each takes the value of the source
    polygon of its source triangle `face_triangle` (ids out of range are clamped)."""
    tri = np.clip(np.asarray(face_triangle, np.int64), 0, len(triangle_polygon) - 1)
    return np.asarray(values)[np.asarray(triangle_polygon)[tri]]


def corner_vertices(face_blocks):
    """The vertex of every corner (loop) of a new mesh whose faces are the rows of the arrays
    `face_blocks` (quads (q,4), then triangles (t,3), ...), in order: as Mesh.from_pydata lays out
    the loops."""
    flat = [np.asarray(block, np.int64).reshape(-1) for block in face_blocks]
    return np.concatenate(flat) if flat else np.zeros(0, np.int64)


def group_weight_matrix(vertex_ids, group_ids, weights, num_vertices, num_groups):
    """Vertex group weights as a dense (num_vertices, num_groups) float64 array (0 where a vertex is
    not in a group) from the (vertex, group, weight) triples of the memberships."""
    matrix = np.zeros((num_vertices, num_groups))
    matrix[np.asarray(vertex_ids, np.int64), np.asarray(group_ids, np.int64)] = weights
    return matrix

"""Blender glue for the attributes a quad object keeps of its source: reading them off the source
mesh (vertex groups, colour and other generic attributes, the active UV map) and writing them onto
the new mesh, projected through core/attributes.py."""
import numpy as np
from mathutils.bvhtree import BVHTree

from .core import attributes as carry

_DTYPES = {"INT": np.int32, "BOOLEAN": bool}


def _read_values(attribute):
    """An attribute's values: (n,) or (n, width) numpy array."""
    key, width = carry.VALUE_KEYS[attribute.data_type]
    values = np.empty(len(attribute.data) * width, _DTYPES.get(attribute.data_type, np.float32))
    attribute.data.foreach_get(key, values)
    return values.reshape(-1, width) if width > 1 else values


def _read_vertex_groups(obj, mesh):
    """(names, weights (vertices, groups)) of the object's vertex groups on `mesh`."""
    names = [group.name for group in obj.vertex_groups]
    if not names:
        return names, np.zeros((len(mesh.vertices), 0))
    memberships = [(v.index, g.group, g.weight) for v in mesh.vertices for g in v.groups if g.group < len(names)]
    vertex_ids, group_ids, weights = zip(*memberships) if memberships else ((), (), ())
    return names, carry.group_weight_matrix(vertex_ids, group_ids, weights, len(mesh.vertices), len(names))


def _active_color_name(mesh):
    colors = getattr(mesh, "color_attributes", None)
    active = getattr(colors, "active_color", None) if colors is not None else None
    return active.name if active is not None else None


class SourceAttributes:
    """What a quad object keeps of its source mesh, read while the (evaluated) mesh exists: the
    carried generic attributes as (name, domain, data type, values), the vertex groups (names and
    a dense weight matrix), the active colour attribute's name and, with keep_uvs, the active UV
    map (name, per-loop UVs)."""

    def __init__(self, obj, mesh, keep_attributes, keep_uvs):
        self.layers, self.group_names, self.group_weights = [], [], None
        self.active_color = _active_color_name(mesh)
        self.uv = None
        if keep_attributes:
            uv_names = {layer.name for layer in mesh.uv_layers}
            self.layers = [(a.name, a.domain, a.data_type, _read_values(a)) for a in mesh.attributes
                           if carry.is_carried(a.name, a.domain, a.data_type, uv_names)]
            self.group_names, self.group_weights = _read_vertex_groups(obj, mesh)
        active_uv = mesh.uv_layers.active
        if keep_uvs and active_uv is not None:
            uv = np.empty(2 * len(mesh.loops), np.float32)
            active_uv.data.foreach_get("uv", uv)
            self.uv = (active_uv.name, uv.reshape(-1, 2))

    def empty(self):
        return not self.layers and not self.group_names and self.uv is None


def project_onto_source(points, source_mesh):
    """(source triangle (n,), barycentric weights (n,3)) of each of `points` (object space): the
    source triangle nearest to it, and its projection onto that triangle (clamped into it)."""
    tree = BVHTree.FromPolygons(source_mesh.vertices.tolist(), source_mesh.triangles.tolist(), all_triangles=True)
    find_nearest = tree.find_nearest
    # find_nearest gives no triangle only for an empty tree (every source triangle degenerate).
    triangle = np.array([find_nearest(point)[2] or 0 for point in points.tolist()], np.int64)
    corners = source_mesh.vertices[source_mesh.triangles[triangle]]
    return triangle, carry.barycentric_weights(points, corners[:, 0], corners[:, 1], corners[:, 2])


def _write_attribute(mesh, name, domain, data_type, values):
    key, _ = carry.VALUE_KEYS[data_type]
    attribute = mesh.attributes.new(name, data_type, domain)
    attribute.data.foreach_set(key, np.ascontiguousarray(values, _DTYPES.get(data_type, np.float32)).reshape(-1))
    return attribute


def _write_vertex_groups(obj, names, weights):
    """Vertex groups `names` on obj with the weights (vertices, groups); zero weights stay out."""
    for column, name in enumerate(names):
        group = obj.vertex_groups.new(name=name)
        column_weights = weights[:, column]
        for vertex in np.flatnonzero(column_weights > 0).tolist():
            group.add([vertex], float(column_weights[vertex]), "REPLACE")


def _carried_values(layer, source_mesh, face_triangle, corners, triangle, weights):
    """The values of one source attribute layer on the new mesh's domain."""
    _, domain, data_type, values = layer
    discrete = data_type in carry.DISCRETE_TYPES
    if domain == "FACE":
        return carry.face_values(values, source_mesh.triangle_polygon, face_triangle)
    if domain == "POINT":
        return carry.point_values(values, source_mesh.triangles, triangle, weights, discrete)
    return carry.corner_values(values, source_mesh.triangle_loops, triangle[corners], weights[corners], discrete)


def keep_source_attributes(obj, vertices, face_blocks, face_triangle, source_mesh):
    """Writes onto the new object `obj` (made from `vertices` and the faces of `face_blocks`, each
    on its source triangle `face_triangle`) the attributes its source keeps (source_mesh.attributes):
    point values and vertex groups interpolated at each vertex's nearest point on the source, corner
    values and the UV map at that point for each corner, face values of each face's source polygon."""
    source = source_mesh.attributes
    if source is None or source.empty() or len(vertices) == 0:
        return
    mesh = obj.data
    triangle, weights = project_onto_source(vertices, source_mesh)
    corners = carry.corner_vertices(face_blocks)
    for layer in source.layers:
        name, domain, data_type, _ = layer
        values = _carried_values(layer, source_mesh, face_triangle, corners, triangle, weights)
        _write_attribute(mesh, name, domain, data_type, values)
    if source.active_color and source.active_color in mesh.attributes and hasattr(mesh, "color_attributes"):
        mesh.color_attributes.active_color = mesh.color_attributes[source.active_color]
    if source.group_names:
        point_weights = carry.point_values(source.group_weights, source_mesh.triangles, triangle, weights)
        _write_vertex_groups(obj, source.group_names, point_weights)
    if source.uv is not None:
        name, uv = source.uv
        loop_uv = carry.corner_values(uv, source_mesh.triangle_loops, triangle[corners], weights[corners])
        layer = mesh.uv_layers.new(name=name)
        layer.data.foreach_set("uv", np.ascontiguousarray(loop_uv, np.float32).reshape(-1))


def read_density(obj, mesh, group_name, color_name, factor):
    """The painted density per vertex of `mesh` (object `obj`'s, evaluated or not): `factor` where the
    vertex group `group_name` has weight 1 or the colour attribute `color_name` is white, geometric in
    between (carry.painted_density; both: their product); None when neither is named. A name the
    object does not have raises KeyError naming it."""
    if not group_name and not color_name:
        return None
    density = np.ones(len(mesh.vertices))
    if group_name:
        group = obj.vertex_groups.get(group_name)
        if group is None:
            raise KeyError(f"the object has no vertex group '{group_name}' (Density Group)")
        weights = np.zeros(len(mesh.vertices))
        for v in mesh.vertices:
            for g in v.groups:
                if g.group == group.index:
                    weights[v.index] = g.weight
        density *= carry.painted_density(weights, factor)
    if color_name:
        density *= carry.painted_density(_color_weights(mesh, color_name), factor)
    return density


def _color_weights(mesh, name):
    """Per vertex, the luminance of colour attribute `name` (a corner attribute averaged per vertex)."""
    layer = mesh.attributes.get(name)
    if layer is None or layer.data_type not in ("FLOAT_COLOR", "BYTE_COLOR") or layer.domain not in ("POINT", "CORNER"):
        raise KeyError(f"the mesh has no point or corner colour attribute '{name}' (Density Colour)")
    colors = np.empty(4 * len(layer.data), np.float32)
    layer.data.foreach_get("color", colors)
    weights = carry.luminance(colors.reshape(-1, 4))
    if layer.domain == "POINT":
        return weights
    loop_vertices = np.empty(len(mesh.loops), np.int64)
    mesh.loops.foreach_get("vertex_index", loop_vertices)
    sums = np.bincount(loop_vertices, weights, minlength=len(mesh.vertices))
    counts = np.bincount(loop_vertices, minlength=len(mesh.vertices))
    return sums / np.maximum(counts, 1)

"""Blender glue: reading a mesh object's data for the native library and writing results back."""
import os

import bpy
import numpy as np

from . import attributes
from .core import binding, meshdata


def _edge_attribute_flags(mesh, names, edge_property):
    """Flag per edge from the first of the boolean edge attributes `names` the mesh has (where
    Blender 4.x/5.x keeps the flag), else from the MeshEdge property `edge_property` (3.x); all off
    when neither exists."""
    flags = np.zeros(len(mesh.edges), bool)
    for name in names:
        attribute = mesh.attributes.get(name)
        if attribute is not None and attribute.domain == "EDGE" and attribute.data_type == "BOOLEAN":
            attribute.data.foreach_get("value", flags)
            return flags
    if len(mesh.edges) and hasattr(mesh.edges[0], edge_property):
        mesh.edges.foreach_get(edge_property, flags)
    return flags


def sharp_edge_flags(mesh):
    """Marked-sharp flag per edge: the 'sharp_edge' attribute (Blender 4.1+) or use_edge_sharp (3.x)."""
    return _edge_attribute_flags(mesh, ("sharp_edge",), "use_edge_sharp")


def seam_edge_flags(mesh):
    """Marked-seam flag per edge: the 'uv_seam' attribute (Blender 4.5, 5.0), '.uv_seam' (earlier
    4.x) or use_seam (3.x)."""
    return _edge_attribute_flags(mesh, (".uv_seam", "uv_seam"), "use_seam")


def _polygon_boundary_flags(mesh, polygon_value):
    """Flag per edge: set between polygons of different `polygon_value` (one int per polygon)."""
    loop_start = np.empty(len(mesh.polygons), np.int32)
    loop_total = np.empty(len(mesh.polygons), np.int32)
    mesh.polygons.foreach_get("loop_start", loop_start)
    mesh.polygons.foreach_get("loop_total", loop_total)
    loop_edge = np.empty(len(mesh.loops), np.int32)
    mesh.loops.foreach_get("edge_index", loop_edge)
    return meshdata.edges_between_differing_faces(loop_edge, meshdata.loop_polygons(loop_start, loop_total),
                                                  polygon_value, len(mesh.edges))


def material_boundary_flags(mesh):
    """Flag per edge: set between polygons of different materials."""
    materials = np.zeros(len(mesh.polygons), np.int32)
    mesh.polygons.foreach_get("material_index", materials)
    return _polygon_boundary_flags(mesh, materials)


def face_set_boundary_flags(mesh):
    """Flag per edge: set between different sculpt face sets (the int face attribute
    '.sculpt_face_set', Blender 4.x/5.x, or 'sculpt_face_set'); all off without face sets."""
    for name in (".sculpt_face_set", "sculpt_face_set"):
        attribute = mesh.attributes.get(name)
        if attribute is not None and attribute.domain == "FACE" and attribute.data_type == "INT":
            face_sets = np.zeros(len(mesh.polygons), np.int32)
            attribute.data.foreach_get("value", face_sets)
            return _polygon_boundary_flags(mesh, face_sets)
    return np.zeros(len(mesh.edges), bool)


# The guides an operator can keep as quad edges besides marked-sharp edges: name -> edge flags.
GUIDES = {"SEAM": seam_edge_flags, "MATERIAL": material_boundary_flags, "FACE_SET": face_set_boundary_flags}


def feature_edges(mesh, use_marked_sharp, guides=()):
    """Vertex pairs (k,2) int32 of the edges kept as quad edges: marked sharp (with
    use_marked_sharp) and those of the `guides` (names of GUIDES)."""
    flags = sharp_edge_flags(mesh) if use_marked_sharp else np.zeros(len(mesh.edges), bool)
    for guide in guides:
        flags |= GUIDES[guide](mesh)
    return meshdata.edge_vertex_pairs(mesh, flags)


class SourceMesh:
    """Arrays of a mesh object for the native library: vertices (object space), triangles, the
    loop of every triangle corner, the polygon of every triangle, and the feature edges (marked
    sharp, and the `guides`: see feature_edges). With keep_attributes, also the attributes carried
    over to the quads (attributes.SourceAttributes; with keep_uvs, the active UV map too). density:
    (vertex group name, colour attribute name, factor) of a painted density (attributes.read_density;
    self.density is None when neither is named)."""

    def __init__(self, context, obj, evaluated, use_marked_sharp, guides=(), keep_attributes=False,
                 keep_uvs=False, density=("", "", 1.0)):
        if evaluated:
            evaluated_obj = obj.evaluated_get(context.evaluated_depsgraph_get())
            mesh = evaluated_obj.to_mesh()
        else:
            evaluated_obj, mesh = None, obj.data
        try:
            self.vertices, self.triangles, self.triangle_loops, self.triangle_polygon = meshdata.mesh_arrays(mesh)
            materials = np.zeros(len(mesh.polygons), np.int32)
            mesh.polygons.foreach_get("material_index", materials)
            self.polygon_material = materials
            self.num_loops = len(mesh.loops)
            self.features = feature_edges(mesh, use_marked_sharp, guides)
            self.attributes = (attributes.SourceAttributes(obj, mesh, keep_attributes, keep_uvs)
                               if keep_attributes or keep_uvs else None)
            self.density = attributes.read_density(obj, mesh, *density)
        finally:
            if evaluated_obj is not None:
                evaluated_obj.to_mesh_clear()

    def fingerprint(self):
        """Identifies the geometry and its feature edges, so a cached native session is reused only
        for the same mesh and features."""
        return hash((self.vertices.tobytes(), self.triangles.tobytes(), self.features.tobytes()))


def new_mesh(name, vertices, faces):
    """A new mesh from vertex positions and faces (vertex index lists); its edges derived.
    Blender 5.0.1's Mesh.from_pydata leaves the edge selection attribute '.select_edge' with the
    type of the edge vertices (INT32_2D), and writing an edge selection into it crashes Blender
    (select_faces does): such an attribute is removed (Blender makes a boolean one when an edge
    selection is written)."""
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata(vertices, [], faces)
    mesh.update(calc_edges=True)
    attribute = mesh.attributes.get(".select_edge")
    if attribute is not None and attribute.data_type != "BOOLEAN":
        mesh.attributes.remove(attribute)
    return mesh


def read_mesh(path):
    """A new mesh named after the file from an OBJ, PLY or OFF file, read by the native reader
    (polygons kept)."""
    vertices, sizes, corners = binding.read_mesh_file(path)
    starts = np.concatenate(([0], np.cumsum(sizes)))
    flat = corners.tolist()
    faces = [flat[starts[i]:starts[i + 1]] for i in range(len(sizes))]
    return new_mesh(os.path.splitext(os.path.basename(path))[0], vertices.tolist(), faces)


def _placed_like(context, source, obj):
    """Gives obj the source's parent and transform and links it to the source's collections."""
    obj.parent = source.parent
    obj.matrix_parent_inverse = source.matrix_parent_inverse.copy()
    obj.matrix_basis = source.matrix_basis.copy()
    collections = source.users_collection or (context.scene.collection,)
    for collection in collections:
        collection.objects.link(obj)
    return obj


def _object_like(context, source, name, vertices, faces, face_triangle, source_mesh, loop_uv=None,
                 layer_name=None):
    """New object `name` with the source's transform, parent, collections and materials; each face
    takes the material of the source triangle `face_triangle` names. loop_uv: (loops, 2) per face
    corner in face order, written to the UV layer `layer_name`."""
    mesh = new_mesh(name, vertices.tolist(), faces if isinstance(faces, list) else faces.tolist())
    for slot in source.material_slots:
        mesh.materials.append(slot.material)
    if len(source.material_slots) > 1 and len(faces):
        tri = np.clip(face_triangle, 0, len(source_mesh.triangle_polygon) - 1)
        index = source_mesh.polygon_material[source_mesh.triangle_polygon[tri]]
        mesh.polygons.foreach_set("material_index", index.astype(np.int32))
    if loop_uv is not None:
        layer = mesh.uv_layers.new(name=layer_name)
        layer.data.foreach_set("uv", loop_uv.astype(np.float32).reshape(-1))
        mesh.uv_layers.active = layer
    mesh.validate(clean_customdata=False)
    obj = _placed_like(context, source, bpy.data.objects.new(name, mesh))
    for other in context.selected_objects:
        other.select_set(False)
    obj.select_set(True)
    context.view_layer.objects.active = obj
    return obj


def create_quad_object(context, source, vertices, quads, quad_triangle, source_mesh, kept=None):
    """New object '<source>_quads' with the source's transform, parent, collections and materials,
    and the attributes source_mesh keeps (see attributes.keep_source_attributes). kept: (vertices,
    triangles, source triangle per triangle) of parts that could not be quadded, added after the
    quads as triangles."""
    blocks = [quads]
    if kept is not None and len(kept[1]):
        blocks.append(kept[1] + len(vertices))
        vertices = np.concatenate([vertices, kept[0]])
        quad_triangle = np.concatenate([quad_triangle, kept[2]])
    faces = [face for block in blocks for face in block.tolist()]
    obj = _object_like(context, source, source.name + "_quads", vertices, faces, quad_triangle, source_mesh)
    attributes.keep_source_attributes(obj, vertices, blocks, quad_triangle, source_mesh)
    return obj


def create_layout_object(context, source, points, segments):
    """New object '<source>_layout': the quad layout's lines (points (n,3), segments (s,2)) as a
    mesh of edges only, with the source's transform, parent and collections, drawn in front. It is
    not selected."""
    mesh = bpy.data.meshes.new(source.name + "_layout")
    mesh.from_pydata(points.tolist(), segments.tolist(), [])
    mesh.validate(clean_customdata=False)
    obj = _placed_like(context, source, bpy.data.objects.new(source.name + "_layout", mesh))
    obj.show_in_front = True
    return obj


def select_faces(mesh, face_ids):
    """Selects exactly the polygons `face_ids` (with their edges and vertices, so every select mode
    shows them in Edit Mode) and deselects the rest. Ids out of range are ignored. Returns how many
    polygons are selected."""
    ids = np.asarray(face_ids, np.int64).reshape(-1)
    ids = ids[(ids >= 0) & (ids < len(mesh.polygons))]
    polygon_flags = np.zeros(len(mesh.polygons), bool)
    polygon_flags[ids] = True
    # Each polygon's loops are the block loop_start .. loop_start + loop_total.
    loop_start = np.empty(len(mesh.polygons), np.int32)
    loop_total = np.empty(len(mesh.polygons), np.int32)
    mesh.polygons.foreach_get("loop_start", loop_start)
    mesh.polygons.foreach_get("loop_total", loop_total)
    order = np.argsort(loop_start)
    loops = polygon_flags[np.repeat(order, loop_total[order])]  # per loop: its polygon is selected
    loop_vertex = np.empty(len(mesh.loops), np.int32)
    loop_edge = np.empty(len(mesh.loops), np.int32)
    mesh.loops.foreach_get("vertex_index", loop_vertex)
    mesh.loops.foreach_get("edge_index", loop_edge)
    vertex_flags = np.zeros(len(mesh.vertices), bool)
    vertex_flags[loop_vertex[loops]] = True
    edge_flags = np.zeros(len(mesh.edges), bool)
    edge_flags[loop_edge[loops]] = True
    mesh.polygons.foreach_set("select", polygon_flags)
    mesh.edges.foreach_set("select", edge_flags)
    mesh.vertices.foreach_set("select", vertex_flags)
    return int(polygon_flags.sum())


def create_grid_uv_object(context, source, vertices, triangles, corner_uv, triangle_source, source_mesh,
                          quads_per_unit, layer_name="QGP Grid"):
    """New object '<source>_grid_uv': the refined triangles of a flip-free integer-grid map
    (corner_uv: (triangles, 3, 2), 1 unit = 1 quad) in the UV layer `layer_name`, scaled to
    `quads_per_unit` quads per UV unit."""
    loop_uv = np.nan_to_num(corner_uv.reshape(-1, 2) / float(quads_per_unit))
    return _object_like(context, source, source.name + "_grid_uv", vertices, triangles, triangle_source, source_mesh,
                        loop_uv, layer_name)


def write_grid_uvs(mesh, source_mesh, corner_uv, quads_per_unit, layer_name="QGP Grid"):
    """Writes per-loop UVs (corner_uv: (triangles, 3, 2), 1 unit = 1 quad) scaled to
    `quads_per_unit` quads per UV unit into the layer `layer_name` (created if needed)."""
    loop_uv = meshdata.loop_uvs_from_triangles(corner_uv, source_mesh.triangles, source_mesh.triangle_loops,
                                               source_mesh.triangle_polygon, source_mesh.num_loops)
    loop_uv = np.nan_to_num(loop_uv / float(quads_per_unit)).astype(np.float32)
    layer = mesh.uv_layers.get(layer_name) or mesh.uv_layers.new(name=layer_name)
    layer.data.foreach_set("uv", loop_uv.reshape(-1))
    mesh.uv_layers.active = layer
    return layer


def mark_uv_seams(mesh, uv_layer, tolerance):
    """Marks as seams the edges whose two polygons disagree in the UV layer `uv_layer` (by more than
    `tolerance`): the boundaries of its UV islands inside the mesh. Returns how many edges that is."""
    flags = meshdata.uv_seam_edges(mesh, uv_layer, tolerance)
    seams = np.zeros(len(mesh.edges), bool)
    mesh.edges.foreach_get("use_seam", seams)
    mesh.edges.foreach_set("use_seam", seams | flags)
    return int(flags.sum())

"""Texture atlas helpers: the atlas UV layer of the quad object or of integer-grid UVs, and seam stitching of
an image in it."""
import numpy as np

from .core import binding

ATLAS_LAYER = "QGP Atlas"


def write_atlas_uvs(mesh, vertices, quads, size, mip_levels=0):
    """Writes the atlas of the first len(quads) polygons (the quads, corners in order) into the UV layer
    'QGP Atlas' and makes it active; later polygons (triangles kept of parts that could not be quadded)
    get (0, 0). Returns the atlas figures (binding.atlas_quads)."""
    corner_uv, info = binding.atlas_quads(vertices, quads, size, mip_levels=mip_levels)
    loop_uv = np.zeros((len(mesh.loops), 2), np.float32)
    loop_uv[:4 * len(quads)] = corner_uv.reshape(-1, 2)
    layer = mesh.uv_layers.get(ATLAS_LAYER) or mesh.uv_layers.new(name=ATLAS_LAYER)
    layer.data.foreach_set("uv", loop_uv.reshape(-1))
    mesh.uv_layers.active = layer
    return info


def material_image(obj):
    """The image a bake writes to: the active Image Texture node of the active material, else its first."""
    material = obj.active_material
    if material is None or not material.use_nodes:
        return None
    active = material.node_tree.nodes.active
    if active is not None and active.type == "TEX_IMAGE" and active.image is not None:
        return active.image
    return next((n.image for n in material.node_tree.nodes if n.type == "TEX_IMAGE" and n.image is not None), None)


def polygon_loops(mesh, uv_layer):
    """The polygons as the library takes them: (sizes, the loops in polygon order, their vertex indices, their UVs
    in the layer (float64))."""
    sizes = np.empty(len(mesh.polygons), np.int32)
    mesh.polygons.foreach_get("loop_total", sizes)
    starts = np.empty(len(mesh.polygons), np.int32)
    mesh.polygons.foreach_get("loop_start", starts)
    order = np.concatenate([np.arange(s, s + n) for s, n in zip(starts, sizes)]) if len(sizes) else np.zeros(0, int)
    corners = np.empty(len(mesh.loops), np.int32)
    mesh.loops.foreach_get("vertex_index", corners)
    uv = np.empty(2 * len(mesh.loops), np.float32)
    uv_layer.data.foreach_get("uv", uv)
    return sizes, order, corners[order], uv.reshape(-1, 2)[order].astype(np.float64)


def write_polygon_atlas(mesh, grid_layer, quads_per_unit, size, mip_levels=0):
    """Writes a texture atlas of the mesh's polygons, made from their integer-grid UVs in grid_layer (scaled to
    quads_per_unit quads per UV unit), into the UV layer 'QGP Atlas' and makes it active. Returns the atlas
    figures (binding.atlas_polygons)."""
    sizes, order, corners, grid_uv = polygon_loops(mesh, grid_layer)
    corner_uv, info = binding.atlas_polygons(sizes, corners, grid_uv * quads_per_unit, size, mip_levels)
    loop_uv = np.zeros((len(mesh.loops), 2), np.float32)
    loop_uv[order] = corner_uv
    layer = mesh.uv_layers.get(ATLAS_LAYER) or mesh.uv_layers.new(name=ATLAS_LAYER)
    layer.data.foreach_set("uv", loop_uv.reshape(-1))
    mesh.uv_layers.active = layer
    return info


def stitch_image(mesh, uv_layer, image):
    """Stitches the seams of `image` in place for the mesh's UV layer; returns the figures
    (binding.stitch_seams)."""
    sizes, _, corners, uv = polygon_loops(mesh, uv_layer)
    width, height = image.size
    channels = image.channels
    pixels = np.empty(width * height * channels, np.float32)
    image.pixels.foreach_get(pixels)
    info = binding.stitch_seams(sizes, corners, uv, pixels, width, height, channels)
    image.pixels.foreach_set(pixels)
    image.update()
    return info

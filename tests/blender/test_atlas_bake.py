"""The texture atlas and Stitch Seams in Blender, headless (blender -b --factory-startup --python-exit-code 1
--python THIS -- --meshes DIR).

spot is remeshed to 1 000 quads with Texture Atlas on (a 512 x 512 texture). Checks: the UV map 'QGP Atlas'
is active, every UV in [0,1], no texel covered twice (rasterized at texel resolution). A smooth procedural
3D texture (Cycles noise in object space, emission bake, 1 sample, Blender's 16-texel margin) is baked into
the atlas; Stitch Seams then fills the gutters; 1 000 random seam points (not within a texel of an
irregular vertex) are sampled bilinearly from both sides of their seam. After stitching the largest colour
difference must be at most 1/255; before (Blender's margin only) and on a copy of the quads with Smart UV
Project's UVs (bake and margin the same) it is measured and printed beside it. Then Integer-Grid UVs with
Texture Atlas on spot's own triangles: no texel twice, every seam texel-aligned.
"""
import os
import random
import sys

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import addon_checks  # noqa: E402

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
ARGS = addon_checks.script_arguments()
MESHES = addon_checks.argument(ARGS, "--meshes", os.path.join(REPO, "..", "shared", "meshes"))
SIZE = 512


def loop_data(mesh, layer):
    """Per polygon its (vertex, uv) corners, in order."""
    uv = np.empty(2 * len(mesh.loops), np.float32)
    layer.data.foreach_get("uv", uv)
    uv = uv.reshape(-1, 2).astype(np.float64)
    return [[(mesh.loops[i].vertex_index, uv[i]) for i in p.loop_indices] for p in mesh.polygons]


def seam_sides(faces):
    """(uv of a, uv of b on one side, uv of a, uv of b on the other, a, b) per seam edge (UVs apart)."""
    side = {}
    for f in faces:
        for i in range(len(f)):
            side[(f[i][0], f[(i + 1) % len(f)][0])] = (f[i][1], f[(i + 1) % len(f)][1])
    seams = []
    for (a, b), (ua, ub) in side.items():
        other = side.get((b, a))
        if a < b and other is not None and max(np.abs(ua - other[1]).max(), np.abs(ub - other[0]).max()) > 1e-6:
            seams.append((ua, ub, other[1], other[0], a, b))
    return seams


def irregular_vertices(faces):
    count, sides = {}, set()
    for f in faces:
        for i in range(len(f)):
            count[f[i][0]] = count.get(f[i][0], 0) + 1
            sides.add((f[i][0], f[(i + 1) % len(f)][0]))
    open_sides = [(a, b) for a, b in sides if (b, a) not in sides]
    return {v for v, n in count.items() if n != 4} | {v for s in open_sides for v in s}


def bilinear(pixels, uv):
    h, w = pixels.shape[:2]
    x, y = uv[0] * w - 0.5, uv[1] * h - 0.5
    x0, y0 = int(np.floor(x)), int(np.floor(y))
    fx, fy = x - x0, y - y0

    def at(xi, yi):
        return pixels[min(max(yi, 0), h - 1), min(max(xi, 0), w - 1), :3]
    return ((1 - fx) * (1 - fy) * at(x0, y0) + fx * (1 - fy) * at(x0 + 1, y0) + (1 - fx) * fy * at(x0, y0 + 1)
            + fx * fy * at(x0 + 1, y0 + 1))


def largest_seam_difference(mesh, layer, image):
    """The largest colour difference (0..1) between the two sides of 1 000 random seam points."""
    faces = loop_data(mesh, layer)
    seams, irregular = seam_sides(faces), irregular_vertices(faces)
    pixels = np.empty(SIZE * SIZE * 4, np.float32)
    image.pixels.foreach_get(pixels)
    pixels = pixels.reshape(SIZE, SIZE, 4)
    rng, largest, samples = random.Random(5), 0.0, 0
    while samples < 1000:
        ua, ub, oa, ob, a, b = seams[rng.randrange(len(seams))]
        s = rng.random()
        length = np.linalg.norm((ub - ua) * SIZE)
        if (a in irregular and s * length < 1) or (b in irregular and (1 - s) * length < 1):
            continue
        one, other = bilinear(pixels, ua + s * (ub - ua)), bilinear(pixels, oa + s * (ob - oa))
        largest = max(largest, float(np.abs(one - other).max()))
        samples += 1
    return largest, len(seams)


def noise_material():
    """Emission of a noise texture in object space, and an Image Texture node (the bake's target, active)."""
    material = bpy.data.materials.new("qgp_noise")
    material.use_nodes = True
    nodes, links = material.node_tree.nodes, material.node_tree.links
    nodes.clear()
    coords, noise = nodes.new("ShaderNodeTexCoord"), nodes.new("ShaderNodeTexNoise")
    noise.inputs["Scale"].default_value = 4.0
    emission, output = nodes.new("ShaderNodeEmission"), nodes.new("ShaderNodeOutputMaterial")
    links.new(coords.outputs["Object"], noise.inputs["Vector"])
    links.new(noise.outputs["Color"], emission.inputs["Color"])
    links.new(emission.outputs["Emission"], output.inputs["Surface"])
    return material


def bake_noise(obj, layer_name):
    """Bakes the noise into a new 8-bit SIZE x SIZE image through the UV map layer_name; returns the image."""
    obj.data.materials.clear()
    material = noise_material()
    obj.data.materials.append(material)
    image = bpy.data.images.new(obj.name + "_baked", SIZE, SIZE)
    node = material.node_tree.nodes.new("ShaderNodeTexImage")
    node.image = image
    material.node_tree.nodes.active = node
    obj.data.uv_layers.active = obj.data.uv_layers[layer_name]
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = 1
    scene.cycles.use_denoising = False  # Debian's Blender is built without OpenImageDenoise: a black bake
    addon_checks.select_only(obj)
    assert bpy.ops.object.bake(type="EMIT", margin=16, use_clear=True) == {"FINISHED"}
    return image


def check_atlas_layer(quad):
    """'QGP Atlas' active, UVs in [0,1], every quad a square of whole texels, no texel covered twice."""
    layer = quad.data.uv_layers.active
    assert layer.name == "QGP Atlas", layer.name
    uv = np.empty(2 * len(quad.data.loops), np.float32)
    layer.data.foreach_get("uv", uv)
    texels = np.round(uv.reshape(-1, 4, 2) * SIZE).astype(int)
    assert uv.min() >= 0 and uv.max() <= 1, (uv.min(), uv.max())
    assert np.abs(uv.reshape(-1, 4, 2) * SIZE - texels).max() < 1e-3, "atlas corners off whole texels"
    covered = np.zeros((SIZE, SIZE), int)
    for square in texels:
        lo, hi = square.min(0), square.max(0)
        covered[lo[1]:hi[1], lo[0]:hi[0]] += 1
    assert covered.max() == 1, "a texel covered twice"
    return covered.sum() / SIZE ** 2


def check_grid_uv_atlas(binding, module):
    """Integer-Grid UVs with Texture Atlas on spot's own triangles: 'QGP Atlas' active beside 'QGP Grid', UVs in
    [0,1], no texel centre in two triangles, every seam a quarter turn plus whole texels (stitching matches them
    all), the source's geometry unchanged."""
    addon_checks.reset_scene()
    source = addon_checks.import_mesh(binding, os.path.join(MESHES, "spot.obj"))
    before = addon_checks.mesh_data_state(source)[:7]  # all but the UV maps, selection and modifiers
    assert bpy.ops.object.qgp_grid_uv(target_faces=1000, texture_atlas=True, atlas_size=SIZE,
                                      flip_free_copy=False) == {"FINISHED"}
    mesh = source.data
    assert mesh.uv_layers.active.name == "QGP Atlas" and "QGP Grid" in mesh.uv_layers, list(mesh.uv_layers.keys())
    faces = loop_data(mesh, mesh.uv_layers["QGP Atlas"])
    covered = np.zeros((SIZE, SIZE), int)
    for f in faces:
        p = np.array([uv for _, uv in f]) * SIZE
        assert p.min() >= 0 and p.max() <= SIZE, p
        lo, hi = np.floor(p.min(0)).astype(int), np.ceil(p.max(0)).astype(int)
        xs, ys = np.meshgrid(np.arange(lo[0], hi[0]) + 0.5, np.arange(lo[1], hi[1]) + 0.5)
        inside = np.ones(xs.shape, bool)
        for k in range(3):
            a, b = p[k], p[(k + 1) % 3]
            inside &= (b[0] - a[0]) * (ys - a[1]) - (b[1] - a[1]) * (xs - a[0]) >= 0
        covered[lo[1]:hi[1], lo[0]:hi[0]] += inside
    assert covered.max() <= 1, "a texel centre in two triangles"
    image = bpy.data.images.new("spot_grid_atlas", SIZE, SIZE)
    info = module.atlas.stitch_image(mesh, mesh.uv_layers["QGP Atlas"], image)
    assert info["unmatched_seam_edges"] == 0 and info["seam_edges"] > 0, info
    assert addon_checks.mesh_data_state(source)[:7] == before, "Integer-Grid UVs changed the geometry"
    print(f"Integer-Grid UVs atlas on spot's {len(faces)} triangles: {100 * (covered > 0).mean():.0f} % of the "
          f"texture covered, no texel twice, {info['seam_edges']} seam edges all texel-aligned")


def main():
    module = addon_checks.install_legacy_addon(REPO, "quantized_retopo")
    binding = sys.modules[module.__name__ + ".core.binding"]
    addon_checks.reset_scene()
    source = addon_checks.import_mesh(binding, os.path.join(MESHES, "spot.obj"))
    quad = addon_checks.run_quad_remesh(source, target_faces=1000, texture_atlas=True, atlas_size=SIZE)
    use = check_atlas_layer(quad)
    assert abs(use - quad["qgp"]["atlas"]["texture_use"]) < 1e-5, (use, quad["qgp"]["atlas"].to_dict())
    smart = quad.copy()
    smart.data = quad.data.copy()
    smart.name = "spot_smart_uv"
    bpy.context.scene.collection.objects.link(smart)
    image = bake_noise(quad, "QGP Atlas")
    margin_only, seams = largest_seam_difference(quad.data, quad.data.uv_layers["QGP Atlas"], image)
    addon_checks.select_only(quad)
    assert bpy.ops.object.qgp_stitch_seams(image_name=image.name) == {"FINISHED"}
    stitched, _ = largest_seam_difference(quad.data, quad.data.uv_layers["QGP Atlas"], image)
    addon_checks.select_only(smart)
    layer = smart.data.uv_layers.new(name="Smart UV")
    smart.data.uv_layers.active = layer
    bpy.ops.object.mode_set(mode="EDIT")
    bpy.ops.mesh.select_all(action="SELECT")
    bpy.ops.uv.smart_project(island_margin=16 / SIZE)
    bpy.ops.object.mode_set(mode="OBJECT")
    smart_image = bake_noise(smart, "Smart UV")
    smart_difference, smart_seams = largest_seam_difference(smart.data, layer, smart_image)
    print(f"spot, {len(quad.data.polygons)} quads, {SIZE} x {SIZE}: atlas {100 * use:.0f} % used, {seams} seam "
          f"edges; largest seam difference over 1000 points: {255 * stitched:.2f}/255 stitched, "
          f"{255 * margin_only:.2f}/255 with Blender's margin only; Smart UV Project ({smart_seams} seam edges): "
          f"{255 * smart_difference:.2f}/255")
    assert margin_only > 1 / 255, "the unstitched seams already agree: the check cannot fail"
    assert stitched <= 1 / 255, f"stitched seams differ by {255 * stitched:.2f}/255"
    check_grid_uv_atlas(binding, module)
    print("atlas bake test: OK")


main()

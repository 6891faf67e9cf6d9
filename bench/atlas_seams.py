"""Seams of a baked texture, rendered: Smart UV Project | the qgp atlas | the qgp atlas after `qgp stitch`.

    blender -b --factory-startup --python bench/atlas_seams.py -- [--qgp build/bin/qgp]
        [--mesh ../shared/meshes/spot.obj] [--faces 1000] [--texture-size 512] [--out docs/images]

`qgp remesh --atlas-out` makes the quads and their atlas; Blender (Cycles, emission bake, 1 sample,
Blender's 16-texel margin) bakes two procedural 3D textures in object space into it (noise, and a checker
of 3D cells); `qgp stitch` fills the gutters from across each seam; the same bake on a copy of the quads
with Smart UV Project's UVs is beside it (512 x 512 texels for 1 000 quads: 14 texels per quad). The
renders show the textures with linear filtering as emission; the checker's edges show where a seam
breaks them.
Writes OUT/atlas_seams.png (rows: noise, checker; columns as above).
"""
import argparse
import os
import subprocess
import sys
import tempfile

import bpy
from mathutils import Vector

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)
PANEL = 360


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    ap = argparse.ArgumentParser(prog="blender -b --python bench/atlas_seams.py --")
    ap.add_argument("--qgp", default=os.path.join(REPO, "build", "bin", "qgp"))
    ap.add_argument("--mesh", default=os.path.join(os.path.dirname(REPO), "shared", "meshes", "spot.obj"))
    ap.add_argument("--faces", type=int, default=1000)
    ap.add_argument("--texture-size", type=int, default=512)
    ap.add_argument("--out", default=os.path.join(REPO, "docs", "images"))
    return ap.parse_args(argv)


def procedural(kind):
    """A material emitting a 3D texture of object coordinates: 'noise' or 'checker'."""
    material = bpy.data.materials.new(kind)
    material.use_nodes = True
    nodes, links = material.node_tree.nodes, material.node_tree.links
    nodes.clear()
    coords = nodes.new("ShaderNodeTexCoord")
    texture = nodes.new("ShaderNodeTexNoise" if kind == "noise" else "ShaderNodeTexChecker")
    texture.inputs["Scale"].default_value = 12.0 if kind == "noise" else 6.0
    emission, output = nodes.new("ShaderNodeEmission"), nodes.new("ShaderNodeOutputMaterial")
    links.new(coords.outputs["Object"], texture.inputs["Vector"])
    links.new(texture.outputs["Color"], emission.inputs["Color"])
    links.new(emission.outputs["Emission"], output.inputs["Surface"])
    return material


def image_material(image):
    """A material emitting `image` through the active UV map, linearly filtered."""
    material = bpy.data.materials.new(image.name)
    material.use_nodes = True
    nodes, links = material.node_tree.nodes, material.node_tree.links
    nodes.clear()
    kinds = ("ShaderNodeTexImage", "ShaderNodeEmission", "ShaderNodeOutputMaterial")
    texture, emission, output = (nodes.new(t) for t in kinds)
    texture.image, texture.interpolation = image, "Linear"
    links.new(texture.outputs["Color"], emission.inputs["Color"])
    links.new(emission.outputs["Emission"], output.inputs["Surface"])
    return material


def bake(obj, kind, size, path):
    """Bakes the procedural texture `kind` into a size x size image through obj's active UV map; saves it."""
    obj.hide_render = False
    obj.data.materials.clear()
    material = procedural(kind)
    obj.data.materials.append(material)
    image = bpy.data.images.new(f"{obj.name}_{kind}", size, size)
    node = material.node_tree.nodes.new("ShaderNodeTexImage")
    node.image = image
    material.node_tree.nodes.active = node
    for other in bpy.context.selected_objects:
        other.select_set(False)
    obj.select_set(True)
    bpy.context.view_layer.objects.active = obj
    bpy.ops.object.bake(type="EMIT", margin=16, use_clear=True)
    image.filepath_raw, image.file_format = path, "PNG"
    image.save()
    return path


def render_panel(obj, image_path, path, camera_at, look_at):
    """obj alone, emitting the image, seen from camera_at; saved to path."""
    for other in bpy.context.scene.objects:
        other.hide_render = other is not obj and other.type == "MESH"
    obj.data.materials.clear()
    obj.data.materials.append(image_material(bpy.data.images.load(image_path, check_existing=False)))
    scene = bpy.context.scene
    camera = scene.camera
    camera.location = camera_at
    camera.rotation_euler = (Vector(look_at) - Vector(camera_at)).to_track_quat("-Z", "Y").to_euler()
    scene.render.filepath = path
    bpy.ops.render.render(write_still=True)


def setup_scene():
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = 16
    scene.cycles.use_denoising = False  # Debian's Blender is built without OpenImageDenoise
    scene.render.resolution_x = scene.render.resolution_y = PANEL
    scene.view_settings.view_transform = "Standard"
    scene.world = bpy.data.worlds.new("white")
    scene.world.color = (1, 1, 1)
    camera = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
    camera.data.lens = 50
    scene.collection.objects.link(camera)
    scene.camera = camera


def import_obj(path, name):
    bpy.ops.wm.obj_import(filepath=path)
    obj = bpy.context.selected_objects[0]
    obj.name = name
    return obj


def smart_uv_copy(obj, size):
    copy = obj.copy()
    copy.data = obj.data.copy()
    copy.name = "smart_uv"
    bpy.context.scene.collection.objects.link(copy)
    for other in bpy.context.selected_objects:
        other.select_set(False)
    copy.select_set(True)
    bpy.context.view_layer.objects.active = copy
    bpy.ops.object.mode_set(mode="EDIT")
    bpy.ops.mesh.select_all(action="SELECT")
    bpy.ops.uv.smart_project(island_margin=2.0 / size)
    bpy.ops.object.mode_set(mode="OBJECT")
    return copy


def main():
    args = parse_args()
    tmp = tempfile.mkdtemp()
    atlas = os.path.join(tmp, "atlas.obj")
    subprocess.run([args.qgp, "remesh", args.mesh, "-o", os.path.join(tmp, "q.obj"), "--faces", str(args.faces),
                    "--atlas-out", atlas, "--texture-size", str(args.texture_size)], check=True)
    setup_scene()
    quads = import_obj(atlas, "qgp_atlas")
    smart = smart_uv_copy(quads, args.texture_size)
    centre = sum((Vector(v.co) for v in quads.data.vertices), Vector()) / len(quads.data.vertices)
    size = max(quads.dimensions)
    camera_at, look_at = centre + Vector((0.9, 0.3, -0.9)) * size, centre + Vector((0.1, 0.05, -0.15)) * size
    panels = []
    for kind in ("noise", "checker"):
        baked = bake(quads, kind, args.texture_size, os.path.join(tmp, f"qgp_{kind}.png"))
        stitched = os.path.join(tmp, f"qgp_{kind}_stitched.png")
        subprocess.run([args.qgp, "stitch", atlas, baked, "-o", stitched], check=True)
        smart_baked = bake(smart, kind, args.texture_size, os.path.join(tmp, f"smart_{kind}.png"))
        for obj, image, label in ((smart, smart_baked, "Smart UV Project"), (quads, baked, "qgp atlas"),
                                  (quads, stitched, "qgp atlas, stitched")):
            panel = os.path.join(tmp, f"panel_{len(panels)}.png")
            render_panel(obj, image, panel, camera_at, look_at)
            panels.append((panel, f"{kind}: {label}"))
    compose = os.path.join(HERE, "compose_panels.py")
    os.makedirs(args.out, exist_ok=True)
    subprocess.run(["/usr/bin/python3", compose, os.path.join(args.out, "atlas_seams.png"), "3"]
                   + [x for p in panels for x in p], check=True)


main()

"""Side-by-side renders: input | Quantized Retopo | QuadriFlow, Workbench, wireframe visible.

    blender -b --factory-startup --python bench/render.py -- [--cases spot.obj:2000,fandisk.obj:8000]
        [--results bench/results] [--out docs/images] [--mesh-dir DIR] [--width 1200]

Reads the result meshes written by `compare_quadriflow.py --save-meshes` (RESULTS/meshes/) and the
captions from RESULTS/compare.csv. A tool without a result (refused, unchanged, timeout) gets a panel
naming its status and message instead of a mesh. Writes OUT/compare_<mesh>_<target>.png (8-bit
PNG, compressed; about 100-200 KB at the default size).
"""
import argparse
import csv
import os
import sys

import bpy
import numpy as np
from mathutils import Matrix, Vector

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)
sys.path.insert(0, HERE)
from compare_quadriflow import load_addon, read_input, new_object  # noqa: E402  (same reader and glue)

# View direction (from the object towards the camera) and up axis per mesh; default: Z up, 3/4 front view.
VIEWS = {
    "spot.obj": ((0.7, 0.4, -1.0), (0, 1, 0)),
    "bunny.off": ((0.3, 0.2, 1.0), (0, 1, 0)),
    "armadillo.obj": ((0.2, 0.2, -1.0), (0, 1, 0)),
    "fertility.off": ((0.0, -1.0, 0.3), (0, 0, 1)),
    "fandisk.obj": ((1.0, -0.8, 0.9), (0, 0, 1)),
    "torus.obj": ((0.3, -1.0, 0.9), (0, 0, 1)),
}
DEFAULT_VIEW = ((0.6, -1.0, 0.5), (0, 0, 1))
TOOLS = [("qgp", "Quantized Retopo"), ("quadriflow", "QuadriFlow")]


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    ap = argparse.ArgumentParser(prog="blender -b --python bench/render.py --")
    ap.add_argument("--cases", default="spot.obj:2000,fertility.off:2000,fandisk.obj:8000")
    ap.add_argument("--results", default=os.path.join(REPO, "bench", "results"))
    ap.add_argument("--out", default=os.path.join(REPO, "docs", "images"))
    ap.add_argument("--mesh-dir",
                    default=os.environ.get("QGP_MESHES", os.path.join(os.path.dirname(REPO), "shared", "meshes")))
    ap.add_argument("--width", type=int, default=1000)
    return ap.parse_args(argv)


def load_rows(results):
    path = os.path.join(results, "compare.csv")
    if not os.path.exists(path):
        return {}
    with open(path) as f:
        return {(r["mesh"], int(r["target"]), r["tool"]): r for r in csv.DictReader(f)}


def read_obj_polygons(path):
    vertices, polygons = [], []
    with open(path) as f:
        for line in f:
            if line.startswith("v "):
                vertices.append(tuple(map(float, line.split()[1:4])))
            elif line.startswith("f "):
                polygons.append([int(p.split("/")[0]) - 1 for p in line.split()[1:]])
    return np.asarray(vertices, np.float64).reshape(-1, 3), polygons


def material(name, rgba):
    mat = bpy.data.materials.get(name) or bpy.data.materials.new(name)
    mat.diffuse_color = rgba
    return mat


def add_panel(obj, wire):
    """Light surface plus (when `wire`) a dark wireframe copy of its edges."""
    obj.data.materials.append(material("surface", (0.80, 0.80, 0.78, 1.0)))
    for p in obj.data.polygons:
        p.use_smooth = False
    if not wire:
        return
    copy = obj.copy()
    copy.data = obj.data.copy()
    copy.data.materials.clear()
    copy.data.materials.append(material("wire", (0.05, 0.05, 0.08, 1.0)))
    bpy.context.scene.collection.objects.link(copy)
    edges = np.empty(2 * len(obj.data.edges), np.int32)
    obj.data.edges.foreach_get("vertices", edges)
    co = np.empty(3 * len(obj.data.vertices))
    obj.data.vertices.foreach_get("co", co)
    co = co.reshape(-1, 3)
    edges = edges.reshape(-1, 2)
    mean_edge = float(np.linalg.norm(co[edges[:, 0]] - co[edges[:, 1]], axis=1).mean()) if len(edges) else 0.0
    modifier = copy.modifiers.new("wire", "WIREFRAME")
    diagonal = float(np.linalg.norm(co.max(0) - co.min(0))) if len(co) else 0.0
    modifier.thickness = min(0.07 * mean_edge, 0.0015 * diagonal)
    modifier.use_replace = True
    modifier.use_even_offset = False


def add_text(body, location, rotation, size):
    curve = bpy.data.curves.new("label", "FONT")
    curve.body = body
    curve.size = size
    curve.align_x = "CENTER"
    obj = bpy.data.objects.new("label", curve)
    obj.location = location
    obj.rotation_euler = rotation
    obj.data.materials.append(material("text", (0.0, 0.0, 0.0, 1.0)))
    bpy.context.scene.collection.objects.link(obj)
    return obj


def caption(row, label):
    if row is None:
        return f"{label}: not run"
    if row["status"] != "ok":
        words, lines = row["message"].split(), [""]
        for word in words:  # wrap at ~56 characters, at most 3 lines
            if len(lines[-1]) + len(word) > 56:
                lines.append("")
            lines[-1] += (" " if lines[-1] else "") + word
        if len(lines) > 3:
            lines = lines[:3]
            lines[2] += " ..."
        return f"{label}: {row['status']}\n" + "\n".join(lines)
    hd = float(row["hausdorff"]) * 100 if row["hausdorff"] else float("nan")
    return (f"{label}: {int(float(row['quads'])):,} quads, {row['irregular_vertices']} irregular\n"
            f"{float(row['seconds']):.1f} s, Hausdorff {hd:.2f}% diag")


def clear_scene():
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj, do_unlink=True)
    for collection in (bpy.data.meshes, bpy.data.curves, bpy.data.cameras):
        for block in list(collection):
            collection.remove(block)


def render_case(binding, args, name, target, rows):
    clear_scene()
    stem = os.path.splitext(name)[0]
    vertices, polygons, triangles = read_input(binding, os.path.join(args.mesh_dir, name))
    center = 0.5 * (vertices.min(0) + vertices.max(0))
    direction, up = VIEWS.get(name, DEFAULT_VIEW)
    back = Vector(direction).normalized()
    right = Vector(up).cross(back).normalized()
    true_up = back.cross(right)
    to_camera_frame = Matrix((right, true_up, back))  # rows: world -> camera axes
    local = (vertices - center) @ np.asarray(to_camera_frame).T
    middle = 0.5 * (local.min(0) + local.max(0))  # centre of the projected outline, camera frame
    width = float(np.ptp(local[:, 0]))
    height = float(np.ptp(local[:, 1]))
    spacing = 1.12 * max(width, 0.6 * height)
    panels = [("input", f"Input: {len(triangles):,} triangles", None)]
    for tool, label in TOOLS:
        panels.append((tool, caption(rows.get((name, target, tool)), label), rows.get((name, target, tool))))
    camera_rotation = to_camera_frame.transposed().to_euler()
    for i, (tool, text, row) in enumerate(panels):
        offset = Vector(((i - 1) * spacing - middle[0], -middle[1], 0))  # camera-frame offset of this panel
        world_offset = to_camera_frame.transposed() @ offset
        if tool == "input":
            obj = new_object(stem + "_input", vertices - center, polygons)
            add_panel(obj, wire=len(polygons) <= 12000)
        else:
            path = os.path.join(args.results, "meshes", f"{stem}_{target}_{tool}.obj")
            if row is not None and row["status"] == "ok" and os.path.exists(path):
                v, p = read_obj_polygons(path)
                obj = new_object(f"{stem}_{tool}", v - center, p)
                add_panel(obj, wire=True)
            else:
                obj = None
        for o in [o for o in bpy.context.scene.objects if o.type == "MESH" and o.get("placed") is None]:
            o.location = world_offset
            o["placed"] = True
        label_pos = to_camera_frame.transposed() @ Vector(((i - 1) * spacing, -0.5 * height - 0.08 * spacing, 0))
        add_text(text, label_pos, camera_rotation, 0.045 * spacing)
    camera = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
    camera.data.type = "ORTHO"
    camera.data.ortho_scale = 3.05 * spacing
    camera.data.clip_end = 100 * spacing
    camera.rotation_euler = camera_rotation
    camera.location = to_camera_frame.transposed() @ Vector((0, -0.075 * spacing, 10 * spacing))
    bpy.context.scene.collection.objects.link(camera)
    scene = bpy.context.scene
    scene.camera = camera
    scene.render.engine = "BLENDER_WORKBENCH"
    scene.display.shading.light = "STUDIO"
    scene.display.shading.color_type = "MATERIAL"
    scene.display.shading.show_cavity = False
    scene.display.shading.show_specular_highlight = False
    scene.display.render_aa = "8"
    scene.render.resolution_x = args.width
    scene.render.resolution_y = int(args.width * (height + 0.25 * spacing) / (3.05 * spacing))
    scene.render.resolution_percentage = 100
    scene.render.image_settings.file_format = "PNG"
    scene.render.image_settings.color_mode = "BW"  # grey levels only: small PNGs
    scene.render.image_settings.color_depth = "8"
    scene.render.image_settings.compression = 100
    scene.view_settings.view_transform = "Standard"
    scene.world = scene.world or bpy.data.worlds.new("world")
    scene.world.color = (1.0, 1.0, 1.0)
    scene.render.film_transparent = False
    path = os.path.join(args.out, f"compare_{stem}_{target}.png")
    scene.render.filepath = path
    bpy.ops.render.render(write_still=True)
    print(f"render: {path} {os.path.getsize(path) // 1024} KB", flush=True)


def main():
    args = parse_args()
    os.makedirs(args.out, exist_ok=True)
    addon = load_addon()
    binding = sys.modules[addon.__name__ + ".core.binding"]
    rows = load_rows(args.results)
    for case in [c for c in args.cases.split(",") if c]:
        name, target = case.rsplit(":", 1)
        render_case(binding, args, name, int(target), rows)


if __name__ == "__main__":
    main()

"""Batch remeshing in Blender:

    blender -b --factory-startup --python addon/batch.py -- IN [IN ...] --out DIR
            [--faces N | --edge-length L] [--sharp-angle DEG] [--uv] [--quads-per-unit Q]

Imports each mesh (OBJ, PLY, OFF; read by the native reader, polygons kept), runs Quantized Retopo
(and Integer-Grid UVs with --uv), writes DIR/<name>.obj (and DIR/<name>_uv.obj) and
DIR/report.json with one entry per input (status, reason, quads, seconds). Continues past
failures; exits with status 1 if any input failed.
"""
import argparse
import importlib.util
import json
import math
import os
import sys
import time

import bpy


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    ap = argparse.ArgumentParser(prog="blender -b --python addon/batch.py --")
    ap.add_argument("inputs", nargs="+")
    ap.add_argument("--out", required=True)
    group = ap.add_mutually_exclusive_group()
    group.add_argument("--faces", type=int, default=2000)
    group.add_argument("--edge-length", type=float)
    ap.add_argument("--sharp-angle", type=float, help="also keep edges sharper than DEG degrees")
    ap.add_argument("--uv", action="store_true", help="also write integer-grid UVs (<name>_uv.obj)")
    ap.add_argument("--quads-per-unit", type=float, default=1.0)
    return ap.parse_args(argv)


def load_addon():
    """The registered add-on if it is enabled, else this folder's add-on, registered now."""
    if hasattr(bpy.types, "OBJECT_OT_qgp_quad_remesh"):
        return sys.modules[bpy.types.OBJECT_OT_qgp_quad_remesh.__module__.rsplit(".", 1)[0]]
    here = os.path.dirname(os.path.abspath(__file__))
    spec = importlib.util.spec_from_file_location("quantized_retopo", os.path.join(here, "__init__.py"),
                                                  submodule_search_locations=[here])
    module = importlib.util.module_from_spec(spec)
    sys.modules["quantized_retopo"] = module
    spec.loader.exec_module(module)
    module.register()
    return module


def new_object(name, vertices, faces):
    """A mesh object linked to the scene from vertices ((n,3) array or list) and faces (index lists)."""
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata(vertices.tolist() if hasattr(vertices, "tolist") else vertices, [], faces)
    mesh.update(calc_edges=True)
    obj = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(obj)
    return obj


def import_mesh(binding, path):
    vertices, sizes, corners = binding.read_mesh_file(path)
    starts = [0]
    for n in sizes.tolist():
        starts.append(starts[-1] + n)
    flat = corners.tolist()
    faces = [flat[starts[i]:starts[i + 1]] for i in range(len(sizes))]
    return new_object(os.path.splitext(os.path.basename(path))[0], vertices, faces)


def activate(obj):
    for other in bpy.context.selected_objects:
        other.select_set(False)
    obj.hide_set(False)
    obj.select_set(True)
    bpy.context.view_layer.objects.active = obj


def write_obj(path, obj, with_uv=False):
    mesh = obj.data
    with open(path, "w") as f:
        f.write(f"# {obj.name} - Quantized Retopo\n")
        for v in mesh.vertices:
            f.write("v %.9g %.9g %.9g\n" % tuple(v.co))
        if with_uv:
            uv = mesh.uv_layers["QGP Grid"].data
            for loop in uv:
                f.write("vt %.9g %.9g\n" % tuple(loop.uv))
        for p in mesh.polygons:
            if with_uv:
                f.write("f " + " ".join(f"{v + 1}/{l + 1}" for v, l in zip(p.vertices, p.loop_indices)) + "\n")
            else:
                f.write("f " + " ".join(str(v + 1) for v in p.vertices) + "\n")


def target_kwargs(args):
    kwargs = {"target_mode": "EDGE", "edge_length": args.edge_length} if args.edge_length else \
        {"target_mode": "FACES", "target_faces": args.faces}
    if args.sharp_angle is not None:
        kwargs.update(use_sharp_angle=True, sharp_angle=math.radians(args.sharp_angle))
    return kwargs


def process(binding, path, args):
    entry = {"input": path, "status": "ok", "reason": "", "quads": 0, "flipped_quads": 0, "seconds": 0.0}
    start = time.perf_counter()
    try:
        source = import_mesh(binding, path)
        name = source.name
        activate(source)
        bpy.ops.object.qgp_quad_remesh(**target_kwargs(args), keep_source_visible=True)
        result = bpy.context.active_object
        if result is source or not result.name.startswith(name + "_quads"):
            raise RuntimeError("the operator did not create a quad object")
        entry["quads"] = len(result.data.polygons)
        # The operator selects the quads that face against the source surface.
        entry["flipped_quads"] = sum(p.select for p in result.data.polygons)
        write_obj(os.path.join(args.out, name + ".obj"), result)
        if args.uv:
            activate(source)
            bpy.ops.object.qgp_grid_uv(**target_kwargs(args), quads_per_unit=args.quads_per_unit)
            # Where only a refined copy has a flip-free map, the operator made it the active object.
            mapped = bpy.context.active_object
            refined = mapped is not source and mapped.name.startswith(name + "_grid_uv")
            write_obj(os.path.join(args.out, name + "_uv.obj"), mapped if refined else source, with_uv=True)
            entry["uv"] = True
            entry["uv_refined"] = refined
    except (RuntimeError, binding.QGPError) as e:
        entry["status"] = "error"
        entry["reason"] = str(e).replace("Error: ", "").strip()
    entry["seconds"] = round(time.perf_counter() - start, 3)
    return entry


def main():
    args = parse_args()
    os.makedirs(args.out, exist_ok=True)
    addon = load_addon()
    binding = importlib.import_module(addon.__name__ + ".core.binding")
    entries = []
    for path in args.inputs:
        entry = process(binding, path, args)
        print(f"batch: {os.path.basename(path)}: {entry['status']} {entry['reason']} "
              f"{entry['quads']} quads ({entry['flipped_quads']} flipped) {entry['seconds']} s", flush=True)
        entries.append(entry)
    with open(os.path.join(args.out, "report.json"), "w") as f:
        json.dump({"entries": entries, "failed": sum(e["status"] != "ok" for e in entries)}, f, indent=2)
    if any(e["status"] != "ok" for e in entries):
        sys.exit(1)


if __name__ == "__main__":
    main()

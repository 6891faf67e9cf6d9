"""Batch remeshing in Blender:

    blender -b --factory-startup --python addon/batch.py -- IN [IN ...] --out DIR
            [--faces N | --edge-length L] [--sharp-angle DEG] [--uv] [--quads-per-unit Q] [--atlas SIZE]

or, with Blender as a Python module (PyPI's bpy, 4.2 and later), `python addon/batch.py -- IN ...`.

Imports each mesh (OBJ, PLY, OFF; read by the native reader, polygons kept), runs Quantized Retopo
(and Integer-Grid UVs with --uv), writes DIR/<name>.obj (with --atlas, its quads carry a texture
atlas for a SIZE x SIZE texture as vt: Texture Atlas of Quantized Retopo) (and DIR/<name>_uv.obj) and
DIR/report.json with one entry per input (status "ok", "partial" (parts of a many-part mesh kept as
their triangles in the output) or "error"; reason, quads, seconds). Any failure of an
input (a refused mesh, an unwritable output, a bug) is recorded with its reason and the batch goes
on with the next input; the report is written whatever failed, and the exit status is 1 if
anything failed (2 if not even the report could be written), else 3 if an input is partial, else 0.
"""
import argparse
import importlib.util
import json
import math
import os
import sys
import time
import traceback

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
    ap.add_argument("--atlas", type=int, metavar="SIZE", help="give the quads a texture atlas for SIZE x SIZE texels")
    return ap.parse_args(argv)


def load_addon():
    """(package, registered here): the registered add-on if it is enabled, else this folder's add-on,
    registered now (the caller unregisters it: see main)."""
    if hasattr(bpy.types, "OBJECT_OT_qgp_quad_remesh"):
        return sys.modules[bpy.types.OBJECT_OT_qgp_quad_remesh.__module__.rsplit(".", 1)[0]], False
    here = os.path.dirname(os.path.abspath(__file__))
    spec = importlib.util.spec_from_file_location("quantized_retopo", os.path.join(here, "__init__.py"),
                                                  submodule_search_locations=[here])
    module = importlib.util.module_from_spec(spec)
    sys.modules["quantized_retopo"] = module
    spec.loader.exec_module(module)
    module.register()
    return module, True


def import_mesh(blender_mesh, path):
    """The mesh file as a new object linked to the scene."""
    mesh = blender_mesh.read_mesh(path)
    obj = bpy.data.objects.new(mesh.name, mesh)
    bpy.context.scene.collection.objects.link(obj)
    return obj


def activate(obj):
    for other in bpy.context.selected_objects:
        other.select_set(False)
    obj.hide_set(False)
    obj.select_set(True)
    bpy.context.view_layer.objects.active = obj


def write_obj(path, obj, uv_layer=None):
    """The object's mesh as OBJ; with uv_layer (a UV map's name), a vt per face corner from it."""
    mesh = obj.data
    with open(path, "w") as f:
        f.write(f"# {obj.name} - Quantized Retopo\n")
        for v in mesh.vertices:
            f.write("v %.9g %.9g %.9g\n" % tuple(v.co))
        if uv_layer:
            for loop in mesh.uv_layers[uv_layer].data:
                f.write("vt %.9g %.9g\n" % tuple(loop.uv))
        for p in mesh.polygons:
            if uv_layer:
                f.write("f " + " ".join(f"{v + 1}/{l + 1}" for v, l in zip(p.vertices, p.loop_indices)) + "\n")
            else:
                f.write("f " + " ".join(str(v + 1) for v in p.vertices) + "\n")


def target_kwargs(args):
    kwargs = {"target_mode": "EDGE", "edge_length": args.edge_length} if args.edge_length else \
        {"target_mode": "FACES", "target_faces": args.faces}
    if args.sharp_angle is not None:
        kwargs.update(use_sharp_angle=True, sharp_angle=math.radians(args.sharp_angle))
    return kwargs


def process(binding, blender_mesh, path, args):
    entry = {"input": path, "status": "ok", "reason": "", "quads": 0, "flipped_quads": 0, "collapsed_edge_quads": 0,
             "seconds": 0.0}
    start = time.perf_counter()
    try:
        source = import_mesh(blender_mesh, path)
        name = source.name
        activate(source)
        atlas = {"texture_atlas": True, "atlas_size": args.atlas} if args.atlas else {}
        bpy.ops.object.qgp_quad_remesh(**target_kwargs(args), keep_source_visible=True, **atlas)
        result = bpy.context.active_object
        if result is source or not result.name.startswith(name + "_quads"):
            raise RuntimeError("the operator did not create a quad object")
        figures = result.get("qgp", {})
        entry["quads"] = len(result.data.polygons) - int(figures.get("kept_triangles", 0))
        if figures.get("kept_parts", 0):  # complete except parts kept as triangles (selected)
            entry["status"] = "partial"
            entry["reason"] = f"{figures['kept_parts']} part(s) kept as {figures['kept_triangles']} triangles"
        else:  # the operator selects the quads that face against the source surface (and those with a
            # collapsed edge); the figures count each
            entry["flipped_quads"] = int(figures.get("flipped_quads", 0))
            entry["collapsed_edge_quads"] = int(figures.get("collapsed_edge_quads", 0))
            if figures.get("rescued_parts", 0):
                entry["reason"] = (f"{figures['rescued_parts']} part(s) quadded again: with another field, "
                                   "on a remesh, finer or by splitting their triangles")
        if args.atlas:
            if "atlas" not in figures:
                raise RuntimeError("no texture atlas: " + str(figures.get("atlas_note", "")))
            entry["atlas"] = figures["atlas"].to_dict()
        write_obj(os.path.join(args.out, name + ".obj"), result, "QGP Atlas" if args.atlas else None)
        if args.uv:
            activate(source)
            bpy.ops.object.qgp_grid_uv(**target_kwargs(args), quads_per_unit=args.quads_per_unit)
            # Where only a refined copy has a flip-free map, the operator made it the active object.
            mapped = bpy.context.active_object
            refined = mapped is not source and mapped.name.startswith(name + "_grid_uv")
            write_obj(os.path.join(args.out, name + "_uv.obj"), mapped if refined else source, "QGP Grid")
            entry["uv"] = True
            entry["uv_refined"] = refined
    except Exception as e:  # whatever failed, this input is recorded and the batch goes on
        entry["status"] = "error"
        entry["reason"] = failure_reason(binding, e)
    entry["seconds"] = round(time.perf_counter() - start, 3)
    return entry


def failure_reason(binding, error):
    """The message of an operator's or the library's error as the user saw it; any other exception
    (a file that cannot be written, a bug) with its type, and its traceback on stderr."""
    if isinstance(error, binding.QGPError) or type(error) is RuntimeError:  # bpy.ops: "Error: <message>"
        return str(error).replace("Error: ", "").strip()
    traceback.print_exception(type(error), error, error.__traceback__)
    return f"{type(error).__name__}: {error}"


def main():
    """Runs the batch; returns the exit status."""
    args = parse_args()
    entries = []
    try:
        os.makedirs(args.out, exist_ok=True)
        addon, registered = load_addon()
        binding = importlib.import_module(addon.__name__ + ".core.binding")
        blender_mesh = importlib.import_module(addon.__name__ + ".blender_mesh")
    except Exception as e:  # no input can run: each is recorded with the reason
        traceback.print_exc()
        reason = f"the batch could not start: {type(e).__name__}: {e}"
        entries = [{"input": path, "status": "error", "reason": reason, "quads": 0, "flipped_quads": 0,
                    "collapsed_edge_quads": 0, "seconds": 0.0} for path in args.inputs]
    else:
        try:
            for path in args.inputs:
                entry = process(binding, blender_mesh, path, args)
                print(f"batch: {os.path.basename(path)}: {entry['status']} {entry['reason']} "
                      f"{entry['quads']} quads ({entry['flipped_quads']} flipped) {entry['seconds']} s", flush=True)
                entries.append(entry)
        finally:
            # What this script registered, it unregisters (which also ends the worker processes):
            # Blender 4.5 as a Python module (PyPI's bpy) hangs at exit while an operator is registered.
            if registered:
                addon.unregister()
    failed = sum(e["status"] == "error" for e in entries)
    partial = sum(e["status"] == "partial" for e in entries)
    try:
        with open(os.path.join(args.out, "report.json"), "w") as f:
            json.dump({"entries": entries, "failed": failed, "partial": partial}, f, indent=2)
    except OSError as e:
        print(f"batch: cannot write the report: {e}", file=sys.stderr, flush=True)
        return 2
    return 1 if failed else 3 if partial else 0


if __name__ == "__main__":
    # Blender exits 0 after a --python script that raised: every outcome leaves through sys.exit.
    try:
        status = main()
    except SystemExit:
        raise
    except BaseException:
        traceback.print_exc()
        status = 1
    sys.exit(status)

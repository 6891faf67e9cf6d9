"""Side-by-side benchmark: Quantized Retopo against Blender's built-in QuadriFlow, in one Blender process.

    blender -b --factory-startup --python bench/compare_quadriflow.py -- \
        [--meshes NAME[,NAME...]] [--targets 2000,8000] [--out bench/results] [--mesh-dir DIR]
        [--sharp-angle 60] [--timeout 900] [--tools qgp,quadriflow] [--save-meshes]
        [--sculpts spot.obj:3,spot.obj:4]

For every mesh and target quad count both tools run on a fresh copy of the input (the order of the two
alternates from case to case), then the SAME native measurement (binding.measure_polygon_mesh, see
docs/report.md) is applied to both results against the input triangles. Writes
OUT/compare.csv (one row per mesh x target x tool), OUT/compare.json and, with --save-meshes,
OUT/meshes/<mesh>_<target>_<tool>.obj for bench/render.py. Plots and the markdown table are made
from the CSV by bench/plots.py (system Python with matplotlib).

--sculpts BASE:LEVELS,...: dense sculpt-like inputs made here, as a user makes them in Blender: BASE with
a Catmull-Clark Subdivision Surface modifier at LEVELS, then a Displace modifier with a Clouds noise
texture (size 0.05, strength 0.2 % of the bounding-box diagonal along the normals), applied and
triangulated (spot.obj:3 about 0.56 M triangles, spot.obj:4 about 2.2 M). They are named
sculpt-BASE-LLEVELS in the table, category "sculpt", and run after the meshes. Each qgp row records
the native pipeline's peak memory (its report's peak_memory_mb).

Status per run: ok (a mesh came back), refused (the tool reported an error; message kept),
unchanged (the tool returned without error but left the mesh as it was: QuadriFlow does this when
its solver fails), timeout (Quantized Retopo did not finish within --timeout s and was cancelled),
crashed (Quantized Retopo's worker process died, or Blender died during the run: recorded by the next
--resume run, which scripts/bench.sh starts).
"""
import argparse
import csv
import importlib.util
import json
import os
import sys
import time

import bpy
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)

# The manifold meshes of ../shared/meshes (README table) with their category.
MANIFOLD_MESHES = {
    "spot.obj": "organic", "bunny.off": "organic", "armadillo.obj": "organic", "nefertiti.obj": "organic",
    "igea.ply": "organic", "dragon-genus1.obj": "genus>0", "torus.obj": "genus>0", "rocker-arm.obj": "genus>0",
    "kitten.obj": "genus>0", "fertility.off": "genus>0", "mnf07HeadFem_rem_rem_p.obj": "CAD",
    "fandisk.obj": "CAD", "block.obj": "CAD", "joint.obj": "CAD", "joint_rem_p.obj": "CAD", "wingnut.obj": "CAD",
    "stanford-bunny.obj": "boundary", "face.obj": "boundary", "camelhead.off": "boundary",
    "decimated-max.obj": "organic", "beetle.off": "boundary",
}

COLUMNS = ["mesh", "category", "input_triangles", "target", "tool", "status", "message", "seconds", "quads",
           "faces", "non_quads", "irregular_vertices", "flipped_quads", "euler_characteristic_preserved",
           "quads_per_target", "fewest_quads", "hausdorff", "hausdorff_result_to_input", "hausdorff_input_to_result",
           "mean_angle_deviation_deg",
           "p95_angle_deviation_deg", "min_scaled_jacobian", "sharp_edges", "sharp_edge_coverage",
           "non_manifold_edges", "stage_seconds", "peak_memory_mb"]


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    ap = argparse.ArgumentParser(prog="blender -b --python bench/compare_quadriflow.py --")
    ap.add_argument("--meshes", default="",
                    help="comma-separated file names in --mesh-dir (default: all manifold; none: only --sculpts)")
    ap.add_argument("--targets", default="2000,8000", help="comma-separated target quad counts")
    ap.add_argument("--mesh-dir",
                    default=os.environ.get("QGP_MESHES", os.path.join(os.path.dirname(REPO), "shared", "meshes")))
    ap.add_argument("--out", default=os.path.join(REPO, "bench", "results"))
    ap.add_argument("--sharp-angle", type=float, default=60.0,
                    help="dihedral angle (deg) of the sharp edges kept by Quantized Retopo on CAD meshes "
                         "and measured for sharp-edge coverage")
    ap.add_argument("--timeout", type=float, default=900.0, help="seconds before a Quantized Retopo run is cancelled")
    ap.add_argument("--tools", default="qgp,quadriflow")
    ap.add_argument("--quantizer", default="", help="Quantized Retopo quantizer (greedy / round); default: the "
                                                    "library's default")
    ap.add_argument("--sculpts", default="", help="comma-separated BASE:LEVELS sculpts to generate and run "
                                                  "(e.g. spot.obj:3,spot.obj:4)")
    ap.add_argument("--save-meshes", action="store_true", help="write every result as OBJ under OUT/meshes/")
    ap.add_argument("--resume", action="store_true",
                    help="keep the rows of OUT/compare.csv and run only the missing cases; a case that was "
                         "running when Blender crashed is recorded as 'crashed'")
    return ap.parse_args(argv)


def _load_batch():
    spec = importlib.util.spec_from_file_location("qgp_batch", os.path.join(REPO, "addon", "batch.py"))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


# addon/batch.py: the add-on loader and the Blender object helpers shared with the batch command.
batch = _load_batch()
activate, write_obj = batch.activate, batch.write_obj


def new_object(name, vertices, polygons):
    """A new object linked to the scene from vertex positions and polygons (vertex index lists)."""
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata(vertices, [], polygons)
    mesh.update(calc_edges=True)
    obj = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(obj)
    return obj


def load_addon():
    """This repository's add-on, registered by addon/batch.py's loader (the package)."""
    return batch.load_addon()[0]


def read_input(binding, path):
    """(vertices (n,3), polygons as lists, triangles (t,3) by fan triangulation) of a mesh file."""
    vertices, sizes, corners = binding.read_mesh_file(path)
    flat = corners.tolist()
    polygons, triangles, start = [], [], 0
    for n in sizes.tolist():
        poly = flat[start:start + n]
        start += n
        polygons.append(poly)
        triangles.extend([poly[0], poly[i], poly[i + 1]] for i in range(1, n - 1))
    return vertices, polygons, np.asarray(triangles, np.int32).reshape(-1, 3)


def sculpt_input(binding, mesh_dir, base, levels):
    """(vertices, polygons, triangles) of BASE subdivided LEVELS times and displaced by a small noise."""
    vertices, polygons, _ = read_input(binding, os.path.join(mesh_dir, base))
    obj = new_object("sculpt_source", vertices, polygons)
    diagonal = float(np.linalg.norm(np.ptp(np.asarray(vertices), axis=0)))
    subdivision = obj.modifiers.new("subdivision", "SUBSURF")
    subdivision.levels = subdivision.render_levels = levels
    noise = bpy.data.textures.new("sculpt_noise", "CLOUDS")
    noise.noise_scale = 0.05 * diagonal
    displace = obj.modifiers.new("displace", "DISPLACE")
    displace.texture = noise
    displace.strength = 0.002 * diagonal
    displace.mid_level = 0.5
    obj.modifiers.new("triangulate", "TRIANGULATE")
    evaluated = obj.evaluated_get(bpy.context.evaluated_depsgraph_get())
    mesh = bpy.data.meshes.new_from_object(evaluated)
    v, sizes, corners = mesh_polygons(mesh)
    triangles = corners.reshape(-1, 3)
    assert (sizes == 3).all()
    bpy.data.meshes.remove(mesh)
    bpy.data.textures.remove(noise)
    remove_object(obj)
    return v, triangles.tolist(), triangles


def sculpt_name(base, levels):
    return f"sculpt-{os.path.splitext(base)[0]}-L{levels}"


def remove_object(obj):
    mesh = obj.data
    bpy.data.objects.remove(obj, do_unlink=True)
    if mesh is not None and mesh.users == 0:
        bpy.data.meshes.remove(mesh)


def mesh_polygons(mesh):
    """(vertices (n,3), face sizes (f,), corners (c,)) of a Blender mesh."""
    v = np.empty(3 * len(mesh.vertices), np.float64)
    mesh.vertices.foreach_get("co", v)
    sizes = np.empty(len(mesh.polygons), np.int32)
    mesh.polygons.foreach_get("loop_total", sizes)
    corners = np.empty(len(mesh.loops), np.int32)
    mesh.loops.foreach_get("vertex_index", corners)
    return v.reshape(-1, 3), sizes, corners


def run_qgp(addon, binding, source, target, sharp_angle, timeout, quantizer=""):
    """Quantized Retopo the way the operator runs it (same mesh glue, a worker process), with a cancel
    after `timeout` s. Returns (status, message, result object or None, the native report or {});
    status "crashed" when the worker process died (Blender goes on)."""
    blender_mesh = sys.modules[addon.__name__ + ".blender_mesh"]
    worker = sys.modules[addon.__name__ + ".core.worker"]
    session = None
    try:
        src = blender_mesh.SourceMesh(bpy.context, source, evaluated=True, use_marked_sharp=True)
        session = worker.WorkerSession(src.vertices, src.triangles)
        session.set_option("sharp_angle", sharp_angle)
        session.set_option("target_faces", target)
        if quantizer:
            session.set_option_string("quantizer", quantizer)
        session.start(binding.JOB_REMESH)
        state = session.wait(timeout)
        if state == binding.STATE_RUNNING:
            session.cancel()
            try:
                state = session.wait(30.0)
            except binding.QGPError:
                state = binding.STATE_CANCELLED
            if state == binding.STATE_RUNNING:  # the cancel was not honoured: close() ends the process
                return "timeout", f"cancelled after {timeout:.0f} s; the cancel was not honoured within 30 s", \
                    None, {}
            return "timeout", f"cancelled after {timeout:.0f} s", None, native_report(session)
        vertices, quads, quad_triangle = session.quad_mesh()
        result = blender_mesh.create_quad_object(bpy.context, source, vertices, quads, quad_triangle, src)
        return "ok", "", result, native_report(session)
    except binding.QGPError as e:
        if session is not None and not session.alive:
            return "crashed", e.message, None, {}
        return "refused", e.message, None, native_report(session)
    finally:
        if session is not None:
            session.close()


def native_report(session):
    if session is None:
        return {}
    try:
        return session.report()
    except Exception:  # the report is informative only
        return {}


def run_quadriflow(source, target):
    """bpy.ops.object.quadriflow_remesh in place (preserve sharp and boundary on).
    Returns (status, message, result object or None)."""
    before = mesh_polygons(source.data)
    activate(source)
    with CapturedStdout() as captured:
        try:
            bpy.ops.object.quadriflow_remesh(mode="FACES", target_faces=target, use_preserve_sharp=True,
                                             use_preserve_boundary=True, use_mesh_symmetry=False,
                                             preserve_paint_mask=False, smooth_normals=False, seed=0)
            error = None
        except RuntimeError as e:
            error = str(e).replace("Error: ", "").strip()
    if error is not None:
        return "refused", error, None
    after = mesh_polygons(source.data)
    if all(a.shape == b.shape and np.array_equal(a, b) for a, b in zip(before, after)):
        # QuadriFlow reports why only as a warning on the console (not to the caller): keep that text.
        warnings = [line.split(":", 1)[1].strip() for line in captured.text.splitlines()
                    if line.startswith(("Warning:", "Error:"))]
        return "unchanged", "; ".join(warnings) or "finished without error but left the mesh unchanged", None
    return "ok", "", source


class CapturedStdout:
    """Captures what native code writes to file descriptor 1 (Blender prints operator reports there in
    background mode); the text is echoed back afterwards, so the log still shows it."""

    def __enter__(self):
        import tempfile
        sys.stdout.flush()
        self._file = tempfile.TemporaryFile(mode="w+b")
        self._saved = os.dup(1)
        os.dup2(self._file.fileno(), 1)
        self.text = ""
        return self

    def __exit__(self, *exc):
        sys.stdout.flush()
        os.dup2(self._saved, 1)
        os.close(self._saved)
        self._file.seek(0)
        self.text = self._file.read().decode(errors="replace")
        self._file.close()
        sys.stdout.write(self.text)
        sys.stdout.flush()
        return False


def measure(binding, result, ref_vertices, ref_triangles, sharp_angle):
    vertices, sizes, corners = mesh_polygons(result.data)
    return binding.measure_polygon_mesh(vertices, sizes, corners, ref_vertices, ref_triangles, sharp_angle)


def run_case(addon, binding, args, name, category, data, target, tool):
    vertices, polygons, triangles = data
    is_cad = category == "CAD"
    row = {"mesh": name, "category": category, "input_triangles": len(triangles), "target": target, "tool": tool}
    source = new_object(f"{os.path.splitext(name)[0]}_{target}_{tool}", vertices, polygons)
    result = None
    start = time.perf_counter()
    if tool == "qgp":
        status, message, result, report = run_qgp(addon, binding, source, target,
                                                  args.sharp_angle if is_cad else -1.0, args.timeout,
                                                  args.quantizer)
        stages = report.get("timings_s", {})
        row["stage_seconds"] = ";".join(f"{k}={v:.3f}" for k, v in stages.items() if isinstance(v, (int, float)))
        # The fewest quads the layout allows, when the report names it (the count asked is below it).
        row["fewest_quads"] = report.get("quantization", {}).get("count", {}).get("fewest_quads", "")
        row["peak_memory_mb"] = report.get("peak_memory_mb", "")
    else:
        status, message, result = run_quadriflow(source, target)
    row["seconds"] = round(time.perf_counter() - start, 3)
    row.update(status=status, message=message)
    if result is not None:
        try:
            m = measure(binding, result, vertices, triangles, args.sharp_angle if is_cad else -1.0)
            row["quads_per_target"] = round(m.get("quads", 0) / target, 4)
            row.update({k: m.get(k) for k in ["quads", "faces", "non_quads", "irregular_vertices", "flipped_quads",
                                              "euler_characteristic_preserved", "hausdorff",
                                              "mean_angle_deviation_deg", "p95_angle_deviation_deg",
                                              "min_scaled_jacobian", "non_manifold_edges"]})
            row["hausdorff_result_to_input"] = m.get("hausdorff_quads_to_mesh")
            row["hausdorff_input_to_result"] = m.get("hausdorff_mesh_to_quads")
            if is_cad:
                row["sharp_edges"] = m.get("sharp_edges")
                row["sharp_edge_coverage"] = m.get("sharp_edge_coverage")
        except binding.QGPError as e:
            row["message"] = (row["message"] + "; " if row["message"] else "") + "measurement failed: " + e.message
        if args.save_meshes:
            write_obj(os.path.join(args.out, "meshes", f"{os.path.splitext(name)[0]}_{target}_{tool}.obj"), result)
        if result is not source:
            remove_object(result)
    remove_object(source)
    return row


def main():
    args = parse_args()
    names = [m for m in args.meshes.split(",") if m and m != "none"] or (
        [] if args.meshes == "none" else list(MANIFOLD_MESHES))
    sculpts = {}
    for spec in filter(None, args.sculpts.split(",")):
        base, levels = spec.rsplit(":", 1)
        sculpts[sculpt_name(base, int(levels))] = (base, int(levels))
    names += list(sculpts)
    targets = [int(t) for t in args.targets.split(",") if t]
    tools = [t for t in args.tools.split(",") if t]
    os.makedirs(os.path.join(args.out, "meshes") if args.save_meshes else args.out, exist_ok=True)
    addon = load_addon()
    binding = sys.modules[addon.__name__ + ".core.binding"]
    csv_path = os.path.join(args.out, "compare.csv")
    pending_path = os.path.join(args.out, "compare.pending")  # the case running now; left behind by a crash
    rows = []
    if not args.resume and os.path.exists(pending_path):
        os.remove(pending_path)
    if args.resume and os.path.exists(csv_path):
        with open(csv_path) as f:
            rows = list(csv.DictReader(f))
    done = {(r["mesh"], str(r["target"]), r["tool"]) for r in rows}
    with open(csv_path, "a" if rows else "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=COLUMNS)
        if not rows:
            writer.writeheader()

        def emit(row):
            writer.writerow(row)
            f.flush()
            rows.append(row)
            print(f"compare: {row['mesh']} {row['target']} {row['tool']}: {row['status']} {row.get('quads', '')} "
                  f"quads {row['seconds']} s {row['message'][:120]}", flush=True)

        if args.resume and os.path.exists(pending_path):
            with open(pending_path) as p:
                crashed = json.load(p)
            if (crashed["mesh"], str(crashed["target"]), crashed["tool"]) not in done:
                crashed.update(status="crashed", seconds="",
                               message="Blender exited during this run (crash, or a script error: see compare.log)")
                emit(crashed)
                done.add((crashed["mesh"], str(crashed["target"]), crashed["tool"]))
        case = 0
        for name in names:
            data = None
            for target in targets:
                order = tools if case % 2 == 0 else list(reversed(tools))  # alternate who goes first
                case += 1
                for tool in order:
                    if (name, str(target), tool) in done:
                        continue
                    if data is None and name in sculpts:
                        data = sculpt_input(binding, args.mesh_dir, *sculpts[name])
                    elif data is None:
                        data = read_input(binding, os.path.join(args.mesh_dir, name))
                    category = "sculpt" if name in sculpts else MANIFOLD_MESHES.get(name, "other")
                    with open(pending_path, "w") as p:
                        json.dump({"mesh": name, "category": category, "input_triangles": len(data[2]),
                                   "target": target, "tool": tool}, p)
                    emit(run_case(addon, binding, args, name, category, data, target, tool))
                    os.remove(pending_path)
    with open(os.path.join(args.out, "compare.json"), "w") as f:
        json.dump({"blender": bpy.app.version_string, "qgp": binding.version(), "sharp_angle": args.sharp_angle,
                   "quantizer": args.quantizer or "default",
                   "targets": targets, "rows": rows}, f, indent=1)
    print(f"compare: wrote {csv_path} ({len(rows)} rows)", flush=True)


if __name__ == "__main__":
    main()

#!/usr/bin/python3
"""Scaling benchmark of the native pipeline (build/bin/qgp): time per stage and peak memory
against input size and against target density.

    python3 bench/scaling.py [--shapes spot.obj,torus.obj,fandisk.obj] [--max-triangles 1200000]
        [--target 4000] [--density-shape spot.obj] [--density-level 2] [--densities 500,2000,8000,32000]
        [--timeout 1800] [--out bench/results] [--qgp build/bin/qgp]

Inputs: each shape of ../shared/meshes is refined by midpoint subdivision (every triangle -> 4, the
surface is unchanged) until the next level would exceed --max-triangles; levels are written as OBJ
under OUT/scaling_inputs/ (regenerated only when missing). Every run is one `qgp remesh` process;
its wall time and peak resident memory (GNU time's %M, else ru_maxrss from wait4) are recorded with the
per-stage timings of its JSON report. Writes OUT/scaling.csv (one row per run).
"""
import argparse
import csv
import json
import os
import signal
import subprocess
import sys
import time

import numpy as np

GNU_TIME = "/usr/bin/time"
HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)
STAGES = ["intake", "working_mesh", "cross_field", "cut_graph", "seamless_map", "tmesh", "quantization", "igm",
          "quad_extraction", "metrics"]
COLUMNS = ["series", "shape", "level", "triangles", "target", "status", "message", "wall_s", "peak_rss_mb",
           "quads"] + [s + "_s" for s in STAGES] + ["total_s"]


def read_mesh(path):
    """Triangles of an OBJ or OFF file (polygons fan-triangulated): (vertices (n,3), faces (f,3))."""
    vertices, faces = [], []
    with open(path) as f:
        if path.endswith(".off"):
            tokens = f.read().split()
            if tokens[0] != "OFF":
                raise ValueError(f"{path}: not an OFF file")
            nv, nf = int(tokens[1]), int(tokens[2])
            pos = 4
            vertices = [tuple(map(float, tokens[pos + 3 * i:pos + 3 * i + 3])) for i in range(nv)]
            pos += 3 * nv
            for _ in range(nf):
                n = int(tokens[pos])
                poly = [int(t) for t in tokens[pos + 1:pos + 1 + n]]
                pos += 1 + n
                faces.extend((poly[0], poly[i], poly[i + 1]) for i in range(1, n - 1))
        else:
            for line in f:
                parts = line.split()
                if not parts:
                    continue
                if parts[0] == "v":
                    vertices.append(tuple(map(float, parts[1:4])))
                elif parts[0] == "f":
                    poly = [int(p.split("/")[0]) for p in parts[1:]]
                    poly = [p - 1 if p > 0 else len(vertices) + p for p in poly]
                    faces.extend((poly[0], poly[i], poly[i + 1]) for i in range(1, len(poly) - 1))
    return np.asarray(vertices, np.float64), np.asarray(faces, np.int64)


def subdivide(vertices, faces):
    """Midpoint subdivision: one new vertex per edge, every triangle split into four."""
    edges = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    edges.sort(axis=1)
    unique, inverse = np.unique(edges, axis=0, return_inverse=True)
    inverse = inverse.reshape(-1)
    mid = 0.5 * (vertices[unique[:, 0]] + vertices[unique[:, 1]])
    n, f = len(vertices), len(faces)
    m01, m12, m20 = (n + inverse[i * f:(i + 1) * f] for i in range(3))
    a, b, c = faces[:, 0], faces[:, 1], faces[:, 2]
    new_faces = np.concatenate([np.stack([a, m01, m20], 1), np.stack([m01, b, m12], 1),
                                np.stack([m20, m12, c], 1), np.stack([m01, m12, m20], 1)])
    return np.concatenate([vertices, mid]), new_faces


def write_obj(path, vertices, faces):
    with open(path + ".tmp", "w") as f:
        f.write("".join("v %.9g %.9g %.9g\n" % tuple(v) for v in vertices.tolist()))
        f.write("".join("f %d %d %d\n" % (a + 1, b + 1, c + 1) for a, b, c in faces.tolist()))
    os.replace(path + ".tmp", path)


def make_levels(mesh_dir, shape, out_dir, max_triangles, max_level=None):
    """[(level, triangles, path)] of the shape refined until the next level exceeds max_triangles."""
    vertices, faces = read_mesh(os.path.join(mesh_dir, shape))
    levels, level = [], 0
    while True:
        path = os.path.join(out_dir, f"{os.path.splitext(shape)[0]}_L{level}.obj")
        if not os.path.exists(path):
            write_obj(path, vertices, faces)
        levels.append((level, len(faces), path))
        if 4 * len(faces) > max_triangles or (max_level is not None and level >= max_level):
            return levels
        vertices, faces = subdivide(vertices, faces)
        level += 1


def run_qgp(qgp, path, target, out_dir, timeout):
    """One `qgp remesh` process: (status, message, wall s, peak RSS MB, report dict)."""
    stem = os.path.splitext(os.path.basename(path))[0] + f"_{target}"
    report_path = os.path.join(out_dir, stem + ".json")
    if os.path.exists(report_path):
        os.remove(report_path)
    cmd = [qgp, "remesh", path, "-o", os.path.join(out_dir, stem + ".obj"), "--faces", str(target),
           "--report", report_path]
    # Peak memory from GNU time when present: a child forked from this Python would inherit Python's
    # high-water mark in ru_maxrss (Linux keeps it across exec), GNU time's own is tiny.
    rss_path = os.path.join(out_dir, stem + ".maxrss")
    if os.path.exists(rss_path):
        os.remove(rss_path)
    if os.access(GNU_TIME, os.X_OK):
        cmd = [GNU_TIME, "-f", "%M", "-o", rss_path] + cmd
    start = time.perf_counter()
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, start_new_session=True)
    status, message = None, ""
    while True:
        pid, exit_status, usage = os.wait4(proc.pid, os.WNOHANG)
        if pid:
            break
        if time.perf_counter() - start > timeout:
            os.killpg(proc.pid, signal.SIGKILL)
            pid, exit_status, usage = os.wait4(proc.pid, 0)
            status, message = "timeout", f"killed after {timeout:.0f} s"
            break
        time.sleep(0.05)
    wall = time.perf_counter() - start
    proc.returncode = os.waitstatus_to_exitcode(exit_status)
    stderr = proc.stderr.read().decode(errors="replace").strip()
    # Linux: kilobytes. Not for a killed run under GNU time: that figure would be GNU time's own, which
    # inherits this Python's high-water mark.
    peak_mb = None if status == "timeout" and GNU_TIME in cmd else usage.ru_maxrss / 1024.0
    if os.path.exists(rss_path):
        with open(rss_path) as f:
            lines = [line for line in f.read().split() if line.isdigit()]
        if lines:
            peak_mb = int(lines[-1]) / 1024.0
    report = {}
    if os.path.exists(report_path):
        with open(report_path) as f:
            report = json.load(f)
    if status is None:
        if report.get("status") == "ok" and proc.returncode == 0:
            status = "ok"
        elif report.get("status") == "partial" and proc.returncode == 5:  # parts kept as triangles
            status = "partial"
            failed = report.get("failed_components") or []
            message = f"{len(failed)} part(s) kept as triangles"
        else:
            status = "refused" if report.get("error") else "error"
            message = (report.get("error") or {}).get("message") or stderr.splitlines()[-1:] or \
                f"exit status {proc.returncode}"
            if isinstance(message, list):
                message = message[0] if message else ""
    return status, message, wall, peak_mb, report


def row_for(series, shape, level, triangles, target, result):
    status, message, wall, peak_mb, report = result
    timings = report.get("timings_s", {})
    row = {"series": series, "shape": shape, "level": level, "triangles": triangles, "target": target,
           "status": status, "message": message, "wall_s": round(wall, 3),
           "peak_rss_mb": None if peak_mb is None else round(peak_mb, 1),
           "total_s": timings.get("total")}
    quad = report.get("quad") or report.get("quads") or {}  # the report object was renamed "quad"
    row["quads"] = quad.get("faces")
    for stage in STAGES:
        row[stage + "_s"] = timings.get(stage)
    return row


def main():
    ap = argparse.ArgumentParser(prog="bench/scaling.py")
    ap.add_argument("--shapes", default="spot.obj,torus.obj,fandisk.obj")
    ap.add_argument("--max-triangles", type=int, default=1_200_000)
    ap.add_argument("--target", type=int, default=4000, help="target quads of the size series")
    ap.add_argument("--density-shape", default="spot.obj")
    ap.add_argument("--density-level", type=int, default=2, help="subdivision level of the density series")
    ap.add_argument("--densities", default="500,1000,2000,4000,8000,16000,32000")
    ap.add_argument("--timeout", type=float, default=1800.0, help="seconds before a run is killed")
    ap.add_argument("--mesh-dir",
                    default=os.environ.get("QGP_MESHES", os.path.join(os.path.dirname(REPO), "shared", "meshes")))
    ap.add_argument("--out", default=os.path.join(REPO, "bench", "results"))
    ap.add_argument("--qgp", default=os.path.join(REPO, "build", "bin", "qgp"))
    args = ap.parse_args()
    if not os.access(args.qgp, os.X_OK):
        sys.exit(f"scaling: {args.qgp} not found; run ./scripts/build.sh first")
    inputs_dir = os.path.join(args.out, "scaling_inputs")
    runs_dir = os.path.join(args.out, "scaling_runs")
    os.makedirs(inputs_dir, exist_ok=True)
    os.makedirs(runs_dir, exist_ok=True)
    csv_path = os.path.join(args.out, "scaling.csv")
    with open(csv_path, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=COLUMNS)
        writer.writeheader()

        def emit(row):
            writer.writerow(row)
            f.flush()
            print(f"scaling: {row['series']} {row['shape']} L{row['level']} {row['triangles']} tris "
                  f"target {row['target']}: {row['status']} {row['wall_s']} s {row['peak_rss_mb']} MB "
                  f"{str(row['message'])[:100]}", flush=True)

        for shape in [s for s in args.shapes.split(",") if s]:
            for level, triangles, path in make_levels(args.mesh_dir, shape, inputs_dir, args.max_triangles):
                emit(row_for("size", shape, level, triangles, args.target,
                             run_qgp(args.qgp, path, args.target, runs_dir, args.timeout)))
        if args.density_shape:
            levels = make_levels(args.mesh_dir, args.density_shape, inputs_dir, 1 << 62, args.density_level)
            level, triangles, path = levels[-1]
            for target in [int(t) for t in args.densities.split(",") if t]:
                emit(row_for("density", args.density_shape, level, triangles, target,
                             run_qgp(args.qgp, path, target, runs_dir, args.timeout)))
    print(f"scaling: wrote {csv_path}", flush=True)


if __name__ == "__main__":
    main()

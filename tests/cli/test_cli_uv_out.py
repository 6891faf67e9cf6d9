#!/usr/bin/python3
"""`qgp remesh --uv-out` on meshes whose global integer-grid solve has left flipped triangles
(joint at 500 quads, fertility at 2000) and on ones where it has not (spot, torus).

Checks the written map itself, whichever path made it (the global solve or the fallback cell
map on the mesh with the T-mesh inserted): no flipped uv triangle; across every edge the two
sides differ by a quarter turn plus an integer translation (residual <= 1e-9); every vertex whose
uv angle sum is not 2 pi (a cone, where its triangles are not degenerate) sits on an integer
point; the report's igm.cell_map_components agrees with the file (more triangles than the
working mesh means the cell map). Prints one row per run.
"""
import argparse
import json
import math
import os
import subprocess
import sys
import tempfile

import numpy as np

RUNS = [("joint.obj", 500), ("fertility.off", 2000), ("spot.obj", 500), ("torus.obj", 2000)]


def read_obj(path):
    vt, faces = [], []
    for line in open(path):
        t = line.split()
        if t and t[0] == "vt":
            vt.append((float(t[1]), float(t[2])))
        elif t and t[0] == "f":
            faces.append([tuple(int(x) - 1 for x in c.split("/")[:2]) for c in t[1:]])
    return np.array(vt), faces


def check_map(vt, faces):
    """(flipped, degenerate, worst seam residual, cones off integer points)"""
    flipped = degenerate = 0
    angle, sides, degenerate_ring, boundary = {}, {}, set(), set()
    for f in faces:
        p = [vt[c[1]] for c in f]
        area = (p[1][0] - p[0][0]) * (p[2][1] - p[0][1]) - (p[1][1] - p[0][1]) * (p[2][0] - p[0][0])
        flipped += area < 0
        if area == 0:
            degenerate += 1
            degenerate_ring.update(c[0] for c in f)
        for k in range(3):
            u, w = p[(k + 1) % 3] - p[k], p[(k + 2) % 3] - p[k]
            angle[f[k][0]] = angle.get(f[k][0], 0) + math.atan2(u[0] * w[1] - u[1] * w[0], u @ w)
            sides[(f[k][0], f[(k + 1) % 3][0])] = (p[k], p[(k + 1) % 3])
    worst = 0.0
    for (a, b), (pa, pb) in sides.items():
        other = sides.get((b, a))
        if other is None:
            boundary.update((a, b))
            continue
        qb, qa = other
        best = math.inf
        for c, s in ((1, 0), (0, 1), (-1, 0), (0, -1)):
            rot = np.array([[c, -s], [s, c]])
            t = qa - rot @ pa
            best = min(best, max(np.abs(rot @ pb + t - qb).max(), np.abs(t - np.round(t)).max()))
        worst = max(worst, best)
    off = set()
    for f in faces:
        for v, c in f:
            if v in boundary or v in degenerate_ring or abs(angle[v] - 2 * math.pi) < 1e-6:
                continue
            if np.abs(vt[c] - np.round(vt[c])).max() > 1e-9:
                off.add(v)
    return flipped, degenerate, worst, len(off)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--qgp", required=True)
    ap.add_argument("--meshes", required=True)
    args = ap.parse_args()
    failures = []
    print("mesh | quads | igm flipped | cell map | uv triangles | flipped | degenerate | seam residual | "
          "cones off grid")
    with tempfile.TemporaryDirectory() as tmp:
        for name, faces in RUNS:
            out, uv, rep = (os.path.join(tmp, name + s) for s in (".obj", "_uv.obj", ".json"))
            proc = subprocess.run([args.qgp, "remesh", os.path.join(args.meshes, name), "-o", out, "--faces",
                                   str(faces), "--uv-out", uv, "--report", rep], capture_output=True, text=True)
            if proc.returncode != 0:
                failures.append(f"{name}: exit {proc.returncode}: {proc.stderr.strip()}")
                continue
            report = json.load(open(rep))
            igm = report["igm"]
            vt, tris = read_obj(uv)
            flipped, degenerate, worst, off = check_map(vt, tris)
            print(f"{name} | {faces} | {igm['flipped_triangles']} | {igm['cell_map_components']} | {len(tris)} | "
                  f"{flipped} | {degenerate} | {worst:.2g} | {off}")
            if flipped:
                failures.append(f"{name}@{faces}: {flipped} flipped uv triangles")
            if worst > 1e-9:
                failures.append(f"{name}@{faces}: seam residual {worst}")
            if off:
                failures.append(f"{name}@{faces}: {off} cones off integer points")
            cell_map = igm["cell_map_components"] > 0
            if cell_map != (igm["flipped_triangles"] + igm["winding_defects"] > 0):
                failures.append(f"{name}@{faces}: the cell map is used iff the global map is flipped or wound")
            working = report["working_mesh"]["working_faces"]
            if cell_map and len(tris) <= working:
                failures.append(f"{name}@{faces}: the cell map's file has no more triangles than the working mesh")
    for f in failures:
        print("FAIL", f)
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()

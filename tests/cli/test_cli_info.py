#!/usr/bin/python3
"""`qgp info` over every file of the shared mesh set.

Checks: exit code 0 (every shared mesh is usable: non-manifold edges are cut into sheets; with
--refuse-non-manifold, truck and cycloidal exit 2 with a one-line reason), never a signal; the
report JSON is written either way; every repair names where it happened (input_vertices);
components / genus / boundary loops match the meshes' README for the manifold meshes. Prints a
table (status, repairs, components, genus, loops, ms).
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

# From ../shared/meshes/README.md: (components, genus per component, boundary loops per component).
EXPECTED = {
    "spot.obj": (1, [0], [0]), "bunny.off": (1, [0], [0]), "armadillo.obj": (1, [0], [0]),
    "nefertiti.obj": (1, [0], [0]), "igea.ply": (1, [0], [0]), "dragon-genus1.obj": (1, [1], [0]),
    "torus.obj": (1, [1], [0]), "rocker-arm.obj": (1, [1], [0]), "kitten.obj": (1, [1], [0]),
    "fertility.off": (1, [4], [0]), "mnf07HeadFem_rem_rem_p.obj": (1, [9], [0]),
    "fandisk.obj": (1, [0], [0]), "block.obj": (1, [3], [0]), "joint.obj": (1, [2], [0]),
    "joint_rem_p.obj": (1, [2], [0]), "wingnut.obj": (1, [0], [0]),
    "stanford-bunny.obj": (1, [0], [5]), "face.obj": (1, [0], [1]), "camelhead.off": (1, [0], [1]),
    "decimated-max.obj": (1, [0], [0]), "beetle.off": (1, [0], [11]),
}
# Non-manifold edges: cut into sheets by default, refused with --refuse-non-manifold.
NON_MANIFOLD = {"truck.obj", "cycloidal.ply"}


def check_refuse_option(qgp, path, name, failures):
    proc = subprocess.run([qgp, "info", path, "--refuse-non-manifold"], capture_output=True, text=True)
    if proc.returncode != 2 or "non-manifold edge" not in proc.stderr:
        failures.append(f"{name}: --refuse-non-manifold should refuse it (exit {proc.returncode})")


def check_repairs_located(name, repairs, failures):
    for r in repairs:
        where = r.get("input_vertices")
        if not isinstance(where, list) or not 1 <= len(where) <= 10:
            failures.append(f"{name}: repair {r['kind']} without 1..10 input_vertices: {where}")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--qgp", required=True)
    ap.add_argument("--meshes", required=True)
    args = ap.parse_args()
    files = sorted(f for f in os.listdir(args.meshes) if f.rsplit(".", 1)[-1] in ("obj", "off", "ply"))
    failures = []
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for name in files:
            report_path = os.path.join(tmp, name + ".json")
            start = time.perf_counter()
            proc = subprocess.run([args.qgp, "info", os.path.join(args.meshes, name), "--report", report_path],
                                  capture_output=True, text=True)
            ms = (time.perf_counter() - start) * 1000
            code = proc.returncode
            if code < 0:
                failures.append(f"{name}: killed by signal {-code}")
                continue
            if code not in (0, 2):
                failures.append(f"{name}: exit {code}: {proc.stderr.strip()}")
                continue
            if not os.path.exists(report_path):
                failures.append(f"{name}: no report written")
                continue
            report = json.load(open(report_path))
            if code == 2:
                lines = proc.stderr.strip().splitlines()
                if len(lines) != 1 or report["status"] != "error" or not report["error"]["message"]:
                    failures.append(f"{name}: unusable input needs a one-line reason and an error report")
                failures.append(f"{name}: refused unexpectedly: {proc.stderr.strip()}")
                rows.append((name, "refused", lines[0][:60] if lines else "", "", "", "", ms))
                continue
            inp = report["input"]
            check_repairs_located(name, inp["repairs"], failures)
            if name in NON_MANIFOLD:
                if not any(r["kind"] == "cut_nonmanifold_edges" for r in inp["repairs"]):
                    failures.append(f"{name}: its non-manifold edges should be cut (cut_nonmanifold_edges)")
                check_refuse_option(args.qgp, os.path.join(args.meshes, name), name, failures)
            if name in EXPECTED:
                comps, genus, loops = EXPECTED[name]
                got = (inp["components"], inp["genus"], inp["boundary_loops"])
                if got != (comps, genus, loops):
                    failures.append(f"{name}: expected {(comps, genus, loops)}, got {got}")
            repairs = ", ".join(f"{r['kind']} {r['count']}" for r in inp["repairs"]) or "-"
            g = inp["genus"] if len(inp["genus"]) <= 4 else f"{len(inp['genus'])} comps, sum {sum(inp['genus'])}"
            b = inp["boundary_loops"] if len(inp["boundary_loops"]) <= 4 else f"sum {sum(inp['boundary_loops'])}"
            rows.append((name, "ok", repairs, inp["components"], g, b, ms))
    print("| file | status | repairs / reason | components | genus | boundary loops | ms |")
    print("|---|---|---|---|---|---|---|")
    for r in rows:
        print("| " + " | ".join(str(x) if not isinstance(x, float) else f"{x:.0f}" for x in r) + " |")
    if len(files) < 27:
        failures.append(f"expected the 27 shared meshes, found {len(files)}")
    for f in failures:
        print("FAIL:", f)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())

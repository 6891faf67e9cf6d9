"""Every mesh of ../shared/meshes through `qgp remesh` at several quad counts: outcome, quads, repairs, time.

    /usr/bin/python3 bench/robustness.py [--qgp build/bin/qgp] [--mesh-dir ../shared/meshes]
        [--targets 500,2000,8000] [--meshes a.obj,b.off] [--sharp-meshes c.ply,...] [--sharp-angle 40]
        [--timeout 300] [--out bench/results]

Each run is one `qgp remesh IN --faces N --report R` process (killed after --timeout s: the issue's
bound for a hang). The outcome of a run is checked from its report and its output file, as
issue 23 asks of every part: only quads (besides parts kept as triangles), no non-manifold or
inconsistently oriented edge, the Euler characteristic of the parts it stands for, no quad flipped
against the input, no quad with a collapsed edge (two corners on one point), and the Hausdorff
distance (relative to the bounding-box diagonal). The CAD parts run a second time with their sharp
edges kept (--sharp-angle), as a CAD user runs them. Writes
OUT/robustness.csv and OUT/robustness.md. Timings are figures, not checks.
"""
import argparse
import csv
import json
import os
import subprocess
import time

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)
MESH_SUFFIXES = (".obj", ".off", ".ply")
CAD_MESHES = "block.obj,cycloidal.ply,fandisk.obj,featuretype.ply,joint.obj,wingnut.obj"
COLUMNS = ["mesh", "sharp_angle", "target", "exit", "outcome", "seconds", "quads", "kept_triangles", "rescued_parts",
           "parts",
           "failed_parts", "euler_expected", "euler", "non_manifold_edges", "inconsistent_edges", "flipped_quads",
           "collapsed_edge_quads", "hausdorff", "repairs", "message"]


def parse_args():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--qgp", default=os.path.join(REPO, "build", "bin", "qgp"))
    ap.add_argument("--mesh-dir", default=os.path.join(os.path.dirname(REPO), "shared", "meshes"))
    ap.add_argument("--targets", default="500,2000,8000")
    ap.add_argument("--meshes", default="", help="comma-separated file names (default: every mesh in --mesh-dir)")
    ap.add_argument("--sharp-meshes", default=CAD_MESHES,
                    help="comma-separated file names run again with --sharp-angle (default: the CAD parts)")
    ap.add_argument("--sharp-angle", type=float, default=40.0)
    ap.add_argument("--timeout", type=float, default=300.0)
    ap.add_argument("--out", default=os.path.join(REPO, "bench", "results"))
    return ap.parse_args()


def face_arities(path):
    """Counts of output faces by number of corners."""
    counts = {}
    with open(path) as f:
        for line in f:
            if line.startswith("f "):
                n = len(line.split()) - 1
                counts[n] = counts.get(n, 0) + 1
    return counts


def repairs_summary(report):
    repairs = report.get("input", {}).get("repairs", [])
    return "; ".join(f"{r['kind']} {r.get('count', '')}".strip() for r in repairs)


def expected_euler(report):
    """Euler characteristic of the parts the quads stand for: every intake component not kept as triangles."""
    chi = report.get("input", {}).get("euler_characteristic", [])
    failed = {f["component"] for f in report.get("failed_components", [])}
    return sum(c for i, c in enumerate(chi) if i not in failed)


def outcome_of(row):
    """'valid' when every part that is not kept as triangles is a valid quad mesh, else what is wrong."""
    if row["exit"] == "timeout":
        return "timeout"
    if row["quads"] in ("", 0):
        return "refused"
    wrong = []
    if row["non_manifold_edges"] or row["inconsistent_edges"]:
        wrong.append("not a manifold oriented mesh")
    if row["euler"] != row["euler_expected"]:
        wrong.append("Euler characteristic")
    if row["flipped_quads"]:
        wrong.append("flipped quads")
    if row["collapsed_edge_quads"]:
        wrong.append("quads with a collapsed edge")
    if wrong:
        return "invalid: " + ", ".join(wrong)
    return "valid" if not row["failed_parts"] else "valid except parts kept as triangles"


def run_case(args, mesh, target, work, sharp_angle=None):
    stem = os.path.splitext(mesh)[0] + (f"_sharp{sharp_angle:g}" if sharp_angle is not None else "")
    out_obj = os.path.join(work, f"{stem}_{target}.obj")
    report_path = os.path.join(work, f"{stem}_{target}.json")
    for p in (out_obj, report_path):
        if os.path.exists(p):
            os.remove(p)
    cmd = [args.qgp, "remesh", os.path.join(args.mesh_dir, mesh), "--faces", str(target), "-o", out_obj,
           "--report", report_path]
    if sharp_angle is not None:
        cmd += ["--sharp-angle", str(sharp_angle)]
    start = time.monotonic()
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=args.timeout)
        code, stderr = str(proc.returncode), proc.stderr
    except subprocess.TimeoutExpired:
        code, stderr = "timeout", ""
    row = {k: "" for k in COLUMNS}
    row.update(mesh=mesh, sharp_angle="" if sharp_angle is None else sharp_angle, target=target, exit=code,
               seconds=round(time.monotonic() - start, 1))
    report = json.load(open(report_path)) if os.path.exists(report_path) else {}
    quad = report.get("quad") or {}
    arities = face_arities(out_obj) if os.path.exists(out_obj) else {}
    row.update(quads=arities.get(4, 0), kept_triangles=sum(n for k, n in arities.items() if k != 4),
               rescued_parts=len(report.get("rescued_components", [])),
               parts=len(report.get("input", {}).get("euler_characteristic", [])),
               failed_parts=len(report.get("failed_components", [])), euler_expected=expected_euler(report),
               euler=quad.get("euler_characteristic", ""), non_manifold_edges=quad.get("non_manifold_edges", ""),
               inconsistent_edges=quad.get("inconsistent_edges", ""), flipped_quads=quad.get("flipped_quads", ""),
               collapsed_edge_quads=quad.get("collapsed_edge_quads", ""),
               hausdorff=round(quad["hausdorff"], 5) if "hausdorff" in quad else "", repairs=repairs_summary(report))
    error = report.get("error") or ""
    message = error.get("message", "") if isinstance(error, dict) else str(error)
    if not message and stderr.strip():
        message = stderr.strip().splitlines()[-1]
    row["message"] = message[:160]
    row["outcome"] = outcome_of(row)
    return row


def write_markdown(rows, path, targets):
    lines = ["# Every shared mesh through `qgp remesh`", "",
             "`bench/robustness.py` (one `qgp remesh` process per run, killed after the timeout). Outcome: "
             "valid = only quads, manifold and oriented, the Euler characteristic of the parts it stands for, "
             "no quad flipped against the input, no quad with a collapsed edge (two corners on one point). "
             "Hausdorff relative to the bounding-box diagonal. Rows with a sharp angle keep the edges sharper "
             "than it as features (the CAD parts).", "",
             "| mesh | target | outcome | s | quads | kept triangles | rescued parts | flipped | collapsed edges | "
             "Hausdorff | repairs |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        name = r["mesh"] + (f" (sharp {r['sharp_angle']:g}°)" if r["sharp_angle"] != "" else "")
        lines.append(f"| {name} | {r['target']} | {r['outcome']} | {r['seconds']} | {r['quads']} | "
                     f"{r['kept_triangles']} | {r['rescued_parts']} | {r['flipped_quads']} | "
                     f"{r['collapsed_edge_quads']} | {r['hausdorff']} | {r['repairs']} |")
    plain = [r for r in rows if r["sharp_angle"] == ""]
    sharp = [r for r in rows if r["sharp_angle"] != ""]
    lines += ["", f"{sum(r['outcome'] == 'valid' for r in plain)} of {len(plain)} runs valid with every part "
              f"quadded (targets {targets})."]
    if sharp:
        lines.append(f"With sharp edges: {sum(r['outcome'] == 'valid' for r in sharp)} of {len(sharp)} runs valid.")
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")


def main():
    args = parse_args()
    meshes = [m for m in args.meshes.split(",") if m] or sorted(
        m for m in os.listdir(args.mesh_dir) if m.endswith(MESH_SUFFIXES))
    targets = [int(t) for t in args.targets.split(",")]
    os.makedirs(args.out, exist_ok=True)
    work = os.path.join(args.out, "robustness")
    os.makedirs(work, exist_ok=True)
    rows = []
    with open(os.path.join(args.out, "robustness.csv"), "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=COLUMNS)
        writer.writeheader()
        sharp_meshes = [m for m in args.sharp_meshes.split(",") if m and m in meshes]
        cases = [(m, None) for m in meshes] + [(m, args.sharp_angle) for m in sharp_meshes]
        for mesh, sharp_angle in cases:
            for target in targets:
                row = run_case(args, mesh, target, work, sharp_angle)
                rows.append(row)
                writer.writerow(row)
                f.flush()
                print(f"robustness {mesh} {sharp_angle or ''} {target}: {row['outcome']} in {row['seconds']} s, "
                      f"{row['quads']} quads, {row['kept_triangles']} kept triangles {row['message'][:100]}",
                      flush=True)
    write_markdown(rows, os.path.join(args.out, "robustness.md"), args.targets)


if __name__ == "__main__":
    main()

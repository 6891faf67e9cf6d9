#!/usr/bin/python3
"""Re-quantizing at a new density (the add-on's redo panel) against a first run, per mesh.

    python3 bench/requantize.py [--meshes spot.obj,fandisk.obj] [--first 2000] [--seconds 1000,3000]
        [--mesh-dir ../shared/meshes] [--out bench/results]

One native session per mesh and density (addon/core/binding.py, the library of build/lib): a remesh
job at --first quads, then one at each --seconds count in the same session, as the redo panel does.
Records the wall time of each job and the stages the second one ran (its report's timings_s);
ratio = second / first. Writes OUT/requantize.csv and OUT/requantize.md. No figure is a pass/fail test.
"""
import argparse
import csv
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)
sys.path.insert(0, os.path.join(REPO, "addon", "core"))
import binding  # noqa: E402

DEFAULT_MESHES = "spot.obj,kitten.obj,fandisk.obj,rocker-arm.obj,stanford-bunny.obj,armadillo.obj,nefertiti.obj"
COLUMNS = ["mesh", "first_target", "first_s", "first_quads", "second_target", "second_s", "second_quads", "ratio",
           "second_stages"]


def timed_remesh(session, target):
    """(wall seconds, quads, report) of one remesh job at `target` quads."""
    session.set_option("target_faces", target)
    start = time.perf_counter()
    session.run(binding.JOB_REMESH)
    seconds = time.perf_counter() - start
    report = session.report()
    return seconds, report.get("quad", {}).get("faces"), report


def stages_run(report):
    """The stages a job spent time in, as 'stage=seconds;...' (total left out)."""
    timings = report.get("timings_s", {})
    return ";".join(f"{k}={v:.2f}" for k, v in timings.items() if k != "total" and v >= 0.005)


def measure(path, first, second):
    with binding.Session.from_file(path) as session:
        first_s, first_quads, _ = timed_remesh(session, first)
        second_s, second_quads, report = timed_remesh(session, second)
    return {"mesh": os.path.basename(path), "first_target": first, "first_s": round(first_s, 3),
            "first_quads": first_quads, "second_target": second, "second_s": round(second_s, 3),
            "second_quads": second_quads, "ratio": round(second_s / first_s, 4) if first_s > 0 else "",
            "second_stages": stages_run(report)}


def markdown(rows):
    lines = ["| mesh | first run | s | second run | s | second / first | stages of the second run (s) |",
             "|---|---:|---:|---:|---:|---:|---|"]
    for r in rows:
        lines.append(f"| {r['mesh']} | {r['first_target']} → {r['first_quads']} | {r['first_s']:.2f} "
                     f"| {r['second_target']} → {r['second_quads']} | {r['second_s']:.2f} | {100 * r['ratio']:.1f} % "
                     f"| {r['second_stages'].replace(';', ', ')} |")
    return "\n".join(lines) + "\n"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--meshes", default=DEFAULT_MESHES)
    ap.add_argument("--first", type=int, default=2000)
    ap.add_argument("--seconds", default="1000,3000")
    shared_meshes = os.path.join(os.path.dirname(REPO), "shared", "meshes")
    ap.add_argument("--mesh-dir", default=os.environ.get("QGP_MESHES", shared_meshes))
    ap.add_argument("--out", default=os.path.join(REPO, "bench", "results"))
    args = ap.parse_args()
    rows = []
    for name in args.meshes.split(","):
        for second in (int(s) for s in args.seconds.split(",")):
            try:
                row = measure(os.path.join(args.mesh_dir, name), args.first, second)
            except binding.QGPError as e:
                print(f"requantize: {name} {args.first} -> {second}: {e}", flush=True)
                continue
            rows.append(row)
            print(f"requantize: {name} {args.first} -> {second}: {row['first_s']:.2f} s then {row['second_s']:.2f} s "
                  f"({100 * row['ratio']:.1f} %)", flush=True)
    os.makedirs(args.out, exist_ok=True)
    with open(os.path.join(args.out, "requantize.csv"), "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=COLUMNS)
        writer.writeheader()
        writer.writerows(rows)
    with open(os.path.join(args.out, "requantize.md"), "w") as f:
        f.write(markdown(rows))


if __name__ == "__main__":
    main()

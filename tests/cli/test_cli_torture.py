#!/usr/bin/python3
"""`qgp remesh` over the generated torture set (tests/torture_set.py): each case ends as documented.

Per case: the exit status of its outcome (0 quads, 5 partial, 2 refused, 3 failed) within the
time limit, never a signal; the message on stderr; the report written, with the repairs intake
must make; for outcomes with output, a valid OBJ (torture_set.validate_output); for refusals, no
OBJ. Prints one row per case: outcome, quads, repairs, seconds.
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # tests/
import torture_set  # noqa: E402

check = torture_set.Checks()


def read_obj(path):
    vertices, faces = [], []
    for line in open(path):
        parts = line.split()
        if parts and parts[0] == "v":
            vertices.append(tuple(map(float, parts[1:4])))
        elif parts and parts[0] == "f":
            faces.append([int(p.split("/")[0]) - 1 for p in parts[1:]])
    return vertices, faces


def run_case(qgp, case, folder):
    path = case.write(folder, case.name)
    out, report_path = os.path.join(folder, case.name + "_quads.obj"), os.path.join(folder, case.name + ".json")
    start = time.monotonic()
    try:
        proc = subprocess.run([qgp, "remesh", path, "-o", out, "--faces", str(torture_set.TARGET_QUADS),
                               "--report", report_path], capture_output=True, text=True,
                              timeout=torture_set.TIMEOUT_S)
    except subprocess.TimeoutExpired:
        check(False, f"{case.name}: still running after {torture_set.TIMEOUT_S} s")
        return
    seconds = time.monotonic() - start
    where = f"{case.name} ({case.outcome})"
    check(proc.returncode == torture_set.EXIT_STATUS[case.outcome],
          f"{where}: exit {proc.returncode}: {proc.stderr.strip()[-300:]}")
    check(case.message in proc.stderr, f"{where}: stderr does not say '{case.message}': {proc.stderr[-300:]}")
    check(os.path.exists(report_path), f"{where}: no report")
    report = json.load(open(report_path)) if os.path.exists(report_path) else {}
    missing = torture_set.repairs_missing(case, report)
    check(not missing, f"{where}: repairs {missing} missing from {report.get('input', {}).get('repairs')}")
    quads = None
    check(not torture_set.rescue_problems(case, report), f"{where}: {torture_set.rescue_problems(case, report)}")
    if case.outcome in ("quads", "rescued", "partial"):
        check(os.path.exists(out), f"{where}: no OBJ")
        if os.path.exists(out):
            vertices, faces = read_obj(out)
            problems = torture_set.validate_output(vertices, faces, report)
            check(not problems, f"{where}: {problems}")
            quads = sum(len(f) == 4 for f in faces)
    else:
        check(not os.path.exists(out), f"{where}: an OBJ was written")
    repairs = ", ".join(f"{r['kind']} {r['count']}" for r in report.get("input", {}).get("repairs", []))
    print(f"{case.name} | {report.get('status')} | exit {proc.returncode} | {quads} quads | {repairs} | "
          f"{seconds:.1f} s")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--qgp", required=True)
    args = ap.parse_args()
    print("case | status | exit | quads | repairs | time")
    with tempfile.TemporaryDirectory() as folder:
        for case in torture_set.CASES:
            run_case(args.qgp, case, folder)
    check.exit("CLI")


if __name__ == "__main__":
    main()

#!/usr/bin/python3
"""The C API over the generated torture set (tests/torture_set.py), through the add-on's ctypes
binding (addon/core/binding.py, no Blender): qgp_session_create_from_file, a remesh job, the report,
the quads and the kept triangles. Each case must end as documented, as it does for the CLI
(tests/cli/test_cli_torture.py) and the add-on (tests/blender/test_torture.py): refusals raise
QGPError with the code of unusable input and the message; other outcomes give a valid polygon mesh
(torture_set.validate_output) and the report's status.
"""
import argparse
import os
import sys
import tempfile
import time

sys.dont_write_bytecode = True  # nothing written into addon/
HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))  # tests/: torture_set
sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(HERE)), "addon"))
import torture_set  # noqa: E402
from core import binding  # noqa: E402

STATUS = {"quads": "ok", "rescued": "ok", "partial": "partial"}
ERROR_CODE = {"refused": (binding.ERR_INVALID_MESH, binding.ERR_UNREADABLE_FILE), "failed": (binding.ERR_STAGE_FAILED,)}
check = torture_set.Checks()


def remesh(path):
    """(report, vertices, faces) of a remesh job on the file, or raises QGPError."""
    with binding.Session.from_file(path) as session:
        session.set_option("target_faces", torture_set.TARGET_QUADS)
        session.run(binding.JOB_REMESH)
        report = session.report()
        vertices, quads, _ = session.quad_mesh()
        kept_vertices, kept, _, _ = session.kept_triangles()
        faces = [list(map(int, q)) for q in quads] + [[len(vertices) + int(i) for i in t] for t in kept]
        return report, [tuple(p) for p in vertices] + [tuple(p) for p in kept_vertices], faces


def run_case(case, folder):
    path = case.write(folder, case.name)
    where = f"{case.name} ({case.outcome})"
    start = time.monotonic()
    try:
        report, vertices, faces = remesh(path)
    except binding.QGPError as e:
        check(case.outcome in ERROR_CODE and e.code in ERROR_CODE[case.outcome], f"{where}: QGPError {e.code}: {e}")
        check(case.message in str(e), f"{where}: the error does not say '{case.message}': {e}")
        print(f"{case.name} | error {e.code} | {str(e)[:80]} | {time.monotonic() - start:.1f} s")
        return
    check(report["status"] == STATUS.get(case.outcome), f"{where}: status {report['status']}")
    failed = report.get("failed_components") or []
    check(all(case.message in f["message"] for f in failed), f"{where}: {failed} do not say '{case.message}'")
    missing = torture_set.repairs_missing(case, report)
    check(not missing, f"{where}: repairs {missing} missing")
    check(not torture_set.rescue_problems(case, report), f"{where}: {torture_set.rescue_problems(case, report)}")
    problems = torture_set.validate_output(vertices, faces, report)
    check(not problems, f"{where}: {problems}")
    print(f"{case.name} | {report['status']} | {sum(len(f) == 4 for f in faces)} quads | "
          f"{time.monotonic() - start:.1f} s")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--library", required=True)
    args = ap.parse_args()
    binding.load_library(args.library)
    with tempfile.TemporaryDirectory() as folder:
        for case in torture_set.CASES:
            run_case(case, folder)
    check.exit("C API")


if __name__ == "__main__":
    main()

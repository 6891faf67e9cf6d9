#!/usr/bin/python3
"""The add-on's worker process (addon/core/worker.py), outside Blender:
a remesh in the worker gives exactly the in-process result, over a socket pair and over the loopback
connection Windows uses; native errors keep their code and
message; a worker killed mid-job (SIGKILL, SIGSEGV) is an error naming the signal and the session
reports itself dead; closing during a job ends the child; a worker that cannot start is a
WorkerStartError; the child is isolated from the user's PYTHON* variables (a PYTHONPATH with
poisoned modules, a bogus PYTHONHOME) and writes no bytecode into the add-on's folder.
The add-on is used from a temporary copy of addon/ (removed at exit), which this process does not
write bytecode into either. Usage: test_worker.py --library libqgp.so --meshes DIR"""
import argparse
import atexit
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
COPY = os.path.join(tempfile.mkdtemp(prefix="qgp_addon_copy_"), "addon")
shutil.copytree(os.path.join(ROOT, "addon"), COPY, ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
atexit.register(shutil.rmtree, os.path.dirname(COPY), ignore_errors=True)
sys.dont_write_bytecode = True  # any __pycache__ in the copy is the worker's,
os.environ.pop("PYTHONDONTWRITEBYTECODE", None)  # which must not rely on the caller's environment to avoid it
sys.path.insert(0, COPY)
from core import binding, worker  # noqa: E402

failures = []


def check(condition, message):
    print(("ok   " if condition else "FAIL ") + message)
    if not condition:
        failures.append(message)


def load(meshes, name):
    vertices, sizes, corners = binding.read_mesh_file(os.path.join(meshes, name))
    assert (sizes == 3).all()
    return vertices, corners.reshape(-1, 3)


def same_result_as_in_process(meshes):
    for name, target in (("bunny.off", 800), ("joint.obj", 500), ("face.obj", 600)):
        vertices, triangles = load(meshes, name)
        results = []
        # The worker over a socket pair (Linux, macOS) and over a loopback connection (Windows).
        for make in (binding.Session, worker.WorkerSession, loopback_worker):
            with make(vertices, triangles) as session:
                session.set_option("target_faces", target)
                session.run(binding.JOB_REMESH)
                v, q, src = session.quad_mesh()
                results.append((v, q, src, session.report()["quad"]["faces"]))
        (v0, q0, s0, n0) = results[0]
        for transport, (v1, q1, s1, n1) in zip(("socket pair", "loopback"), results[1:]):
            check(n0 == n1 == len(q1) and np.array_equal(q0, q1) and np.array_equal(s0, s1) and np.array_equal(v0, v1),
                  f"{name}: the worker's {len(q1)} quads ({transport}) are the in-process result")


def loopback_worker(vertices, triangles):
    return worker.WorkerSession(vertices, triangles, loopback=True)


def native_errors_pass_through():
    with worker.WorkerSession([[0, 0, 0], [1, 0, 0], [float("nan"), 1, 0]], [[0, 1, 2]]) as session:
        try:
            session.run(binding.JOB_INTAKE)
            check(False, "NaN input refused")
        except binding.QGPError as e:
            check(e.code == binding.ERR_INVALID_MESH and "non-finite" in e.message and session.alive,
                  f"native error keeps its code and message, worker alive: {e.message[:60]}")


def killed_mid_job(meshes, sig, loopback=False):
    vertices, triangles = load(meshes, "armadillo.obj")
    session = worker.WorkerSession(vertices, triangles, loopback=loopback)
    session.start(binding.JOB_REMESH)
    time.sleep(1.0)
    state = session.poll()[0]
    os.kill(session.pid, sig)
    try:
        session.wait()
        check(False, f"{sig.name}: error raised")
    except binding.QGPError as e:
        check(state == binding.STATE_RUNNING and sig.name in e.message and "unaffected" in e.message,
              f"{sig.name} mid-job: {e.message[:70]}")
    check(not session.alive, f"{sig.name}: session reports the worker dead")
    try:
        session.poll()
        check(False, f"{sig.name}: calls after the death raise")
    except binding.QGPError:
        check(True, f"{sig.name}: calls after the death raise")
    session.close()


def close_during_job_ends_child(meshes):
    vertices, triangles = load(meshes, "armadillo.obj")
    session = worker.WorkerSession(vertices, triangles)
    pid = session.pid
    session.start(binding.JOB_REMESH)
    time.sleep(0.5)
    start = time.perf_counter()
    session.close()
    gone = not os.path.exists(f"/proc/{pid}") or open(f"/proc/{pid}/stat").read().split()[2] == "Z"
    check(gone, f"close() during a job ends the child in {time.perf_counter() - start:.1f} s")


def start_failure():
    original = worker.python_executable
    worker.python_executable = lambda: "/nonexistent/python3"
    try:
        worker.WorkerSession(np.zeros((3, 3)), np.array([[0, 1, 2]]))
        check(False, "a worker that cannot start raises WorkerStartError")
    except worker.WorkerStartError as e:
        check(True, f"a worker that cannot start raises WorkerStartError: {e.message[:60]}")
    finally:
        worker.python_executable = original


def pycache_dirs(folder):
    return sorted(os.path.relpath(os.path.join(d, n), folder)
                  for d, names, _ in os.walk(folder) for n in names if n == "__pycache__")


def poisoned_environment(folder):
    """PYTHON* variables that break a non-isolated interpreter: a sitecustomize that ends the
    process, a numpy and a binding module that raise, a PYTHONHOME without a standard library."""
    with open(os.path.join(folder, "sitecustomize.py"), "w") as f:
        f.write("import os\nos._exit(17)\n")
    for name in ("numpy", "binding"):
        with open(os.path.join(folder, name + ".py"), "w") as f:
            f.write(f"raise ImportError('poisoned {name} from PYTHONPATH')\n")
    return {"PYTHONPATH": folder, "PYTHONHOME": "/nonexistent/python-home", "PYTHONSTARTUP": os.path.join(folder, "x"),
            "PYTHONUSERBASE": folder}


def isolated_from_python_environment(meshes):
    """With the user's environment poisoned, the worker still starts, sees no PYTHON* variable and
    gives the in-process result; no __pycache__ appears in the add-on's folder."""
    poison = tempfile.mkdtemp(prefix="qgp_poison_")
    env = poisoned_environment(poison)
    # The poison works: a plain interpreter given PYTHONPATH or PYTHONHOME alone fails.
    for name in ("PYTHONPATH", "PYTHONHOME"):
        plain = subprocess.run([worker.python_executable(), "-c", "import numpy"], capture_output=True,
                               env=dict(os.environ, **{name: env[name]}))
        check(plain.returncode != 0, f"the poisoned {name} breaks a plain interpreter (exit {plain.returncode})")
    vertices, triangles = load(meshes, "bunny.off")
    with binding.Session(vertices, triangles) as session:
        session.set_option("target_faces", 800)
        session.run(binding.JOB_REMESH)
        expected = session.quad_mesh()[1]
    saved = {name: os.environ.get(name) for name in env}
    os.environ.update(env)
    try:
        with worker.WorkerSession(vertices, triangles) as session:
            with open(f"/proc/{session.pid}/environ", "rb") as f:
                names = [entry.split(b"=", 1)[0].decode() for entry in f.read().split(b"\0") if entry]
            check(not [n for n in names if n.startswith("PYTHON")] and "QGP_LIBRARY" in names,
                  "the worker's environment has no PYTHON* variable, and QGP_LIBRARY")
            session.set_option("target_faces", 800)
            session.run(binding.JOB_REMESH)
            quads = session.quad_mesh()[1]
            check(np.array_equal(quads, expected), f"poisoned PYTHONPATH / PYTHONHOME: the worker's {len(quads)} quads "
                                                   "are the in-process result")
    except binding.QGPError as e:
        check(False, f"poisoned PYTHONPATH / PYTHONHOME: the worker runs a job ({e.message[:100]})")
    finally:
        for name, value in saved.items():
            if value is None:
                os.environ.pop(name, None)
            else:
                os.environ[name] = value
        shutil.rmtree(poison, ignore_errors=True)
    found = pycache_dirs(COPY)
    check(not found, f"no __pycache__ under the add-on's folder after worker jobs: {found or 'none'}")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--library", required=True)
    ap.add_argument("--meshes", required=True)
    args = ap.parse_args()
    binding.load_library(args.library)
    same_result_as_in_process(args.meshes)
    native_errors_pass_through()
    for sig in (signal.SIGKILL, signal.SIGSEGV):
        killed_mid_job(args.meshes, sig)
    killed_mid_job(args.meshes, signal.SIGKILL, loopback=True)
    close_during_job_ends_child(args.meshes)
    start_failure()
    isolated_from_python_environment(args.meshes)
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()

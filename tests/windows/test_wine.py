#!/usr/bin/python3
"""The Windows x64 build (scripts/build_windows.sh) under Wine, against the Linux build:
  - the windows-x64 extension zip: its layout, a manifest listing windows-x64 alone, and qgp.dll
    and qgp.exe importing nothing but Windows' own DLLs, qgp.dll exporting the C API alone;
  - tests/windows/capi_job.c, built for both, loads qgp.dll (LoadLibrary) and libqgp.so (dlopen)
    and runs jobs through the C API: every check passes and both make the same quad count;
  - `qgp.exe remesh` on spot, fandisk (sharp edges at 40 degrees) and camelhead (a boundary): a
    valid quad mesh (only quads, every edge on at most two quads and used once in each direction,
    no quad flipped against the input) with the quad count and Euler characteristic of Linux's.
Usage: test_wine.py --windows-build DIR --qgp LINUX_QGP --capi-job LINUX_CAPI_JOB --library LIBQGP --meshes DIR"""
import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
import tomllib
import zipfile
from collections import Counter

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
# DLLs every Windows x64 system has; nothing else may be imported.
WINDOWS_DLLS = {"kernel32.dll", "msvcrt.dll", "user32.dll", "advapi32.dll", "ws2_32.dll", "psapi.dll",
                "bcrypt.dll", "shell32.dll", "ole32.dll"}
RUNS = (("spot.obj", ["--faces", "2000"]), ("fandisk.obj", ["--faces", "2000", "--sharp-angle", "40"]),
        ("camelhead.off", ["--faces", "8000"]))
failures = []


def check(condition, message):
    print(("ok   " if condition else "FAIL ") + message, flush=True)
    if not condition:
        failures.append(message)


def wine(args, **kwargs):
    env = dict(os.environ, WINEDEBUG="-all", WINEPREFIX=os.environ.get("QGP_WINEPREFIX", "/tmp/qgp-wineprefix"))
    return subprocess.run(["wine"] + args, env=env, capture_output=True, text=True, **kwargs)


def pe_imports_and_exports(path):
    out = subprocess.run(["x86_64-w64-mingw32-objdump", "-p", path], capture_output=True, text=True,
                         check=True).stdout
    imports = {m.lower() for m in re.findall(r"DLL Name: (\S+)", out)}
    table = out.split("[Ordinal/Name Pointer] Table", 1)
    exports = re.findall(r"^\s*\[\s*\d+\] (\S+)$", table[1], re.M) if len(table) == 2 else []
    return imports, exports


def audit_zip(zip_path):
    check(os.path.exists(zip_path), f"{os.path.basename(zip_path)} exists")
    if not os.path.exists(zip_path):
        return None
    folder = tempfile.mkdtemp(prefix="qgp_windows_zip_")
    with zipfile.ZipFile(zip_path) as z:
        names = z.namelist()
        z.extractall(folder)
    for required in ("__init__.py", "blender_manifest.toml", "lib/qgp.dll", "core/binding.py", "core/worker.py"):
        check(required in names, f"the windows zip holds {required}")
    with open(os.path.join(folder, "blender_manifest.toml"), "rb") as f:
        check(tomllib.load(f).get("platforms") == ["windows-x64"], "the windows zip's manifest lists windows-x64 alone")
    check(not [n for n in names if n.endswith(".so") or ".so." in n], "the windows zip holds no Linux library")
    return os.path.join(folder, "lib", "qgp.dll")


def audit_binaries(dll, exe):
    for path in (dll, exe):
        imports, exports = pe_imports_and_exports(path)
        check(imports and imports <= WINDOWS_DLLS,
              f"{os.path.basename(path)} imports only Windows' DLLs: {sorted(imports)}")
    exports = pe_imports_and_exports(dll)[1]
    check(len(exports) > 20 and all(name.startswith("qgp_") for name in exports),
          f"qgp.dll exports the C API alone ({len(exports)} qgp_* functions; others: "
          f"{[n for n in exports if not n.startswith('qgp_')][:5]})")


def capi_job(windows_build, dll, linux_capi_job, library):
    windows = wine([os.path.join(windows_build, "bin", "capi_job.exe"), dll], timeout=600)
    linux = subprocess.run([linux_capi_job, library], capture_output=True, text=True, timeout=600)
    for name, run in (("Windows (Wine)", windows), ("Linux", linux)):
        print(run.stdout.rstrip())
        check(run.returncode == 0 and "FAILED" not in run.stdout, f"capi_job on {name}: every check passed")
    last = [run.stdout.strip().splitlines()[-1] if run.stdout.strip() else "" for run in (windows, linux)]
    check(last[0] == last[1] and last[0].startswith("quads "), f"capi_job: the same result on both: {last}")


def read_quads(path):
    vertices, faces = 0, []
    with open(path) as f:
        for line in f:
            if line.startswith("v "):
                vertices += 1
            elif line.startswith("f "):
                faces.append([int(token.split("/")[0]) - 1 for token in line.split()[1:]])
    return vertices, faces


def validity(path):
    """Problems of the quad mesh in `path` (empty: valid), and its Euler characteristic."""
    vertices, faces = read_quads(path)
    problems = []
    if not faces or any(len(face) != 4 for face in faces):
        problems.append("not only quads")
    directed = Counter((face[k], face[(k + 1) % len(face)]) for face in faces for k in range(len(face)))
    undirected = Counter(tuple(sorted(edge)) for edge in directed.elements())
    if any(count > 1 for count in directed.values()):
        problems.append("an edge used twice in one direction (inconsistent orientation or non-manifold)")
    if any(count > 2 for count in undirected.values()):
        problems.append("an edge on more than two quads")
    return problems, vertices - len(undirected) + len(faces)


def remesh(qgp_exe, linux_qgp, meshes, work):
    for name, options in RUNS:
        stem = os.path.splitext(name)[0]
        results = {}
        for system in ("Windows", "Linux"):
            out, report = os.path.join(work, f"{system}_{stem}.obj"), os.path.join(work, f"{system}_{stem}.json")
            args = ["remesh", os.path.join(meshes, name), "-o", out, "--report", report] + options
            if system == "Windows":
                run = wine([qgp_exe] + args, timeout=900)
            else:
                run = subprocess.run([linux_qgp] + args, capture_output=True, text=True, timeout=900)
            if run.returncode != 0 or not os.path.exists(report):
                check(False, f"{name} on {system}: qgp remesh exit {run.returncode}: {run.stderr.strip()[-300:]}")
                break
            with open(report) as f:
                quad = json.load(f)["quad"]
            problems, euler = validity(out)
            results[system] = (quad["faces"], euler, quad["flipped_quads"], problems, quad["hausdorff"])
        if len(results) < 2:
            continue
        (wq, we, wf, wp, wh), (lq, le, lf, lp, lh) = results["Windows"], results["Linux"]
        check(not wp and not lp and wf == 0 and lf == 0,
              f"{name}: valid quad meshes on both (problems: {wp or 'none'} / {lp or 'none'}; flipped {wf} / {lf})")
        check(wq == lq and we == le, f"{name} {' '.join(options)}: {wq} quads on Windows, {lq} on Linux; Euler "
              f"characteristic {we} / {le}; Hausdorff {wh:.5f} / {lh:.5f}")


def main():
    ap = argparse.ArgumentParser()
    for name in ("--windows-build", "--qgp", "--capi-job", "--library", "--meshes"):
        ap.add_argument(name, required=True)
    args = ap.parse_args()
    manifest = tomllib.load(open(os.path.join(ROOT, "blender_manifest.toml"), "rb"))
    subprocess.run(["/usr/bin/python3", os.path.join(ROOT, "scripts", "build_extension.py"), "--platform",
                    "windows-x64", "--build", args.windows_build], check=True)
    dll = audit_zip(os.path.join(ROOT, "dist", f"{manifest['id']}-{manifest['version']}-windows_x64.zip"))
    qgp_exe = os.path.join(args.windows_build, "bin", "qgp.exe")
    if dll:
        audit_binaries(dll, qgp_exe)
        capi_job(args.windows_build, dll, args.capi_job, args.library)
    with tempfile.TemporaryDirectory(prefix="qgp_wine_") as work:
        remesh(qgp_exe, args.qgp, args.meshes, work)
    print(f"{len(failures)} failure(s)")
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()

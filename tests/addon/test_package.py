#!/usr/bin/python3
"""The extension zip and the legacy zip (scripts/build_extension.py): layout, manifest fields,
bl_info, $ORIGIN RUNPATHs, and the bundled library loading and running an intake job with the
system's copies of its dependencies hidden (bind-mounted away in a private mount namespace)."""
import ast
import glob
import os
import re
import subprocess
import sys
import tempfile
import tomllib
import zipfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
failures = []


def check(condition, message):
    if not condition:
        failures.append(message)


def system_copy(name):
    """Real path of the system's copy of a library, if the system has one."""
    out = subprocess.run(["/sbin/ldconfig", "-p"], capture_output=True, text=True).stdout
    for line in out.splitlines():
        parts = line.strip().split(" => ")
        if len(parts) == 2 and parts[0].split(" ")[0] == name and "x86-64" in parts[0]:
            return os.path.realpath(parts[1])
    return None


def main():
    manifest = tomllib.load(open(os.path.join(ROOT, "blender_manifest.toml"), "rb"))
    ident, version = manifest["id"], manifest["version"]
    ext_zip = os.path.join(ROOT, "dist", f"{ident}-{version}-linux_x64.zip")
    legacy_zip = os.path.join(ROOT, "dist", f"{ident}-{version}-legacy.zip")
    check(os.path.exists(ext_zip) and os.path.exists(legacy_zip), "zips missing (run scripts/build_extension.py)")
    if failures:
        return report()

    # Manifest fields (Blender 4.2 extension schema).
    for key in ("schema_version", "id", "version", "name", "tagline", "maintainer", "type",
                "blender_version_min", "license"):
        check(key in manifest, f"manifest lacks {key}")
    check(manifest["type"] == "add-on", "manifest type must be add-on")
    check(manifest["blender_version_min"] == "4.2.0", "blender_version_min must be 4.2.0")
    check(len(manifest["tagline"]) <= 64 and manifest["tagline"][-1] not in ".!?,;:",
          "tagline: <= 64 chars, no trailing punctuation")
    check(all(entry.startswith("SPDX:") for entry in manifest["license"]), "license entries must be SPDX:...")
    check(manifest.get("platforms") == ["linux-x64", "windows-x64"], "platforms must list the zips that exist")
    with zipfile.ZipFile(ext_zip) as z:
        zip_manifest = tomllib.loads(z.read("blender_manifest.toml").decode())
    check(zip_manifest.get("platforms") == ["linux-x64"], "the linux zip's manifest must list linux-x64 alone")
    check(re.fullmatch(r"[a-z][a-z0-9_]*", ident) is not None, "id must be a Python identifier")
    for key, value in manifest.get("permissions", {}).items():
        check(isinstance(value, str) and value and value[-1] not in ".",
              f"permission {key} needs a reason without trailing period")

    with zipfile.ZipFile(ext_zip) as z:
        names = z.namelist()
    for required in ("__init__.py", "blender_manifest.toml", "lib/libqgp.so", "core/binding.py", "core/worker.py",
                     "operators.py", "ui.py", "batch.py"):
        check(required in names, f"extension zip lacks {required} at its root")
    check(not any("__pycache__" in n for n in names), "extension zip contains __pycache__")
    with zipfile.ZipFile(legacy_zip) as z:
        legacy = z.namelist()
        init = z.read(f"{ident}/__init__.py").decode()
    check(all(n.startswith(ident + "/") for n in legacy), "legacy zip must hold one folder named like the id")
    bl_info = next(ast.literal_eval(node.value) for node in ast.parse(init).body
                   if isinstance(node, ast.Assign) and getattr(node.targets[0], "id", "") == "bl_info")
    check(tuple(bl_info["blender"]) >= (3, 0, 0) and bl_info["name"] == manifest["name"], "bl_info for 3.x")
    check(tuple(bl_info["version"]) == tuple(int(x) for x in version.split(".")), "bl_info version = manifest version")

    with tempfile.TemporaryDirectory() as tmp:
        with zipfile.ZipFile(ext_zip) as z:
            z.extractall(tmp)
        lib_dir = os.path.join(tmp, "lib")
        bundled = sorted(os.path.basename(p) for p in glob.glob(os.path.join(lib_dir, "*.so*")))
        for name in bundled:
            dyn = subprocess.run(["readelf", "-d", os.path.join(lib_dir, name)], capture_output=True, text=True).stdout
            check("$ORIGIN" in dyn, f"{name} lacks an $ORIGIN RUNPATH")
        # The interpreter's own libraries stay visible (it could not start otherwise).
        ldd = subprocess.run(["ldd", "/usr/bin/python3"], capture_output=True, text=True).stdout
        interpreter = {os.path.realpath(m) for m in re.findall(r"=> (\S+)", ldd)}
        hidden = [p for p in (system_copy(n) for n in bundled if n != "libqgp.so") if p and p not in interpreter]
        # Pure ctypes (numpy itself needs the system's BLAS, which is hidden here).
        probe = ("import ctypes, json; l = ctypes.CDLL(%r); "
                 "V = (ctypes.c_double * 12)(0,0,0, 1,0,0, 0,1,0, 0,0,1); "
                 "T = (ctypes.c_int32 * 12)(0,2,1, 0,1,3, 1,2,3, 2,0,3); "
                 "s = ctypes.c_void_p(); assert l.qgp_session_create(V, 4, T, 4, ctypes.byref(s)) == 0; "
                 "assert l.qgp_job_start(s, 0) == 0; st = ctypes.c_int(); "
                 "assert l.qgp_job_wait(s, ctypes.c_double(-1), ctypes.byref(st)) == 0; "
                 "n = ctypes.c_int64(); l.qgp_report_json(s, None, 0, ctypes.byref(n)); "
                 "b = ctypes.create_string_buffer(n.value); l.qgp_report_json(s, b, n, ctypes.byref(n)); "
                 "l.qgp_version.restype = ctypes.c_char_p; "
                 "print(l.qgp_version().decode(), json.loads(b.value)['input']['genus'])"
                 % os.path.join(lib_dir, "libqgp.so"))
        env = dict(os.environ)
        env.pop("QGP_LIBRARY", None)
        env.pop("LD_LIBRARY_PATH", None)
        mounts = " && ".join(f"mount --bind /dev/null '{p}'" for p in hidden) or "true"
        cmd = ["unshare", "-m", "sh", "-c", f"{mounts} && exec /usr/bin/python3 -c \"{probe}\""]
        proc = subprocess.run(cmd, capture_output=True, text=True, env=env)
        if proc.returncode != 0 and "unshare" in proc.stderr and "Operation not permitted" in proc.stderr:
            # No mount namespaces here: verify through the loader's own log instead.
            env["LD_DEBUG"] = "libs"
            proc = subprocess.run(["/usr/bin/python3", "-c", probe], capture_output=True, text=True, env=env)
            for path in hidden:
                check(f"init: {path}" not in proc.stderr, f"system copy {path} was loaded")
        check(proc.returncode == 0 and "[0]" in proc.stdout,
              f"bundled library failed with system copies hidden: {proc.stdout} {proc.stderr[-800:]}")
        print(f"bundled {len(bundled)} libraries; hid {len(hidden)} system copies; probe: {proc.stdout.strip()}")
    return report()


def report():
    for f in failures:
        print("FAIL:", f)
    print("package test:", "FAILED" if failures else "OK")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())

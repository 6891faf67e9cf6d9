#!/usr/bin/python3
"""Stages the add-on, the manifest and the native library (with every shared library it needs
beyond glibc / libstdc++ / libgcc / libm / zlib, found through an $ORIGIN RUNPATH) into

    dist/<id>-<version>-linux_x64.zip     Blender 4.2+ extension (manifest and __init__.py at the root)
    dist/<id>-<version>-legacy.zip        Blender 3.x add-on (the same files inside a <id>/ folder)

Run after ./scripts/build_portable.sh:  /usr/bin/python3 scripts/build_extension.py [--build DIR]
The default DIR, build-portable/, holds the library that loads on glibc 2.28 and later; --build build
packages the library of ./scripts/build.sh instead, which loads only where it was built.
"""
import os
import re
import shutil
import subprocess
import sys
import tomllib
import zipfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
# Provided by every Linux system Blender runs on; never bundled.
SYSTEM = re.compile(r"^(linux-vdso|ld-linux|libc\.so|libm\.so|libstdc\+\+|libgcc_s|libpthread|libdl\.so|librt\.so|libz\.so)")


def dependencies(path):
    """Resolved shared-library paths ldd reports for `path` (name -> path)."""
    out = subprocess.run(["ldd", path], capture_output=True, text=True, check=True).stdout
    deps = {}
    for line in out.splitlines():
        m = re.match(r"\s*(\S+) => (\S+)", line)
        if m and m.group(2) != "not":
            deps[m.group(1)] = m.group(2)
        elif "not found" in line:
            sys.exit(f"build_extension: {path}: unresolved dependency: {line.strip()}")
    return deps


def bundle_libraries(library, lib_dir):
    """Copies library and its non-system dependencies (transitively) into lib_dir."""
    os.makedirs(lib_dir, exist_ok=True)
    shutil.copy2(library, os.path.join(lib_dir, os.path.basename(library)))
    bundled = {}
    pending = [library]
    while pending:
        for name, path in dependencies(pending.pop()).items():
            if SYSTEM.match(name) or name in bundled:
                continue
            bundled[name] = path
            shutil.copy2(os.path.realpath(path), os.path.join(lib_dir, name))
            pending.append(path)
    for name in [os.path.basename(library)] + sorted(bundled):
        target = os.path.join(lib_dir, name)
        os.chmod(target, 0o755)
        subprocess.run(["patchelf", "--set-rpath", "$ORIGIN", target], check=True)
    return sorted(bundled)


def main():
    manifest_path = os.path.join(ROOT, "blender_manifest.toml")
    with open(manifest_path, "rb") as f:
        manifest = tomllib.load(f)
    ident, version = manifest["id"], manifest["version"]
    build = sys.argv[sys.argv.index("--build") + 1] if "--build" in sys.argv else os.path.join(ROOT, "build-portable")
    library = os.path.join(build, "lib", "libqgp.so")
    if not os.path.exists(library):
        sys.exit(f"build_extension: {library} is missing; run ./scripts/build_portable.sh first")
    dist = os.path.join(ROOT, "dist")
    stage = os.path.join(dist, "stage", ident)
    shutil.rmtree(os.path.join(dist, "stage"), ignore_errors=True)
    shutil.copytree(os.path.join(ROOT, "addon"), stage,
                    ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
    shutil.copy2(manifest_path, os.path.join(stage, "blender_manifest.toml"))
    bundled = bundle_libraries(library, os.path.join(stage, "lib"))

    files = []
    for folder, _, names in os.walk(stage):
        for name in sorted(names):
            full = os.path.join(folder, name)
            files.append((full, os.path.relpath(full, stage)))
    extension_zip = os.path.join(dist, f"{ident}-{version}-linux_x64.zip")
    legacy_zip = os.path.join(dist, f"{ident}-{version}-legacy.zip")
    for path, prefix in ((extension_zip, ""), (legacy_zip, ident + "/")):
        with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as z:
            for full, rel in files:
                z.write(full, prefix + rel)
    print(f"build_extension: {extension_zip}")
    print(f"build_extension: {legacy_zip}")
    print(f"build_extension: bundled {len(bundled)} libraries: {' '.join(bundled)}")


if __name__ == "__main__":
    main()

#!/usr/bin/python3
"""Stages the add-on, the manifest and the native library into

    dist/<id>-<version>-linux_x64.zip            Blender 4.2+ extension (manifest and __init__.py at the root)
    dist/<id>-<version>-legacy.zip               Blender 3.x add-on (the same files inside a <id>/ folder)

or, with --platform windows-x64,

    dist/<id>-<version>-windows_x64.zip          Blender 4.2+ extension
    dist/<id>-<version>-legacy_windows_x64.zip   Blender 3.x add-on

Each zip's manifest lists its one platform. Linux: run after ./scripts/build_portable.sh
  /usr/bin/python3 scripts/build_extension.py [--build DIR]
The default DIR, build-portable/, holds the library that loads on glibc 2.28 and later (with every
shared library it needs beyond glibc / libstdc++ / libgcc / libm / zlib, found through an $ORIGIN
RUNPATH); --build build packages the library of ./scripts/build.sh instead, which loads only where it
was built. Windows: run after ./scripts/build_windows.sh (the default DIR is build-windows/; qgp.dll
needs no DLL beyond Windows' own).
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


# Per platform: the default build folder, the library in it, the zip names' platform part.
PLATFORMS = {
    "linux-x64": ("build-portable", os.path.join("lib", "libqgp.so"), "linux_x64"),
    "windows-x64": ("build-windows", os.path.join("bin", "qgp.dll"), "windows_x64"),
}


def option(name, default):
    return sys.argv[sys.argv.index(name) + 1] if name in sys.argv else default


def stage_manifest(manifest_path, platform, target):
    """The manifest with `platforms` naming only the zip's own platform."""
    with open(manifest_path) as f:
        text = f.read()
    text, count = re.subn(r"(?m)^platforms = \[.*\]$", f'platforms = ["{platform}"]', text)
    if count != 1:
        sys.exit(f"build_extension: {manifest_path}: no single `platforms = [...]` line")
    with open(target, "w") as f:
        f.write(text)


def write_zips(stage, ident, names):
    files = []
    for folder, _, entries in os.walk(stage):
        for name in sorted(entries):
            full = os.path.join(folder, name)
            files.append((full, os.path.relpath(full, stage)))
    for path, prefix in zip(names, ("", ident + "/")):
        with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as z:
            for full, rel in files:
                z.write(full, prefix + rel)
        print(f"build_extension: {path}")


def main():
    manifest_path = os.path.join(ROOT, "blender_manifest.toml")
    with open(manifest_path, "rb") as f:
        manifest = tomllib.load(f)
    ident, version = manifest["id"], manifest["version"]
    platform = option("--platform", "linux-x64")
    if platform not in PLATFORMS:
        sys.exit(f"build_extension: --platform must be one of {', '.join(PLATFORMS)}")
    default_build, library_path, zip_platform = PLATFORMS[platform]
    library = os.path.join(option("--build", os.path.join(ROOT, default_build)), library_path)
    if not os.path.exists(library):
        script = "build_windows.sh" if platform == "windows-x64" else "build_portable.sh"
        sys.exit(f"build_extension: {library} is missing; run ./scripts/{script} first")
    dist = os.path.join(ROOT, "dist")
    stage = os.path.join(dist, f"stage-{platform}", ident)  # one per platform: both may be built at once
    shutil.rmtree(os.path.dirname(stage), ignore_errors=True)
    shutil.copytree(os.path.join(ROOT, "addon"), stage,
                    ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
    stage_manifest(manifest_path, platform, os.path.join(stage, "blender_manifest.toml"))
    if platform == "windows-x64":
        os.makedirs(os.path.join(stage, "lib"))
        shutil.copy2(library, os.path.join(stage, "lib", "qgp.dll"))
        bundled = []
    else:
        bundled = bundle_libraries(library, os.path.join(stage, "lib"))
    legacy = "legacy" if platform == "linux-x64" else f"legacy_{zip_platform}"
    write_zips(stage, ident, [os.path.join(dist, f"{ident}-{version}-{zip_platform}.zip"),
                              os.path.join(dist, f"{ident}-{version}-{legacy}.zip")])
    print(f"build_extension: bundled {len(bundled)} libraries: {' '.join(bundled)}")


if __name__ == "__main__":
    main()

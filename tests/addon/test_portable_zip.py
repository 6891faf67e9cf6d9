#!/usr/bin/python3
"""Every ELF file in the Linux extension zips loads on glibc 2.28 (Blender's own Linux builds need no
newer): checked with objdump, as issue 25 asks.

For each shared library in dist/*-linux_x64.zip and dist/*-legacy.zip:
  - no symbol version newer than GLIBC_2.28, and no GLIBCXX_ / CXXABI_ version at all (no C++
    runtime is taken from the system; the portable build links libc++ statically);
  - every DT_NEEDED entry is another file of the zip or a library every glibc 2.28 system has;
  - libgcc_s and zlib versions no newer than those of a glibc 2.28 system (RHEL 8: GCC 8, zlib 1.2.11);
  - the RUNPATH is $ORIGIN alone.
Usage: test_portable_zip.py [ZIP...] (default: both zips of blender_manifest.toml's version)."""
import os
import re
import subprocess
import sys
import tempfile
import tomllib
import zipfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SYSTEM_LIBRARIES = {"libc.so.6", "libm.so.6", "libpthread.so.0", "libdl.so.2", "librt.so.1",
                    "ld-linux-x86-64.so.2", "libgcc_s.so.1", "libz.so.1"}
NEWEST = {"GLIBC": (2, 28), "GCC": (8, 0, 0), "ZLIB": (1, 2, 11)}
FORBIDDEN = ("GLIBCXX", "CXXABI")


def version_tuple(text):
    return tuple(int(part) for part in text.split(".") if part.isdigit())


def version_problems(dynamic_symbols):
    """Symbol versions in `objdump -T` output that a glibc 2.28 system cannot satisfy."""
    problems = set()
    for name, number in re.findall(r"\b([A-Z]+)_([0-9][0-9.]*)\b", dynamic_symbols):
        if name in FORBIDDEN:
            problems.add(f"{name}_{number} (no C++ runtime may come from the system)")
        elif name in NEWEST and version_tuple(number) > NEWEST[name]:
            problems.add(f"{name}_{number} (newest allowed: {name}_{'.'.join(map(str, NEWEST[name]))})")
    return sorted(problems)


def dynamic_section(path):
    """(NEEDED names, RUNPATH or None) from `objdump -p`."""
    out = subprocess.run(["objdump", "-p", path], capture_output=True, text=True, check=True).stdout
    needed = re.findall(r"^\s*NEEDED\s+(\S+)", out, re.M)
    runpath = re.findall(r"^\s*(?:RUNPATH|RPATH)\s+(\S+)", out, re.M)
    return needed, (runpath[0] if runpath else None)


def check_zip(path):
    """Problems of one zip's ELF files; also returns how many ELF files it holds."""
    problems, elf_count = [], 0
    with tempfile.TemporaryDirectory() as work, zipfile.ZipFile(path) as archive:
        archive.extractall(work)
        files = {}
        for folder, _, names in os.walk(work):
            for name in names:
                files[name] = os.path.join(folder, name)
        for name, full in sorted(files.items()):
            with open(full, "rb") as f:
                if f.read(4) != b"\x7fELF":
                    continue
            elf_count += 1
            symbols = subprocess.run(["objdump", "-T", full], capture_output=True, text=True, check=True).stdout
            problems += [f"{name}: needs {p}" for p in version_problems(symbols)]
            needed, runpath = dynamic_section(full)
            problems += [f"{name}: needs {lib}, which is neither in the zip nor on every glibc 2.28 system"
                         for lib in needed if lib not in files and lib not in SYSTEM_LIBRARIES]
            if runpath != "$ORIGIN":
                problems.append(f"{name}: RUNPATH {runpath!r}, expected '$ORIGIN'")
    return problems, elf_count


def main():
    zips = sys.argv[1:]
    if not zips:
        manifest = tomllib.load(open(os.path.join(ROOT, "blender_manifest.toml"), "rb"))
        stem = os.path.join(ROOT, "dist", f"{manifest['id']}-{manifest['version']}")
        zips = [stem + "-linux_x64.zip", stem + "-legacy.zip"]
    failed = False
    for path in zips:
        if not os.path.exists(path):
            print(f"{path}: missing (run scripts/build_portable.sh and scripts/build_extension.py)")
            failed = True
            continue
        problems, elf_count = check_zip(path)
        if elf_count == 0:
            problems.append("no shared library in the zip")
        print(f"{os.path.basename(path)}: {elf_count} ELF files, {len(problems)} problems")
        for problem in problems:
            print("  " + problem)
        failed |= bool(problems)
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""Lists the functions in native/src longer than a limit (default 120 lines) that carry no reason.

A long function is allowed when the comment just above its definition says why, in a line that
contains "long because". Lambdas count as part of the function that holds them. Reads the compile
commands of a CMake build (CMAKE_EXPORT_COMPILE_COMMANDS) and parses each source with libclang
(Debian: python3-clang-14). Exit 1 when a function is over the limit.

usage: check_function_length.py [--build build] [--limit 120]
"""
import argparse
import json
import multiprocessing
import os
import shlex
import sys

import clang.cindex as ci

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SOURCE_DIR = os.path.join(ROOT, "native", "src")
FUNCTION_KINDS = {ci.CursorKind.FUNCTION_DECL, ci.CursorKind.CXX_METHOD, ci.CursorKind.CONSTRUCTOR,
                  ci.CursorKind.DESTRUCTOR, ci.CursorKind.FUNCTION_TEMPLATE, ci.CursorKind.CONVERSION_FUNCTION}
CONTAINER_KINDS = {ci.CursorKind.NAMESPACE, ci.CursorKind.CLASS_DECL, ci.CursorKind.STRUCT_DECL,
                   ci.CursorKind.CLASS_TEMPLATE, ci.CursorKind.UNEXPOSED_DECL}


def use_debian_libclang():
    if ci.Config.loaded:
        return
    for path in ("/usr/lib/llvm-14/lib/libclang-14.so.1", "/usr/lib/llvm-14/lib/libclang.so"):
        if os.path.exists(path):
            ci.Config.set_library_file(path)
            return


def parse_flags(command):
    """Include paths, defines and the language standard of one compile command."""
    argv, flags = shlex.split(command)[1:], []
    for i, arg in enumerate(argv):
        if arg == "-isystem":
            flags += [arg, argv[i + 1]]
        elif arg.startswith(("-I", "-D", "-std")):
            flags.append(arg)
    return flags + ["-x", "c++"]


def has_reason(lines, first_line):
    """The comment block ending just above line `first_line` (1-based) says 'long because'."""
    i = first_line - 2
    while i >= 0 and lines[i].strip().startswith("//"):
        if "long because" in lines[i].lower():
            return True
        i -= 1
    return False


def function_definitions(cursor, path):
    for child in cursor.get_children():
        if child.location.file is None or os.path.realpath(child.location.file.name) != path:
            continue
        if child.kind in FUNCTION_KINDS and child.is_definition():
            yield child
        elif child.kind in CONTAINER_KINDS:
            yield from function_definitions(child, path)


def long_functions(job):
    """(lines, file, line, name) of the functions over `limit` in a source and its header."""
    source, flags, limit = job
    use_debian_libclang()
    tu = ci.Index.create().parse(source, args=flags)
    found = []
    for path in (source, source[:-4] + ".h"):
        if not os.path.exists(path):
            continue
        lines = open(path).read().split("\n")
        for d in function_definitions(tu.cursor, path):
            n = d.extent.end.line - d.extent.start.line + 1
            if n > limit and not has_reason(lines, d.extent.start.line):
                found.append((n, os.path.relpath(path, ROOT), d.extent.start.line, d.spelling))
    return found


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--build", default=os.path.join(ROOT, "build"))
    parser.add_argument("--limit", type=int, default=120)
    args = parser.parse_args()
    with open(os.path.join(args.build, "compile_commands.json")) as f:
        commands = json.load(f)
    jobs = {}
    for entry in commands:
        source = os.path.realpath(os.path.join(entry["directory"], entry["file"]))
        if source.startswith(SOURCE_DIR + os.sep) and source.endswith(".cpp"):
            jobs[source] = (source, parse_flags(entry["command"]), args.limit)
    with multiprocessing.Pool() as pool:
        over = sorted({f for found in pool.map(long_functions, jobs.values()) for f in found}, reverse=True)
    for n, path, line, name in over:
        print(f"{path}:{line}: {name} is {n} lines (limit {args.limit}): split it, or say why in a comment "
              f"containing 'long because' just above it")
    print(f"check_function_length: {len(jobs)} sources, {len(over)} function(s) over {args.limit} lines")
    return 1 if over else 0


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/python3
"""The same input and options give byte-identical output, as a user runs `qgp remesh`.

For spot (500 quads), fandisk (sharp edges at 40 degrees, 500 quads), a multi-part mesh that intake
repairs (truck, 500 quads) and a cube of 8 x 8 square quads per side (300 quads; each square's two
diagonals tie): a copy of the file with its faces shuffled and each face's corners rotated (the same surface, in
the order another exporter or a new Blender mesh gives it), a second run of the same file, and a run with
one thread instead of two all write the same quad mesh, byte for byte, as the first run (the header
comment, which names the input file, aside). OMP_NUM_THREADS caps CHOLMOD's and OpenBLAS's threads and
the library's own (core/parallel.h): with two, truck's flip rounds run the trial one ring wider beside
each trial and use it after the trial is not kept; with one, they run each trial in turn.
"""
import argparse
import os
import random
import sys
import tempfile

from cli_checks import check, run, summary

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # tests/: shapes
import shapes  # noqa: E402

CASES = [("spot.obj", 500, []), ("fandisk.obj", 500, ["--sharp-angle", "40"]), ("truck.obj", 500, []),
         ("cube_8x8.obj", 300, [])]


def shuffled_copy(source, target, seed):
    """Writes `source` (an OBJ of v and f lines) with its faces shuffled and each face's corners rotated."""
    vertices, faces = [], []
    for line in open(source):
        t = line.split()
        if t and t[0] == "v":
            vertices.append(line.rstrip("\n"))
        elif t and t[0] == "f":
            faces.append([c.split("/")[0] for c in t[1:]])
    rng = random.Random(seed)
    rng.shuffle(faces)
    with open(target, "w") as out:
        out.write("\n".join(vertices) + "\n")
        for f in faces:
            k = rng.randrange(len(f))
            out.write("f " + " ".join(f[k:] + f[:k]) + "\n")
    return len(faces)


def remesh(qgp, mesh, target, extra, out, threads):
    """(exit status, the written OBJ without its comment lines) of one run with `threads` threads."""
    env = dict(os.environ, OMP_NUM_THREADS=str(threads))
    r = run(qgp, "remesh", mesh, "--faces", target, "-o", out, *extra, env=env)
    if not os.path.exists(out):
        return r.returncode, b""
    return r.returncode, b"".join(line for line in open(out, "rb") if not line.startswith(b"#"))


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--qgp", required=True)
    parser.add_argument("--meshes", required=True)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        shapes.write_obj(os.path.join(tmp, "cube_8x8.obj"), *shapes.grid_cube(8))
        for name, target, extra in CASES:
            mesh = os.path.join(args.meshes if os.path.exists(os.path.join(args.meshes, name)) else tmp, name)
            rc, first = remesh(args.qgp, mesh, target, extra, os.path.join(tmp, "first.obj"), threads=2)
            check(rc == 0 and first.count(b"\nf ") > 0, f"{name}: remeshed (exit {rc})")
            rc, again = remesh(args.qgp, mesh, target, extra, os.path.join(tmp, "again.obj"), threads=2)
            check(rc == 0 and again == first, f"{name}: a second run writes the same bytes")
            rc, single = remesh(args.qgp, mesh, target, extra, os.path.join(tmp, "single.obj"), threads=1)
            check(rc == 0 and single == first, f"{name}: one thread writes the same bytes as two")
            copy = os.path.join(tmp, "shuffled.obj")
            faces = shuffled_copy(mesh, copy, seed=len(name))
            rc, shuffled = remesh(args.qgp, copy, target, extra, os.path.join(tmp, "shuffled_out.obj"), threads=2)
            check(rc == 0 and shuffled == first,
                  f"{name}: its {faces} faces shuffled and rotated give the same bytes")
    return summary()


if __name__ == "__main__":
    sys.exit(main())

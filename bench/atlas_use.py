"""Texture use of `qgp remesh --atlas-out` beside Blender's Smart UV Project + Pack Islands on the
same quads (issue 26).

    /usr/bin/python3 bench/atlas_use.py [--qgp build/bin/qgp] [--mesh-dir ../shared/meshes]
        [--faces 2000] [--texture-size 1024] [--out bench/results]

Per mesh, `qgp remesh IN --faces N --atlas-out A.obj --texture-size S` writes the quads with the
atlas; Blender (Debian's binary, headless) reads A.obj, replaces its UVs by Smart UV Project (66°,
island margin 2 texels) and Pack Islands, and writes it again. Both UV layouts are rasterized at
S x S texels (a texel counts when its centre lies in a face): used = texels covered once / all,
overlap = texels covered more than once / all. Suzanne is written by scripts/make_suzanne.py.
Writes OUT/atlas_use.md. Figures, not checks.
"""
import argparse
import os
import subprocess
import sys
import tempfile

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)
MESHES = [("spot.obj", []), ("bunny.off", []), ("fandisk.obj", ["--sharp-angle", "40"]), ("suzanne", []),
          ("truck.obj", [])]
SMART_UV = """
import sys, bpy
src, dst, margin = sys.argv[sys.argv.index("--") + 1:][:3]
bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.wm.obj_import(filepath=src)
obj = bpy.context.selected_objects[0]
bpy.context.view_layer.objects.active = obj
bpy.ops.object.mode_set(mode="EDIT")
bpy.ops.mesh.select_all(action="SELECT")
bpy.ops.uv.smart_project(angle_limit=1.15192, island_margin=float(margin))
bpy.ops.uv.pack_islands(margin=float(margin))
bpy.ops.object.mode_set(mode="OBJECT")
bpy.ops.wm.obj_export(filepath=dst, export_selected_objects=True, export_uv=True, export_normals=False,
                      export_materials=False, apply_modifiers=False)
"""


def read_uv_faces(path):
    """Per face the UVs of its corners (faces without vt skipped)."""
    vt, faces = [], []
    for line in open(path):
        parts = line.split()
        if parts and parts[0] == "vt":
            vt.append((float(parts[1]), float(parts[2])))
        elif parts and parts[0] == "f" and all("/" in p and p.split("/")[1] for p in parts[1:]):
            faces.append([vt[int(p.split("/")[1]) - 1] for p in parts[1:]])
    return faces


def coverage(faces, size):
    """Texels (size x size) covered once and more than once, by texel centres inside faces."""
    count = np.zeros((size, size), np.int32)
    for face in faces:
        uv = np.array(face) * size
        lo = np.clip(np.floor(uv.min(axis=0) - 0.5).astype(int), 0, size - 1)
        hi = np.clip(np.ceil(uv.max(axis=0) - 0.5).astype(int), 0, size - 1)
        xs, ys = np.meshgrid(np.arange(lo[0], hi[0] + 1) + 0.5, np.arange(lo[1], hi[1] + 1) + 0.5)
        inside = np.zeros(xs.shape, bool)
        for k in range(1, len(uv) - 1):  # the face as a fan of triangles; a centre counts once per face
            inside |= in_triangle(xs, ys, uv[0], uv[k], uv[k + 1])
        count[lo[1]:hi[1] + 1, lo[0]:hi[0] + 1] += inside
    return float((count == 1).sum()) / size ** 2, float((count > 1).sum()) / size ** 2


def in_triangle(xs, ys, a, b, c):
    area = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
    if area == 0:
        return np.zeros(xs.shape, bool)
    w0 = ((b[0] - xs) * (c[1] - ys) - (b[1] - ys) * (c[0] - xs)) / area
    w1 = ((c[0] - xs) * (a[1] - ys) - (c[1] - ys) * (a[0] - xs)) / area
    return (w0 >= 0) & (w1 >= 0) & (w0 + w1 <= 1)


def mesh_path(name, mesh_dir, tmp):
    if name != "suzanne":
        return os.path.join(mesh_dir, name)
    path = os.path.join(tmp, "suzanne.obj")
    subprocess.run(["blender", "-b", "--factory-startup", "--python", os.path.join(REPO, "scripts", "make_suzanne.py"),
                    "--", path], check=True, capture_output=True)
    return path


def measure(name, extra, args, tmp):
    atlas = os.path.join(tmp, name + "_atlas.obj")
    proc = subprocess.run([args.qgp, "remesh", mesh_path(name, args.mesh_dir, tmp), "-o", os.path.join(tmp, "q.obj"),
                           "--faces", str(args.faces), "--atlas-out", atlas, "--texture-size", str(args.texture_size),
                           *extra], capture_output=True, text=True)
    if proc.returncode != 0:
        return [name, f"exit {proc.returncode}: {proc.stderr.strip()[:80]}"]
    charts = next(line for line in proc.stdout.splitlines() if line.startswith("atlas: "))
    smart = os.path.join(tmp, name + "_smart.obj")
    script = os.path.join(tmp, "smart_uv.py")
    with open(script, "w") as f:
        f.write(SMART_UV)
    subprocess.run(["blender", "-b", "--factory-startup", "--python-exit-code", "1", "--python", script, "--", atlas,
                    smart, str(2.0 / args.texture_size)], check=True, capture_output=True)
    ours, theirs = coverage(read_uv_faces(atlas), args.texture_size), coverage(read_uv_faces(smart), args.texture_size)
    return [name, charts[len("atlas: "):], f"{100 * ours[0]:.1f} %", f"{100 * ours[1]:.2f} %",
            f"{100 * theirs[0]:.1f} %", f"{100 * theirs[1]:.2f} %"]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--qgp", default=os.path.join(REPO, "build", "bin", "qgp"))
    ap.add_argument("--mesh-dir", default=os.path.join(os.path.dirname(REPO), "shared", "meshes"))
    ap.add_argument("--faces", type=int, default=2000)
    ap.add_argument("--texture-size", type=int, default=1024)
    ap.add_argument("--out", default=os.path.join(HERE, "results"))
    args = ap.parse_args()
    header = ["mesh", "qgp atlas", "qgp used", "qgp overlap", "Smart UV used", "Smart UV overlap"]
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for name, extra in MESHES:
            rows.append(measure(name, extra, args, tmp))
            print(" | ".join(rows[-1]), flush=True)
    lines = [f"Texture use at {args.faces} quads, {args.texture_size}² texels (bench/atlas_use.py)", "",
             "| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(r + [""] * (len(header) - len(r))) + " |" for r in rows]
    os.makedirs(args.out, exist_ok=True)
    with open(os.path.join(args.out, "atlas_use.md"), "w") as f:
        f.write("\n".join(lines) + "\n")
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())

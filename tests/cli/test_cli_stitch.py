#!/usr/bin/python3
"""`qgp stitch` as a user runs it after `qgp remesh --atlas-out`.

Each atlas (spot and fandisk with sharp edges at 500 quads, a 512 x 512 texture; spot again with
--mip-levels 2) is painted here as an 8-bit PNG: every texel inside a quad gets a smooth colour of the
surface point at its centre, the rest stays black. After `qgp stitch`: texels inside quads are
unchanged, and bilinear samples at 1 000 random seam points (not within a texel of an irregular or
boundary vertex) read from the two sides of the seam differ by at most 1/255, at every mip level the
atlas keeps seam-free (box-filtered here). Then the refusals: an OBJ without vt (exit 1), a missing
image (exit 2), an unwritable output (exit 1); an atlas whose seams are not texel-aligned (spot's own
UVs) is filled as borders there, with a warning. --uv-atlas-out (the integer-grid map's triangles with an
atlas): vt in [0,1], every seam texel-aligned.
"""
import argparse
import json
import os
import random
import sys
import tempfile

import numpy as np
from PIL import Image

from cli_checks import check, run, summary


def read_atlas(path):
    """Vertices (n x 3), vt (m x 2), quads as lists of (vertex, vt) pairs."""
    v, vt, faces = [], [], []
    for line in open(path):
        t = line.split()
        if t and t[0] == "v":
            v.append([float(x) for x in t[1:4]])
        elif t and t[0] == "vt":
            vt.append([float(x) for x in t[1:3]])
        elif t and t[0] == "f":
            faces.append([tuple(int(x) - 1 for x in c.split("/")[:2]) for c in t[1:]])
    return np.array(v), np.array(vt), faces


def paint(v, vt, faces, size, k):
    """An RGB float image (row 0 at v = 0): smooth colours of the surface inside each quad's K x K texels."""
    image = np.zeros((size, size, 3))
    scale = np.linalg.norm(v.max(0) - v.min(0))
    i, j = np.meshgrid(np.arange(k) + 0.5, np.arange(k) + 0.5, indexing="ij")
    a, b = (i / k).ravel(), (j / k).ravel()
    for f in faces:
        p = [v[c[0]] for c in f]
        o, s = vt[f[0][1]] * size, vt[f[1][1]] * size - vt[f[0][1]] * size
        t = np.array([-s[1], s[0]])
        x = np.floor(o[0] + a * s[0] + b * t[0]).astype(int)
        y = np.floor(o[1] + a * s[1] + b * t[1]).astype(int)
        pos = (np.outer((1 - a) * (1 - b), p[0]) + np.outer(a * (1 - b), p[1]) + np.outer(a * b, p[2])
               + np.outer((1 - a) * b, p[3]))
        for ch in range(3):
            image[y, x, ch] = 0.5 + 0.5 * np.sin(25 * pos[:, ch] / scale + 6 * pos[:, (ch + 1) % 3] / scale + ch)
    return image


def save_png(path, image):
    Image.fromarray(np.round(np.clip(image, 0, 1) * 255).astype(np.uint8)[::-1]).save(path)


def load_png(path):
    return np.asarray(Image.open(path).convert("RGB"), dtype=float)[::-1] / 255


def bilinear(image, u, w):
    h, wd = image.shape[:2]
    x, y = u * wd - 0.5, w * h - 0.5
    x0, y0 = int(np.floor(x)), int(np.floor(y))
    fx, fy = x - x0, y - y0

    def at(xi, yi):
        return image[min(max(yi, 0), h - 1), min(max(xi, 0), wd - 1)]
    return ((1 - fx) * (1 - fy) * at(x0, y0) + fx * (1 - fy) * at(x0 + 1, y0)
            + (1 - fx) * fy * at(x0, y0 + 1) + fx * fy * at(x0 + 1, y0 + 1))


def seams(faces):
    """(vt of the side's start, end, vt of the other side's start, end, the two vertices) per seam side."""
    side = {}
    for f in faces:
        for i in range(4):
            side[(f[i][0], f[(i + 1) % 4][0])] = (f[i][1], f[(i + 1) % 4][1])
    out = []
    for (a, b), (ta, tb) in side.items():
        other = side.get((b, a))
        if other and (ta, tb) != (other[1], other[0]) and a < b:
            out.append((ta, tb, other[1], other[0], a, b))
    return out


def special_vertices(faces):
    """Vertices with other than 4 quads or on the boundary."""
    count, sides = {}, set()
    for f in faces:
        for i in range(4):
            count[f[i][0]] = count.get(f[i][0], 0) + 1
            sides.add((f[i][0], f[(i + 1) % 4][0]))
    boundary = {a for a, b in sides if (b, a) not in sides} | {b for a, b in sides if (b, a) not in sides}
    return {x for x, n in count.items() if n != 4} | boundary


def largest_seam_difference(image, vt, faces, edge_texels):
    rng = random.Random(3)
    seam_list, special = seams(faces), special_vertices(faces)
    largest, samples = 0.0, 0
    while samples < 1000:
        ta, tb, oa, ob, a, b = seam_list[rng.randrange(len(seam_list))]
        s = rng.random()
        if (a in special and s * edge_texels < 1) or (b in special and (1 - s) * edge_texels < 1):
            continue
        one = bilinear(image, *(vt[ta] * (1 - s) + vt[tb] * s))
        other = bilinear(image, *(vt[oa] * (1 - s) + vt[ob] * s))
        largest = max(largest, float(np.abs(one - other).max()))
        samples += 1
    return largest


def stitch_case(qgp, meshes, tmp, name, extra):
    mesh, size = os.path.join(meshes, name), 512
    atlas, png, out, report = (os.path.join(tmp, n) for n in ("atlas.obj", "baked.png", "stitched.png", "r.json"))
    proc = run(qgp, "remesh", mesh, "-o", os.path.join(tmp, "q.obj"), "--faces", 500, "--atlas-out", atlas,
               "--texture-size", size, "--report", report, *extra)
    check(proc.returncode == 0, f"{name} {extra}: remesh --atlas-out exit 0 ({proc.stderr.strip()[-200:]})")
    r = json.load(open(report))["atlas"]
    v, vt, faces = read_atlas(atlas)
    painted = paint(v, vt, faces, size, r["texels_per_quad"])
    save_png(png, painted)
    proc = run(qgp, "stitch", atlas, png, "-o", out, "--report", report)
    s = json.load(open(report))["stitch"] if proc.returncode == 0 else {}
    check(proc.returncode == 0 and s.get("seam_edges") == r["seam_edges"] and s.get("unmatched_seam_edges") == 0
          and "stitched" in proc.stdout, f"{name}: stitch exit 0, every seam edge stitched ({s})")
    before, after = load_png(png), load_png(out)
    inside = painted.any(axis=2)
    check(np.array_equal(before[inside], after[inside]), f"{name}: texels inside quads unchanged")
    level, worst = after, []
    for lv in range(r["mip_levels"] + 1):
        worst.append(largest_seam_difference(level, vt, faces, r["texels_per_quad"] / 2 ** lv))
        h, w = level.shape[0] // 2, level.shape[1] // 2
        level = level[:2 * h, :2 * w].reshape(h, 2, w, 2, 3).mean(axis=(1, 3))
    unstitched = largest_seam_difference(before, vt, faces, r["texels_per_quad"])
    check(max(worst) <= 1 / 255 and unstitched > 1 / 255,
          f"{name}: seam differences {worst} per mip level (<= 1/255), {unstitched:.4f} unstitched")
    return r


def test_stitch(qgp, meshes, tmp):
    stitch_case(qgp, meshes, tmp, "spot.obj", [])
    stitch_case(qgp, meshes, tmp, "fandisk.obj", ["--sharp-angle", 40])
    r = stitch_case(qgp, meshes, tmp, "spot.obj", ["--mip-levels", 2])
    k = r["texels_per_quad"]
    check(k >= 4 and k & (k - 1) == 0 and r["gutter"] % 8 == 0,
          f"--mip-levels 2: texels per quad a power of two >= 4 ({k}), gutter a multiple of 8 ({r['gutter']})")


def test_uv_atlas(qgp, meshes, tmp):
    """--uv-atlas-out: the integer-grid map's triangles with an atlas: vt in [0,1], and every seam texel-aligned
    (qgp stitch matches them all)."""
    atlas, report, png = (os.path.join(tmp, n) for n in ("uv_atlas.obj", "uv.json", "blank.png"))
    proc = run(qgp, "remesh", os.path.join(meshes, "camelhead.off"), "-o", os.path.join(tmp, "q.obj"), "--faces", 1000,
               "--uv-atlas-out", atlas, "--texture-size", 512, "--report", report)
    r = json.load(open(report)).get("uv_atlas", {})
    check(proc.returncode == 0 and r.get("charts", 0) >= 1 and "uv atlas: " in proc.stdout,
          f"--uv-atlas-out: exit 0, the report's uv_atlas {r}")
    vt = [tuple(map(float, line.split()[1:3])) for line in open(atlas) if line.startswith("vt ")]
    check(vt and all(0 <= u <= 1 and 0 <= v <= 1 for u, v in vt), f"--uv-atlas-out: {len(vt)} vt, all in [0,1]")
    save_png(png, np.zeros((512, 512, 3)))
    proc = run(qgp, "stitch", atlas, png, "-o", os.path.join(tmp, "stitched.png"), "--report", report)
    s = json.load(open(report)).get("stitch", {})
    check(proc.returncode == 0 and s.get("unmatched_seam_edges") == 0 and s.get("seam_edges") == r.get("seam_edges"),
          f"--uv-atlas-out: every seam maps texels onto texels ({s})")


def test_refusals(qgp, meshes, tmp):
    png = os.path.join(tmp, "baked.png")
    save_png(png, np.zeros((8, 8, 3)))
    proc = run(qgp, "stitch", os.path.join(meshes, "fandisk.obj"), png, "-o", os.path.join(tmp, "o.png"))
    check(proc.returncode == 1 and "no texture coordinates" in proc.stderr, f"no vt: exit 1 ({proc.stderr.strip()})")
    proc = run(qgp, "stitch", os.path.join(meshes, "spot.obj"), png, "-o", os.path.join(tmp, "o.png"))
    check(proc.returncode == 0 and "do not map texels onto texels" in proc.stdout,
          f"spot's own UVs (not a grid atlas): exit 0 with a warning ({proc.stdout.strip()})")
    proc = run(qgp, "stitch", os.path.join(tmp, "atlas.obj"), os.path.join(tmp, "missing.png"), "-o", png)
    check(proc.returncode == 2 and "missing.png" in proc.stderr, f"missing image: exit 2 ({proc.stderr.strip()})")
    proc = run(qgp, "stitch", os.path.join(tmp, "atlas.obj"), png, "-o", os.path.join(tmp, "no", "such", "o.png"))
    check(proc.returncode == 1 and "cannot write" in proc.stderr, f"unwritable output: exit 1 ({proc.stderr.strip()})")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--qgp", required=True)
    ap.add_argument("--meshes", required=True)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        for test in (test_stitch, test_uv_atlas, test_refusals):
            print(f"== {test.__name__}")
            test(args.qgp, args.meshes, tmp)
    return summary()


if __name__ == "__main__":
    sys.exit(main())

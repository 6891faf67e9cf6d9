#!/usr/bin/python3
"""Every `qgp` option and exit code, as a batch user meets them.

Exit codes: 0 success, 1 bad command line, a features file that says nothing usable or an output
that cannot be written, 2 unusable input (also with --uv-out / --layout-out asked), 3 a stage
failed, 5 complete except named parts. Outputs are read back: the -o quad mesh (only quads,
edge-manifold, the input's Euler characteristic, as many faces as the report says), the
--layout-out polylines (one per T-edge),
features from --sharp-angle and --features (counted here independently from the input's dihedral
angles), --edge-length, --quantizer, --refuse-non-manifold with --drop-bad-components, the report's
peak memory (the run's own, not its parent's), and the welding of a triangle soup (--no-weld), a
many-part mesh some of whose parts' layouts give no quads (rescued, exit 0), a non-orientable part
(exit 5, kept as triangles), and --atlas-out's texture atlas.
"""
import argparse
import json
import math
import os
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # tests/: shapes
from shapes import grid_cube, moebius_strip, write_obj  # noqa: E402
from test_cli_uv_out import read_obj as read_obj_vt  # noqa: E402
from cli_checks import check, run, summary  # noqa: E402


def read_obj(path):
    """Vertices and faces (0-based index lists) of an OBJ; `l` polylines separately."""
    vertices, faces, lines = [], [], []
    for line in open(path):
        parts = line.split()
        if not parts:
            continue
        if parts[0] == "v":
            vertices.append(tuple(map(float, parts[1:4])))
        elif parts[0] == "f":
            faces.append([int(p.split("/")[0]) - 1 for p in parts[1:]])
        elif parts[0] == "l":
            lines.append([int(p) - 1 for p in parts[1:]])
    return vertices, faces, lines


def edge_faces(faces):
    count = {}
    for f in faces:
        for i in range(len(f)):
            a, b = f[i], f[(i + 1) % len(f)]
            count.setdefault((min(a, b), max(a, b)), []).append(f)
    return count


def sharp_edges(vertices, faces, degrees):
    """Edges of a triangle mesh whose two face normals differ by more than `degrees`."""
    def normal(f):
        a, b, c = (vertices[i] for i in f)
        u = [b[k] - a[k] for k in range(3)]
        v = [c[k] - a[k] for k in range(3)]
        n = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]
        length = math.sqrt(sum(x * x for x in n))
        return [x / length for x in n]
    sharp = []
    for edge, fs in edge_faces(faces).items():
        if len(fs) == 2:
            n1, n2 = normal(fs[0]), normal(fs[1])
            cos = max(-1.0, min(1.0, sum(a * b for a, b in zip(n1, n2))))
            if math.degrees(math.acos(cos)) > degrees:
                sharp.append(edge)
    return sharp


def test_usage_errors(qgp, meshes, tmp):
    spot = os.path.join(meshes, "spot.obj")
    out = os.path.join(tmp, "never.obj")
    for args, what in [((), "no command"), (("remesh", spot), "no -o"),
                       (("remesh", spot, "-o", out, "--bogus"), "unknown option"),
                       (("remesh", spot, "-o", out, "--faces", 100, "--edge-length", 0.1), "both sizes"),
                       (("remesh", spot, "-o", out, "--quantizer", "magic"), "unknown quantizer"),
                       (("remesh", spot, "-o", out, "--sharp-angle", 200), "sharp angle above 180"),
                       (("remesh", spot, "-o", out, "--adaptive", 2), "adaptive size above 1"),
                       (("remesh", spot, "-o", out, "--faces", "many"), "a word for a number"),
                       (("remesh", spot, "-o", out, "--symmetry", "xw"), "an unknown symmetry plane"),
                       (("remesh", spot, "-o", out, "--symmetry", "x", "--uv-out", out + ".uv.obj"),
                        "symmetry with the map of the input's triangles"),
                       (("frobnicate", spot), "unknown command")]:
        proc = run(qgp, *args)
        check(proc.returncode == 1 and proc.stderr.startswith("qgp: "), f"usage error ({what}): exit 1 with a reason")
    check(not os.path.exists(out), "a usage error writes nothing")
    for args in (("--help",), ("remesh", "--help"), ("info", "--help")):
        proc = run(qgp, *args)
        check(proc.returncode == 0 and "Usage" in proc.stdout, f"qgp {' '.join(args)}: exit 0 with the usage")


def test_unusable_input(qgp, tmp):
    bad = os.path.join(tmp, "nan.obj")
    with open(bad, "w") as f:
        f.write("v 0 0 0\nv 1 0 0\nv 0 nan 0\nf 1 2 3\n")
    for extra in ([], ["--uv-out", os.path.join(tmp, "uv.obj")], ["--layout-out", os.path.join(tmp, "l.obj")]):
        report = os.path.join(tmp, "nan.json")
        proc = run(qgp, "remesh", bad, "-o", os.path.join(tmp, "nan_quads.obj"), "--report", report, *extra)
        r = json.load(open(report))
        check(proc.returncode == 2 and r["status"] == "error" and r["error"]["code"] == "invalid_mesh",
              f"NaN coordinate {' '.join(extra[:1])}: exit 2, error report")
    proc = run(qgp, "remesh", os.path.join(tmp, "missing.obj"), "-o", os.path.join(tmp, "m.obj"))
    check(proc.returncode == 2, "missing input file: exit 2")
    check(not os.path.exists(os.path.join(tmp, "nan_quads.obj")), "no quad mesh written for unusable input")


def test_stage_failure(qgp, meshes, tmp):
    # Direct rounding folds joint's layout at 600 quads: the round baseline is refused with its reason.
    out, report = os.path.join(tmp, "round.obj"), os.path.join(tmp, "round.json")
    proc = run(qgp, "remesh", os.path.join(meshes, "joint.obj"), "-o", out, "--faces", 600, "--quantizer", "round",
               "--report", report)
    r = json.load(open(report))
    check(proc.returncode == 3 and r["error"]["code"] == "stage_failed" and "round" in r["error"]["message"],
          f"joint with --quantizer round: exit 3, stage_failed ({proc.stderr.strip()[:80]})")
    check(not os.path.exists(out), "a failed stage writes no quad mesh")


def test_remesh_outputs(qgp, meshes, tmp):
    out, report, layout = (os.path.join(tmp, n) for n in ("spot.obj", "spot.json", "spot_layout.obj"))
    proc = run(qgp, "remesh", os.path.join(meshes, "spot.obj"), "-o", out, "--faces", 500, "--report", report,
               "--layout-out", layout)
    check(proc.returncode == 0, f"spot at 500 quads: exit 0 ({proc.stderr.strip()[:80]})")
    r = json.load(open(report))
    vertices, faces, _ = read_obj(out)
    check(all(len(f) == 4 for f in faces), "-o: every face a quad")
    check(len(faces) == r["quad"]["faces"] == r["quantization"]["quads_expected"],
          "-o: as many quads as the report says")
    check(all(0 <= i < len(vertices) for f in faces for i in f), "-o: indices in range")
    edges = edge_faces(faces)
    check(all(len(fs) == 2 for fs in edges.values()), "-o: closed and edge-manifold (spot is closed)")
    check(len(vertices) - len(edges) + len(faces) == 2, "-o: Euler characteristic 2, as spot's")
    _, _, lines = read_obj(layout)
    check(len(lines) == r["tmesh"]["edges"], f"--layout-out: one polyline per T-edge ({len(lines)})")
    # An output that cannot be written (here the report, in a missing folder): exit 1, the quads written.
    out2 = os.path.join(tmp, "spot2.obj")
    proc = run(qgp, "remesh", os.path.join(meshes, "spot.obj"), "-o", out2, "--faces", 500,
               "--report", os.path.join(tmp, "missing", "r.json"))
    check(proc.returncode == 1 and "cannot write report" in proc.stderr and os.path.exists(out2),
          "unwritable --report: exit 1 with the reason, the quads still written")


def test_edge_length(qgp, meshes, tmp):
    report = os.path.join(tmp, "edge.json")
    proc = run(qgp, "remesh", os.path.join(meshes, "spot.obj"), "-o", os.path.join(tmp, "edge.obj"),
               "--edge-length", 0.05, "--report", report)
    r = json.load(open(report))
    check(proc.returncode == 0 and r["seamless"]["edge_length"] == 0.05, "--edge-length: the map is solved for it")


def test_quad_count(qgp, meshes, tmp):
    """--faces: within 5 % of the count asked (bunny.off and fandisk at 40 degrees, 1 000 quads);
    below the fewest the layout allows (a cube asked 3: one quad per side), that many quads and a
    note naming the minimum."""
    for name, extra in (("bunny.off", []), ("fandisk.obj", ["--sharp-angle", 40])):
        out = os.path.join(tmp, "count.obj")
        proc = run(qgp, "remesh", os.path.join(meshes, name), "-o", out, "--faces", 1000, *extra)
        quads = sum(1 for line in open(out) if line.startswith("f ")) if proc.returncode == 0 else 0
        check(abs(quads - 1000) <= 50 and "note:" not in proc.stdout,
              f"{name} {' '.join(map(str, extra))} --faces 1000: {quads} quads, within 5 %")
    cube, report = os.path.join(tmp, "cube.obj"), os.path.join(tmp, "count.json")
    write_obj(cube, *grid_cube(6))
    proc = run(qgp, "remesh", cube, "-o", os.path.join(tmp, "few.obj"), "--faces", 3, "--report", report)
    count = json.load(open(report))["quantization"]["count"] if proc.returncode == 0 else {}
    check(proc.returncode == 0 and count.get("fewest_quads") == 6 == count["quads"]
          and "note: 3 quads asked, 6 made: 6 is the fewest this layout allows" in proc.stdout,
          f"cube --faces 3: exit 0, 6 quads, the fewest named on stdout ({proc.stdout.strip()[-160:]})")


def test_symmetry(qgp, meshes, tmp):
    """--symmetry: spot about x (its plane of symmetry) and the block about x, y and z (sharp edges at
    40 degrees) give quads whose every vertex has its mirror image among the vertices, exactly, and
    no open edge; fandisk lies on the negative side of z = 0: refused, naming the plane."""
    for name, axes, extra in (("spot.obj", "x", []), ("block.obj", "xyz", ["--sharp-angle", 40])):
        out, report = os.path.join(tmp, "symmetric.obj"), os.path.join(tmp, "symmetric.json")
        proc = run(qgp, "remesh", os.path.join(meshes, name), "-o", out, "--faces", 1000, "--symmetry", axes,
                   "--report", report, *extra)
        vertices, faces, _ = read_obj(out) if proc.returncode == 0 else ([], [], [])
        points = set(vertices)
        images = [tuple(-c if "xyz"[i] == axis else c for i, c in enumerate(v)) for axis in axes for v in vertices]
        open_edges = [e for e, fs in edge_faces(faces).items() if len(fs) == 1]
        symmetry = json.load(open(report)).get("symmetry", {}) if proc.returncode == 0 else {}
        check(proc.returncode == 0 and faces and all(image in points for image in images) and not open_edges
              and symmetry.get("axes") == axes and abs(len(faces) - 1000) <= 50,
              f"{name} --symmetry {axes}: {len(faces)} quads, every mirror image a vertex, no open edge ({symmetry})")
    proc = run(qgp, "remesh", os.path.join(meshes, "fandisk.obj"), "-o", os.path.join(tmp, "none.obj"),
               "--symmetry", "z")
    check(proc.returncode != 0 and "positive side of z = 0" in proc.stderr,
          f"fandisk --symmetry z: refused, naming the plane ({proc.stderr.strip()[-160:]})")


def read_off_vertices(path):
    tokens = open(path).read().split()
    count = int(tokens[1])
    return [tuple(map(float, tokens[4 + 3 * i:7 + 3 * i])) for i in range(count)]


def mean_edge(vertices, faces, keep):
    """Mean length of the faces' edges whose midpoint passes keep(midpoint)."""
    lengths = []
    for f in faces:
        for a, b in zip(f, f[1:] + f[:1]):
            mid = [(p + q) / 2 for p, q in zip(vertices[a], vertices[b])]
            if keep(mid):
                lengths.append(sum((p - q) ** 2 for p, q in zip(vertices[a], vertices[b])) ** 0.5)
    return sum(lengths) / len(lengths)


def test_sizing(qgp, meshes, tmp):
    """--adaptive and --density: bunny.off adaptive 1 within 5 % of 1 000 quads; painted 3 above its
    median height, the quads there are shorter than below; a density file with the wrong count or a
    word is refused, naming what is wrong."""
    bunny = os.path.join(meshes, "bunny.off")
    out = os.path.join(tmp, "sized.obj")
    proc = run(qgp, "remesh", bunny, "-o", out, "--faces", 1000, "--adaptive", 1)
    quads = sum(1 for line in open(out) if line.startswith("f ")) if proc.returncode == 0 else 0
    check(abs(quads - 1000) <= 50, f"bunny --adaptive 1: {quads} quads, within 5 % of 1 000")
    heights = sorted(v[2] for v in read_off_vertices(bunny))
    middle = heights[len(heights) // 2]
    density = os.path.join(tmp, "density.txt")
    with open(density, "w") as f:
        f.write("# bunny: 3 above the median height\n")
        f.writelines("3\n" if v[2] > middle else "1\n" for v in read_off_vertices(bunny))
    proc = run(qgp, "remesh", bunny, "-o", out, "--faces", 1000, "--density", density)
    vertices, faces, _ = read_obj(out) if proc.returncode == 0 else ([], [], [])
    ratio = (mean_edge(vertices, faces, lambda m: m[2] > middle) / mean_edge(vertices, faces, lambda m: m[2] < middle)
             if faces else 1.0)
    check(proc.returncode == 0 and ratio < 0.85 and abs(len(faces) - 1000) <= 50,
          f"bunny --density (3 above the median): {len(faces)} quads, edges above / below {ratio:.2f}")
    for content, expected in (("1\n2\n", "give one per vertex"), ("1\nmany\n", "line 2: expected a number")):
        with open(density, "w") as f:
            f.write(content)
        proc = run(qgp, "remesh", bunny, "-o", out, "--density", density)
        check(proc.returncode != 0 and expected in proc.stderr, f"density file {content!r}: refused ({expected})")


def test_features(qgp, meshes, tmp):
    joint = os.path.join(meshes, "joint.obj")
    vertices, faces, _ = read_obj(joint)
    sharp = sharp_edges(vertices, faces, 40)
    check(len(sharp) > 100, f"joint has sharp edges at 40 degrees ({len(sharp)})")
    by_angle = os.path.join(tmp, "angle.json")
    proc = run(qgp, "remesh", joint, "-o", os.path.join(tmp, "angle.obj"), "--faces", 500, "--sharp-angle", 40,
               "--report", by_angle)
    check(proc.returncode == 0 and json.load(open(by_angle))["working_mesh"]["input_feature_edges"] == len(sharp),
          "--sharp-angle 40: exactly the edges sharper than 40 degrees are features")
    pairs = os.path.join(tmp, "joint.feat")
    with open(pairs, "w") as f:
        f.write("# sharp edges of joint.obj at 40 degrees\n" + "".join(f"{a} {b}\n" for a, b in sharp))
    by_file = os.path.join(tmp, "file.json")
    proc = run(qgp, "remesh", joint, "-o", os.path.join(tmp, "file.obj"), "--faces", 500, "--features", pairs,
               "--report", by_file)
    check(proc.returncode == 0 and json.load(open(by_file))["working_mesh"]["input_feature_edges"] == len(sharp),
          "--features FILE: the listed edges are the features")
    broken = os.path.join(tmp, "broken.feat")
    with open(broken, "w") as f:
        f.write("0 1\n7\n")
    proc = run(qgp, "remesh", joint, "-o", os.path.join(tmp, "b.obj"), "--features", broken)
    check(proc.returncode == 1 and "line 2" in proc.stderr, "--features with a malformed line: exit 1 naming the line")
    proc = run(qgp, "remesh", joint, "-o", os.path.join(tmp, "b.obj"), "--features", os.path.join(tmp, "none.feat"))
    check(proc.returncode == 2, "--features with a missing file: exit 2")


def test_drop_bad_components(qgp, meshes, tmp):
    # spot plus, far away, three triangles on one edge (a non-manifold part).
    vertices, faces, _ = read_obj(os.path.join(meshes, "spot.obj"))
    n = len(vertices)
    fan = [(10, 0, 0), (11, 0, 0), (10.5, 1, 0), (10.5, -1, 0), (10.5, 0, 1)]
    path = os.path.join(tmp, "spot_and_fan.obj")
    with open(path, "w") as f:
        for v in vertices + fan:
            f.write("v %r %r %r\n" % v)
        for face in faces + [[n, n + 1, n + 2], [n + 1, n, n + 3], [n, n + 1, n + 4]]:
            f.write("f " + " ".join(str(i + 1) for i in face) + "\n")
    report = os.path.join(tmp, "cut.json")
    proc = run(qgp, "info", path, "--report", report)
    kinds = [rep["kind"] for rep in json.load(open(report))["input"]["repairs"]]
    check(proc.returncode == 0 and "cut_nonmanifold_edges" in kinds, "a non-manifold part: cut into sheets by default")
    proc = run(qgp, "remesh", path, "-o", os.path.join(tmp, "refused.obj"), "--faces", 500, "--refuse-non-manifold")
    check(proc.returncode == 2 and "non-manifold edge" in proc.stderr,
          "a non-manifold part: refused (exit 2) with --refuse-non-manifold")
    report = os.path.join(tmp, "dropped.json")
    out = os.path.join(tmp, "dropped.obj")
    proc = run(qgp, "remesh", path, "-o", out, "--faces", 500, "--refuse-non-manifold", "--drop-bad-components",
               "--report", report)
    r = json.load(open(report))
    kinds = [rep["kind"] for rep in r["input"]["repairs"]]
    check(proc.returncode == 0 and "dropped_nonmanifold_components" in kinds,
          "--refuse-non-manifold --drop-bad-components: the part is dropped and the report says so")
    qv, qf, _ = read_obj(out)
    check(len(qv) - len(edge_faces(qf)) + len(qf) == 2 and max(v[0] for v in qv) < 5, "only spot is remeshed")


def test_weld(qgp, meshes, tmp):
    # spot written as a triangle soup: every face with its own three vertices.
    vertices, faces, _ = read_obj(os.path.join(meshes, "spot.obj"))
    path = os.path.join(tmp, "spot_soup.obj")
    with open(path, "w") as f:
        for face in faces:
            for i in face:
                f.write("v %r %r %r\n" % vertices[i])
        for k in range(len(faces)):
            f.write("f %d %d %d\n" % (3 * k + 1, 3 * k + 2, 3 * k + 3))
    report = os.path.join(tmp, "soup.json")
    proc = run(qgp, "info", path, "--report", report)
    inp = json.load(open(report))["input"]
    welded = [r for r in inp["repairs"] if r["kind"] == "welded_vertices"]
    check(proc.returncode == 0 and inp["components"] == 1 and inp["vertices"] == len(vertices)
          and welded and welded[0]["count"] == 3 * len(faces) - len(vertices)
          and 1 <= len(welded[0]["input_vertices"]) <= 10,
          "a triangle soup is welded back into one component (welded_vertices, located)")
    proc = run(qgp, "info", path, "--no-weld", "--report", report)
    inp = json.load(open(report))["input"]
    check(proc.returncode == 0 and inp["components"] == len(faces), "--no-weld keeps the soup's triangles apart")


def test_rescued_parts(qgp, meshes, tmp):
    """Parts whose layout gives no quads are rescued (quadded finer, or their triangles split), named on
    stderr with why; every part is quads (exit 0)."""
    out, report = os.path.join(tmp, "featuretype.obj"), os.path.join(tmp, "featuretype.json")
    proc = run(qgp, "remesh", os.path.join(meshes, "featuretype.ply"), "--no-weld", "-o", out, "--faces", 2000,
               "--report", report)
    r = json.load(open(report))
    rescued = r.get("rescued_components", [])
    check(proc.returncode == 0 and r["status"] == "ok" and rescued and "failed_components" not in r,
          f"featuretype unwelded ({r['input']['components']} parts): exit 0, status ok "
          f"({len(rescued)} part(s) rescued)")
    check(all(f"component {p['component']} ({p['triangles']} triangles) quadded " in proc.stderr
              and f"into {p['quads']} quads, as its own gave none valid: {p['stage']}: {p['message']}" in proc.stderr
              for p in rescued), "stderr names every rescued part, with its stage and reason")
    check("rescued" in r["quantization"]["count"]["note"], "the count note names the rescue")
    vertices, faces, _ = read_obj(out)
    objects = [line.split()[1] for line in open(out) if line.startswith("o ")]
    check(all(len(f) == 4 for f in faces) and len(faces) == r["quad"]["faces"], "-o: only the report's quads")
    check(len(objects) == r["input"]["components"], "-o: every part is an object of quads")
    check(all(0 <= i < len(vertices) for f in faces for i in f), "-o: indices in range")
    check(all(len(fs) <= 2 for fs in edge_faces(faces).values()) and r["quad"]["non_manifold_edges"] == 0
          and r["quad"]["inconsistent_edges"] == 0, "-o: the quads are edge-manifold and consistently oriented")
    check(r["quad"]["euler_characteristic"] == sum(r["input"]["euler_characteristic"]),
          "-o: the Euler characteristic of every part")
    check(all(r["extraction"]["components"][p["component"]] is None for p in rescued),
          "report: a rescued part has no extraction entry (null)")


def test_atlas_out(qgp, meshes, tmp):
    """--atlas-out: the quad mesh again, every corner with a vt in [0,1] on whole texels of the
    texture asked, each quad a square of the report's texels per quad; a texture too small: exit 1."""
    out, atlas, report = (os.path.join(tmp, n) for n in ("fq.obj", "fq_atlas.obj", "fq.json"))
    proc = run(qgp, "remesh", os.path.join(meshes, "fandisk.obj"), "-o", out, "--faces", 500, "--sharp-angle", 40,
               "--atlas-out", atlas, "--texture-size", 512, "--report", report)
    r = json.load(open(report))
    check(proc.returncode == 0 and r["atlas"]["texture_width"] == 512 and r["atlas"]["charts"] >= 1
          and "atlas: " in proc.stdout, f"--atlas-out: exit 0, the report's atlas {r.get('atlas')}")
    vt, faces = read_obj_vt(atlas)
    corners = [[c[1] if len(c) > 1 else None for c in f] for f in faces]
    _, quads, _ = read_obj(atlas)
    _, plain, _ = read_obj(out)
    check(quads == plain and all(None not in c for c in corners), "--atlas-out: the same quads, every corner a vt")
    check(all(0 <= u <= 1 and 0 <= v <= 1 and abs(u * 512 - round(u * 512)) < 1e-9
              and abs(v * 512 - round(v * 512)) < 1e-9 for u, v in vt), "--atlas-out: vt in [0,1], on whole texels")
    k = r["atlas"]["texels_per_quad"]
    sides = {round(512 * math.dist(vt[c[i]], vt[c[(i + 1) % 4]])) for c in corners for i in range(4)}
    check(sides == {k}, f"--atlas-out: every quad side {k} texels ({sorted(sides)[:5]})")
    proc = run(qgp, "remesh", os.path.join(meshes, "fandisk.obj"), "-o", out, "--faces", 500, "--atlas-out", atlas,
               "--texture-size", 16, "--texels-per-quad", 4)
    check(proc.returncode == 1 and "do not fit a 16 x 16 texture" in proc.stderr,
          "--atlas-out on a texture too small: exit 1 naming the sizes")


def test_non_orientable_part(qgp, meshes, tmp):
    """A Moebius strip beside spot: spot is quadded, the strip written as its input triangles (exit 5)."""
    vertices, faces, _ = read_obj(os.path.join(meshes, "spot.obj"))
    strip_vertices, strip_faces = moebius_strip(centre=(10.0, 0.0, 0.0))
    path, out = os.path.join(tmp, "spot_and_strip.obj"), os.path.join(tmp, "spot_and_strip_quads.obj")
    write_obj(path, vertices + strip_vertices, faces + [[len(vertices) + i for i in t] for t in strip_faces])
    report = os.path.join(tmp, "strip.json")
    proc = run(qgp, "remesh", path, "-o", out, "--faces", 500, "--report", report)
    r = json.load(open(report))
    failed = r.get("failed_components", [])
    check(proc.returncode == 5 and r["status"] == "partial" and len(failed) == 1
          and failed[0]["stage"] == "intake" and failed[0]["component"] == 1 and failed[0]["triangles"] == 16
          and "non-orientable" in failed[0]["message"], f"a non-orientable part beside spot: exit 5, {failed}")
    check("component 1 (16 triangles) kept as triangles: intake: non-orientable" in proc.stderr,
          "stderr names the strip and why")
    out_vertices, out_faces, _ = read_obj(out)
    objects = [line.split()[1] for line in open(out) if line.startswith("o ")]
    kept = [[out_vertices[i] for i in face] for face in out_faces if len(face) == 3]
    expected = [[strip_vertices[i] for i in t] for t in strip_faces]
    close = all(abs(a - b) < 1e-9 for k, e in zip(kept, expected) for p, q in zip(k, e) for a, b in zip(p, q))
    check(objects[-1] == "component_1_triangles" and len(kept) == 16 and close,
          "-o: the strip's 16 input triangles, corner by corner, as the last object")


def test_peak_memory_is_its_own(qgp, meshes, tmp):
    """The report's peak_memory_mb is the run's own: started by a parent holding 800 MB (as Blender
    holding a dense sculpt starts the worker), spot at 500 quads reports far less than that (getrusage's
    ru_maxrss carried the parent's resident memory at the fork across the exec)."""
    ballast = bytearray(800 << 20)
    for i in range(0, len(ballast), 4096):  # touch every page, so that it is resident
        ballast[i] = 1
    report = os.path.join(tmp, "memory.json")
    proc = run(qgp, "remesh", os.path.join(meshes, "spot.obj"), "-o", os.path.join(tmp, "memory.obj"), "--faces", 500,
               "--report", report)
    del ballast
    peak = json.load(open(report)).get("peak_memory_mb", 0) if proc.returncode == 0 else 0
    check(0 < peak < 400, f"peak_memory_mb of a run started by an 800 MB parent: {peak:.0f} MB, its own")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--qgp", required=True)
    ap.add_argument("--meshes", required=True)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        for test in (test_usage_errors, test_unusable_input, test_stage_failure, test_remesh_outputs, test_edge_length,
                     test_quad_count, test_symmetry, test_sizing,
                     test_features, test_drop_bad_components, test_weld, test_rescued_parts, test_non_orientable_part,
                     test_atlas_out, test_peak_memory_is_its_own):
            print(f"== {test.__name__}")
            if test in (test_unusable_input,):
                test(args.qgp, tmp)
            else:
                test(args.qgp, args.meshes, tmp)
    return summary()


if __name__ == "__main__":
    sys.exit(main())

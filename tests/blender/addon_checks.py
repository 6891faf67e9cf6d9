"""Helpers shared by the add-on tests inside Blender: the binary (test_addon.py, Blender 3.4) and the
Python module (module/test_extension_module.py, PyPI's bpy 4.5 and 5.0). Scene set-up, the checks
of an operator's result, and the batch runner. Needs bpy; imports nothing of the add-on itself (the
add-on's package name differs: `quantized_retopo` as a legacy add-on, `bl_ext.<repo>.quantized_retopo`
as an extension)."""
import glob
import json
import math
import os
import re
import subprocess
import sys

import bpy


def install_legacy_addon(repo, module, enable=True):
    """Installs the legacy zip built into repo/dist (Blender 3.4) into the temporary user scripts
    directory named by BLENDER_USER_SCRIPTS and (with enable) enables it; returns its module."""
    zips = sorted(glob.glob(os.path.join(repo, "dist", module + "-*-legacy.zip")))
    assert zips, "build the zips first (scripts/build_extension.py)"
    user_scripts = os.environ.get("BLENDER_USER_SCRIPTS")
    assert user_scripts and bpy.utils.user_resource("SCRIPTS").startswith(user_scripts), \
        "the add-on must be installed into a temporary user scripts directory"
    bpy.ops.preferences.addon_install(filepath=zips[-1], overwrite=True)
    installed = os.path.join(bpy.utils.user_resource("SCRIPTS"), "addons", module)
    assert os.path.exists(os.path.join(installed, "__init__.py")), "add-on not installed"
    if not enable:
        return None
    bpy.ops.preferences.addon_enable(module=module)
    assert module in bpy.context.preferences.addons, "add-on not enabled"
    assert os.path.exists(os.path.join(installed, "lib", "libqgp.so")), "native library not installed"
    return sys.modules[module]


def mesh_data_state(obj):
    """Everything of an object's mesh data an operator could change."""
    m = obj.data
    return (m.name, len(m.vertices), len(m.edges), len(m.polygons), [tuple(v.co) for v in m.vertices],
            [tuple(p.vertices) for p in m.polygons], [e.use_seam for e in m.edges],
            [layer.name for layer in m.uv_layers], [p.select for p in m.polygons], [len(obj.modifiers)])


def reset_scene():
    """Empties the scene (read_factory_settings would also disable the add-on)."""
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj)
    for mesh in list(bpy.data.meshes):
        bpy.data.meshes.remove(mesh)


def scene_state():
    """Everything an operator could change: objects, their data, selection, UV layers, seams."""
    state = []
    for obj in sorted(bpy.data.objects, key=lambda o: o.name):
        entry = [obj.name, obj.type, obj.select_get(), obj.hide_get(), tuple(map(tuple, obj.matrix_world))]
        if obj.type == "MESH":
            m = obj.data
            entry += [len(m.vertices), len(m.polygons), [layer.name for layer in m.uv_layers],
                      hash(repr([v.co[:] for v in m.vertices])),  # repr: a NaN coordinate equals itself
                      sum(e.use_seam for e in m.edges)]
        state.append(entry)
    return state, len(bpy.data.meshes)


def object_state(obj):
    """scene_state's entry of one object, without its selection and visibility."""
    return [e for e in scene_state()[0] if e[0] == obj.name][0][4:]


def select_only(obj):
    for other in bpy.context.selected_objects:
        other.select_set(False)
    obj.select_set(True)
    bpy.context.view_layer.objects.active = obj


def import_mesh(binding, path):
    """A new object from a mesh file (read by the add-on's native reader, polygons kept), linked to
    the scene, selected and active."""
    # The add-on's reader; its package is the binding's, two levels up.
    mesh = sys.modules[binding.__name__.rsplit(".", 2)[0] + ".blender_mesh"].read_mesh(path)
    obj = bpy.data.objects.new(mesh.name, mesh)
    bpy.context.scene.collection.objects.link(obj)
    select_only(obj)
    return obj


def euler_characteristic(mesh):
    return len(mesh.vertices) - len(mesh.edges) + len(mesh.polygons)


def mark_sharp_edges(obj, angle):
    """Marks the edges whose faces meet at more than `angle` (radians) as sharp, as a user would."""
    import bmesh
    bm = bmesh.new()
    bm.from_mesh(obj.data)
    count = 0
    for edge in bm.edges:
        sharp = edge.is_manifold and edge.calc_face_angle(0.0) > angle
        edge.smooth = not sharp
        count += sharp
    bm.to_mesh(obj.data)
    bm.free()
    return count


def measure_against_source(binding, source, quad, sharp_angle):
    """The library's own measurement of the quads against the source triangles (dict: flipped
    quads, Hausdorff distance, share of the sharp edges' length covered by quad edges, ...)."""
    import numpy as np
    src = source.data
    src.calc_loop_triangles()
    tris = np.array([t.vertices[:] for t in src.loop_triangles], np.int32)
    sv = np.array([v.co[:] for v in src.vertices])
    qv = np.array([v.co[:] for v in quad.data.vertices])
    sizes = np.array([len(p.vertices) for p in quad.data.polygons], np.int32)
    corners = np.array([i for p in quad.data.polygons for i in p.vertices], np.int32)
    return binding.measure_polygon_mesh(qv, sizes, corners, sv, tris, math.degrees(sharp_angle))


def edge_face_counts(mesh):
    """How many polygons use each edge (vertex pair) of the mesh's polygons."""
    counts = {}
    for poly in mesh.polygons:
        for key in poly.edge_keys:
            key = tuple(sorted(key))
            counts[key] = counts.get(key, 0) + 1
    return counts


def run_quad_remesh(source, **options):
    """Runs Quantized Retopo on `source`: it finishes with one new object '<source>_quads', selected
    and active, and the source's data unchanged. Returns the new object."""
    select_only(source)
    before = object_state(source)
    names = {o.name for o in bpy.data.objects}
    result = bpy.ops.object.qgp_quad_remesh(**options)
    assert result == {"FINISHED"}, result
    created = [o for o in bpy.data.objects if o.name not in names]
    assert len(created) == 1, created
    quad = created[0]
    assert quad.name == source.name + "_quads", quad.name
    assert bpy.context.view_layer.objects.active == quad and quad.select_get()
    assert object_state(source) == before, "source data changed"
    return quad


def check_quad_object(binding, source, quad, target):
    """The checks every quad remesh result passes: all quads, exactly the quads the quantization
    counted (the native figures on the object's 'qgp' property), edge-manifold, the source's Euler
    characteristic and boundary-edge count kept, the source's transform and parent. Returns the
    figures."""
    sizes = {len(p.vertices) for p in quad.data.polygons}
    assert sizes == {4}, f"not all quads: {sizes}"
    # The mesh has exactly the quads the quantization counted (its integer cell areas, before any
    # quad was extracted): none lost or added between the library and Blender.
    figures = quad["qgp"].to_dict()
    n = len(quad.data.polygons)
    assert n == figures["quads_expected"], (source.name, n, figures)
    assert figures["target_mode"] == "FACES" and figures["target"] == target, figures
    assert len(figures["quad_paths"]) == figures["components"] >= 1, figures
    assert figures["layout_components"] == sum(p.startswith("T-mesh layout") for p in figures["quad_paths"])
    assert figures["seconds"] > 0 and figures["library"] == binding.version(), figures
    counts = edge_face_counts(quad.data)
    assert max(counts.values()) <= 2, "an edge of the quads has more than two faces"
    assert len(counts) == len(quad.data.edges), "loose or duplicate edges"
    source_boundary = sum(c == 1 for c in edge_face_counts(source.data).values()) > 0
    assert (sum(c == 1 for c in counts.values()) > 0) == source_boundary, "boundary appeared or vanished"
    assert euler_characteristic(quad.data) == euler_characteristic(source.data), (
        euler_characteristic(quad.data), euler_characteristic(source.data))
    bpy.context.view_layer.update()
    assert quad.parent == source.parent, (quad.parent, source.parent)
    assert all(abs(a - b) < 1e-6 for ra, rb in zip(quad.matrix_world, source.matrix_world)
               for a, b in zip(ra, rb)), (quad.matrix_world, source.matrix_world)
    return figures


def check_sharp_edges_kept(binding, source, quad, marked, angle):
    """The marked edges are exactly those sharper than `angle`: the library measures how much of
    their length quad edges cover (within 0.1 % of the diagonal). Returns the coverage."""
    m = measure_against_source(binding, source, quad, angle)
    assert m["sharp_edges"] == marked, (m["sharp_edges"], marked)
    assert m["sharp_edge_coverage"] > 0.95, m["sharp_edge_coverage"]
    assert m["flipped_quads"] == 0, m["flipped_quads"]
    return m["sharp_edge_coverage"]


def grid_seam_residual(mesh, layer, quads_per_unit):
    """Largest deviation, over all edges shared by two polygons, of the UV transition from a
    90-degree rotation plus an integer translation (in grid units): 0 for an integer-grid map."""
    uv = [(d.uv[0] * quads_per_unit, d.uv[1] * quads_per_unit) for d in layer.data]
    sides = {}
    for poly in mesh.polygons:
        loops = list(poly.loop_indices)
        for i, li in enumerate(loops):
            lj = loops[(i + 1) % len(loops)]
            a, b = mesh.loops[li].vertex_index, mesh.loops[lj].vertex_index
            sides.setdefault((min(a, b), max(a, b)), []).append({a: uv[li], b: uv[lj]})

    def rotate(p, r):
        return p if r == 0 else rotate((-p[1], p[0]), r - 1)

    worst = 0.0
    for (a, b), pair in sides.items():
        if len(pair) != 2:
            continue
        p, q = pair
        d = (p[b][0] - p[a][0], p[b][1] - p[a][1])
        e = (q[b][0] - q[a][0], q[b][1] - q[a][1])
        best = math.inf
        for r in range(4):
            rd = rotate(d, r)
            if abs(rd[0] - e[0]) + abs(rd[1] - e[1]) > 1e-3:
                continue
            ra = rotate(p[a], r)
            t = (q[a][0] - ra[0], q[a][1] - ra[1])
            best = min(best, abs(t[0] - round(t[0])) + abs(t[1] - round(t[1])))
        worst = max(worst, best)
    return worst


def uv_cut_edges(mesh, layer, tolerance=1e-4):
    """Vertex pairs of the edges whose two polygons disagree in the UV layer (by more than
    `tolerance` in a coordinate at one end): the UV islands' inner boundaries, derived here from the
    loops on their own (not by the add-on's code)."""
    uv = [d.uv[:] for d in layer.data]
    loop_vertex = [loop.vertex_index for loop in mesh.loops]
    sides = {}
    for poly in mesh.polygons:
        loops = list(poly.loop_indices)
        for i, li in enumerate(loops):
            lj = loops[(i + 1) % len(loops)]
            a, b = loop_vertex[li], loop_vertex[lj]
            sides.setdefault((min(a, b), max(a, b)), []).append({a: uv[li], b: uv[lj]})
    return {key for key, pair in sides.items() for other in pair[1:]
            if any(abs(other[v][k] - pair[0][v][k]) > tolerance for v in key for k in (0, 1))}


def seam_edges(mesh):
    return {tuple(sorted(e.vertices)) for e in mesh.edges if e.use_seam}


def native_cut_edges(operators, obj):
    """The map's cut edges as the native session of the object's last Integer-Grid UVs run lists
    them (vertex pairs), restricted to the mesh's edges (a cut may run along a polygon's diagonal).
    operators: the add-on's operators module (it holds the session cache)."""
    obj.data.calc_loop_triangles()
    _, cuts = operators._session_cache[obj.name][1].grid_uv(len(obj.data.loop_triangles))
    edges = {tuple(sorted(e.vertices)) for e in obj.data.edges}
    return {(min(a, b), max(a, b)) for a, b in cuts.tolist()} & edges


def run_grid_uv(operators, obj, target, per_unit):
    """Runs Integer-Grid UVs on `obj` with Mark Seams, on the source (Flip-Free Copy off), and
    checks: the 'QGP Grid' layer with finite UVs, the geometry unchanged, the seams exactly the UV
    islands' inner boundaries and including every cut the library lists, and an integer-grid map
    (float32 UVs: the residual is at the level of float precision, not of the grid).
    operators: the add-on's operators module. Returns (loops, seams, residual)."""
    select_only(obj)
    vertices_before = [tuple(v.co) for v in obj.data.vertices]
    result = bpy.ops.object.qgp_grid_uv(target_faces=target, mark_seams=True, quads_per_unit=per_unit,
                                        flip_free_copy=False)
    assert result == {"FINISHED"}, result
    layer = obj.data.uv_layers.get("QGP Grid")
    assert layer is not None, [layer.name for layer in obj.data.uv_layers]
    uv = [tuple(d.uv) for d in layer.data]
    assert all(math.isfinite(u) and math.isfinite(v) for u, v in uv)
    assert len({(round(u, 4), round(v, 4)) for u, v in uv}) > 100
    assert [tuple(v.co) for v in obj.data.vertices] == vertices_before, "geometry changed"
    seams = seam_edges(obj.data)
    islands = uv_cut_edges(obj.data, layer, 1e-4 / per_unit)
    assert seams and seams == islands, (len(seams), len(islands), len(seams - islands), len(islands - seams))
    cuts = native_cut_edges(operators, obj)
    assert cuts and cuts <= seams, len(cuts - seams)
    residual = grid_seam_residual(obj.data, layer, per_unit)
    assert residual < 1e-3, residual
    return len(uv), len(seams), residual


def run_batch(command, inputs, out, *options, timeout=None):
    """Runs the batch script (command: the interpreter and script up to its `--`) on `inputs` into
    `out`; returns (process, report). The report must exist whatever failed. timeout: seconds, after
    which the batch is ended and the test fails (subprocess.TimeoutExpired)."""
    proc = subprocess.run(command + inputs + ["--out", out] + list(options), capture_output=True, text=True,
                          timeout=timeout)
    path = os.path.join(out, "report.json")
    assert os.path.exists(path), f"no report (exit {proc.returncode}): {proc.stderr[-2000:]}"
    with open(path) as f:
        return proc, json.load(f)


def argument(args, name, default):
    """The value after `name` in a test script's arguments (after Blender's `--`), or default."""
    return args[args.index(name) + 1] if name in args else default


def script_arguments():
    return sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]


# Guides and attributes: a UV sphere (32 x 16) with one ring of edges, at the fifth ring from the
# top, as the curve a guide marks; the faces above it are the other region.
GUIDE_RING = 5


def guide_sphere(guide):
    """A UV sphere whose ring GUIDE_RING is marked as `guide`: 'SEAM' (seams), 'MATERIAL' (two
    materials, the faces above the ring the second one) or 'FACE_SET' (two face sets: the int face
    attribute '.sculpt_face_set', or 'sculpt_face_set' before Blender 3.5). Returns (object, the
    ring's edges as vertex pairs)."""
    import bmesh
    bpy.ops.mesh.primitive_uv_sphere_add(segments=32, ring_count=16, radius=1.0)
    obj = bpy.context.active_object
    mesh = obj.data
    height = math.cos(math.pi * GUIDE_RING / 16)
    ring = {tuple(sorted(e.vertices)) for e in mesh.edges
            if all(abs(mesh.vertices[v].co.z - height) < 1e-4 for v in e.vertices)}
    assert len(ring) == 32, len(ring)
    above = [int(p.center.z > height) for p in mesh.polygons]
    if guide == "SEAM":
        bm = bmesh.new()
        bm.from_mesh(mesh)
        for edge in bm.edges:
            edge.seam = tuple(sorted(v.index for v in edge.verts)) in ring
        bm.to_mesh(mesh)
        bm.free()
    elif guide == "MATERIAL":
        for name in ("qgp_below", "qgp_above"):
            mesh.materials.append(bpy.data.materials.get(name) or bpy.data.materials.new(name))
        mesh.polygons.foreach_set("material_index", above)
    else:
        name = ".sculpt_face_set" if bpy.app.version >= (3, 5, 0) else "sculpt_face_set"
        mesh.attributes.new(name, "INT", "FACE").data.foreach_set("value", [a + 1 for a in above])
    mesh.update()
    return obj, ring


def _segment_distances(points, starts, ends):
    """Distance of each point to the nearest of the segments (starts[i], ends[i])."""
    import numpy as np
    d = ends - starts
    t = np.einsum("pk,sk->ps", points, d) - np.einsum("sk,sk->s", starts, d)[None, :]
    t = np.clip(t / np.maximum(np.einsum("sk,sk->s", d, d), 1e-30)[None, :], 0.0, 1.0)
    nearest = starts[None, :, :] + t[:, :, None] * d[None, :, :]
    return np.linalg.norm(points[:, None, :] - nearest, axis=2).min(axis=1)


def guide_distance(source, quad, ring):
    """How far the quads' edges are from the guide `ring` (source edges as vertex pairs): the largest
    distance of a ring edge's midpoint to the nearest quad edge, in units of the mean quad edge
    length (both meshes in the same object space)."""
    import numpy as np
    sv = np.array([v.co[:] for v in source.data.vertices])
    qv = np.array([v.co[:] for v in quad.data.vertices])
    edges = np.array([e.vertices[:] for e in quad.data.edges])
    starts, ends = qv[edges[:, 0]], qv[edges[:, 1]]
    mean_length = np.linalg.norm(ends - starts, axis=1).mean()
    ring = np.array(sorted(ring))
    midpoints = 0.5 * (sv[ring[:, 0]] + sv[ring[:, 1]])
    return float(_segment_distances(midpoints, starts, ends).max() / mean_length)


def run_guide(guide, option, target=300):
    """Quantized Retopo on a guide_sphere marked as `guide`, with the operator option `option` off
    and then on. On, every ring edge's midpoint lies near a quad edge: within 15 % of the mean quad
    edge length (a ring marked sharp gives the same quads: their edges are chords of the ring, whose
    vertices need not be quad vertices); off, some midpoint lies over twice as far (about halfway
    between quad edges). Returns the two distances (off, on)."""
    source, ring = guide_sphere(guide)
    distances = []
    for use in (False, True):
        quad = run_quad_remesh(source, target_faces=target, keep_source_visible=True, **{option: use})
        assert {len(p.vertices) for p in quad.data.polygons} == {4}
        distances.append(guide_distance(source, quad, ring))
        bpy.data.objects.remove(quad)
    assert distances[1] < 0.15 and distances[0] > 2 * distances[1], (guide, distances)
    return distances


ATTRIBUTE_SPLIT = 0.3  # the sphere's faces above this height have the second material


def attribute_sphere():
    """A UV sphere with what a quad object keeps: two materials (the faces above ATTRIBUTE_SPLIT the
    second), the vertex group 'gradient' (weight (z + 1) / 2), the point colour 'Col' ((position +
    1) / 2), the corner colour 'Paint' (bytes), the face int 'region' (the material index) and its
    UV map 'UVMap'."""
    bpy.ops.mesh.primitive_uv_sphere_add(segments=32, ring_count=16, radius=1.0)
    obj = bpy.context.active_object
    mesh = obj.data
    for name in ("qgp_below", "qgp_above"):
        mesh.materials.append(bpy.data.materials.get(name) or bpy.data.materials.new(name))
    region = [int(p.center.z > ATTRIBUTE_SPLIT) for p in mesh.polygons]
    mesh.polygons.foreach_set("material_index", region)
    mesh.attributes.new("region", "INT", "FACE").data.foreach_set("value", region)
    group = obj.vertex_groups.new(name="gradient")
    for v in mesh.vertices:
        group.add([v.index], (v.co.z + 1) / 2, "REPLACE")
    colors = mesh.color_attributes.new("Col", "FLOAT_COLOR", "POINT")
    colors.data.foreach_set("color", [c for v in mesh.vertices for c in ((v.co.x + 1) / 2, (v.co.y + 1) / 2,
                                                                         (v.co.z + 1) / 2, 1.0)])
    mesh.color_attributes.new("Paint", "BYTE_COLOR", "CORNER")
    mesh.color_attributes.active_color = mesh.color_attributes["Col"]
    assert "UVMap" in mesh.uv_layers, [layer.name for layer in mesh.uv_layers]
    mesh.update()
    return obj


def check_attributes_kept(source, quad, keep_uvs):
    """The quad object made from an attribute_sphere keeps its attributes: materials per face (and
    the face int 'region' equal to them, both of the source polygon under the quad; the material as
    the quad's centre height says, away from the split), the vertex group weights and point colours
    at each vertex close to what the source has there, the corner colour, the active colour, and
    with keep_uvs the UV map 'UVMap' (per corner, in [0, 1]). Returns the largest weight error."""
    mesh = quad.data
    n = len(mesh.vertices)
    materials = [p.material_index for p in mesh.polygons]
    region = mesh.attributes["region"]
    assert (region.domain, region.data_type) == ("FACE", "INT")
    assert [d.value for d in region.data] == materials
    edge = sum((mesh.vertices[e.vertices[0]].co - mesh.vertices[e.vertices[1]].co).length
               for e in mesh.edges) / len(mesh.edges)
    for p in mesh.polygons:
        if abs(p.center.z - ATTRIBUTE_SPLIT) > edge:
            assert p.material_index == int(p.center.z > ATTRIBUTE_SPLIT), (p.index, p.center.z, p.material_index)
    assert set(materials) == {0, 1}, set(materials)
    assert [g.name for g in quad.vertex_groups] == ["gradient"], list(quad.vertex_groups)
    weights = [sum(g.weight for g in v.groups) for v in mesh.vertices]
    weight_error = max(abs(w - (v.co.z + 1) / 2) for w, v in zip(weights, mesh.vertices))
    assert weight_error < 0.02, weight_error
    colors = mesh.color_attributes["Col"]
    assert (colors.domain, colors.data_type, len(colors.data)) == ("POINT", "FLOAT_COLOR", n)
    color_error = max(abs(c - (x + 1) / 2) for d, v in zip(colors.data, mesh.vertices)
                      for c, x in zip(d.color[:3], v.co))
    assert color_error < 0.02, color_error
    assert mesh.color_attributes.active_color.name == "Col"
    paint = mesh.color_attributes["Paint"]
    assert (paint.domain, paint.data_type, len(paint.data)) == ("CORNER", "BYTE_COLOR", len(mesh.loops))
    if keep_uvs:
        assert [layer.name for layer in mesh.uv_layers] == ["UVMap"], list(mesh.uv_layers)
        uv = [c for d in mesh.uv_layers["UVMap"].data for c in d.uv]
        assert len(uv) == 2 * len(mesh.loops) and all(-1e-6 <= c <= 1 + 1e-6 for c in uv)
        assert len({round(c, 3) for c in uv}) > 50, "the UVs are not interpolated"
    else:
        assert not mesh.uv_layers, list(mesh.uv_layers)
    return weight_error


def check_attributes_not_kept(quad):
    """With Keep Attributes off: the materials still, nothing else."""
    mesh = quad.data
    assert not quad.vertex_groups and "Col" not in mesh.attributes and "region" not in mesh.attributes
    assert not mesh.uv_layers and {p.material_index for p in mesh.polygons} == {0, 1}


def check_symmetric(quad, axes):
    """The quad object is mirror-symmetric about its local planes `axes` ("x", "xz", ...): every
    vertex's mirror image is within 1e-6 of the bounding-box diagonal of a vertex, and no edge on a
    plane is open (the two sides are welded). Returns the largest image distance / diagonal."""
    from mathutils import kdtree
    mesh = quad.data
    points = [v.co.copy() for v in mesh.vertices]
    tree = kdtree.KDTree(len(points))
    for i, p in enumerate(points):
        tree.insert(p, i)
    tree.balance()
    low = [min(p[i] for p in points) for i in range(3)]
    high = [max(p[i] for p in points) for i in range(3)]
    diagonal = sum((h - lo) ** 2 for h, lo in zip(high, low)) ** 0.5
    indices = ["xyz".index(a) for a in axes]
    worst = 0.0
    for i in indices:
        for p in points:
            image = p.copy()
            image[i] = -image[i]
            worst = max(worst, tree.find(image)[2])
    assert worst <= 1e-6 * diagonal, (axes, worst / diagonal)
    tolerance = 1e-6 * diagonal
    open_on_plane = [key for key, count in edge_face_counts(mesh).items() if count == 1 and any(
        all(abs(points[v][i]) <= tolerance for v in key) for i in indices)]
    assert not open_on_plane, f"{len(open_on_plane)} open edge(s) on a symmetry plane"
    return worst / diagonal


# (planes, quads asked) of the symmetry tests: Suzanne about X, a UV sphere about X and Z.
SYMMETRY_CASES = (("x", 1200), ("xz", 800))


def moved_suzanne():
    """Suzanne subdivided once (the modifier applied), moved and turned away from the origin."""
    bpy.ops.mesh.primitive_monkey_add()
    monkey = bpy.context.active_object
    monkey.modifiers.new("subsurf", "SUBSURF").levels = 1
    bpy.ops.object.modifier_apply(modifier="subsurf")
    monkey.location = (1.5, -2.0, 0.25)
    monkey.rotation_euler = (0.3, 0.0, 1.1)
    bpy.context.view_layer.update()
    return monkey


def symmetry_source(axes):
    """The source of a SYMMETRY_CASES test: for "x" moved_suzanne (the planes are the object's own,
    not the world's), else a UV sphere."""
    if axes == "x":
        return moved_suzanne()
    bpy.ops.mesh.primitive_uv_sphere_add(segments=48, ring_count=24)
    return bpy.context.active_object


def run_symmetry(source, axes, target):
    """Quantized Retopo with Symmetry `axes` on `source`: the quads are symmetric and welded
    (check_symmetric), within 5 % of `target` or with the count's note, the figures name the planes
    and the source is unchanged. Returns (quads, largest image distance / diagonal)."""
    before = mesh_data_state(source)
    flags = tuple(a in axes for a in "xyz")
    quad = run_quad_remesh(source, target_faces=target, symmetry=flags, keep_source_visible=True)
    figures = quad["qgp"].to_dict()
    assert figures["symmetry"] == axes, figures
    count = len(quad.data.polygons)
    assert abs(count - target) <= 0.05 * target or figures["count_note"], (count, figures)
    assert all(len(p.vertices) == 4 for p in quad.data.polygons)
    assert figures["flipped_quads"] == 0, figures
    assert mesh_data_state(source) == before, "the source changed"
    return count, check_symmetric(quad, axes)


def mean_quad_edge(quad, keep):
    """Mean length of the quad object's edges whose midpoint (object space) passes keep(midpoint)."""
    mesh = quad.data
    lengths = [(mesh.vertices[a].co - mesh.vertices[b].co).length for a, b in (e.vertices for e in mesh.edges)
               if keep((mesh.vertices[a].co + mesh.vertices[b].co) / 2)]
    return sum(lengths) / len(lengths)


def painted_sphere():
    """A UV sphere whose upper half (z > 0) is painted: weight 1 in the vertex group 'detail' and white
    in the point colour attribute 'paint' (black below)."""
    bpy.ops.mesh.primitive_uv_sphere_add(segments=64, ring_count=32)
    obj = bpy.context.active_object
    group = obj.vertex_groups.new(name="detail")
    group.add([v.index for v in obj.data.vertices if v.co.z > 0], 1.0, "REPLACE")
    paint = obj.data.attributes.new("paint", "FLOAT_COLOR", "POINT")
    colors = [((1.0,) * 3 if v.co.z > 0 else (0.0,) * 3) + (1.0,) for v in obj.data.vertices]
    paint.data.foreach_set("color", [c for color in colors for c in color])
    return obj


def count_is_kept(quad, target):
    """The operator's count promise: within 5 % of `target`, or the layout's count steps over that
    band and the quads are the step nearer to it, as the object's count note says."""
    count = len(quad.data.polygons)
    if abs(count - target) <= 0.05 * target:
        return True
    steps = re.search(r"steps from (\d+) to (\d+)", quad["qgp"]["count_note"])
    if not steps:
        return False
    below, above = int(steps.group(1)), int(steps.group(2))
    return below <= target <= above and count == min((below, above), key=lambda n: abs(n - target))


def run_density(source, target=800, factor=4.0):
    """Quantized Retopo on a painted_sphere with its group, then its colour attribute, as the density
    map (Density Factor `factor`): each time the quads above are shorter than below (ratio < 0.8),
    the count kept (count_is_kept), the source unchanged. A density map the object does not have is refused by
    name. Returns the two edge length ratios (above / below)."""
    before = mesh_data_state(source)
    ratios = []
    for option in ("density_group", "density_color"):
        name = "detail" if option == "density_group" else "paint"
        quad = run_quad_remesh(source, target_faces=target, density_factor=factor, keep_source_visible=True,
                               **{option: name})
        ratio = mean_quad_edge(quad, lambda m: m.z > 0.3) / mean_quad_edge(quad, lambda m: m.z < -0.3)
        count = len(quad.data.polygons)
        assert ratio < 0.8 and count_is_kept(quad, target), (option, ratio, count, quad["qgp"]["count_note"])
        ratios.append(ratio)
        bpy.data.objects.remove(quad)
    select_only(source)
    try:
        bpy.ops.object.qgp_quad_remesh(target_faces=target, density_group="no such group")
        raise AssertionError("a missing density group was not refused")
    except RuntimeError as e:
        assert "no vertex group 'no such group'" in str(e), e
    assert mesh_data_state(source) == before, "the source changed"
    return ratios

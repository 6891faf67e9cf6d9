"""The add-on in Blender (blender -b --factory-startup --python-exit-code 1 --python THIS -- --meshes DIR):
installed from the built legacy zip into a temporary user scripts directory (BLENDER_USER_SCRIPTS),
enabled, then exercised through its operators, panel, menu and batch runner."""
import contextlib
import io
import math
import os
import random
import sys
import tempfile
import time

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # tests/: shapes
from addon_checks import (check_quad_object, check_sharp_edges_kept, grid_seam_residual,  # noqa: E402
                          mark_sharp_edges, reset_scene, run_batch, run_grid_uv, run_quad_remesh, scene_state,
                          seam_edges, select_only, uv_cut_edges)
import addon_checks  # noqa: E402
from shapes import grid_cube, moebius_strip, write_obj  # noqa: E402

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
ARGS = addon_checks.script_arguments()
MESHES = addon_checks.argument(ARGS, "--meshes", os.path.join(REPO, "..", "shared", "meshes"))
MODULE = "quantized_retopo"
# The batch script of this checkout in Blender 3.4 (it registers the add-on in addon/ itself).
BATCH = [bpy.app.binary_path, "-b", "--factory-startup", "--python", os.path.join(REPO, "addon", "batch.py"), "--"]


def import_mesh(binding, name):
    return addon_checks.import_mesh(binding, os.path.join(MESHES, name))


def expect_operator_error(op, **kwargs):
    before = scene_state()
    try:
        op(**kwargs)
    except RuntimeError as e:
        message = str(e)
    else:
        raise AssertionError(f"{op} should have reported an error")
    assert scene_state() == before, f"{op} changed the scene although it failed"
    return message


def test_registration():
    assert hasattr(bpy.types, "OBJECT_OT_qgp_quad_remesh") and hasattr(bpy.types, "OBJECT_OT_qgp_grid_uv")
    assert "REGISTER" in bpy.types.OBJECT_OT_qgp_quad_remesh.bl_options
    assert "UNDO" in bpy.types.OBJECT_OT_qgp_grid_uv.bl_options
    assert hasattr(bpy.types, "VIEW3D_PT_qgp_retopo")
    assert bpy.types.VIEW3D_PT_qgp_retopo.bl_category == "Retopo"
    assert hasattr(bpy.context.scene, "qgp_settings")
    draw_funcs = getattr(bpy.types.VIEW3D_MT_object.draw, "_draw_funcs", [])
    assert any(getattr(f, "__module__", "").startswith(MODULE) for f in draw_funcs), "Object menu entry missing"
    print("registration: OK")


def test_broken_inputs(binding):
    # A Moebius strip alone cannot be oriented: both operators refuse it, nothing changes.
    reset_scene()
    vertices, faces = moebius_strip()
    mesh = bpy.data.meshes.new("moebius")
    mesh.from_pydata(vertices, [], faces)
    obj = bpy.data.objects.new("moebius", mesh)
    bpy.context.scene.collection.objects.link(obj)
    obj.select_set(True)
    bpy.context.view_layer.objects.active = obj
    for op in (bpy.ops.object.qgp_quad_remesh, bpy.ops.object.qgp_grid_uv):
        message = expect_operator_error(op, target_faces=500)
        assert "non-orientable" in message, message
    assert "QGP Grid" not in obj.data.uv_layers
    print(f"moebius strip: refused without changes: {message[:70]}")
    # Beside a torus, the strip is kept as its 16 input triangles (selected) and the torus quadded.
    reset_scene()
    bpy.ops.mesh.primitive_torus_add(major_segments=64, minor_segments=24)
    obj = bpy.context.active_object
    strip_vertices, strip_faces = moebius_strip(centre=(6.0, 0.0, 0.0))
    strip = bpy.data.objects.new("strip", bpy.data.meshes.new("strip"))
    strip.data.from_pydata(strip_vertices, [], strip_faces)
    bpy.context.scene.collection.objects.link(strip)
    strip.select_set(True)
    obj.select_set(True)
    bpy.context.view_layer.objects.active = obj
    assert bpy.ops.object.join() == {"FINISHED"}
    assert len(obj.data.polygons) == 64 * 24 + 16, len(obj.data.polygons)
    # A vertex group with a weight growing along x: the kept triangles get it too (Keep Attributes).
    group = obj.vertex_groups.new(name="along_x")
    for v in obj.data.vertices:
        group.add([v.index], (v.co.x + 10) / 20, "REPLACE")
    before = addon_checks.mesh_data_state(obj)
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        assert bpy.ops.object.qgp_quad_remesh(target_faces=600, keep_source_visible=True) == {"FINISHED"}
    warning = next(line for line in out.getvalue().splitlines() if line.startswith("Warning:"))
    assert "complete except 1 part(s)" in warning and "non-orientable" in warning, warning
    assert addon_checks.mesh_data_state(obj) == before, "the source changed"
    quad = bpy.data.objects[obj.name + "_quads"]
    kept = [p for p in quad.data.polygons if len(p.vertices) == 3]
    assert len(kept) == 16 and all(p.select == (len(p.vertices) == 3) for p in quad.data.polygons), len(kept)
    group = quad.vertex_groups["along_x"].index
    weights = {v.index: sum(g.weight for g in v.groups if g.group == group) for v in quad.data.vertices}
    error = max(abs(weights[i] - (quad.data.vertices[i].co.x + 10) / 20) for p in kept for i in p.vertices)
    assert error < 1e-4, error
    print(f"moebius strip beside a torus: kept as 16 triangles (with their vertex group), torus quadded: "
          f"{warning[:100]}")
    # Truck: its 54 non-manifold edges are cut into sheets (no refusal at intake); the parts whose
    # holes are narrower than a quad at this density are rescued (quadded finer, or their triangles
    # split), named in a warning; only quads; the source is unchanged.
    reset_scene()
    truck = import_mesh(binding, "truck.obj")
    before = addon_checks.mesh_data_state(truck)
    out = io.StringIO()
    with contextlib.redirect_stdout(out):  # bpy.ops writes an operator's reports to sys.stdout
        assert bpy.ops.object.qgp_quad_remesh(target_faces=500, keep_source_visible=True) == {"FINISHED"}
    warning = next(line for line in out.getvalue().splitlines() if line.startswith("Warning:"))
    assert "rescued: part" in warning and "try more quads" in warning, warning
    assert addon_checks.mesh_data_state(truck) == before, "the source changed"
    quad = bpy.data.objects[truck.name + "_quads"]
    assert all(len(p.vertices) == 4 for p in quad.data.polygons) and quad["qgp"]["rescued_parts"] > 0
    print(f"truck.obj: cut at intake, thin parts rescued: {warning[:120]}")
    # Teapot: its 403 duplicate boundary positions are welded (4 parts, not 19 loose patches with
    # 38 non-manifold vertices), and 500 quads then fit.
    reset_scene()
    import_mesh(binding, "teapot.obj")
    assert bpy.ops.object.qgp_quad_remesh(target_faces=500) == {"FINISHED"}
    print("teapot.obj: welded and remeshed")
    # An object without faces.
    reset_scene()
    mesh = bpy.data.meshes.new("empty")
    mesh.from_pydata([(0, 0, 0), (1, 0, 0)], [(0, 1)], [])
    obj = bpy.data.objects.new("empty", mesh)
    bpy.context.scene.collection.objects.link(obj)
    bpy.context.view_layer.objects.active = obj
    message = expect_operator_error(bpy.ops.object.qgp_quad_remesh)
    assert "no faces" in message, message
    print("empty mesh: refused")


def test_cancel_leaves_scene_unchanged(binding):
    """A native job cancelled mid-way: nothing reaches the scene (operators only touch it on success)."""
    reset_scene()
    bpy.ops.mesh.primitive_uv_sphere_add(segments=400, ring_count=200)
    obj = bpy.context.active_object
    before = scene_state()
    from importlib import import_module
    source = import_module(MODULE + ".blender_mesh").SourceMesh(bpy.context, obj, True, True)
    session = binding.Session(source.vertices, source.triangles)
    session.start(binding.JOB_REMESH)
    session.cancel()
    try:
        session.wait()
        cancelled = False
    except binding.QGPError as e:
        cancelled = e.code == binding.ERR_CANCELLED
    session.close()
    assert cancelled, "cancel did not stop the job"
    assert scene_state() == before
    print("cancel: scene unchanged")


def test_worker_fault_leaves_blender_running():
    """The native job runs in a worker process: a crash there (here a SIGSEGV sent to it mid-job)
    is a reported error, the scene is unchanged, and the next run starts a fresh worker."""
    import signal
    import threading
    import time
    operators = sys.modules[MODULE + ".operators"]
    reset_scene()
    bpy.ops.mesh.primitive_uv_sphere_add(segments=400, ring_count=200)
    obj = bpy.context.active_object
    before = scene_state()
    killed = []

    def crash_the_worker():
        deadline = time.time() + 60
        while time.time() < deadline and not killed:
            cached = operators._session_cache.get(obj.name)
            pid = getattr(cached[1], "pid", None) if cached else None
            if pid:
                time.sleep(0.5)  # the job is running by now: intake alone takes longer
                os.kill(pid, signal.SIGSEGV)
                killed.append(pid)
            time.sleep(0.01)

    thread = threading.Thread(target=crash_the_worker)
    thread.start()
    message = expect_operator_error(bpy.ops.object.qgp_quad_remesh, target_faces=800)
    thread.join()
    assert killed, "the operator did not run in a worker process"
    assert "SIGSEGV" in message and "unaffected" in message, message
    assert scene_state() == before
    assert bpy.ops.object.qgp_quad_remesh(target_faces=800) == {"FINISHED"}, "no fresh worker after a crash"
    assert operators._session_cache[obj.name][1].pid != killed[0]
    print(f"worker crash: reported ({message[:60]}...), scene unchanged, next run fine")


def test_worker_start_failure_warns():
    """A worker that cannot start (the add-on's hook worker.python_executable pointed at a missing
    interpreter): both operators still run the job, inside Blender, and report a WARNING naming why;
    the cached in-process session warns again on its next job."""
    worker = sys.modules[MODULE + ".core.worker"]
    operators = sys.modules[MODULE + ".operators"]
    reset_scene()
    bpy.ops.mesh.primitive_uv_sphere_add(segments=40, ring_count=20)
    obj = bpy.context.active_object
    original = worker.python_executable
    worker.python_executable = lambda: "/nonexistent/qgp-python3"
    outputs = []
    try:
        for op, options in ((bpy.ops.object.qgp_quad_remesh, dict(target_faces=400, keep_source_visible=True)),
                            (bpy.ops.object.qgp_grid_uv, dict(target_faces=400, flip_free_copy=False))):
            select_only(obj)
            out = io.StringIO()
            with contextlib.redirect_stdout(out):  # bpy.ops writes an operator's reports to sys.stdout
                result = op(**options)
            print(out.getvalue(), end="")
            assert result == {"FINISHED"}, result
            outputs.append(out.getvalue())
        session = operators._session_cache[obj.name][1]
        assert not hasattr(session, "pid"), "the job ran in a worker process"
    finally:
        worker.python_executable = original
        entry = operators._session_cache.pop(obj.name, None)
        if entry:
            entry[1].close()
    quad = bpy.data.objects[obj.name + "_quads"]
    assert {len(p.vertices) for p in quad.data.polygons} == {4}
    assert len(quad.data.polygons) == quad["qgp"]["quads_expected"] > 0, quad["qgp"].to_dict()
    assert "QGP Grid" in obj.data.uv_layers
    for output in outputs:
        warnings = [line for line in output.splitlines() if line.startswith("Warning:")]
        assert any("inside Blender" in w and "/nonexistent/qgp-python3" in w for w in warnings), output
    print(f"worker start failure: {len(quad.data.polygons)} quads and grid UVs in-process, warned: {warnings[0][:90]}")


def test_quad_remesh(binding):
    """Suzanne (subdivided), a torus, camelhead (open), fandisk with its sharp edges marked and a CAD
    part with the angle option: a new all-quad object next to an untouched source, with the
    source's name, transform, collection and materials."""
    reset_scene()
    cases = [(addon_checks.moved_suzanne(), 1200, {})]
    bpy.ops.mesh.primitive_torus_add(major_segments=64, minor_segments=24)
    cases.append((bpy.context.active_object, 600, {}))
    cases.append((import_mesh(binding, "camelhead.off"), 2000, {}))  # open: a boundary loop
    fandisk = import_mesh(binding, "fandisk.obj")
    marked = mark_sharp_edges(fandisk, math.radians(40))
    assert marked > 600, marked
    cases.append((fandisk, 2000, dict(use_marked_sharp=True, use_sharp_angle=False)))
    # A CAD part: edges sharper than 40 degrees are kept (the operator's angle option).
    cases.append((import_mesh(binding, "joint.obj"), 2000,
                  dict(use_marked_sharp=False, use_sharp_angle=True, sharp_angle=math.radians(40))))
    material = bpy.data.materials.new("qgp_test_material")
    collection = bpy.data.collections.new("qgp_test_collection")
    bpy.context.scene.collection.children.link(collection)
    for source, _, _ in cases:
        source.data.materials.append(material)
        for c in list(source.users_collection):
            c.objects.unlink(source)
        collection.objects.link(source)
    for source, target, options in cases:
        quad = run_quad_remesh(source, target_faces=target, **options)
        assert [c.name for c in quad.users_collection] == ["qgp_test_collection"], quad.users_collection
        assert [m.name for m in quad.data.materials] == ["qgp_test_material"], list(quad.data.materials)
        figures = check_quad_object(binding, source, quad, target)
        n = len(quad.data.polygons)
        extra = ""
        if options.get("use_marked_sharp"):
            coverage = check_sharp_edges_kept(binding, source, quad, marked, math.radians(40))
            extra = f", {100 * coverage:.1f} % of the marked sharp edges covered, no flipped quad"
        # The operator selects the quads that face against the source, and only those: none here.
        selected = sum(p.select for p in quad.data.polygons)
        assert selected == 0 == figures["flipped_quads"], (selected, figures)
        paths = ", ".join(sorted(set(figures["quad_paths"])))
        print(f"{source.name}: {n} quads = quads_expected (target {target}; {paths}), Euler characteristic "
              f"kept{extra}")


def test_keep_source_visible():
    """Keep Source Visible (the remesh operator's keep_source_visible, also in the panel): on, the
    source stays visible; off (the default), it is hidden; either way its mesh data is unchanged and
    the new object is visible."""
    assert bpy.context.scene.qgp_settings.keep_source_visible is False
    assert bpy.ops.object.qgp_quad_remesh.get_rna_type().properties["keep_source_visible"].default is False
    reset_scene()
    bpy.ops.mesh.primitive_torus_add(major_segments=48, minor_segments=16)
    torus = bpy.context.active_object
    before = addon_checks.mesh_data_state(torus)
    for keep in (True, False):
        select_only(torus)
        assert not torus.hide_get()
        result = bpy.ops.object.qgp_quad_remesh(target_faces=300, keep_source_visible=keep)
        assert result == {"FINISHED"}, result
        quad = bpy.context.active_object
        assert quad is not torus and not quad.hide_get()
        assert torus.hide_get() is (not keep), (keep, torus.hide_get())
        assert torus.visible_get() is keep
        assert addon_checks.mesh_data_state(torus) == before, "the source's mesh data changed"
        torus.hide_set(False)
    print("Keep Source Visible: on keeps the source shown, off hides it; its data unchanged")


def test_redo_reuses_session():
    """Redo (undo, then the operator again with new options, as the redo panel does) with only the
    density changed reuses the object's native session: the report shows the seamless map solved
    for the first density, re-quantized at a scale other than 1. Moving a vertex drops the session:
    a fresh worker solves the map for the new density (scale 1)."""
    operators = sys.modules[MODULE + ".operators"]
    reset_scene()
    bpy.ops.mesh.primitive_torus_add(major_segments=64, minor_segments=24)
    name = bpy.context.active_object.name
    bpy.ops.ed.undo_push(message="torus")
    assert bpy.ops.object.qgp_quad_remesh(target_faces=600) == {"FINISHED"}
    session = operators._session_cache[name][1]
    first = session.report()

    def scales(report):  # the scale the density gives (the count kept may move the one used)
        return [c["nominal_scale"] for c in report["quantization"]["components"]]

    assert set(scales(first)) == {1.0}, scales(first)  # solved for this density
    assert first["timings_s"]["seamless_map"] > 0.01, first["timings_s"]
    bpy.ops.ed.undo_push(message="remesh at 600")
    bpy.ops.ed.undo()
    assert bpy.data.objects.get(name + "_quads") is None, "undo did not remove the quads"
    select_only(bpy.data.objects[name])
    assert bpy.ops.object.qgp_quad_remesh(target_faces=900) == {"FINISHED"}
    assert operators._session_cache[name][1] is session and session.alive, "the session was not reused"
    redo = session.report()
    assert redo["seamless"]["edge_length"] == first["seamless"]["edge_length"], "the seamless map was solved again"
    assert all(s != 1.0 for s in scales(redo)), scales(redo)
    assert redo["timings_s"]["seamless_map"] < 0.01 * first["timings_s"]["seamless_map"], redo["timings_s"]
    quads = bpy.data.objects[name + "_quads"]
    assert len(quads.data.polygons) == quads["qgp"]["quads_expected"] != first["quantization"]["quads_expected"]
    # An edit of the source drops the session.
    torus = bpy.data.objects[name]
    torus.data.vertices[0].co.z += 0.05
    torus.data.update()
    select_only(torus)
    assert bpy.ops.object.qgp_quad_remesh(target_faces=900) == {"FINISHED"}
    fresh = operators._session_cache[name][1]
    assert fresh is not session and not session.alive, "the edited mesh reused the old session"
    if hasattr(session, "pid"):
        assert fresh.pid != session.pid
    again = fresh.report()
    assert set(scales(again)) == {1.0}, scales(again)
    assert again["seamless"]["edge_length"] != first["seamless"]["edge_length"]
    print(f"redo: session reused (seamless map of {first['timings_s']['seamless_map']:.2f} s kept, re-quantized at "
          f"scale {scales(redo)[0]:.3f}); after a vertex moved: a fresh solve")


def test_guides():
    """Seams, material boundaries and face sets as guides (each an operator option, off by default):
    a ring of a UV sphere marked each way becomes a curve of quad edges with its option on; the
    option changes the features, so it re-solves instead of reusing the cached session."""
    operators = sys.modules[MODULE + ".operators"]
    properties = bpy.ops.object.qgp_quad_remesh.get_rna_type().properties
    for guide, option in (("SEAM", "use_seams"), ("MATERIAL", "use_material_boundaries"),
                          ("FACE_SET", "use_face_sets")):
        assert properties[option].default is False, option
        reset_scene()
        off, on = addon_checks.run_guide(guide, option)
        print(f"guide {guide}: ring edges within {on:.3f} (on) / {off:.3f} (off) quad edge lengths of a quad edge")
    source = bpy.data.objects[0]
    session = operators._session_cache[source.name][1]
    select_only(source)
    assert bpy.ops.object.qgp_quad_remesh(target_faces=300, use_face_sets=False) == {"FINISHED"}
    assert operators._session_cache[source.name][1] is not session, "a changed guide reused the session"


def test_attributes_kept():
    """Keep Attributes (on by default) and Keep Source UVs (off by default): the quad object gets the
    source's vertex groups, colour and face attributes, and with Keep Source UVs its UV map; with
    both off only its materials. The source is unchanged."""
    properties = bpy.ops.object.qgp_quad_remesh.get_rna_type().properties
    assert properties["keep_attributes"].default is True and properties["keep_source_uvs"].default is False
    reset_scene()
    source = addon_checks.attribute_sphere()
    before = addon_checks.mesh_data_state(source)
    for keep_uvs in (False, True):
        quad = run_quad_remesh(source, target_faces=300, keep_source_visible=True, keep_source_uvs=keep_uvs)
        error = addon_checks.check_attributes_kept(source, quad, keep_uvs)
        print(f"attributes kept on {len(quad.data.polygons)} quads (UV map: {keep_uvs}): weights within {error:.4f}")
        bpy.data.objects.remove(quad)
    quad = run_quad_remesh(source, target_faces=300, keep_attributes=False)
    addon_checks.check_attributes_not_kept(quad)
    assert addon_checks.mesh_data_state(source) == before, "the source changed"
    print("Keep Attributes off: materials only")


def test_symmetry():
    """Symmetry (X, Y, Z toggles, all off by default): Suzanne (subdivided, moved and turned: the
    planes are the object's own) about X, and a UV sphere about X and Z: mirror-symmetric quads,
    welded on the planes, the count asked for; the source unchanged."""
    properties = bpy.ops.object.qgp_quad_remesh.get_rna_type().properties
    assert tuple(properties["symmetry"].default_array) == (False, False, False)
    for axes, target in addon_checks.SYMMETRY_CASES:
        reset_scene()
        source = addon_checks.symmetry_source(axes)
        count, error = addon_checks.run_symmetry(source, axes, target)
        print(f"symmetry {axes.upper()} on {source.name}: {count} quads (target {target}), mirror images within "
              f"{error:.1e} of the diagonal, welded")


def test_polygon_order():
    """Blender gives a new mesh's polygons and loops in another order from run to run (a UV sphere's
    do): the same vertices and polygons in any order, each from any corner, give the same quads."""
    reset_scene()
    bpy.ops.mesh.primitive_uv_sphere_add(segments=64, ring_count=32)
    ellipsoid = bpy.context.active_object
    ellipsoid.scale = (1, 1, 3)
    bpy.ops.object.transform_apply(scale=True)
    vertices = [tuple(v.co) for v in ellipsoid.data.vertices]
    polygons = [list(p.vertices) for p in ellipsoid.data.polygons]
    rng = random.Random(7)
    rng.shuffle(polygons)
    polygons = [p[k:] + p[:k] for p, k in ((p, rng.randrange(len(p))) for p in polygons)]
    mesh = bpy.data.meshes.new("shuffled")
    mesh.from_pydata(vertices, [], polygons)
    shuffled = bpy.data.objects.new("shuffled", mesh)
    bpy.context.collection.objects.link(shuffled)
    results = []
    for source in (ellipsoid, shuffled):
        quad = run_quad_remesh(source, target_faces=800, keep_source_visible=True)
        results.append(([tuple(v.co) for v in quad.data.vertices], [tuple(p.vertices) for p in quad.data.polygons]))
    assert results[0] == results[1], [(len(v), len(p)) for v, p in results]
    print(f"polygon order: the same {len(results[0][1])} quads from the ellipsoid and its shuffled copy")


def test_density():
    """Adaptive Size (0 by default) and the painted density (Density Group / Density Colour, none by
    default): a sphere stretched to an ellipsoid gets shorter edges at its tips with Adaptive Size 1
    than with 0; a sphere painted on its upper half gets shorter edges there, by vertex group and by
    colour attribute; a missing map is refused by name."""
    properties = bpy.ops.object.qgp_quad_remesh.get_rna_type().properties
    assert properties["adaptive"].default == 0 and properties["density_group"].default == ""
    reset_scene()
    bpy.ops.mesh.primitive_uv_sphere_add(segments=64, ring_count=32)
    ellipsoid = bpy.context.active_object
    ellipsoid.scale = (1, 1, 3)
    bpy.ops.object.transform_apply(scale=True)
    ratios = []
    for adaptive in (0.0, 1.0):
        quad = run_quad_remesh(ellipsoid, target_faces=800, adaptive=adaptive, keep_source_visible=True)
        ratios.append(addon_checks.mean_quad_edge(quad, lambda m: abs(m.z) > 2.5) /
                      addon_checks.mean_quad_edge(quad, lambda m: abs(m.z) < 1.0))
        bpy.data.objects.remove(quad)
    assert ratios[1] < 0.85 * ratios[0], ratios
    print(f"adaptive size: ellipsoid tips / middle edge length {ratios[0]:.2f} (0) -> {ratios[1]:.2f} (1)")
    reset_scene()
    group, color = addon_checks.run_density(addon_checks.painted_sphere())
    print(f"painted density 4 on the upper half: edges above / below {group:.2f} (vertex group), "
          f"{color:.2f} (colour attribute)")


def test_show_layout():
    """Show Layout (off by default): beside the quads, an object '<name>_layout' of edges only with
    the source's transform: exactly the native session's layout lines (the T-mesh, traced on the
    seamless map before quantization, so its lines need not run along quad edges), every point on
    the source surface; the quad object stays the active one."""
    from mathutils.bvhtree import BVHTree
    operators = sys.modules[MODULE + ".operators"]
    assert bpy.ops.object.qgp_quad_remesh.get_rna_type().properties["show_layout"].default is False
    reset_scene()
    bpy.ops.mesh.primitive_torus_add(major_segments=48, minor_segments=16)
    torus = bpy.context.active_object
    torus.location = (0.5, 0.0, 1.0)
    bpy.context.view_layer.update()
    assert bpy.ops.object.qgp_quad_remesh(target_faces=300, show_layout=True) == {"FINISHED"}
    quad, layout = bpy.data.objects[torus.name + "_quads"], bpy.data.objects[torus.name + "_layout"]
    assert bpy.context.active_object == quad and not layout.select_get()
    assert layout.matrix_world == torus.matrix_world and layout.show_in_front
    mesh = layout.data
    points, segments = operators._session_cache[torus.name][1].layout_lines()
    assert len(mesh.polygons) == 0 and len(mesh.edges) == len(segments) > 100, (len(mesh.edges), len(segments))
    assert len(mesh.vertices) == len(points)
    assert {tuple(sorted(e.vertices)) for e in mesh.edges} == {tuple(sorted(s)) for s in segments.tolist()}
    tree = BVHTree.FromObject(torus, bpy.context.evaluated_depsgraph_get())
    off_surface = max(tree.find_nearest(v.co)[3] for v in mesh.vertices)
    assert off_surface < 1e-5, off_surface
    select_only(torus)
    assert bpy.ops.object.qgp_quad_remesh(target_faces=300) == {"FINISHED"}
    assert bpy.data.objects.get(torus.name + "_layout.001") is None, "a layout without Show Layout"
    print(f"layout: {len(mesh.edges)} segments, all on the surface (within {off_surface:.1e}); none when off")


class RecordingLayout:
    """Stands in for a UILayout when drawing headless (blender -b draws no panel): records every
    property drawn and checks it exists on its data and is drawn without property split (a split
    cuts long labels at the sidebar's default width); operator buttons check the options set on
    them against the operator's properties."""

    def __init__(self, drawn, parent=None):
        self.drawn, self.parent = drawn, parent
        self.use_property_split = False
        self.use_property_decorate = True
        self.active = True

    def _child(self, *args, **kwargs):
        return RecordingLayout(self.drawn, self)

    column = row = box = split = _child

    def _split(self):
        return self.use_property_split or (self.parent is not None and self.parent._split())

    def prop(self, data, name, **kwargs):
        assert name in data.bl_rna.properties, (data, name)
        assert not self._split(), f"{name} drawn with property split"
        self.drawn.append(name)

    def prop_search(self, data, name, search_data, search_name, **kwargs):
        assert search_name in search_data.bl_rna.properties, (search_data, search_name)
        self.prop(data, name)

    def label(self, text="", **kwargs):
        assert text, "an empty label"

    def separator(self, **kwargs):
        pass

    def operator(self, idname, **kwargs):
        self.drawn.append(idname)
        category, name = idname.split(".")
        return OptionsCheck(getattr(getattr(bpy.ops, category), name).get_rna_type().properties)


class OptionsCheck:
    """An operator button's options: only the operator's own properties can be set."""

    def __init__(self, properties):
        object.__setattr__(self, "properties", properties)

    def __setattr__(self, name, value):
        assert name in self.properties, f"the operator has no option {name}"


class RedoOptions:
    """An operator's options as its redo panel's draw() sees them: the defaults, and the layout."""

    def __init__(self, operator_class, layout):
        self.bl_rna = getattr(bpy.ops.object, operator_class.bl_idname.split(".")[1]).get_rna_type()
        self.layout = layout
        for prop in self.bl_rna.properties:
            if prop.identifier != "rna_type":
                setattr(self, prop.identifier, getattr(prop, "default", None))
        self._draw_target = lambda layout: operator_class._draw_target(self, layout)


def test_panel_draws():
    """The sidebar panel and its sub-panels (Density, Features, Output) and both operators' redo
    panels draw every option (each with a tooltip), without property split; the panel's buttons get
    only options their operator has."""
    ui = sys.modules[MODULE + ".ui"]
    operators = sys.modules[MODULE + ".operators"]
    settings = bpy.context.scene.qgp_settings
    assert [p.bl_label for p in ui.PANELS] == ["Quantized Retopo", "Density", "Features", "Output"]
    assert all(p.bl_parent_id == "VIEW3D_PT_qgp_retopo" for p in ui.PANELS[1:])
    reset_scene()
    bpy.ops.mesh.primitive_cube_add()
    drawn = []
    for mode in ("FACES", "EDGE"):
        settings.target_mode = mode
        for panel in ui.PANELS:
            panel.draw(type("Panel", (), {"layout": RecordingLayout(drawn)})(), bpy.context)
    settings.target_mode = "FACES"
    names = {p.identifier for p in settings.bl_rna.properties} - {"rna_type", "name"}
    assert set(drawn) >= names, names - set(drawn)
    assert {"object.qgp_quad_remesh", "object.qgp_grid_uv"} <= set(drawn)
    missing = [p.identifier for p in settings.bl_rna.properties if p.identifier in names and not p.description]
    for operator_class in (operators.OBJECT_OT_qgp_quad_remesh, operators.OBJECT_OT_qgp_grid_uv):
        redo = []
        options = RedoOptions(operator_class, RecordingLayout(redo))
        operator_class.draw(options, bpy.context)
        own = {p.identifier for p in options.bl_rna.properties} - {"rna_type", "edge_length"}
        assert set(redo) == own, (operator_class.bl_idname, own ^ set(redo))
        missing += [f"{operator_class.bl_idname}.{p.identifier}" for p in options.bl_rna.properties
                    if p.identifier != "rna_type" and not p.description]
    assert not missing, f"options without a tooltip: {missing}"
    print(f"panel: {len(ui.PANELS)} panels drew {len(set(drawn))} options and buttons; redo panels complete")


def test_select_faces():
    """The remesh operator's flipped-quad selection: exactly the listed polygons, with their edges
    and vertices; the rest deselected; ids out of range ignored."""
    blender_mesh = sys.modules[MODULE + ".blender_mesh"]
    reset_scene()
    n = 4  # 4 x 4 quads
    vertices = [(x, y, 0.0) for y in range(n + 1) for x in range(n + 1)]
    faces = [(y * (n + 1) + x, y * (n + 1) + x + 1, (y + 1) * (n + 1) + x + 1, (y + 1) * (n + 1) + x)
             for y in range(n) for x in range(n)]
    mesh = bpy.data.meshes.new("qgp_select_test")
    mesh.from_pydata(vertices, [], faces)
    mesh.update(calc_edges=True)
    for v in mesh.vertices:
        v.select = True
    assert blender_mesh.select_faces(mesh, [5, 10, -1, 99]) == 2
    assert [p.index for p in mesh.polygons if p.select] == [5, 10]
    want_vertices = set(faces[5]) | set(faces[10])
    assert {v.index for v in mesh.vertices if v.select} == want_vertices
    want_edges = {tuple(sorted(k)) for i in (5, 10) for k in mesh.polygons[i].edge_keys}
    assert {tuple(sorted(e.vertices)) for e in mesh.edges if e.select} == want_edges
    assert len(want_edges) == 8  # the two quads share a corner, not an edge
    assert blender_mesh.select_faces(mesh, []) == 0
    assert not any(p.select for p in mesh.polygons) and not any(v.select for v in mesh.vertices)
    assert not any(e.select for e in mesh.edges)
    bpy.data.meshes.remove(mesh)
    print("select_faces: exactly the listed quads")


def test_grid_uv(binding):
    reset_scene()
    bpy.ops.mesh.primitive_monkey_add()
    monkey = bpy.context.active_object  # quads and triangles
    monkey.modifiers.new("subsurf", "SUBSURF").levels = 1
    bpy.ops.object.modifier_apply(modifier="subsurf")
    cases = [(monkey, 1000, 4.0), (import_mesh(binding, "bunny.off"), 800, 1.0)]
    bpy.ops.mesh.primitive_torus_add(major_segments=64, minor_segments=24)
    cases.append((bpy.context.active_object, 600, 2.0))
    cases.append((import_mesh(binding, "camelhead.off"), 2000, 1.0))
    fandisk = import_mesh(binding, "fandisk.obj")
    mark_sharp_edges(fandisk, math.radians(40))  # the operator uses marked sharp edges by default
    cases.append((fandisk, 2000, 1.0))
    for obj, target, per_unit in cases:
        loops, seams, residual = run_grid_uv(sys.modules[MODULE + ".operators"], obj, target, per_unit)
        print(f"{obj.name}: grid UVs on {loops} loops, {seams} seams, transition residual {residual:.2e}")


def test_grid_uv_seams_off():
    """Mark Seams off: the map has cuts (UV islands), but no edge is marked."""
    reset_scene()
    bpy.ops.mesh.primitive_torus_add(major_segments=64, minor_segments=24)
    torus = bpy.context.active_object
    result = bpy.ops.object.qgp_grid_uv(target_faces=600, mark_seams=False)
    assert result == {"FINISHED"}, result
    cuts = uv_cut_edges(torus.data, torus.data.uv_layers["QGP Grid"])
    assert cuts, "no UV island boundary: the check below would be empty"
    assert not seam_edges(torus.data), len(seam_edges(torus.data))
    print(f"Mark Seams off: {len(cuts)} cut edges, none marked")


def test_grid_uv_flip_free_copy(binding):
    """spot at 200 quads: its global map keeps 2 wound one-rings (joint at 300 quads, used here until
    2026-12-02, now has a regular map), so Flip-Free Copy writes a new object (the layout's edges
    inserted) whose map has none; without it, the source gets the map."""
    reset_scene()
    spot = import_mesh(binding, "spot.obj")
    before = [tuple(v.co) for v in spot.data.vertices]
    result = bpy.ops.object.qgp_grid_uv(target_faces=200, quads_per_unit=2.0)
    assert result == {"FINISHED"}, result
    copy = bpy.data.objects.get("spot_grid_uv")
    assert copy is not None, [o.name for o in bpy.data.objects]
    assert "QGP Grid" not in spot.data.uv_layers and [tuple(v.co) for v in spot.data.vertices] == before
    assert copy.matrix_world == spot.matrix_world and bpy.context.active_object == copy
    mesh = copy.data
    assert len(mesh.polygons) > len(spot.data.polygons) and all(len(p.vertices) == 3 for p in mesh.polygons)
    layer = mesh.uv_layers["QGP Grid"]
    uv = [(d.uv[0] * 2.0, d.uv[1] * 2.0) for d in layer.data]
    areas = []
    for poly in mesh.polygons:
        a, b, c = (uv[i] for i in poly.loop_indices)
        areas.append(0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])))
    # Float32 UVs: exactly degenerate triangles (collapsed cells) may round to a tiny negative area.
    flipped = sum(a < -1e-6 for a in areas)
    assert flipped == 0, flipped
    residual = grid_seam_residual(mesh, layer, 2.0)
    assert residual < 1e-3, residual
    print(f"{copy.name}: flip-free grid UVs on {len(mesh.polygons)} triangles (source {len(spot.data.polygons)}), "
          f"uv area {sum(areas):.1f} quads, transition residual {residual:.2e}, source unchanged")
    assert not seam_edges(mesh), "Mark Seams is off"
    assert copy["qgp"]["refined_components"] >= 1 and copy["qgp"]["seams"] == 0, copy["qgp"].to_dict()
    select_only(spot)
    result = bpy.ops.object.qgp_grid_uv(target_faces=200, flip_free_copy=False)
    assert result == {"FINISHED"}, result
    assert "QGP Grid" in spot.data.uv_layers and bpy.data.objects.get("spot_grid_uv.001") is None
    # Mark Seams with a Flip-Free Copy: the copy's seams are its UV islands' inner boundaries; the
    # source keeps none.
    select_only(spot)
    result = bpy.ops.object.qgp_grid_uv(target_faces=200, quads_per_unit=2.0, mark_seams=True)
    assert result == {"FINISHED"}, result
    copy = bpy.data.objects["spot_grid_uv.001"]
    seams = seam_edges(copy.data)
    islands = uv_cut_edges(copy.data, copy.data.uv_layers["QGP Grid"], 1e-4 / 2.0)
    assert seams and seams == islands, (len(seams), len(islands), len(seams - islands), len(islands - seams))
    assert copy["qgp"]["seams"] == len(seams), (copy["qgp"].to_dict(), len(seams))
    assert not seam_edges(spot.data), "the source got seams"
    print(f"{copy.name}: {len(seams)} seams marked on the copy, none on the source")


def test_undo_restores_scene():
    reset_scene()
    bpy.ops.mesh.primitive_torus_add(major_segments=64, minor_segments=24)
    bpy.ops.ed.undo_push(message="before remesh")
    before = scene_state()
    assert bpy.ops.object.qgp_quad_remesh(target_faces=600) == {"FINISHED"}
    bpy.ops.ed.undo_push(message="after remesh")
    assert scene_state() != before
    bpy.ops.ed.undo()
    assert scene_state() == before, "undo did not restore the scene"
    print("undo: scene restored")


def test_batch():
    out, sources = tempfile.mkdtemp(prefix="qgp_batch_"), tempfile.mkdtemp(prefix="qgp_batch_in_")
    inputs = []
    for name, width in (("moebius_a.obj", 0.3), ("moebius_b.obj", 0.5)):  # non-orientable: refused
        inputs.append(os.path.join(sources, name))
        write_obj(inputs[-1], *moebius_strip(width=width))
    proc, report = run_batch(BATCH, inputs, out, "--faces", "300")
    assert proc.returncode != 0, "batch must exit non-zero when an input fails"
    assert [os.path.basename(e["input"]) for e in report["entries"]] == ["moebius_a.obj", "moebius_b.obj"]
    for e in report["entries"]:
        assert e["status"] == "error" and "non-orientable" in e["reason"], e
        assert set(e) >= {"status", "reason", "quads", "seconds"}
    print("batch: failures recorded, continued past them")


def test_batch_success():
    out = tempfile.mkdtemp(prefix="qgp_batch_")
    inputs = [os.path.join(MESHES, n) for n in ("torus.obj", "bunny.off", "spot.obj")]
    proc, report = run_batch(BATCH, inputs, out, "--faces", "200", "--uv", "--atlas", "512")
    status = {os.path.basename(e["input"]): e["status"] for e in report["entries"]}
    assert status == {"torus.obj": "ok", "bunny.off": "ok", "spot.obj": "ok"}, (status, proc.stderr[-2000:])
    assert proc.returncode == 0 and report["failed"] == 0 and report["partial"] == 0, (proc.returncode, report)
    flipped = {os.path.basename(e["input"]): e["flipped_quads"] for e in report["entries"]}
    assert flipped == {"torus.obj": 0, "bunny.off": 0, "spot.obj": 0}, flipped
    # spot at 200 quads: only the refined copy has a flip-free map; its triangles are written.
    refined = {os.path.basename(e["input"]): e.get("uv_refined") for e in report["entries"]}
    assert refined == {"torus.obj": False, "bunny.off": False, "spot.obj": True}, refined
    spot_uv = [line for line in open(os.path.join(out, "spot_uv.obj")) if line.startswith("f ")]
    assert len(spot_uv) > 5856 and all(len(line.split()) == 4 for line in spot_uv), len(spot_uv)
    for name in ("torus", "bunny", "spot"):
        path = os.path.join(out, name + ".obj")
        faces = [line for line in open(path) if line.startswith("f ")]
        assert faces and all(len(line.split()) == 5 and "/" in line for line in faces), path
        # --atlas 512: every quad corner has a vt in [0,1] (the texture atlas), the entry its figures
        vt = [tuple(map(float, line.split()[1:3])) for line in open(path) if line.startswith("vt ")]
        assert len(vt) == 4 * len(faces) and all(0 <= u <= 1 and 0 <= v <= 1 for u, v in vt), path
        entry = next(e for e in report["entries"] if os.path.splitext(os.path.basename(e["input"]))[0] == name)
        assert entry["atlas"]["charts"] >= 1 and entry["atlas"]["texels_per_quad"] >= 1, entry
        assert os.path.exists(os.path.join(out, name + "_uv.obj"))
    # truck: no longer refused at intake (its non-manifold edges are cut); at 300 quads the parts
    # whose holes are narrower than a quad are rescued, as `qgp remesh truck.obj --faces 300` does:
    # ok, with the rescue as the reason. (Its grid UVs are left out: with --uv it took 280 s of this
    # test's 313 s, 2026-11-29.)
    proc, report = run_batch(BATCH, [os.path.join(MESHES, "truck.obj")], out, "--faces", "300")
    [truck] = report["entries"]
    assert truck["status"] == "ok" and proc.returncode == 0, (truck, proc.stderr[-2000:])
    assert ("quadded again: with another field, on a remesh, finer or by splitting their triangles"
            in truck["reason"]), truck
    print("batch: inputs written with grid UVs and atlases; truck rescued, exit", proc.returncode)


def test_parts_rescued(binding):
    """featuretype with Weld Open Edges off is 852 loose parts; the few whose layout gives no quads are
    rescued (quadded finer, or their triangles split), a WARNING names them with why, every part
    becomes quads, and the source is unchanged."""
    reset_scene()
    obj = import_mesh(binding, "featuretype.ply")
    select_only(obj)
    before = addon_checks.mesh_data_state(obj)
    out = io.StringIO()
    with contextlib.redirect_stdout(out):  # bpy.ops writes an operator's reports to sys.stdout
        result = bpy.ops.object.qgp_quad_remesh(target_faces=2000, weld=False, keep_source_visible=True)
    print(out.getvalue(), end="")
    assert result == {"FINISHED"}, result
    assert addon_checks.mesh_data_state(obj) == before, "the source changed"
    quad = bpy.data.objects[obj.name + "_quads"]
    figures = quad["qgp"].to_dict()
    assert figures["rescued_parts"] > 0 and figures["kept_parts"] == 0, figures
    assert all(len(p.vertices) == 4 for p in quad.data.polygons), "only quads"
    assert sum(p.startswith("rescued: ") for p in figures["quad_paths"]) == figures["rescued_parts"], \
        figures["quad_paths"]
    warnings = [line for line in out.getvalue().splitlines() if line.startswith("Warning:")]
    assert any("rescued: part " in w and "T-mesh" in w for w in warnings), warnings
    print(f"parts rescued: {len(quad.data.polygons)} quads, {figures['rescued_parts']} part(s) rescued; "
          f"{warnings[0][:100]}")


def test_count_note(binding):
    """A count the layout cannot give (a cube's six sides at 10 quads: its counts step from 6 to 12):
    the quads come, the operator warns with the report's note, which the object's figures keep."""
    reset_scene()
    path = os.path.join(tempfile.mkdtemp(prefix="qgp_cube_"), "cube.obj")
    write_obj(path, *grid_cube(6))
    obj = addon_checks.import_mesh(binding, path)
    select_only(obj)
    out = io.StringIO()
    with contextlib.redirect_stdout(out):  # bpy.ops writes an operator's reports to sys.stdout
        result = bpy.ops.object.qgp_quad_remesh(target_faces=10)
    print(out.getvalue(), end="")
    assert result == {"FINISHED"}, result
    figures = bpy.data.objects[obj.name + "_quads"]["qgp"].to_dict()
    note = figures["count_note"]
    assert note.startswith("10 quads asked, ") and "steps from" in note, figures
    warnings = [line for line in out.getvalue().splitlines() if line.startswith("Warning:")]
    assert any(note in w for w in warnings), warnings


def test_batch_all_ok():
    """Every input succeeds: exit status 0, every entry ok with its quads, the files written."""
    out = tempfile.mkdtemp(prefix="qgp_batch_")
    proc, report = run_batch(BATCH, [os.path.join(MESHES, n) for n in ("torus.obj", "bunny.off")], out,
                             "--faces", "300")
    assert proc.returncode == 0, (proc.returncode, report, proc.stderr[-2000:])
    assert report["failed"] == 0 and [e["status"] for e in report["entries"]] == ["ok", "ok"], report
    for e in report["entries"]:
        name = os.path.splitext(os.path.basename(e["input"]))[0]
        faces = [line for line in open(os.path.join(out, name + ".obj")) if line.startswith("f ")]
        assert e["quads"] == len(faces) > 0 and e["reason"] == "", (e, len(faces))
    print("batch: all inputs ok, exit 0")


def test_batch_unexpected_failure():
    """An input failing with an exception no operator raises (its output path is a directory:
    IsADirectoryError, an OSError) is recorded with the reason, the next input still runs, the
    report is written and the exit status is non-zero."""
    out = tempfile.mkdtemp(prefix="qgp_batch_")
    os.mkdir(os.path.join(out, "torus.obj"))  # the output file of the first input cannot be written
    proc, report = run_batch(BATCH, [os.path.join(MESHES, n) for n in ("torus.obj", "bunny.off")], out,
                             "--faces", "300")
    assert proc.returncode == 1, (proc.returncode, proc.stderr[-2000:])
    entries = {os.path.basename(e["input"]): e for e in report["entries"]}
    assert list(entries) == ["torus.obj", "bunny.off"] and report["failed"] == 1, report
    torus, bunny = entries["torus.obj"], entries["bunny.off"]
    assert torus["status"] == "error" and "IsADirectoryError" in torus["reason"], torus
    assert os.path.join(out, "torus.obj") in torus["reason"], torus
    assert bunny["status"] == "ok" and bunny["quads"] > 0, bunny
    assert os.path.exists(os.path.join(out, "bunny.obj"))
    print(f"batch: unexpected failure recorded ({torus['reason'][:60]}...), continued, exit 1")


def main():
    addon = addon_checks.install_legacy_addon(REPO, MODULE)
    from importlib import import_module
    binding = import_module(MODULE + ".core.binding")
    print("installed", addon.__file__, "library", binding.version())
    tests = [(test_registration, ()), (test_broken_inputs, (binding,)),
             (test_cancel_leaves_scene_unchanged, (binding,)), (test_worker_fault_leaves_blender_running, ()),
             (test_worker_start_failure_warns, ()), (test_select_faces, ()), (test_keep_source_visible, ()),
             (test_redo_reuses_session, ()), (test_guides, ()), (test_attributes_kept, ()), (test_symmetry, ()),
             (test_density, ()), (test_polygon_order, ()), (test_panel_draws, ()),
             (test_show_layout, ()),
             (test_quad_remesh, (binding,)), (test_grid_uv, (binding,)), (test_grid_uv_seams_off, ()),
             (test_grid_uv_flip_free_copy, (binding,)), (test_undo_restores_scene, ()), (test_batch, ()),
             (test_batch_success, ()), (test_batch_all_ok, ()), (test_batch_unexpected_failure, ()),
             (test_parts_rescued, (binding,)), (test_count_note, (binding,))]
    # --only NAME[,NAME...]: just these tests (while working on them); the suite runs them all.
    only = ARGS[ARGS.index("--only") + 1].split(",") if "--only" in ARGS else None
    assert only is None or {t.__name__ for t, _ in tests} >= set(only), only
    for test, args in tests:
        if only is None or test.__name__ in only:
            start = time.monotonic()
            test(*args)
            print(f"-- {test.__name__}: {time.monotonic() - start:.1f} s")
    print("add-on test: OK" if only is None else f"add-on test: OK ({len(only)} of {len(tests)} tests)")


main()

"""The add-on as a Blender 4.2+ extension, in Blender as a Python module (PyPI's bpy; scripts/setup_bpy.sh
makes one virtual environment per Blender version):

    .venv-bpy-4.5/bin/python THIS [--blender 4.5] [--meshes ../shared/meshes]

Installs the linux-x64 extension zip through Blender's extensions API into a temporary user resource
directory (BLENDER_USER_RESOURCES: nothing lands in ~/.config), enables it, runs both operators on
fandisk with its edges sharper than 40 degrees marked sharp and on the Stanford bunny, checks them as
test_addon.py does (addon_checks.py), and runs the installed extension's batch script with this
interpreter on joint (a CAD part, with --sharp-angle) and a torus. Blender's UI (panels, modal jobs,
Esc, redo) has no module counterpart: the Blender 3.4 binary tests cover it. The targets are small
(400 quads) to keep each version's run short."""
import glob
import math
import os
import shutil
import sys
import tempfile

# Before bpy is imported: Blender reads its user resource directory once, at start.
USER_RESOURCES = tempfile.mkdtemp(prefix="qgp_bpy_user_")
os.environ["BLENDER_USER_RESOURCES"] = USER_RESOURCES
os.environ.pop("QGP_LIBRARY", None)  # the extension's own lib/libqgp.so, as a user gets it

import bpy  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))
import addon_checks  # noqa: E402
from addon_checks import (check_quad_object, check_sharp_edges_kept, mark_sharp_edges, reset_scene,  # noqa: E402
                          run_batch, run_grid_uv, run_quad_remesh)

REPO = os.path.dirname(os.path.dirname(os.path.dirname(HERE)))
ARGS = addon_checks.script_arguments()
MESHES = addon_checks.argument(ARGS, "--meshes", os.path.join(REPO, "..", "shared", "meshes"))
# --blender X.Y: the Blender series the venv must hold (so a venv with another bpy cannot pass for it).
EXPECTED = addon_checks.argument(ARGS, "--blender", None)
EXTENSION_ID = "quantized_retopo"
REPO_MODULE = "user_default"  # Blender's default local extension repository
PACKAGE = f"bl_ext.{REPO_MODULE}.{EXTENSION_ID}"
TARGET = 400


def install_extension():
    """Installs and enables the extension zip the way Preferences > Get Extensions > Install from
    Disk does; returns the add-on's package."""
    zips = sorted(glob.glob(os.path.join(REPO, "dist", EXTENSION_ID + "-*-linux_x64.zip")))
    assert zips, "build the zips first (scripts/build_extension.py)"
    extensions = bpy.utils.user_resource("EXTENSIONS")
    assert extensions.startswith(USER_RESOURCES), (extensions, USER_RESOURCES)
    result = bpy.ops.extensions.package_install_files(filepath=zips[-1], repo=REPO_MODULE, enable_on_install=True)
    assert result == {"FINISHED"}, result
    assert PACKAGE in bpy.context.preferences.addons, [a.module for a in bpy.context.preferences.addons]
    package = sys.modules[PACKAGE]
    folder = os.path.dirname(package.__file__)
    assert folder == os.path.join(extensions, REPO_MODULE, EXTENSION_ID), folder
    assert os.path.exists(os.path.join(folder, "lib", "libqgp.so")), "native library not installed"
    return package


def test_registration(binding):
    assert hasattr(bpy.types, "OBJECT_OT_qgp_quad_remesh") and hasattr(bpy.types, "OBJECT_OT_qgp_grid_uv")
    assert hasattr(bpy.types, "VIEW3D_PT_qgp_retopo") and hasattr(bpy.context.scene, "qgp_settings")
    prefs = bpy.context.preferences.addons[PACKAGE].preferences
    assert prefs is not None and prefs.isolate, "the add-on's preferences are not registered"
    binding.load_library()
    installed = os.path.dirname(sys.modules[PACKAGE].__file__)
    assert binding.loaded_library_path() == os.path.join(installed, "lib", "libqgp.so"), binding.loaded_library_path()
    print(f"registered; library {binding.version()} from the extension's lib/")


def fandisk_marked_sharp(binding):
    """fandisk with its edges sharper than 40 degrees marked sharp; (object, marked edge count). The
    add-on reads back exactly the marks (Blender 4.1+ keeps them in the 'sharp_edge' attribute)."""
    fandisk = addon_checks.import_mesh(binding, os.path.join(MESHES, "fandisk.obj"))
    marked = mark_sharp_edges(fandisk, math.radians(40))
    assert marked > 600, marked
    flags = sys.modules[PACKAGE + ".blender_mesh"].sharp_edge_flags(fandisk.data)
    assert int(flags.sum()) == marked, (int(flags.sum()), marked)
    return fandisk, marked


def worker_session(obj):
    """The object's cached native session; it ran in a worker process (the venv's interpreter
    started it), not inside Blender."""
    session = sys.modules[PACKAGE + ".operators"]._session_cache[obj.name][1]
    assert getattr(session, "pid", None), "the job ran inside Blender: no worker process started"
    return session


def test_operators(binding):
    """Quantized Retopo, then Integer-Grid UVs on the same source (one native session: fandisk's
    seamless map, the slow stage, is solved once): fandisk with marked sharp edges, and the bunny."""
    reset_scene()
    fandisk, marked = fandisk_marked_sharp(binding)
    bunny = addon_checks.import_mesh(binding, os.path.join(MESHES, "bunny.off"))
    operators = sys.modules[PACKAGE + ".operators"]
    for source in (fandisk, bunny):
        quad = run_quad_remesh(source, target_faces=TARGET, use_marked_sharp=True, use_sharp_angle=False,
                               keep_source_visible=True)
        session = worker_session(source)
        # The zip's static OpenBLAS runs its baseline kernels on every CPU (core/blas_kernels.h).
        assert session.report()["blas_kernels"] == "Prescott", session.report().get("blas_kernels")
        figures = check_quad_object(binding, source, quad, TARGET)
        extra = ""
        if source is fandisk:
            coverage = check_sharp_edges_kept(binding, source, quad, marked, math.radians(40))
            extra = f", {100 * coverage:.1f} % of the {marked} marked sharp edges covered, no flipped quad"
        assert sum(p.select for p in quad.data.polygons) == 0 == figures["flipped_quads"], figures
        print(f"{source.name}: {len(quad.data.polygons)} quads = quads_expected (target {TARGET}), edge-manifold, "
              f"Euler characteristic kept{extra}")
        loops, seams, residual = run_grid_uv(operators, source, TARGET, 1.0)
        assert worker_session(source) is session, "the grid UVs did not reuse the remesh's session"
        print(f"{source.name}: grid UVs on {loops} loops, {seams} seams, transition residual {residual:.2e}")


def test_atlas_and_stitch(binding):
    """Texture Atlas and Stitch Seams through this Blender's UV map and image pixel APIs: the bunny's
    quads with the UV map 'QGP Atlas' (UVs in [0,1]); an image of random colours stitched: texels inside
    quads unchanged, gutter texels beside seams filled."""
    import numpy as np
    reset_scene()
    bunny = addon_checks.import_mesh(binding, os.path.join(MESHES, "bunny.off"))
    quad = run_quad_remesh(bunny, target_faces=TARGET, texture_atlas=True, atlas_size=256, keep_source_visible=True)
    layer = quad.data.uv_layers.active
    uv = np.empty(2 * len(quad.data.loops), np.float32)
    layer.data.foreach_get("uv", uv)
    assert layer.name == "QGP Atlas" and uv.min() >= 0 and uv.max() <= 1, (layer.name, uv.min(), uv.max())
    covered = np.zeros((256, 256), bool)
    for square in np.round(uv.reshape(-1, 4, 2) * 256).astype(int):
        lo, hi = square.min(0), square.max(0)
        covered[lo[1]:hi[1], lo[0]:hi[0]] = True
    image = bpy.data.images.new("qgp_random", 256, 256)
    before = np.random.default_rng(1).random(256 * 256 * 4).astype(np.float32)
    image.pixels.foreach_set(before)
    image.pixels.foreach_get(before)  # as the image stores them
    addon_checks.select_only(quad)
    assert bpy.ops.object.qgp_stitch_seams(image_name=image.name) == {"FINISHED"}
    after = np.empty_like(before)
    image.pixels.foreach_get(after)
    before, after = before.reshape(256, 256, 4), after.reshape(256, 256, 4)
    changed = (before != after).any(axis=2)
    assert not changed[covered].any() and changed[~covered].mean() > 0.5, changed[~covered].mean()
    print(f"atlas: {quad['qgp']['atlas']['charts']} charts, {quad['qgp']['atlas']['texels_per_quad']} texels per "
          f"quad; Stitch Seams filled {changed.sum()} of {(~covered).sum()} empty texels")


def test_guides_and_attributes():
    """The APIs that differ from Blender 3.4: seams (the '.uv_seam' attribute), face sets
    ('.sculpt_face_set') and material boundaries as guides; vertex groups, colour and face
    attributes and the UV map kept on the quad object (as test_addon.py checks them in 3.4)."""
    for guide, option in (("SEAM", "use_seams"), ("MATERIAL", "use_material_boundaries"),
                          ("FACE_SET", "use_face_sets")):
        reset_scene()
        off, on = addon_checks.run_guide(guide, option)
        print(f"guide {guide}: ring edges within {on:.3f} (on) / {off:.3f} (off) quad edge lengths of a quad edge")
    reset_scene()
    source = addon_checks.attribute_sphere()
    before = addon_checks.mesh_data_state(source)
    quad = run_quad_remesh(source, target_faces=300, keep_source_visible=True, keep_source_uvs=True)
    error = addon_checks.check_attributes_kept(source, quad, True)
    assert addon_checks.mesh_data_state(source) == before, "the source changed"
    print(f"attributes and UV map kept on {len(quad.data.polygons)} quads, weights within {error:.4f}")


def test_symmetry():
    """Symmetry on this Blender's primitives (as test_addon.py checks it in 3.4): mirror-symmetric
    quads welded on the planes."""
    for axes, target in addon_checks.SYMMETRY_CASES:
        reset_scene()
        source = addon_checks.symmetry_source(axes)
        count, error = addon_checks.run_symmetry(source, axes, target)
        print(f"symmetry {axes.upper()} on {source.name}: {count} quads, mirror images within {error:.1e}, welded")


def test_painted_density():
    """The painted density on this Blender's attribute API (as test_addon.py checks it in 3.4)."""
    reset_scene()
    group, color = addon_checks.run_density(addon_checks.painted_sphere())
    print(f"painted density: edges above / below {group:.2f} (vertex group), {color:.2f} (colour attribute)")


def test_batch():
    """The installed extension's batch script, run by this interpreter (the module has no Blender
    binary: bpy.app.binary_path is empty): it registers the add-on from its own folder, with the
    bundled library."""
    batch = os.path.join(os.path.dirname(sys.modules[PACKAGE].__file__), "batch.py")
    out = tempfile.mkdtemp(prefix="qgp_batch_")
    inputs = [os.path.join(MESHES, n) for n in ("joint.obj", "torus.obj")]
    try:
        # A batch that does not end (as with bpy 4.5 at exit while an operator was registered) fails.
        proc, report = run_batch([sys.executable, batch, "--"], inputs, out, "--faces", str(TARGET),
                                 "--sharp-angle", "40", "--uv", timeout=300)
        assert proc.returncode == 0, (proc.returncode, report, proc.stderr[-2000:])
        assert report["failed"] == 0, report
        for e in report["entries"]:
            name = os.path.splitext(os.path.basename(e["input"]))[0]
            faces = [line for line in open(os.path.join(out, name + ".obj")) if line.startswith("f ")]
            assert e["status"] == "ok" and e["quads"] == len(faces) > 0 and e["flipped_quads"] == 0, e
            assert all(len(line.split()) == 5 for line in faces), name
            assert e["uv"] and os.path.exists(os.path.join(out, name + "_uv.obj")), e
    finally:
        shutil.rmtree(out, ignore_errors=True)
    print("batch: " + ", ".join(f"{os.path.basename(e['input'])} {e['quads']} quads" for e in report["entries"]))


def main():
    print(f"Blender {bpy.app.version_string} (bpy module, {sys.executable})")
    series = "%d.%d" % bpy.app.version[:2]
    assert EXPECTED is None or series == EXPECTED, f"this venv holds Blender {series}, not {EXPECTED}"
    try:
        install_extension()
        binding = sys.modules[PACKAGE + ".core.binding"]
        test_registration(binding)
        test_operators(binding)
        test_atlas_and_stitch(binding)
        test_guides_and_attributes()
        test_symmetry()
        test_painted_density()
        test_batch()
        bpy.ops.preferences.addon_disable(module=PACKAGE)
        assert not hasattr(bpy.types, "OBJECT_OT_qgp_quad_remesh"), "the add-on did not unregister"
    finally:
        shutil.rmtree(USER_RESOURCES, ignore_errors=True)
    print(f"extension module test (Blender {bpy.app.version_string}): OK")


if __name__ == "__main__":
    main()

"""The add-on over the generated torture set (tests/torture_set.py), in Blender 3.4
(blender -b --factory-startup --python-exit-code 1 --python THIS -- --build DIR): each case ends as
documented, as it does for the CLI and the C API.

Per case the file is read by the add-on's own reader into a new object (files it cannot read are
refused there, with the documented message), then Quad Remesh runs on it at TARGET_QUADS: "quads"
finishes with a valid quad object (torture_set.validate_output, against the native report of the
add-on's session) and no warning beyond flipped quads (and, "rescued", the parts rescued, with
why); "partial" finishes with the kept triangles and a warning naming them; "refused" and "failed"
end in an error with the message and change nothing. The source object's mesh data is never changed."""
import contextlib
import io
import os
import sys
import tempfile
import time

import bpy

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.dirname(HERE))  # tests/: torture_set
import addon_checks  # noqa: E402
import torture_set  # noqa: E402

REPO = os.path.dirname(os.path.dirname(HERE))
MODULE = "quantized_retopo"


def read_into_object(addon, path):
    """A new selected, active object of the file, or the reader's error message."""
    try:
        return addon_checks.import_mesh(addon.core.binding, path), ""
    except addon.core.binding.QGPError as e:
        return None, str(e)


def remesh(obj):
    """Runs Quad Remesh on obj: (result set or None, the error or warning lines, the new object)."""
    names = {o.name for o in bpy.data.objects}
    before = addon_checks.scene_state()
    out = io.StringIO()
    try:
        with contextlib.redirect_stdout(out):  # bpy.ops writes an operator's reports to sys.stdout
            result = bpy.ops.object.qgp_quad_remesh(target_faces=torture_set.TARGET_QUADS, keep_source_visible=True)
    except RuntimeError as e:
        assert addon_checks.scene_state() == before, "a failed run changed the scene"
        return None, [str(e)], None
    created = [o for o in bpy.data.objects if o.name not in names]
    lines = [line for line in out.getvalue().splitlines() if line.startswith("Warning:")]
    return result, lines, created[0] if len(created) == 1 else None


def check_output(case, addon, source, result, lines, quad):
    assert result == {"FINISHED"} and quad is not None, (result, lines)
    report = addon.operators._session_cache[source.name][1].report()
    vertices = [tuple(v.co) for v in quad.data.vertices]
    faces = [list(p.vertices) for p in quad.data.polygons]
    problems = torture_set.validate_output(vertices, faces, report)
    assert not problems, problems
    flipped = report["quad"].get("flipped_quads", 0)
    if case.outcome == "partial":
        assert any("complete except" in w and case.message in w for w in lines), lines
    else:
        # Warnings: the flipped quads, and the count note when the count asked could not be met.
        note = report["quantization"]["count"].get("note", "")
        expected = (["face against"] if flipped else []) + ([note] if note else [])
        assert all(any(e in w for e in expected) for w in lines), (lines, expected)
        assert all(any(e in w for w in lines) for e in expected), (lines, expected)
        assert case.outcome != "rescued" or any("rescued: part" in w and case.message in w for w in lines), lines
    assert not torture_set.rescue_problems(case, report), torture_set.rescue_problems(case, report)
    assert not torture_set.repairs_missing(case, report), torture_set.repairs_missing(case, report)
    return sum(len(f) == 4 for f in faces)


def run_case(case, addon, folder):
    addon_checks.reset_scene()
    start = time.monotonic()
    source, read_error = read_into_object(addon, case.write(folder, case.name))
    if source is None:
        assert case.outcome == "refused" and case.message in read_error, read_error
        return f"refused by the reader: {read_error[:70]}", time.monotonic() - start
    before = repr(addon_checks.mesh_data_state(source))
    result, lines, quad = remesh(source)
    assert repr(addon_checks.mesh_data_state(source)) == before, "the source changed"
    if case.outcome in ("refused", "failed"):
        assert result is None and case.message in lines[0], (result, lines)
        return f"error: {lines[0][:70]}", time.monotonic() - start
    quads = check_output(case, addon, source, result, lines, quad)
    return f"{quads} quads", time.monotonic() - start


def main():
    addon = addon_checks.install_legacy_addon(REPO, MODULE)
    import importlib
    for name in ("core.binding", "operators"):
        importlib.import_module(MODULE + "." + name)
    with tempfile.TemporaryDirectory() as folder:
        for case in torture_set.CASES:
            outcome, seconds = run_case(case, addon, folder)
            print(f"{case.name} | {case.outcome} | {outcome} | {seconds:.1f} s")
    print(f"torture set (add-on): all {len(torture_set.CASES)} cases as documented")


main()

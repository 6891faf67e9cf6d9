"""Smoke test in Blender (blender -b --factory-startup --python-exit-code 1 --python THIS):
the add-on's binding loads libqgp.so through ctypes and runs intake on a mesh Blender creates.
Suzanne is three open components (head and two eyes)."""
import os
import sys

import bpy

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, REPO)

from addon.core import binding, meshdata  # noqa: E402


def main():
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.mesh.primitive_monkey_add()
    obj = bpy.context.active_object
    obj.modifiers.new("subdivide", "SUBSURF").levels = 1
    mesh = obj.evaluated_get(bpy.context.evaluated_depsgraph_get()).to_mesh()
    vertices, triangles, _, _ = meshdata.mesh_arrays(mesh)
    print("library", binding.version(), "suzanne", len(vertices), "vertices", len(triangles), "triangles")
    with binding.Session(vertices, triangles) as session:
        session.run(binding.JOB_INTAKE)
        report = session.report()
        v, f, comp, input_vertex = session.intake_mesh()
    inp = report["input"]
    print("intake:", inp["components"], "components, genus", inp["genus"], "boundary loops", inp["boundary_loops"])
    assert report["status"] == "ok", report
    assert inp["components"] == 3, inp
    assert all(b > 0 for b in inp["boundary_loops"]), inp
    assert inp["genus"] == [0, 0, 0], inp
    assert len(f) == len(triangles) and comp.max() == 2
    # A broken mesh gives a clean Python error, not a crash.
    try:
        with binding.Session([[0, 0, 0], [1, 0, 0], [float("nan"), 1, 0]], [[0, 1, 2]]) as bad:
            bad.run(binding.JOB_INTAKE)
        raise AssertionError("NaN input must be refused")
    except binding.QGPError as e:
        assert e.code == binding.ERR_INVALID_MESH and "non-finite" in e.message, e.message
    # A measurement whose JSON outgrows the binding's first buffer: 120 x 120 quads wound against
    # the plane they lie on, so every quad is flipped and listed.
    n = 120
    grid = [(x, y, 0.0) for y in range(n + 1) for x in range(n + 1)]
    quads = [(y * (n + 1) + x, (y + 1) * (n + 1) + x, (y + 1) * (n + 1) + x + 1, y * (n + 1) + x + 1)
             for y in range(n) for x in range(n)]
    plane = [(0, 0, 0), (n, 0, 0), (n, n, 0), (0, n, 0)]
    m = binding.measure_polygon_mesh(grid, [4] * len(quads), [i for q in quads for i in q], plane,
                                     [(0, 1, 2), (0, 2, 3)])
    assert m["flipped_quads"] == n * n and m["flipped_quad_ids"] == list(range(n * n)), m["flipped_quads"]
    print("measurement: all", n * n, "reversed quads flipped and listed")
    print("binding smoke test: OK")


main()

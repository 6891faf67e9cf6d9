#!/usr/bin/python3
"""The add-on's bpy-free arithmetic for guides and attributes (addon/core/meshdata.py and
addon/core/attributes.py), outside Blender: loops to polygons, edges between differing faces
(material and face-set boundaries), barycentric weights of points in triangles and the values
interpolated with them, face values through the source triangle, the filter of carried attributes,
vertex group weights. Usage: test_attributes.py"""
import os
import sys
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.dont_write_bytecode = True  # no __pycache__ in the add-on's folder
sys.path.insert(0, os.path.join(ROOT, "addon"))
from core import attributes, meshdata  # noqa: E402

failures = []


def check(condition, message):
    print(("ok   " if condition else "FAIL ") + message)
    if not condition:
        failures.append(message)


def strip_of_quads():
    """Three quads in a row, their loops stored out of polygon order (as after edits): polygon 0's
    loops 8..11, polygon 1's 0..3, polygon 2's 4..7. Edges: 0 = the inner edge between polygons 0
    and 1, 1 = between 1 and 2; the rest are boundary edges 2..9."""
    loop_start = np.array([8, 0, 4])
    loop_total = np.array([4, 4, 4])
    loop_edge = np.array([0, 2, 1, 3,   1, 4, 5, 6,   7, 8, 0, 9])
    return loop_start, loop_total, loop_edge


def test_boundaries():
    loop_start, loop_total, loop_edge = strip_of_quads()
    loop_polygon = meshdata.loop_polygons(loop_start, loop_total)
    check(loop_polygon.tolist() == [1, 1, 1, 1, 2, 2, 2, 2, 0, 0, 0, 0], f"loop polygons {loop_polygon.tolist()}")
    flags = meshdata.edges_between_differing_faces(loop_edge, loop_polygon, [5, 5, 7], 10)
    check(flags.tolist() == [False, True] + [False] * 8, f"material boundary: only edge 1 ({np.flatnonzero(flags)})")
    flags = meshdata.edges_between_differing_faces(loop_edge, loop_polygon, [1, 2, 3], 10)
    check(np.flatnonzero(flags).tolist() == [0, 1], "three regions: both inner edges")
    flags = meshdata.edges_between_differing_faces(loop_edge, loop_polygon, [4, 4, 4], 10)
    check(not flags.any(), "one region: no edge")
    # A non-manifold edge (three polygons): set when any two differ.
    flags = meshdata.edges_between_differing_faces(np.array([0, 0, 0]), np.array([0, 1, 2]), [3, 3, 8], 1)
    check(flags.tolist() == [True], "non-manifold edge with differing faces")
    flags = meshdata.edges_between_differing_faces(np.zeros(0, np.int32), np.zeros(0, np.int32), [], 4)
    check(flags.tolist() == [False] * 4, "no loops: no edge")


def test_barycentric():
    a, b, c = np.array([0.0, 0, 0]), np.array([2.0, 0, 0]), np.array([0.0, 2, 0])
    points = np.array([[0, 0, 0], [2, 0, 0], [0.5, 0.5, 0], [0.5, 0.5, 3.0], [-1, 0.5, 0], [3, 3, 0]], float)
    n = len(points)
    w = attributes.barycentric_weights(points, np.tile(a, (n, 1)), np.tile(b, (n, 1)), np.tile(c, (n, 1)))
    check(np.allclose(w[0], [1, 0, 0]) and np.allclose(w[1], [0, 1, 0]), "corners")
    check(np.allclose(w[2], [0.5, 0.25, 0.25]), f"inside {w[2]}")
    check(np.allclose(w[3], w[2]), "a point off the plane: its projection")
    check(np.allclose(w.sum(axis=1), 1) and (w >= 0).all(), "clamped outside, sum 1")
    # (-1, 0.5) has weights (1.25, -0.5, 0.25): the negative one dropped, the rest scaled to sum 1.
    check(np.allclose(w[4], [1.25 / 1.5, 0, 0.25 / 1.5]), f"left of the triangle: clamped {w[4]}")
    line = attributes.barycentric_weights(points[:1], [a], [b], [2 * b])
    check(np.allclose(line, 1 / 3), "degenerate triangle: equal weights")


def test_values():
    triangles = np.array([[0, 1, 2], [2, 1, 3]])
    weights = np.array([[0.5, 0.25, 0.25], [0.1, 0.1, 0.8]])
    triangle = np.array([0, 1])
    scalar = np.array([0.0, 4.0, 8.0, 12.0])
    got = attributes.point_values(scalar, triangles, triangle, weights)
    check(np.allclose(got, [3.0, 0.8 + 0.4 + 9.6]), f"scalar point values {got}")
    vectors = np.stack([scalar, -scalar, np.ones(4)], axis=1)
    got = attributes.point_values(vectors, triangles, triangle, weights)
    check(np.allclose(got, [[3, -3, 1], [10.8, -10.8, 1]]), f"vector point values {got.tolist()}")
    ints = np.array([10, 11, 12, 13])
    got = attributes.point_values(ints, triangles, triangle, weights, discrete=True)
    check(got.tolist() == [10, 13], f"discrete point values: nearest corner {got.tolist()}")
    loops = np.array([[5, 6, 7], [0, 1, 2]])
    colors = np.arange(8 * 4, dtype=float).reshape(8, 4)
    got = attributes.corner_values(colors, loops, triangle, weights)
    check(np.allclose(got[0], 0.5 * colors[5] + 0.25 * colors[6] + 0.25 * colors[7]), "corner values")
    got = attributes.face_values(np.array([7, 9]), np.array([1, 0]), np.array([0, 1, 1, 5, -2]))
    check(got.tolist() == [9, 7, 7, 7, 9], f"face values through the source triangle, clamped {got.tolist()}")
    corners = attributes.corner_vertices([np.array([[0, 1, 2, 3]]), np.array([[3, 2, 4]])])
    check(corners.tolist() == [0, 1, 2, 3, 3, 2, 4], "corner vertices of quads and triangles")
    matrix = attributes.group_weight_matrix([0, 2, 2], [1, 0, 1], [0.5, 0.25, 1.0], 3, 2)
    check(matrix.tolist() == [[0, 0.5], [0, 0], [0.25, 1.0]], f"group weights {matrix.tolist()}")


def test_carried():
    cases = {("Col", "POINT", "FLOAT_COLOR"): True, ("Col", "CORNER", "BYTE_COLOR"): True,
             ("weight", "FACE", "FLOAT"): True, ("id", "POINT", "INT"): True, ("flag", "FACE", "BOOLEAN"): True,
             ("offset", "POINT", "FLOAT_VECTOR"): True, ("uv2", "POINT", "FLOAT2"): True,
             ("UVMap", "CORNER", "FLOAT2"): False, ("corner_f", "CORNER", "FLOAT"): False,
             ("edge_f", "EDGE", "FLOAT"): False, (".select_vert", "POINT", "BOOLEAN"): False,
             ("position", "POINT", "FLOAT_VECTOR"): False, ("sharp_face", "FACE", "BOOLEAN"): False,
             ("material_index", "FACE", "INT"): False, ("name", "POINT", "STRING"): False,
             ("q", "POINT", "QUATERNION"): False}
    wrong = [k for k, want in cases.items() if attributes.is_carried(*k) != want]
    check(not wrong, f"carried attributes filter (wrong: {wrong})")
    check(not attributes.is_carried("Map2", "POINT", "FLOAT2", uv_names=("Map2",)), "a UV map is not carried")


def test_split_quads():
    """The same quads from any starting loop give the same triangles (Blender gives a new mesh's loops
    from another start from run to run); a concave quad is split along its inner diagonal; each
    triangle keeps the quad's orientation and its loops follow its corners."""
    vertices = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [2, 0, 0], [2, 1, 0],
                         [3, 0, 0], [5, 1, 0], [3, 2, 0], [3.5, 1, 0]], float)
    quads = np.array([[0, 1, 2, 3], [1, 4, 5, 2], [9, 6, 7, 8]], np.int32)  # the last one a dart
    loops = np.arange(12, dtype=np.int32).reshape(-1, 3 + 1)
    results = []
    for start in range(4):
        turn = (np.array([start, 3 - start, start // 2])[:, None] + np.arange(4)) % 4
        tris, tri_loops = meshdata.split_quads(vertices, np.take_along_axis(quads, turn, 1),
                                               np.take_along_axis(loops, turn, 1))
        results.append((tris, tri_loops))
    check(all(np.array_equal(t, results[0][0]) and np.array_equal(lp, results[0][1]) for t, lp in results),
          "the same quads from any start give the same triangles")
    tris, tri_loops = results[0]
    check(np.array_equal(tris, quads.reshape(-1)[tri_loops]), "the loops follow the triangles' corners")
    normals = np.cross(vertices[tris[:, 1]] - vertices[tris[:, 0]], vertices[tris[:, 2]] - vertices[tris[:, 0]])
    check(np.all(normals[:, 2] > 0), "every triangle faces as its quad does (the dart split inside)")
    check(sorted(map(sorted, tris[4:].tolist())) == [[6, 7, 9], [7, 8, 9]], "the dart along its inner diagonal")


def test_speed():
    rng = np.random.default_rng(1)
    n = 200000
    corners = rng.random((3, n, 3))
    points = rng.random((n, 3))
    start = time.perf_counter()
    weights = attributes.barycentric_weights(points, *corners)
    values = attributes.blend(rng.random((n, 3, 4)), weights)
    seconds = time.perf_counter() - start
    check(values.shape == (n, 4) and seconds < 1.0, f"{n} points weighed and blended in {seconds:.3f} s")


def main():
    test_boundaries()
    test_barycentric()
    test_values()
    test_carried()
    test_split_quads()
    test_speed()
    print(f"{len(failures)} failure(s)" if failures else "attributes: OK")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())

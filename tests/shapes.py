"""Small generated shapes shared by the Python tests (no Blender needed)."""
import math


def moebius_strip(n=8, width=0.3, centre=(0.0, 0.0, 0.0)):
    """Vertices and triangles of a Moebius strip (n quads, 2n triangles) around a circle of radius 2:
    non-orientable, so it has no quad mesh."""
    vertices, faces = [], []
    for i in range(n):
        t = 2 * math.pi * i / n
        for side in (-1, 1):
            w = width * side
            r = 2 + w * math.cos(t / 2)
            vertices.append((centre[0] + r * math.cos(t), centre[1] + r * math.sin(t),
                             centre[2] + w * math.sin(t / 2)))
    for i in range(n):
        a, b = 2 * i, 2 * i + 1
        c, d = 2 * ((i + 1) % n), 2 * ((i + 1) % n) + 1
        if i == n - 1:
            c, d = d, c  # the half twist
        faces += [(a, c, b), (b, c, d)]
    return vertices, faces

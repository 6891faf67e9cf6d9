"""Small generated shapes shared by the Python tests (no Blender needed). Each returns
(vertices, faces): a list of (x, y, z) and a list of vertex index tuples (0-based)."""
import math


def write_obj(path, vertices, faces):
    """An OBJ of the vertices and faces (0-based indices)."""
    with open(path, "w") as f:
        for p in vertices:
            f.write("v %r %r %r\n" % tuple(p))
        for face in faces:
            f.write("f " + " ".join(str(i + 1) for i in face) + "\n")


def moebius_strip(n=8, width=0.3, centre=(0.0, 0.0, 0.0)):
    """A Moebius strip (n quads, 2n triangles) around a circle of radius 2: non-orientable, so it has
    no quad mesh."""
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


def uv_sphere(segments=24, rings=12, radius=1.0, centre=(0.0, 0.0, 0.0)):
    """A closed triangulated sphere with its poles on the x axis (at centre -/+ (radius, 0, 0)),
    outward-facing."""
    vertices = [(centre[0] - radius, centre[1], centre[2])]
    for i in range(1, rings):
        polar = math.pi * i / rings
        for j in range(segments):
            azimuth = 2 * math.pi * j / segments
            vertices.append((centre[0] - radius * math.cos(polar),
                             centre[1] + radius * math.sin(polar) * math.cos(azimuth),
                             centre[2] + radius * math.sin(polar) * math.sin(azimuth)))
    vertices.append((centre[0] + radius, centre[1], centre[2]))
    last = len(vertices) - 1

    def ring(i, j):
        return 1 + (i - 1) * segments + j % segments

    faces = [(0, ring(1, j + 1), ring(1, j)) for j in range(segments)]
    for i in range(1, rings - 1):
        for j in range(segments):
            a, b, c, d = ring(i, j), ring(i, j + 1), ring(i + 1, j + 1), ring(i + 1, j)
            faces += [(a, b, c), (a, c, d)]
    faces += [(last, ring(rings - 1, j), ring(rings - 1, j + 1)) for j in range(segments)]
    return vertices, faces


def torus(major_segments=48, minor_segments=16, major_radius=1.0, minor_radius=0.25):
    """A closed triangulated torus around the z axis, outward-facing."""
    vertices, faces = [], []
    for i in range(major_segments):
        u = 2 * math.pi * i / major_segments
        for j in range(minor_segments):
            v = 2 * math.pi * j / minor_segments
            r = major_radius + minor_radius * math.cos(v)
            vertices.append((r * math.cos(u), r * math.sin(u), minor_radius * math.sin(v)))
    for i in range(major_segments):
        for j in range(minor_segments):
            a = i * minor_segments + j
            b = (i + 1) % major_segments * minor_segments + j
            c = (i + 1) % major_segments * minor_segments + (j + 1) % minor_segments
            d = i * minor_segments + (j + 1) % minor_segments
            faces += [(a, b, c), (a, c, d)]
    return vertices, faces


def grid_cube(n=6, origin=(0.0, 0.0, 0.0), size=1.0):
    """The surface of an axis-aligned cube, each side n x n quads, vertices shared, outward-facing."""
    index, vertices, faces = {}, [], []

    def vertex(p):
        key = tuple(round(c * n) for c in p)
        if key not in index:
            index[key] = len(vertices)
            vertices.append(tuple(origin[k] + size * p[k] for k in range(3)))
        return index[key]

    for axis in range(3):
        u, v = (axis + 1) % 3, (axis + 2) % 3
        for side in (0, 1):
            for i in range(n):
                for j in range(n):
                    corners = []
                    for di, dj in ((0, 0), (1, 0), (1, 1), (0, 1)):
                        p = [0.0, 0.0, 0.0]
                        p[axis], p[u], p[v] = float(side), (i + di) / n, (j + dj) / n
                        corners.append(vertex(p))
                    faces.append(tuple(corners) if side else tuple(reversed(corners)))
    return vertices, faces


def plane_grid(n=12, size=1.0):
    """An n x n grid of quads in the z = 0 plane, vertices shared, facing +z."""
    vertices = [(size * i / n, size * j / n, 0.0) for j in range(n + 1) for i in range(n + 1)]
    faces = [(j * (n + 1) + i, j * (n + 1) + i + 1, (j + 1) * (n + 1) + i + 1, (j + 1) * (n + 1) + i)
             for j in range(n) for i in range(n)]
    return vertices, faces


def merged(*parts):
    """Several (vertices, faces) as one, vertices at the same position (to 1e-9) shared."""
    index, vertices, faces = {}, [], []
    for part_vertices, part_faces in parts:
        remap = []
        for p in part_vertices:
            key = tuple(round(c * 1e9) for c in p)
            if key not in index:
                index[key] = len(vertices)
                vertices.append(p)
            remap.append(index[key])
        faces += [tuple(remap[i] for i in face) for face in part_faces]
    return vertices, faces


def transformed(shape, scale=1.0, offset=(0.0, 0.0, 0.0)):
    vertices, faces = shape
    return [tuple(scale * p[k] + offset[k] for k in range(3)) for p in vertices], list(faces)

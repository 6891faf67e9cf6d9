"""ctypes binding of the native C API (native/include/qgp/qgp.h).

Session wraps one native session: create it from numpy arrays (or a file), set options, start a
job on the native worker thread, poll / cancel / wait, then fetch results and the JSON report.
Every native failure raises QGPError carrying the native status code and message.
"""
import ctypes
import json
import os
import sys

import numpy as np

# Status codes (qgp_status).
OK = 0
ERR_INVALID_ARGUMENT = 1
ERR_INVALID_MESH = 2
ERR_UNREADABLE_FILE = 3
ERR_STAGE_FAILED = 5
ERR_CANCELLED = 6
ERR_BUSY = 7
ERR_INTERNAL = 8
ERR_NOT_READY = 9

# Jobs (qgp_job) and job states (qgp_job_state).
JOB_INTAKE, JOB_REMESH, JOB_GRID_UV = 0, 1, 2
STATE_IDLE, STATE_RUNNING, STATE_DONE, STATE_FAILED, STATE_CANCELLED = 0, 1, 2, 3, 4

LIBRARY_NAME = "qgp.dll" if sys.platform == "win32" else "libqgp.so"  # the windows-x64 zip holds qgp.dll


class QGPError(Exception):
    """A native call failed; `code` is the qgp_status, `message` the native message."""

    def __init__(self, code, message):
        super().__init__(message)
        self.code = code
        self.message = message


def library_candidates():
    """Where the native library (libqgp.so, or qgp.dll on Windows) is looked for, in order."""
    here = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))  # the add-on folder
    paths = []
    if os.environ.get("QGP_LIBRARY"):
        paths.append(os.environ["QGP_LIBRARY"])
    paths.append(os.path.join(here, "lib", LIBRARY_NAME))  # extension zip layout
    paths.append(os.path.join(os.path.dirname(here), "build", "lib", LIBRARY_NAME))  # source checkout
    return paths


_lib = None
_lib_path = None


def loaded_library_path():
    """The path libqgp was loaded from, or None before load_library."""
    return _lib_path


def load_library(path=None):
    """Loads libqgp once and declares the C signatures. Raises QGPError if it cannot be found."""
    global _lib, _lib_path
    if _lib is not None and path is None:
        return _lib
    tried = []
    for candidate in ([path] if path else library_candidates()):
        if candidate and os.path.exists(candidate):
            try:
                lib = ctypes.CDLL(candidate)
            except OSError as e:
                tried.append(f"{candidate}: {e}")
                continue
            _declare(lib)
            _lib, _lib_path = lib, os.path.abspath(candidate)
            return lib
        tried.append(f"{candidate}: not found")
    raise QGPError(ERR_INTERNAL, "cannot load the Quantized Retopo native library (" + "; ".join(tried) + ")")


def _declare(lib):
    c_int, c_int64, c_double, c_char_p = ctypes.c_int, ctypes.c_int64, ctypes.c_double, ctypes.c_char_p
    p_double, p_int32, p_int64 = ctypes.POINTER(c_double), ctypes.POINTER(ctypes.c_int32), ctypes.POINTER(c_int64)
    p_int, vp = ctypes.POINTER(c_int), ctypes.c_void_p
    sigs = {
        "qgp_version": (c_char_p, []),
        "qgp_last_error": (c_char_p, []),
        "qgp_session_create": (c_int, [p_double, c_int64, p_int32, c_int64, ctypes.POINTER(vp)]),
        "qgp_session_create_from_file": (c_int, [c_char_p, ctypes.POINTER(vp)]),
        "qgp_session_free": (None, [vp]),
        "qgp_session_error": (c_char_p, [vp]),
        "qgp_session_set_features": (c_int, [vp, p_int32, c_int64]),
        "qgp_session_set_density": (c_int, [vp, p_double, c_int64]),
        "qgp_session_set_option": (c_int, [vp, c_char_p, c_double]),
        "qgp_session_set_option_string": (c_int, [vp, c_char_p, c_char_p]),
        "qgp_job_start": (c_int, [vp, c_int]),
        "qgp_job_poll": (c_int, [vp, p_int, p_double, ctypes.c_char_p, c_int64]),
        "qgp_job_cancel": (c_int, [vp]),
        "qgp_job_wait": (c_int, [vp, c_double, p_int]),
        "qgp_report_json": (c_int, [vp, ctypes.c_char_p, c_int64, p_int64]),
        "qgp_intake_counts": (c_int, [vp, p_int64, p_int64, p_int64]),
        "qgp_intake_fetch": (c_int, [vp, p_double, p_int32, p_int32, p_int32]),
    }
    sigs.update({
        "qgp_soup_read": (c_int, [c_char_p, ctypes.POINTER(vp)]),
        "qgp_soup_counts": (c_int, [vp, p_int64, p_int64, p_int64]),
        "qgp_soup_fetch": (c_int, [vp, p_double, p_int32, p_int32]),
        "qgp_soup_free": (None, [vp]),
    })
    sigs["qgp_measure_polygon_mesh"] = (c_int, [p_double, c_int64, p_int32, c_int64, p_int32, p_double, c_int64,
                                                p_int32, c_int64, c_double, ctypes.c_char_p, c_int64, p_int64])
    sigs["qgp_atlas_quads"] = (c_int, [p_double, c_int64, p_int32, c_int64, c_int, c_int, c_int, c_int, c_int,
                                       p_double, p_int32])
    sigs["qgp_atlas_polygons"] = (c_int, [p_int32, c_int64, p_int32, p_double, c_int, c_int, c_int, c_int, c_int,
                                          p_double, p_int32])
    sigs["qgp_stitch_seams"] = (c_int, [p_int32, c_int64, p_int32, p_double, ctypes.POINTER(ctypes.c_float), c_int,
                                        c_int, c_int, p_int64])
    optional = {
        "qgp_result_quad_counts": (c_int, [vp, p_int64, p_int64]),
        "qgp_result_quad_fetch": (c_int, [vp, p_double, p_int32, p_int32]),
        "qgp_result_kept_counts": (c_int, [vp, p_int64, p_int64]),
        "qgp_result_kept_fetch": (c_int, [vp, p_double, p_int32, p_int32, p_int32]),
        "qgp_result_uv_counts": (c_int, [vp, p_int64]),
        "qgp_result_uv_fetch": (c_int, [vp, p_double, p_int32]),
        "qgp_result_uv_mesh_counts": (c_int, [vp, p_int64, p_int64, p_int32]),
        "qgp_result_uv_mesh_fetch": (c_int, [vp, p_double, p_int32, p_double, p_int32]),
        "qgp_result_layout_counts": (c_int, [vp, p_int64, p_int64]),
        "qgp_result_layout_fetch": (c_int, [vp, p_double, p_int32]),
    }
    for name, (restype, argtypes) in sigs.items():
        fn = getattr(lib, name)
        fn.restype, fn.argtypes = restype, argtypes
    for name, (restype, argtypes) in optional.items():
        if hasattr(lib, name):
            fn = getattr(lib, name)
            fn.restype, fn.argtypes = restype, argtypes


def version():
    return load_library().qgp_version().decode()


def read_mesh_file(path):
    """Reads OBJ / PLY / OFF as it is: (vertices (n,3) float64, face sizes (f,) int32, corners (c,) int32)."""
    lib = load_library()
    handle = ctypes.c_void_p()
    status = lib.qgp_soup_read(os.fsencode(path), ctypes.byref(handle))
    if status != OK:
        raise QGPError(status, lib.qgp_last_error().decode())
    try:
        nv, nf, nc = ctypes.c_int64(), ctypes.c_int64(), ctypes.c_int64()
        lib.qgp_soup_counts(handle, ctypes.byref(nv), ctypes.byref(nf), ctypes.byref(nc))
        v = np.empty((nv.value, 3), np.float64)
        sizes = np.empty(nf.value, np.int32)
        corners = np.empty(nc.value, np.int32)
        status = lib.qgp_soup_fetch(handle, _ptr(v, ctypes.c_double), _ptr(sizes, ctypes.c_int32),
                                    _ptr(corners, ctypes.c_int32))
        if status != OK:
            raise QGPError(status, lib.qgp_last_error().decode())
        return v, sizes, corners
    finally:
        lib.qgp_soup_free(handle)


def measure_polygon_mesh(vertices, face_sizes, corners, ref_vertices, ref_triangles, sharp_angle=-1.0):
    """Quality figures (dict) of a polygon mesh against a reference triangle mesh (docs/report.md)."""
    lib = load_library()
    v = np.ascontiguousarray(vertices, np.float64).reshape(-1, 3)
    sizes = np.ascontiguousarray(face_sizes, np.int32)
    c = np.ascontiguousarray(corners, np.int32)
    rv = np.ascontiguousarray(ref_vertices, np.float64).reshape(-1, 3)
    rt = np.ascontiguousarray(ref_triangles, np.int32).reshape(-1, 3)
    needed = ctypes.c_int64(1 << 16)
    # The JSON lists the flipped quads, so it can outgrow a first guess: the library then says how
    # many bytes it needs, and the (rare) second call measures again into a buffer that size.
    for _ in range(2):
        buffer = ctypes.create_string_buffer(needed.value)
        status = lib.qgp_measure_polygon_mesh(_ptr(v, ctypes.c_double), len(v), _ptr(sizes, ctypes.c_int32),
                                              len(sizes), _ptr(c, ctypes.c_int32), _ptr(rv, ctypes.c_double), len(rv),
                                              _ptr(rt, ctypes.c_int32), len(rt), float(sharp_angle), buffer,
                                              len(buffer), ctypes.byref(needed))
        if status == OK or needed.value <= len(buffer):
            break
    if status != OK:
        raise QGPError(status, lib.qgp_last_error().decode())
    return json.loads(buffer.value.decode())


def atlas_quads(vertices, quads, size, texels_per_quad=0, gutter=2, mip_levels=0):
    """A texture atlas for quads (n,4) on a size x size texture: (corner UVs (n,4,2) in [0,1], dict of
    charts, texels_per_quad, seam_edges, gutter, texture_use)."""
    lib = load_library()
    v = np.ascontiguousarray(vertices, np.float64).reshape(-1, 3)
    q = np.ascontiguousarray(quads, np.int32).reshape(-1, 4)
    uv = np.empty((len(q), 4, 2), np.float64)
    info = np.zeros(5, np.int32)
    status = lib.qgp_atlas_quads(_ptr(v, ctypes.c_double), len(v), _ptr(q, ctypes.c_int32), len(q), int(size),
                                 int(size), int(texels_per_quad), int(gutter), int(mip_levels),
                                 _ptr(uv, ctypes.c_double), _ptr(info, ctypes.c_int32))
    if status != OK:
        raise QGPError(status, lib.qgp_last_error().decode())
    return uv, _atlas_figures(info)


def _atlas_figures(info):
    """The 5 ints an atlas call gives as a dict."""
    keys = ("charts", "texels_per_quad", "seam_edges", "gutter")
    return {**dict(zip(keys, map(int, info[:4]))), "texture_use": info[4] / 1e6}


def atlas_polygons(face_sizes, corners, grid_uv, size, mip_levels=0):
    """A texture atlas for polygons carrying an integer-grid map (grid_uv (c,2) per corner) on a size x size
    texture: (corner UVs (c,2) in [0,1], figures as atlas_quads gives them)."""
    lib = load_library()
    sizes = np.ascontiguousarray(face_sizes, np.int32)
    c = np.ascontiguousarray(corners, np.int32)
    grid = np.ascontiguousarray(grid_uv, np.float64).reshape(-1, 2)
    uv = np.empty_like(grid)
    info = np.zeros(5, np.int32)
    status = lib.qgp_atlas_polygons(_ptr(sizes, ctypes.c_int32), len(sizes), _ptr(c, ctypes.c_int32),
                                    _ptr(grid, ctypes.c_double), int(size), int(size), 0, 2, int(mip_levels),
                                    _ptr(uv, ctypes.c_double), _ptr(info, ctypes.c_int32))
    if status != OK:
        raise QGPError(status, lib.qgp_last_error().decode())
    return uv, _atlas_figures(info)


def stitch_seams(face_sizes, corners, corner_uv, pixels, width, height, channels):
    """Seam stitching of pixels (float32, width x height x channels, row 0 at v = 0) in place for the
    faces' per-corner UVs (corners (c,) vertex indices, corner_uv (c,2)): dict of seam_edges,
    unmatched_seam_edges, seam_texels, charts."""
    lib = load_library()
    sizes = np.ascontiguousarray(face_sizes, np.int32)
    c = np.ascontiguousarray(corners, np.int32)
    uv = np.ascontiguousarray(corner_uv, np.float64).reshape(-1, 2)
    if pixels.dtype != np.float32 or not pixels.flags.c_contiguous or pixels.size != width * height * channels:
        raise ValueError("pixels must be a contiguous float32 array of width x height x channels")
    info = np.zeros(4, np.int64)
    status = lib.qgp_stitch_seams(_ptr(sizes, ctypes.c_int32), len(sizes), _ptr(c, ctypes.c_int32),
                                  _ptr(uv, ctypes.c_double), _ptr(pixels, ctypes.c_float), int(width), int(height),
                                  int(channels), _ptr(info, ctypes.c_int64))
    if status != OK:
        raise QGPError(status, lib.qgp_last_error().decode())
    return dict(zip(("seam_edges", "unmatched_seam_edges", "seam_texels", "charts"), map(int, info)))


def _ptr(array, ctype):
    return array.ctypes.data_as(ctypes.POINTER(ctype))


class SessionLifetime:
    """What every session kind shares: context manager, close on collection, run = start + wait.
    Subclasses provide close(), start() and wait()."""

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def __del__(self):
        try:
            self.close()
        except Exception:
            pass

    def run(self, job):
        """Starts a job and waits for it (synchronous use)."""
        self.start(job)
        return self.wait()


class Session(SessionLifetime):
    """One native session. Use as a context manager or call close()."""

    def __init__(self, vertices, triangles):
        lib = load_library()
        self._lib = lib
        self._handle = ctypes.c_void_p()
        v = np.ascontiguousarray(vertices, dtype=np.float64).reshape(-1, 3)
        t = np.ascontiguousarray(triangles, dtype=np.int32).reshape(-1, 3)
        status = lib.qgp_session_create(_ptr(v, ctypes.c_double), len(v), _ptr(t, ctypes.c_int32), len(t),
                                        ctypes.byref(self._handle))
        if status != OK:
            raise QGPError(status, lib.qgp_last_error().decode())

    @classmethod
    def from_file(cls, path):
        self = cls.__new__(cls)
        self._lib = load_library()
        self._handle = ctypes.c_void_p()
        status = self._lib.qgp_session_create_from_file(os.fsencode(path), ctypes.byref(self._handle))
        if status != OK:
            raise QGPError(status, self._lib.qgp_last_error().decode())
        return self

    # -- lifetime --
    def close(self):
        if getattr(self, "_handle", None) is not None and self._handle.value:
            self._lib.qgp_session_free(self._handle)
            self._handle = ctypes.c_void_p()

    @property
    def alive(self):
        """False once closed (an in-process session cannot die on its own)."""
        return getattr(self, "_handle", None) is not None and bool(self._handle.value)

    def _check(self, status):
        if status != OK:
            raise QGPError(status, self._lib.qgp_session_error(self._handle).decode())

    # -- options --
    def set_option(self, name, value):
        self._check(self._lib.qgp_session_set_option(self._handle, name.encode(), float(value)))

    def set_option_string(self, name, value):
        self._check(self._lib.qgp_session_set_option_string(self._handle, name.encode(), value.encode()))

    def set_features(self, edges):
        e = np.ascontiguousarray(edges, dtype=np.int32).reshape(-1, 2)
        self._check(self._lib.qgp_session_set_features(self._handle, _ptr(e, ctypes.c_int32), len(e)))

    def set_density(self, density):
        """The linear quad density per input vertex (2: quads half as long there); None clears it."""
        d = np.ascontiguousarray(density if density is not None else [], dtype=np.float64).reshape(-1)
        self._check(self._lib.qgp_session_set_density(self._handle, _ptr(d, ctypes.c_double), len(d)))

    # -- jobs --
    def start(self, job):
        self._check(self._lib.qgp_job_start(self._handle, job))

    def poll(self):
        """Returns (state, fraction of the current stage, stage name)."""
        state, fraction = ctypes.c_int(), ctypes.c_double()
        stage = ctypes.create_string_buffer(64)
        self._check(self._lib.qgp_job_poll(self._handle, ctypes.byref(state), ctypes.byref(fraction), stage, 64))
        return state.value, fraction.value, stage.value.decode()

    def cancel(self):
        self._check(self._lib.qgp_job_cancel(self._handle))

    def wait(self, timeout=-1.0):
        """Waits for the job; returns its state. Raises QGPError if the job failed or was cancelled."""
        state = ctypes.c_int()
        status = self._lib.qgp_job_wait(self._handle, float(timeout), ctypes.byref(state))
        if state.value != STATE_RUNNING:
            self._check(status)
        return state.value

    # -- results --
    def report(self):
        needed = ctypes.c_int64()
        self._check(self._lib.qgp_report_json(self._handle, None, 0, ctypes.byref(needed)))
        buffer = ctypes.create_string_buffer(needed.value)
        self._check(self._lib.qgp_report_json(self._handle, buffer, needed.value, ctypes.byref(needed)))
        return json.loads(buffer.value.decode())

    def intake_mesh(self):
        """The repaired mesh: (vertices (n,3), triangles (m,3), component per triangle, input vertex per vertex)."""
        nv, nf, nc = ctypes.c_int64(), ctypes.c_int64(), ctypes.c_int64()
        self._check(self._lib.qgp_intake_counts(self._handle, ctypes.byref(nv), ctypes.byref(nf), ctypes.byref(nc)))
        v = np.empty((nv.value, 3), np.float64)
        f = np.empty((nf.value, 3), np.int32)
        comp = np.empty(nf.value, np.int32)
        iv = np.empty(nv.value, np.int32)
        self._check(self._lib.qgp_intake_fetch(self._handle, _ptr(v, ctypes.c_double), _ptr(f, ctypes.c_int32),
                                               _ptr(comp, ctypes.c_int32), _ptr(iv, ctypes.c_int32)))
        return v, f, comp, iv

    def quad_mesh(self):
        """(vertices (n,3) float64, quads (q,4) int32 CCW, source triangle per quad (q,) int32)."""
        if not hasattr(self._lib, "qgp_result_quad_counts"):
            raise QGPError(ERR_NOT_READY, "this native library cannot return quad meshes")
        nv, nq = ctypes.c_int64(), ctypes.c_int64()
        self._check(self._lib.qgp_result_quad_counts(self._handle, ctypes.byref(nv), ctypes.byref(nq)))
        v = np.empty((nv.value, 3), np.float64)
        q = np.empty((nq.value, 4), np.int32)
        src = np.empty(nq.value, np.int32)
        self._check(self._lib.qgp_result_quad_fetch(self._handle, _ptr(v, ctypes.c_double),
                                                    _ptr(q, ctypes.c_int32), _ptr(src, ctypes.c_int32)))
        return v, q, src

    def kept_triangles(self):
        """Parts of a many-part mesh the last remesh could not quad, kept as their triangles (the
        report's failed_components says why): (vertices (n,3) float64, triangles (t,3) int32, source
        triangle per triangle (t,) int32, component per triangle (t,) int32); empty when every part
        became quads."""
        nv, nt = ctypes.c_int64(), ctypes.c_int64()
        if hasattr(self._lib, "qgp_result_kept_counts"):
            self._check(self._lib.qgp_result_kept_counts(self._handle, ctypes.byref(nv), ctypes.byref(nt)))
        v = np.empty((nv.value, 3), np.float64)
        t = np.empty((nt.value, 3), np.int32)
        src = np.empty(nt.value, np.int32)
        comp = np.empty(nt.value, np.int32)
        if nt.value:
            self._check(self._lib.qgp_result_kept_fetch(self._handle, _ptr(v, ctypes.c_double), _ptr(t, ctypes.c_int32),
                                                        _ptr(src, ctypes.c_int32), _ptr(comp, ctypes.c_int32)))
        return v, t, src, comp

    def grid_uv(self, num_triangles):
        """Integer-grid map per input triangle corner, (num_triangles, 3, 2) float64 (1 unit = 1 quad;
        NaN on parts remeshed on a decimated working mesh), and the cut edges as input vertex pairs (k, 2) int32."""
        if not hasattr(self._lib, "qgp_result_uv_counts"):
            raise QGPError(ERR_NOT_READY, "this native library cannot return grid UVs")
        ncut = ctypes.c_int64()
        self._check(self._lib.qgp_result_uv_counts(self._handle, ctypes.byref(ncut)))
        uv = np.empty((num_triangles, 3, 2), np.float64)
        cuts = np.empty((ncut.value, 2), np.int32)
        self._check(self._lib.qgp_result_uv_fetch(self._handle, _ptr(uv, ctypes.c_double),
                                                  _ptr(cuts, ctypes.c_int32)))
        return uv, cuts

    def layout_lines(self):
        """The quad layout (T-mesh) of the last remesh or grid-UV job as line segments: (points (n,3)
        float64 on the surface, segments (s,2) int32 point indices)."""
        if not hasattr(self._lib, "qgp_result_layout_counts"):
            raise QGPError(ERR_NOT_READY, "this native library cannot return the quad layout")
        npoints, nsegments = ctypes.c_int64(), ctypes.c_int64()
        self._check(self._lib.qgp_result_layout_counts(self._handle, ctypes.byref(npoints), ctypes.byref(nsegments)))
        points = np.empty((npoints.value, 3), np.float64)
        segments = np.empty((nsegments.value, 2), np.int32)
        self._check(self._lib.qgp_result_layout_fetch(self._handle, _ptr(points, ctypes.c_double),
                                                      _ptr(segments, ctypes.c_int32)))
        return points, segments

    def uv_mesh(self):
        """The integer-grid map as its own triangle mesh: (vertices (n,3) float64, triangles (t,3)
        int32, per-corner uv (t,3,2) float64 with 1 unit = 1 quad, input face per triangle (t,) int32,
        number of components refined by the flip-free fallback (0: the intake triangles))."""
        if not hasattr(self._lib, "qgp_result_uv_mesh_counts"):
            raise QGPError(ERR_NOT_READY, "this native library cannot return the refined grid-UV mesh")
        nv, nt, refined = ctypes.c_int64(), ctypes.c_int64(), ctypes.c_int32()
        self._check(self._lib.qgp_result_uv_mesh_counts(self._handle, ctypes.byref(nv), ctypes.byref(nt),
                                                        ctypes.byref(refined)))
        v = np.empty((nv.value, 3), np.float64)
        t = np.empty((nt.value, 3), np.int32)
        uv = np.empty((nt.value, 3, 2), np.float64)
        src = np.empty(nt.value, np.int32)
        self._check(self._lib.qgp_result_uv_mesh_fetch(self._handle, _ptr(v, ctypes.c_double), _ptr(t, ctypes.c_int32),
                                                       _ptr(uv, ctypes.c_double), _ptr(src, ctypes.c_int32)))
        return v, t, uv, src, refined.value

"""Operators: Quantized Retopo (new quad object) and Integer-Grid UVs (UV layer on the source, or a
refined copy where only that has a flip-free map).

Both run synchronously in execute() (scripts, redo panel, blender -b) and as modal jobs from
invoke() (progress bar, status text, Esc cancels). The native sessions live in worker processes
(core/worker.py), so a fault under the native code is a reported error, not a closed Blender; when
no worker can start, the job runs inside Blender and the operator reports why as a warning. The
source object is only ever changed by a successful Integer-Grid UVs run.
"""
import math
import time

import bpy

from . import atlas, blender_mesh
from .core import binding, worker
from .prefs import preferences

# Native sessions per object: reused when only the density changes (re-quantization only, up to
# 4x in quad count; beyond, the native session solves the seamless map again). Each entry:
# (settings, session, why the worker could not start or None; see _new_session).
_session_cache = {}


def _load_library(context):
    prefs = preferences(context)
    path = prefs.library_path if prefs and prefs.library_path else None
    binding.load_library(bpy.path.abspath(path) if path else None)


def _new_session(source, isolate):
    """(session, fallback): a worker-process session (a native fault cannot end Blender), or an
    in-process one when isolation is off or no worker can start. fallback is None, or, when the
    worker was wanted but could not start, why (the operators report it as a warning)."""
    if isolate:
        try:
            return worker.WorkerSession(source.vertices, source.triangles), None
        except worker.WorkerStartError as e:
            return binding.Session(source.vertices, source.triangles), e.message
    return binding.Session(source.vertices, source.triangles), None


def _fallback_warning(fallback):
    return (f"The native job runs inside Blender, where a fault in it can close Blender: the separate "
            f"process could not start ({fallback})")


def _session_for(obj, source, sharp_angle, isolate):
    """(session, fallback) for this geometry and feature setup, cached per object: quad remesh and
    grid UVs share its stages, and a new density only re-quantizes (up to 4x). A cached in-process
    fallback keeps its reason: every job it runs is reported."""
    key = obj.name
    settings = (source.fingerprint(), sharp_angle, isolate)
    cached = _session_cache.get(key)
    if cached and cached[0] == settings and cached[1].alive:  # a dead worker is replaced
        return cached[1], cached[2]
    if cached:
        cached[1].close()
        del _session_cache[key]
    session, fallback = _new_session(source, isolate)
    if len(source.features):
        session.set_features(source.features)
    session.set_option("sharp_angle", sharp_angle)
    _session_cache[key] = (settings, session, fallback)
    return session, fallback


def _report_figures(report, op, started, **figures):
    """The native report's key figures for the custom property 'qgp' of a new object (Object
    Properties > Custom Properties), for artists and pipeline scripts: the target asked for, the
    native time and library, and the job's own figures."""
    target = op.target_faces if op.target_mode == "FACES" else op.edge_length
    seconds = report.get("timings_s", {}).get("total", time.perf_counter() - started)
    return dict(target_mode=op.target_mode, target=target, seconds=round(float(seconds), 3),
                library=binding.version(), **figures)


def _failed_parts(failed, shown=3):
    """The parts a remesh kept as triangles or rescued, named with why (the first `shown` of them)."""
    names = [f"part {f['component']} ({f['stage']}: {f['message']})" for f in failed[:shown]]
    more = f"; {len(failed) - shown} more in the report" if len(failed) > shown else ""
    return "; ".join(names) + more


def _quad_figures(report):
    """The quad remesh's figures: quads_expected (the quantization's quad count, which the mesh
    has exactly), count_note (why it is more than 5 % off the count asked, or ""), where each
    component's quads come from (quad_paths: 'integer-grid map' or 'T-mesh layout (why)',
    'rescued: split triangles', 'rescued: finer density' or 'rescued: field without cancelled
    pairs' for a part whose layout gave no quads, or 'kept as triangles'), how many components used
    the layout, the parts rescued (rescued_parts), the parts kept as triangles (kept_parts,
    kept_triangles: added after the quads), the planes the quads are mirror-symmetric about
    (symmetry: "", "x", "xz", ...) and the quality figures."""
    extraction = report.get("extraction", {})
    quad = report.get("quad", {})
    failed = report.get("failed_components", [])
    rescued = {int(r["component"]): r["rescue"] for r in report.get("rescued_components", [])}
    count = report.get("quantization", {}).get("count", {})
    return dict(quads_expected=int(report.get("quantization", {}).get("quads_expected", -1)),
                count_note=str(count.get("note", "")),
                components=int(report.get("input", {}).get("components", 0)),
                quad_paths=[str(c.get("path", "")) if c else
                            f"rescued: {rescued[i]}" if i in rescued else "kept as triangles"
                            for i, c in enumerate(extraction.get("components", []))],
                rescued_parts=len(rescued),
                kept_parts=len(failed), kept_triangles=sum(int(f["triangles"]) for f in failed),
                layout_components=int(extraction.get("layout_components", 0)),
                symmetry=str(report.get("symmetry", {}).get("axes", "")),
                flipped_quads=int(quad.get("flipped_quads", 0)),
                collapsed_edge_quads=int(quad.get("collapsed_edge_quads", 0)),
                hausdorff=float(quad.get("hausdorff", -1.0)))


def _active_mesh_object(context):
    obj = context.active_object
    if obj is None or obj.type != "MESH":
        return None
    return obj


class _JobOperator:
    """Shared modal-job machinery: start the native job, poll it on a timer, Esc cancels."""

    _timer = None
    _session = None
    _started = 0.0
    _cancelling = False

    def _start_modal(self, context, session, job):
        session.start(job)
        self._session = session
        self._started = time.perf_counter()
        self._cancelling = False
        wm = context.window_manager
        self._timer = wm.event_timer_add(0.1, window=context.window)
        wm.progress_begin(0, 1000)
        wm.modal_handler_add(self)
        return {"RUNNING_MODAL"}

    def _end_modal(self, context):
        wm = context.window_manager
        if self._timer is not None:
            wm.event_timer_remove(self._timer)
            self._timer = None
        wm.progress_end()
        context.workspace.status_text_set(None)

    def modal(self, context, event):
        if event.type == "ESC":
            # The native job stops at its next cancellation point, which can be seconds away: the
            # timer goes on polling it (Blender stays responsive) and the run ends once it stopped.
            if not self._cancelling:
                self._cancelling = True
                try:
                    self._session.cancel()
                except binding.QGPError:  # the worker died: the next poll reports it
                    pass
                context.workspace.status_text_set(f"{self.bl_label}: cancelling...")
            return {"RUNNING_MODAL"}
        if event.type != "TIMER":
            return {"PASS_THROUGH"}
        try:
            state, fraction, stage = self._session.poll()
        except binding.QGPError as e:  # the worker process died
            self._end_modal(context)
            self.report({"ERROR"}, e.message)
            return {"CANCELLED"}
        if state == binding.STATE_RUNNING:
            if not self._cancelling:
                context.window_manager.progress_update(int(1000 * fraction))
                context.workspace.status_text_set(
                    f"{self.bl_label}: {stage.replace('_', ' ')} {100 * fraction:.0f}%  (Esc to cancel)")
            return {"RUNNING_MODAL"}
        self._end_modal(context)
        if self._cancelling:  # stopped (or finished just before Esc): nothing reaches the scene
            try:
                self._session.wait()
            except binding.QGPError:
                pass
            self.report({"WARNING"}, "Cancelled; the scene is unchanged")
            return {"CANCELLED"}
        try:
            self._session.wait()
            return self._finish(context)
        except binding.QGPError as e:
            self.report({"ERROR"}, e.message)
            return {"CANCELLED"}


_WELD_TOLERANCE = 1e-6  # the native default, relative to the bounding-box diagonal


# Tooltips shared by the operators and the panel's settings (ui.py), which pass them on.
TARGET_MODE_ITEMS = [("FACES", "Quad Count", "Aim for a number of quads"),
                     ("EDGE", "Edge Length", "Aim for a quad edge length")]
DESCRIPTIONS = {
    "target_mode": "Set the density by a number of quads or by a quad edge length",
    "target_faces": "About how many quads the result has (the exact count follows the layout)",
    "edge_length": "About how long the quads' edges are, in object units",
    "use_marked_sharp": "Keep edges marked sharp as quad edges",
    "use_sharp_angle": "Also keep edges whose faces meet sharper than the angle as quad edges",
    "sharp_angle": "Edges whose faces meet at more than this angle are kept as quad edges",
    "use_seams": "Keep edges marked as UV seams as quad edges",
    "use_material_boundaries": "Keep the edges between faces of different materials as quad edges",
    "use_face_sets": "Keep the edges between different sculpt face sets as quad edges",
    "weld": "Join open edges whose vertices coincide (closer than a millionth of the size), as in meshes "
            "split at UV seams or hard normals; off keeps every loose part apart",
    "keep_source_visible": "Leave the source object visible; off hides it (its data is never changed)",
    "keep_attributes": "Give the quads the source's vertex groups, colour and other point and face "
                       "attributes, taken from the nearest point on the source (materials are always kept)",
    "keep_source_uvs": "Give the quads the source's active UV map, taken from the nearest point on the "
                       "source for each face corner (stretched where a quad crosses a UV seam)",
    "adaptive": "Smaller quads where the surface curves more, larger where it is flat: 0 is uniform, 1 "
                "makes the edge length follow the radius of curvature (within 4x either way). The quad count "
                "stays the total asked",
    "density_group": "Vertex group painting the density: where its weight is 1 the quads are Density Factor "
                     "times denser (along each edge), where it is 0 (or unpainted) as the target",
    "density_color": "Colour attribute painting the density, as Density Group does with the colour's "
                     "brightness (white: Density Factor times denser)",
    "density_factor": "Linear quad density where the density map is fully painted (2: quads half as long; "
                      "below 1: larger quads there)",
    "symmetry": "Mirror-symmetric quads about the object's own planes (its origin and local axes): the "
                "positive side is remeshed, mirrored and welded on the plane; the other side of the source "
                "is not used",
    "show_layout": "Also make an object '<name>_layout' with the quad layout's lines (the patches the quads "
                   "are laid out in), drawn in front",
    "texture_atlas": "Also write a texture atlas (UV map 'QGP Atlas'): every quad (grid cell) a square of whole "
                     "texels, charts packed into [0,1] without overlap, every seam a quarter turn plus whole texels, "
                     "so Stitch Seams can hide the seams of a baked or painted image",
    "atlas_size": "Width and height in texels of the texture the atlas is made for",
    "atlas_mip_levels": "Keep this many mip levels seam-free too (texels per quad a power of two, charts on "
                        "multiples of 2^levels texels, a wider gutter): the atlas uses less of the texture",
    "stitch_image": "The image to stitch (empty: the active Image Texture node of the active material)",
    "quads_per_unit": "Grid cells per UV unit: a texture of this period tiles without visible seams",
    "mark_seams": "Mark the map's cuts (the UV islands' boundaries) as seams, on the mesh or on its "
                  "Flip-Free Copy",
}


def draw_density(layout, data, obj=None):
    """The density options of `data` (an operator or the panel's settings): target and its value,
    adaptive size and the painted density (vertex group and colour attribute chosen among `obj`'s
    when given)."""
    layout.use_property_split = False
    layout.row().prop(data, "target_mode", expand=True)
    layout.prop(data, "target_faces" if data.target_mode == "FACES" else "edge_length")
    layout.prop(data, "adaptive", slider=True)
    layout.label(text="Painted Density")
    col = layout.column(align=True)
    mesh = obj.data if obj is not None and obj.type == "MESH" else None
    if mesh is not None:
        col.prop_search(data, "density_group", obj, "vertex_groups", text="Group", icon="GROUP_VERTEX")
        col.prop_search(data, "density_color", mesh, "attributes", text="Colour", icon="COLOR")
    else:
        col.prop(data, "density_group", text="Group", icon="GROUP_VERTEX")
        col.prop(data, "density_color", text="Colour", icon="COLOR")
    sub = col.row(align=True)
    sub.active = bool(data.density_group or data.density_color)
    sub.prop(data, "density_factor")


def draw_features(layout, data):
    """The edges kept as quad edges: marked sharp, sharp angle, seams, material and face-set
    boundaries; and Weld Open Edges."""
    layout.use_property_split = False
    col = layout.column(align=True)
    col.prop(data, "use_marked_sharp")
    col.prop(data, "use_sharp_angle")
    # Below its checkbox, not beside it: a row of both cuts the label at the sidebar's default width.
    sub = col.row(align=True)
    sub.active = data.use_sharp_angle
    sub.prop(data, "sharp_angle")
    col.prop(data, "use_seams")
    col.prop(data, "use_material_boundaries")
    col.prop(data, "use_face_sets")
    layout.prop(data, "weld")


def draw_quad_output(layout, data):
    """The quad object's output options: symmetry (X, Y, Z toggles) and what the object keeps."""
    layout.use_property_split = False
    # The label above its toggles, not beside them: a row of both cuts it at the sidebar's default width.
    layout.label(text="Symmetry")
    row = layout.row(align=True)
    for index, axis in enumerate("XYZ"):
        row.prop(data, "symmetry", index=index, text=axis, toggle=True)
    col = layout.column(align=True)
    col.prop(data, "keep_source_visible")
    col.prop(data, "keep_attributes")
    col.prop(data, "keep_source_uvs")
    col.prop(data, "show_layout")
    draw_atlas_options(layout, data)


def draw_uv_output(layout, data):
    """The integer-grid UVs' output options."""
    layout.use_property_split = False
    layout.prop(data, "quads_per_unit")
    layout.prop(data, "mark_seams")
    draw_atlas_options(layout, data)


def draw_atlas_options(layout, data):
    col = layout.column(align=True)
    col.prop(data, "texture_atlas")
    sub = col.column(align=True)
    sub.active = data.texture_atlas
    sub.prop(data, "atlas_size")
    sub.prop(data, "atlas_mip_levels")


def draw_section(layout, title, draw, data, *args):
    """A box headed `title` with the options `draw` puts in it (draw(layout, data, *args))."""
    box = layout.box()
    box.label(text=title)
    draw(box.column(), data, *args)
    return box


def flag(name, label, default):
    """A checkbox option whose tooltip is DESCRIPTIONS[name]."""
    return bpy.props.BoolProperty(name=label, default=default, description=DESCRIPTIONS[name])


class TargetSettings:
    """The density and feature options: of both operators, and of the panel's settings."""

    target_mode: bpy.props.EnumProperty(name="Target", items=TARGET_MODE_ITEMS, default="FACES",
                                        description=DESCRIPTIONS["target_mode"])
    target_faces: bpy.props.IntProperty(name="Quads", default=2000, min=10, soft_max=100000,
                                        description=DESCRIPTIONS["target_faces"])
    edge_length: bpy.props.FloatProperty(name="Edge Length", default=0.1, min=1e-6, subtype="DISTANCE",
                                         description=DESCRIPTIONS["edge_length"])
    use_marked_sharp: flag("use_marked_sharp", "Marked Sharp", True)
    use_sharp_angle: flag("use_sharp_angle", "Sharp Angle", False)
    sharp_angle: bpy.props.FloatProperty(name="Angle", default=math.radians(40), min=0, max=math.pi,
                                         subtype="ANGLE", description=DESCRIPTIONS["sharp_angle"])
    adaptive: bpy.props.FloatProperty(name="Adaptive Size", default=0.0, min=0.0, max=1.0, subtype="FACTOR",
                                      description=DESCRIPTIONS["adaptive"])
    density_group: bpy.props.StringProperty(name="Density Group", default="",
                                            description=DESCRIPTIONS["density_group"])
    density_color: bpy.props.StringProperty(name="Density Colour", default="",
                                            description=DESCRIPTIONS["density_color"])
    density_factor: bpy.props.FloatProperty(name="Density Factor", default=2.0, min=1 / 16, max=16,
                                            description=DESCRIPTIONS["density_factor"])
    use_seams: flag("use_seams", "Seams", False)
    use_material_boundaries: flag("use_material_boundaries", "Material Boundaries", False)
    use_face_sets: flag("use_face_sets", "Face Sets", False)
    weld: flag("weld", "Weld Open Edges", True)


class AtlasSettings:
    """The texture atlas options both operators take (and the panel holds)."""

    texture_atlas: bpy.props.BoolProperty(name="Texture Atlas", default=False,
                                          description=DESCRIPTIONS["texture_atlas"])
    atlas_size: bpy.props.IntProperty(name="Texture Size", default=1024, min=16, max=16384,
                                      description=DESCRIPTIONS["atlas_size"])
    atlas_mip_levels: bpy.props.IntProperty(name="Seam-Free Mip Levels", default=0, min=0, max=6,
                                            description=DESCRIPTIONS["atlas_mip_levels"])

    def _write_atlas(self, make, figures=None):
        """With Texture Atlas: make() writes the atlas and gives its figures, kept in `figures` (an object's
        "qgp" property) if given; returns (message part, whether it failed)."""
        if not self.texture_atlas:
            return "", False
        try:
            info = make()
        except binding.QGPError as e:
            if figures is not None:
                figures["atlas_note"] = e.message
            return f"; no texture atlas: {e.message}", True
        if figures is not None:
            figures["atlas"] = info
        return (f"; atlas: {info['charts']} charts, {info['texels_per_quad']} texels per quad, "
                f"{100 * info['texture_use']:.0f} % of the {self.atlas_size} x {self.atlas_size} texture"), False


class _TargetProperties(TargetSettings, AtlasSettings):
    """Density and feature options shared by both operators, and their common run."""

    @classmethod
    def poll(cls, context):
        return _active_mesh_object(context) is not None and context.mode == "OBJECT"

    def _prepare(self, context):
        _load_library(context)
        self._source_obj = _active_mesh_object(context)
        keep_attributes, keep_uvs = self._kept_of_source()
        try:
            self._source = blender_mesh.SourceMesh(
                context, self._source_obj, evaluated=self._use_modifiers, use_marked_sharp=self.use_marked_sharp,
                guides=self._guides(), keep_attributes=keep_attributes, keep_uvs=keep_uvs,
                density=(self.density_group, self.density_color, self.density_factor))
        except KeyError as e:
            raise binding.QGPError(binding.ERR_INVALID_ARGUMENT, e.args[0]) from None
        if len(self._source.triangles) == 0:
            raise binding.QGPError(binding.ERR_INVALID_MESH, "the mesh has no faces")
        angle = math.degrees(self.sharp_angle) if self.use_sharp_angle else -1.0
        prefs = preferences(context)
        session, fallback = _session_for(self._source_obj, self._source, angle, prefs.isolate if prefs else True)
        if fallback:
            self.report({"WARNING"}, _fallback_warning(fallback))
        if self.target_mode == "FACES":
            session.set_option("target_faces", self.target_faces)
        else:
            session.set_option("edge_length", self.edge_length)
        session.set_option("fallback_uv_map", 1 if self._wants_fallback_map() else 0)
        session.set_option("weld_tolerance", _WELD_TOLERANCE if self.weld else 0.0)
        session.set_option_string("symmetry", self._symmetry())
        session.set_option("adaptive", self.adaptive)
        session.set_density(self._source.density)
        return session

    def _symmetry(self):
        """The planes the result is mirror-symmetric about ("", "x", "xz", ...)."""
        return ""

    def _wants_fallback_map(self):
        return False

    def _guides(self):
        """The guides (blender_mesh.GUIDES) kept as quad edges besides marked-sharp edges."""
        chosen = (("SEAM", self.use_seams), ("MATERIAL", self.use_material_boundaries),
                  ("FACE_SET", self.use_face_sets))
        return tuple(name for name, use in chosen if use)

    def _kept_of_source(self):
        """(attributes, UV map): what the result keeps of the source besides its materials."""
        return False, False

    def execute(self, context):
        try:
            session = self._prepare(context)
            self._started = time.perf_counter()
            session.run(self._job)
            self._session = session
            return self._finish(context)
        except binding.QGPError as e:
            self.report({"ERROR"}, e.message)
            return {"CANCELLED"}

    def invoke(self, context, event):
        try:
            return self._start_modal(context, self._prepare(context), self._job)
        except binding.QGPError as e:
            self.report({"ERROR"}, e.message)
            return {"CANCELLED"}

    def _draw_target(self, layout):
        # The density maps are the source's: after a run the active object is the new one.
        source = getattr(self, "_source_obj", None) or bpy.context.active_object
        draw_section(layout, "Density", draw_density, self, source)
        draw_section(layout, "Features", draw_features, self)


class OBJECT_OT_qgp_quad_remesh(_TargetProperties, _JobOperator, bpy.types.Operator):
    """Remesh the active mesh into pure quads (Quantized Global Parametrization)"""

    bl_idname = "object.qgp_quad_remesh"
    bl_label = "Quantized Retopo"
    bl_options = {"REGISTER", "UNDO"}
    _job = binding.JOB_REMESH
    _use_modifiers = True  # the result is a new object: remesh what the user sees

    keep_source_visible: bpy.props.BoolProperty(name="Keep Source Visible", default=False,
                                                description=DESCRIPTIONS["keep_source_visible"])
    keep_attributes: bpy.props.BoolProperty(name="Keep Attributes", default=True,
                                            description=DESCRIPTIONS["keep_attributes"])
    keep_source_uvs: bpy.props.BoolProperty(name="Keep Source UVs", default=False,
                                            description=DESCRIPTIONS["keep_source_uvs"])
    show_layout: bpy.props.BoolProperty(name="Show Layout", default=False, description=DESCRIPTIONS["show_layout"])
    symmetry: bpy.props.BoolVectorProperty(name="Symmetry", size=3, subtype="XYZ", default=(False, False, False),
                                           description=DESCRIPTIONS["symmetry"])

    def _kept_of_source(self):
        return self.keep_attributes, self.keep_source_uvs

    def _symmetry(self):
        return "".join(axis for axis, on in zip("xyz", self.symmetry) if on)

    def _finish(self, context):
        vertices, quads, quad_triangle = self._session.quad_mesh()
        kept_vertices, kept, kept_triangle, _ = self._session.kept_triangles()
        report = self._session.report()
        if self.show_layout:
            self._make_layout_object(context)
        obj = blender_mesh.create_quad_object(context, self._source_obj, vertices, quads, quad_triangle, self._source,
                                              kept=(kept_vertices, kept, kept_triangle))
        obj["qgp"] = _report_figures(report, self, self._started, **_quad_figures(report))
        if not self.keep_source_visible:
            self._source_obj.hide_set(True)
        message = f"{obj.name}: {len(quads)} quads in {obj['qgp']['seconds']:.1f} s"
        if obj["qgp"]["symmetry"]:
            message += f", mirror-symmetric in {obj['qgp']['symmetry'].upper()}"
        atlas_note, atlas_failed = self._write_atlas(lambda: atlas.write_atlas_uvs(
            obj.data, vertices, quads, self.atlas_size, self.atlas_mip_levels), obj["qgp"])
        message += atlas_note
        warn = bool(obj["qgp"]["count_note"]) or atlas_failed
        if warn:  # the count asked for could not be met: why, and the fewest quads where that is the reason
            message += f"; {obj['qgp']['count_note']}"
        rescued = report.get("rescued_components", [])
        if rescued:  # parts whose layout gave no quads, quadded again (another field, remesh, finer or split)
            message += f"; rescued: {_failed_parts(rescued)}"
        failed = report.get("failed_components", [])
        if failed:  # the parts kept as triangles are selected, so Edit Mode shows them
            blender_mesh.select_faces(obj.data, list(range(len(quads), len(quads) + len(kept))))
            self.report({"WARNING"}, f"{message}; complete except {len(failed)} part(s) kept as their {len(kept)} "
                                     f"triangles (selected in Edit Mode): {_failed_parts(failed)}")
            return {"FINISHED"}
        # Quads that face against the source surface (where it folds within one quad), and quads with
        # an edge of almost no length (two corners on one point), are selected, so Edit Mode shows
        # them; everything else is deselected.
        quad = report.get("quad", {})
        flipped, collapsed = quad.get("flipped_quad_ids", []), quad.get("collapsed_edge_quad_ids", [])
        blender_mesh.select_faces(obj.data, sorted(set(flipped) | set(collapsed)))
        if flipped:
            message += f"; {len(flipped)} quad(s) face against the source surface (selected in Edit Mode)"
        if collapsed:
            message += f"; {len(collapsed)} quad(s) have an edge of almost no length (selected in Edit Mode)"
        warn = warn or bool(flipped) or bool(collapsed)
        self.report({"WARNING"} if warn else {"INFO"}, message)
        return {"FINISHED"}

    def _make_layout_object(self, context):
        """The layout's lines as '<name>_layout'; a layout the library cannot give is a warning."""
        try:
            points, segments = self._session.layout_lines()
        except binding.QGPError as e:
            self.report({"WARNING"}, f"No layout to show: {e.message}")
            return
        blender_mesh.create_layout_object(context, self._source_obj, points, segments)

    def draw(self, context):
        self._draw_target(self.layout)
        draw_section(self.layout, "Output", draw_quad_output, self)


# Two corners of an edge whose UVs differ by less than this share of a grid cell are one UV point
# (the map's charts meet with a quarter-turn rotation and an integer shift: their corners differ by
# far more, except on edges shorter than this around a cone's rotation center).
_UV_SEAM_TOLERANCE = 1e-4


class OBJECT_OT_qgp_grid_uv(_TargetProperties, _JobOperator, bpy.types.Operator):
    """Write seam-free integer-grid UVs (layer 'QGP Grid') on the active mesh"""

    bl_idname = "object.qgp_grid_uv"
    bl_label = "Integer-Grid UVs"
    bl_options = {"REGISTER", "UNDO"}
    _job = binding.JOB_GRID_UV
    _use_modifiers = False  # UVs belong to the mesh data's own loops

    quads_per_unit: bpy.props.FloatProperty(name="Quads per UV Unit", default=1.0, min=1e-3, soft_max=64,
                                            description=DESCRIPTIONS["quads_per_unit"])
    mark_seams: bpy.props.BoolProperty(name="Mark Seams", default=False, description=DESCRIPTIONS["mark_seams"])
    flip_free_copy: bpy.props.BoolProperty(
        name="Flip-Free Copy", default=True,
        description="Where the map on the mesh's own triangles would keep flipped triangles, write a new "
                    "object '<name>_grid_uv' instead: the mesh with the quad layout's edges inserted, whose "
                    "map has none (the source stays unchanged)")

    def _wants_fallback_map(self):
        return self.flip_free_copy

    def _finish(self, context):
        if self.flip_free_copy:
            vertices, triangles, corner_uv, triangle_source, refined = self._session.uv_mesh()
            if refined:
                obj = blender_mesh.create_grid_uv_object(context, self._source_obj, vertices, triangles, corner_uv,
                                                         triangle_source, self._source, self.quads_per_unit)
                message = (f"{obj.name}: the map needed the layout's edges inserted; UV layer 'QGP Grid' on "
                           f"{len(triangles)} triangles, none flipped (source unchanged)")
                seams = 0
                if self.mark_seams:
                    # The copy's cuts are its own edges (the source's cut edges split by the layout's):
                    # those along which the map's charts meet, i.e. the UV islands' inner boundaries.
                    seams = blender_mesh.mark_uv_seams(obj.data, obj.data.uv_layers["QGP Grid"],
                                                       _UV_SEAM_TOLERANCE / self.quads_per_unit)
                    message += f", {seams} seam edges marked"
                obj["qgp"] = _report_figures(self._session.report(), self, self._started,
                                             refined_components=int(refined), triangles=len(triangles),
                                             seams=seams)
                atlas_note, atlas_failed = self._write_grid_atlas(obj.data, obj.data.uv_layers["QGP Grid"], obj["qgp"])
                self._report_uv_outcome(message + atlas_note, "are not in the copy", warn=atlas_failed)
                return {"FINISHED"}
        corner_uv, _ = self._session.grid_uv(len(self._source.triangles))
        mesh = self._source_obj.data
        layer = blender_mesh.write_grid_uvs(mesh, self._source, corner_uv, self.quads_per_unit)
        message = "UV layer 'QGP Grid' written"
        if self.mark_seams:
            # The cuts as the UV layer has them: the map's cut edges, and where a cut runs inside a
            # polygon (a diagonal of a quad), the polygon's edges that the cut moved to (all its
            # loops are in one chart).
            seams = blender_mesh.mark_uv_seams(mesh, layer, _UV_SEAM_TOLERANCE / self.quads_per_unit)
            message += f", {seams} seam edges marked"
        atlas_note, atlas_failed = self._write_grid_atlas(mesh, layer)
        message += atlas_note
        mesh.update()
        # A map the global solve left flipped: its valid fallback lives on a refined mesh, which the
        # source object's loops cannot hold (Flip-Free Copy writes it as a new object).
        igm = self._session.report().get("igm", {})
        flipped = igm.get("flipped_triangles", 0)
        if flipped:
            hint = "no flip-free fallback was found" if self.flip_free_copy else "turn on Flip-Free Copy"
            message += f"; {flipped} triangle(s) of the map are flipped ({hint})"
        self._report_uv_outcome(message, "got no grid UVs (left at 0, 0)", warn=flipped > 0 or atlas_failed)
        return {"FINISHED"}

    def _write_grid_atlas(self, mesh, grid_layer, figures=None):
        """With Texture Atlas, the atlas of the mesh's polygons from their grid UVs (AtlasSettings._write_atlas)."""
        return self._write_atlas(lambda: atlas.write_polygon_atlas(
            mesh, grid_layer, self.quads_per_unit, self.atlas_size, self.atlas_mip_levels), figures)

    def _report_uv_outcome(self, message, failed_parts_outcome, warn=False):
        """INFO, or WARNING when `warn` or when parts of a many-part mesh failed (named, with why)."""
        failed = self._session.report().get("failed_components", [])
        if failed:
            message += f"; {len(failed)} part(s) {failed_parts_outcome}: {_failed_parts(failed)}"
        self.report({"WARNING"} if warn or failed else {"INFO"}, message)

    def draw(self, context):
        self._draw_target(self.layout)
        box = draw_section(self.layout, "Output", draw_uv_output, self)
        box.prop(self, "flip_free_copy")


class OBJECT_OT_qgp_stitch_seams(bpy.types.Operator):
    """Fill the gutters of an image in the active object's texture atlas from across each seam, so the seams
    of a baked or painted texture do not show (bilinear filtering reads the same colour on both sides)"""

    bl_idname = "object.qgp_stitch_seams"
    bl_label = "Stitch Seams"
    bl_options = {"REGISTER", "UNDO"}

    image_name: bpy.props.StringProperty(name="Image", default="", description=DESCRIPTIONS["stitch_image"])

    @classmethod
    def poll(cls, context):
        obj = context.active_object
        return obj is not None and obj.type == "MESH" and len(obj.data.uv_layers) > 0

    def execute(self, context):
        obj = context.active_object
        image = bpy.data.images.get(self.image_name) if self.image_name else atlas.material_image(obj)
        if image is None or image.size[0] == 0:
            self.report({"ERROR"}, f"No image to stitch: '{self.image_name}' does not exist" if self.image_name else
                        "No image to stitch: give its name, or make it the active Image Texture node of the "
                        "active material")
            return {"CANCELLED"}
        layer = obj.data.uv_layers.get(atlas.ATLAS_LAYER) or obj.data.uv_layers.active
        try:
            info = atlas.stitch_image(obj.data, layer, image)
        except binding.QGPError as e:
            self.report({"ERROR"}, f"Stitch Seams: {e.message}")
            return {"CANCELLED"}
        message = (f"{image.name}: {info['seam_edges']} seam edges of '{layer.name}' stitched "
                   f"({info['seam_texels']} texels)")
        if info["unmatched_seam_edges"]:
            self.report({"WARNING"}, f"{message}; {info['unmatched_seam_edges']} seam edges do not map texels onto "
                                     f"texels (not a grid-aligned atlas there) and were left as borders")
        else:
            self.report({"INFO"}, message)
        return {"FINISHED"}


classes = (OBJECT_OT_qgp_quad_remesh, OBJECT_OT_qgp_grid_uv, OBJECT_OT_qgp_stitch_seams)


def register():
    for cls in classes:
        bpy.utils.register_class(cls)


def unregister():
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)
    for _, session, _ in _session_cache.values():
        session.close()
    _session_cache.clear()

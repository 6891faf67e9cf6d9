"""Sidebar panel (View3D > Sidebar > Retopo) and Object menu entries."""
import math

import bpy

from .operators import OBJECT_OT_qgp_grid_uv, OBJECT_OT_qgp_quad_remesh


class QGP_Settings(bpy.types.PropertyGroup):
    """The panel's options, passed to the operators by its buttons."""

    target_mode: bpy.props.EnumProperty(
        name="Target", items=[("FACES", "Quad Count", ""), ("EDGE", "Edge Length", "")], default="FACES")
    target_faces: bpy.props.IntProperty(name="Quads", default=2000, min=10, soft_max=100000)
    edge_length: bpy.props.FloatProperty(name="Edge Length", default=0.1, min=1e-6, subtype="DISTANCE")
    use_marked_sharp: bpy.props.BoolProperty(name="Marked Sharp Edges", default=True)
    use_sharp_angle: bpy.props.BoolProperty(name="Sharp Angle", default=False)
    sharp_angle: bpy.props.FloatProperty(name="Angle", default=math.radians(40), min=0, max=math.pi,
                                         subtype="ANGLE")
    keep_source_visible: bpy.props.BoolProperty(name="Keep Source Visible", default=False)
    quads_per_unit: bpy.props.FloatProperty(name="Quads per UV Unit", default=1.0, min=1e-3, soft_max=64)
    mark_seams: bpy.props.BoolProperty(name="Mark Seams", default=False)


_SHARED = ("target_mode", "target_faces", "edge_length", "use_marked_sharp", "use_sharp_angle", "sharp_angle")


def _pass(op, settings, names):
    for name in names:
        setattr(op, name, getattr(settings, name))


class VIEW3D_PT_qgp_retopo(bpy.types.Panel):
    bl_label = "Quantized Retopo"
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "Retopo"

    def draw(self, context):
        settings = context.scene.qgp_settings
        layout = self.layout
        layout.use_property_split = True
        layout.use_property_decorate = False
        col = layout.column()
        col.prop(settings, "target_mode")
        col.prop(settings, "target_faces" if settings.target_mode == "FACES" else "edge_length")
        col.prop(settings, "use_marked_sharp")
        row = col.row(heading="Sharp Angle")
        row.prop(settings, "use_sharp_angle", text="")
        sub = row.row()
        sub.active = settings.use_sharp_angle
        sub.prop(settings, "sharp_angle", text="")

        box = layout.box()
        box.prop(settings, "keep_source_visible")
        op = box.operator(OBJECT_OT_qgp_quad_remesh.bl_idname, icon="MOD_REMESH")
        _pass(op, settings, _SHARED + ("keep_source_visible",))

        box = layout.box()
        box.prop(settings, "quads_per_unit")
        box.prop(settings, "mark_seams")
        op = box.operator(OBJECT_OT_qgp_grid_uv.bl_idname, icon="UV")
        _pass(op, settings, _SHARED + ("quads_per_unit", "mark_seams"))


def _object_menu(self, context):
    self.layout.separator()
    self.layout.operator(OBJECT_OT_qgp_quad_remesh.bl_idname, icon="MOD_REMESH")
    self.layout.operator(OBJECT_OT_qgp_grid_uv.bl_idname, icon="UV")


def register():
    bpy.utils.register_class(QGP_Settings)
    bpy.types.Scene.qgp_settings = bpy.props.PointerProperty(type=QGP_Settings)
    bpy.utils.register_class(VIEW3D_PT_qgp_retopo)
    bpy.types.VIEW3D_MT_object.append(_object_menu)


def unregister():
    bpy.types.VIEW3D_MT_object.remove(_object_menu)
    bpy.utils.unregister_class(VIEW3D_PT_qgp_retopo)
    del bpy.types.Scene.qgp_settings
    bpy.utils.unregister_class(QGP_Settings)

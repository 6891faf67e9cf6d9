"""Sidebar panel (View3D > Sidebar > Retopo: Density, Features, Output) and Object menu entries."""
import math

import bpy

from .operators import (DESCRIPTIONS, TARGET_MODE_ITEMS, OBJECT_OT_qgp_grid_uv, OBJECT_OT_qgp_quad_remesh,
                        draw_density, draw_features, draw_quad_output, draw_uv_output)


def _flag(name, label, default):
    return bpy.props.BoolProperty(name=label, default=default, description=DESCRIPTIONS[name])


class QGP_Settings(bpy.types.PropertyGroup):
    """The panel's options, passed to the operators by its buttons."""

    target_mode: bpy.props.EnumProperty(name="Target", items=TARGET_MODE_ITEMS, default="FACES",
                                        description=DESCRIPTIONS["target_mode"])
    target_faces: bpy.props.IntProperty(name="Quads", default=2000, min=10, soft_max=100000,
                                        description=DESCRIPTIONS["target_faces"])
    edge_length: bpy.props.FloatProperty(name="Edge Length", default=0.1, min=1e-6, subtype="DISTANCE",
                                         description=DESCRIPTIONS["edge_length"])
    use_marked_sharp: _flag("use_marked_sharp", "Marked Sharp", True)
    use_sharp_angle: _flag("use_sharp_angle", "Sharp Angle", False)
    sharp_angle: bpy.props.FloatProperty(name="Angle", default=math.radians(40), min=0, max=math.pi,
                                         subtype="ANGLE", description=DESCRIPTIONS["sharp_angle"])
    use_seams: _flag("use_seams", "Seams", False)
    use_material_boundaries: _flag("use_material_boundaries", "Material Boundaries", False)
    use_face_sets: _flag("use_face_sets", "Face Sets", False)
    weld: _flag("weld", "Weld Open Edges", True)
    keep_source_visible: _flag("keep_source_visible", "Keep Source Visible", False)
    keep_attributes: _flag("keep_attributes", "Keep Attributes", True)
    keep_source_uvs: _flag("keep_source_uvs", "Keep Source UVs", False)
    show_layout: _flag("show_layout", "Show Layout", False)
    quads_per_unit: bpy.props.FloatProperty(name="Quads per UV Unit", default=1.0, min=1e-3, soft_max=64,
                                            description=DESCRIPTIONS["quads_per_unit"])
    mark_seams: _flag("mark_seams", "Mark Seams", False)


# The settings both operators take, and those of each one's output.
_SHARED = ("target_mode", "target_faces", "edge_length", "use_marked_sharp", "use_sharp_angle", "sharp_angle",
           "use_seams", "use_material_boundaries", "use_face_sets", "weld")
_QUAD_OUTPUT = ("keep_source_visible", "keep_attributes", "keep_source_uvs", "show_layout")
_UV_OUTPUT = ("quads_per_unit", "mark_seams")


def _pass(op, settings, names):
    for name in names:
        setattr(op, name, getattr(settings, name))


class _RetopoSidebar:
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "Retopo"


class VIEW3D_PT_qgp_retopo(_RetopoSidebar, bpy.types.Panel):
    """The parent panel: which object the buttons remesh; the options are in its sub-panels."""

    bl_label = "Quantized Retopo"

    def draw(self, context):
        obj = context.active_object
        if obj is not None and obj.type == "MESH":
            self.layout.label(text=obj.name, icon="MESH_DATA")
        else:
            self.layout.label(text="Select a mesh object", icon="INFO")


class VIEW3D_PT_qgp_density(_RetopoSidebar, bpy.types.Panel):
    bl_label = "Density"
    bl_parent_id = "VIEW3D_PT_qgp_retopo"

    def draw(self, context):
        draw_density(self.layout.column(), context.scene.qgp_settings)


class VIEW3D_PT_qgp_features(_RetopoSidebar, bpy.types.Panel):
    bl_label = "Features"
    bl_parent_id = "VIEW3D_PT_qgp_retopo"

    def draw(self, context):
        draw_features(self.layout.column(), context.scene.qgp_settings)


class VIEW3D_PT_qgp_output(_RetopoSidebar, bpy.types.Panel):
    """Each operator's button below its own output options."""

    bl_label = "Output"
    bl_parent_id = "VIEW3D_PT_qgp_retopo"

    def draw(self, context):
        settings = context.scene.qgp_settings
        box = self.layout.box()
        draw_quad_output(box.column(), settings)
        op = box.operator(OBJECT_OT_qgp_quad_remesh.bl_idname, icon="MOD_REMESH")
        _pass(op, settings, _SHARED + _QUAD_OUTPUT)
        box = self.layout.box()
        draw_uv_output(box.column(), settings)
        op = box.operator(OBJECT_OT_qgp_grid_uv.bl_idname, icon="UV")
        _pass(op, settings, _SHARED + _UV_OUTPUT)


PANELS = (VIEW3D_PT_qgp_retopo, VIEW3D_PT_qgp_density, VIEW3D_PT_qgp_features, VIEW3D_PT_qgp_output)


def _object_menu(self, context):
    self.layout.separator()
    self.layout.operator(OBJECT_OT_qgp_quad_remesh.bl_idname, icon="MOD_REMESH")
    self.layout.operator(OBJECT_OT_qgp_grid_uv.bl_idname, icon="UV")


def register():
    bpy.utils.register_class(QGP_Settings)
    bpy.types.Scene.qgp_settings = bpy.props.PointerProperty(type=QGP_Settings)
    for panel in PANELS:
        bpy.utils.register_class(panel)
    bpy.types.VIEW3D_MT_object.append(_object_menu)


def unregister():
    bpy.types.VIEW3D_MT_object.remove(_object_menu)
    for panel in reversed(PANELS):
        bpy.utils.unregister_class(panel)
    del bpy.types.Scene.qgp_settings
    bpy.utils.unregister_class(QGP_Settings)

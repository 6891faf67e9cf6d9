"""Sidebar panel (View3D > Sidebar > Retopo: Density, Features, Output) and Object menu entries."""
import bpy

from .operators import (DESCRIPTIONS, OBJECT_OT_qgp_grid_uv, OBJECT_OT_qgp_quad_remesh, OBJECT_OT_qgp_stitch_seams,
                        AtlasSettings, TargetSettings,
                        draw_density, draw_features, draw_quad_output, draw_uv_output, flag)


class QGP_Settings(TargetSettings, AtlasSettings, bpy.types.PropertyGroup):
    """The panel's options, passed to the operators by its buttons."""

    keep_source_visible: flag("keep_source_visible", "Keep Source Visible", False)
    keep_attributes: flag("keep_attributes", "Keep Attributes", True)
    keep_source_uvs: flag("keep_source_uvs", "Keep Source UVs", False)
    show_layout: flag("show_layout", "Show Layout", False)
    symmetry: bpy.props.BoolVectorProperty(name="Symmetry", size=3, subtype="XYZ", default=(False, False, False),
                                           description=DESCRIPTIONS["symmetry"])
    quads_per_unit: bpy.props.FloatProperty(name="Quads per UV Unit", default=1.0, min=1e-3, soft_max=64,
                                            description=DESCRIPTIONS["quads_per_unit"])
    mark_seams: flag("mark_seams", "Mark Seams", False)


# The settings both operators take, and those of each one's output.
_SHARED = tuple(TargetSettings.__annotations__) + tuple(AtlasSettings.__annotations__)
_QUAD_OUTPUT = ("keep_source_visible", "keep_attributes", "keep_source_uvs", "show_layout", "symmetry")
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
        draw_density(self.layout.column(), context.scene.qgp_settings, context.active_object)


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
        box = self.layout.box()
        box.label(text="Baked or painted image in the atlas")
        box.operator(OBJECT_OT_qgp_stitch_seams.bl_idname, icon="IMAGE_DATA")


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

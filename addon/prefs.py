"""Add-on preferences."""
import bpy

from .core import binding


def addon_package():
    return __package__


class QGP_Preferences(bpy.types.AddonPreferences):
    bl_idname = __package__

    library_path: bpy.props.StringProperty(
        name="Native Library",
        description="Path of libqgp.so; empty uses the one shipped with the add-on",
        subtype="FILE_PATH",
        default="",
    )

    isolate: bpy.props.BoolProperty(
        name="Separate Process",
        description="Run native jobs in a child process: a fault in them cannot close Blender",
        default=True,
    )

    def draw(self, context):
        layout = self.layout
        layout.prop(self, "library_path")
        layout.prop(self, "isolate")
        try:
            layout.label(text="Native library version " + binding.version())
        except binding.QGPError as e:
            layout.label(text=str(e), icon="ERROR")


def preferences(context):
    addon = context.preferences.addons.get(__package__)
    return addon.preferences if addon else None


def register():
    bpy.utils.register_class(QGP_Preferences)


def unregister():
    bpy.utils.unregister_class(QGP_Preferences)

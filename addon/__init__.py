"""Quantized Retopo: pure-quad remeshing and integer-grid UVs (Quantized Global Parametrization).

Blender 3.x loads this as a legacy add-on (bl_info); Blender 4.2+ as an extension
(blender_manifest.toml, staged next to this file in the extension zip).
"""

bl_info = {
    "name": "Quantized Retopo",
    "author": "Quantized Retopo developers",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "View3D > Sidebar > Retopo; Object menu",
    "description": "Pure-quad remeshing and seam-free integer-grid UVs (Quantized Global Parametrization)",
    "category": "Mesh",
}

try:
    import bpy  # noqa: F401
except ImportError:  # imported outside Blender: only the bpy-free `core` package is usable
    bpy = None

if bpy is not None:
    from . import operators, prefs, ui

    _modules = (prefs, operators, ui)


def register():
    for module in _modules:
        module.register()


def unregister():
    for module in reversed(_modules):
        module.unregister()

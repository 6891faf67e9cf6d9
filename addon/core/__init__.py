"""bpy-free core of the add-on: the ctypes binding of libqgp and numpy conversions.

Importable without Blender (tests use it directly).
"""

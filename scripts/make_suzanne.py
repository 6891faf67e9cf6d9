"""Writes Blender's Suzanne, subdivided once, as OBJ: blender -b --python make_suzanne.py -- OUT.obj"""
import sys

import bpy

out = sys.argv[sys.argv.index("--") + 1]
bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.mesh.primitive_monkey_add()
obj = bpy.context.active_object
obj.modifiers.new("subdivide", "SUBSURF").levels = 1
mesh = obj.evaluated_get(bpy.context.evaluated_depsgraph_get()).to_mesh()
with open(out, "w") as f:
    f.write("# Suzanne (Blender), subdivided once\n")
    for v in mesh.vertices:
        f.write("v %.6f %.6f %.6f\n" % tuple(v.co))
    for p in mesh.polygons:
        f.write("f " + " ".join(str(i + 1) for i in p.vertices) + "\n")
print("suzanne: %d vertices, %d faces -> %s" % (len(mesh.vertices), len(mesh.polygons), out))

# Imports a mesh written by `dqjulia mesh` into the real Blender and checks its counts.
#
#   blender -b --factory-startup --python-exit-code 1 --python check_mesh.py -- FILE.ply|FILE.obj VERTICES FACES
#
# VERTICES and FACES are what `dqjulia mesh --stats` reported; Blender must import exactly as
# many, with vertex colours, and every edge must be shared by exactly two faces (closed).
import sys

import bpy


def fail(message):
    raise SystemExit("check_mesh: " + message)


def main(argv):
    path, vertices, faces = argv[0], int(argv[1]), int(argv[2])
    before = set(bpy.data.objects)
    if path.endswith(".ply"):
        if "ply_import" in dir(bpy.ops.wm):  # (hasattr is always true on bpy.ops)
            bpy.ops.wm.ply_import(filepath=path)  # Blender 3.6+: the C++ PLY importer
        else:
            bpy.ops.import_mesh.ply(filepath=path)  # Blender 3.4 - 3.5: the PLY add-on (gone in 4.0)
    else:
        bpy.ops.wm.obj_import(filepath=path)  # Blender 3.4: the C++ OBJ importer
    added = [obj for obj in bpy.data.objects if obj not in before]
    if len(added) != 1 or added[0].type != "MESH":
        fail(f"expected one mesh object from {path}, got {added}")
    mesh = added[0].data
    if len(mesh.vertices) != vertices or len(mesh.polygons) != faces:
        fail(
            f"{path}: Blender imported {len(mesh.vertices)} vertices and {len(mesh.polygons)} faces; "
            f"dqjulia reported {vertices} and {faces}"
        )
    if not mesh.color_attributes:
        fail(f"{path}: no vertex colours imported")
    uses = {}
    for polygon in mesh.polygons:
        for key in polygon.edge_keys:
            uses[key] = uses.get(key, 0) + 1
    open_edges = sum(1 for count in uses.values() if count != 2)
    if open_edges:
        fail(f"{path}: {open_edges} edges are not shared by exactly two faces")
    print(f"check_mesh: {path}: {vertices} vertices, {faces} faces, colours {mesh.color_attributes[0].name}: OK")


main(sys.argv[sys.argv.index("--") + 1 :])

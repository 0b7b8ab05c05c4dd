# Loads baked OpenVDB files in the real Blender and checks what Blender finds in them.
#
#   blender -b --factory-startup --python-exit-code 1 --python check_vdb.py -- FILE.vdb GRIDS
#   blender -b --factory-startup --python-exit-code 1 --python check_vdb.py -- --sequence FIRST.vdb COUNT GRIDS
#
# GRIDS: the comma-separated grid names the file must hold (they must include "density", the
# grid Blender's Principled Volume reads). With --sequence, the files FIRST_0001.vdb ... are
# imported together and must become one volume sequence of COUNT frames, each holding GRIDS.
# Any failed check raises, and --python-exit-code 1 makes Blender exit with status 1.
import os
import sys

import bpy


def fail(message):
    raise SystemExit("check_vdb: " + message)


def check_grids(volume, expected, where):
    if not volume.grids.load():
        fail(f"{where}: Blender could not load the grids: {volume.grids.error_message}")
    found = {grid.name: grid for grid in volume.grids}
    for name in expected:
        if name not in found:
            fail(f"{where}: no grid {name!r}; Blender found {sorted(found)}")
    for name in expected:
        grid = found[name]
        wanted = "VECTOR_FLOAT" if name == "color" else "FLOAT"
        if grid.data_type != wanted:
            fail(f"{where}: grid {name!r} is {grid.data_type}, expected {wanted}")
        if not grid.load():
            fail(f"{where}: grid {name!r} does not load")
    print(f"check_vdb: {where}: grids {sorted(found)}")


def main(argv):
    scene = bpy.context.scene
    if argv[0] == "--sequence":
        first, count, grids = argv[1], int(argv[2]), argv[3].split(",")
        folder = os.path.dirname(first)
        stem = os.path.basename(first)[: -len("_0001.vdb")]
        names = [f"{stem}_{frame:04d}.vdb" for frame in range(1, count + 1)]
        bpy.ops.object.volume_import(filepath=first, directory=folder + "/", files=[{"name": name} for name in names])
        obj = bpy.context.active_object
        if obj is None or obj.type != "VOLUME":
            fail("importing the files made no volume object")
        volume = obj.data
        if not volume.is_sequence or volume.frame_duration != count or volume.frame_start != 1:
            fail(
                f"not a sequence of {count} frames from frame 1: is_sequence={volume.is_sequence}, "
                f"frame_start={volume.frame_start}, frame_duration={volume.frame_duration}"
            )
        # Last frame first: each check follows a real frame change. Blender 4.2 (bpy 4.2.23)
        # reports "NAME_0000.vdb not found" for a sequence that has not seen a frame change
        # since it was made (4.5, 5.0 and 3.4 load frame 1 at once).
        for frame in range(count, 0, -1):
            scene.frame_set(frame)
            evaluated = obj.evaluated_get(bpy.context.evaluated_depsgraph_get()).data
            check_grids(evaluated, grids, f"frame {frame}")
            if not evaluated.grids.frame_filepath.endswith(names[frame - 1]):
                fail(f"frame {frame} reads {evaluated.grids.frame_filepath}, expected {names[frame - 1]}")
    else:
        path, grids = argv[0], argv[1].split(",")
        volume = bpy.data.volumes.new("dqjulia")
        volume.filepath = path
        obj = bpy.data.objects.new("dqjulia", volume)
        scene.collection.objects.link(obj)
        check_grids(volume, grids, os.path.basename(path))
        # The volume has extent: its bounding box spans the fractal (a few units across).
        bpy.context.view_layer.update()
        corners = [tuple(corner) for corner in obj.bound_box]
        size = max(max(c[axis] for c in corners) - min(c[axis] for c in corners) for axis in range(3))
        if not 0.5 < size < 20.0:
            fail(f"bounding box of {size} units; expected the fractal's size")
    print("check_vdb: OK")


main(sys.argv[sys.argv.index("--") + 1 :])

"""Loads libdqjulia through the add-on's own native.py (outside Blender) and bakes a VDB and a
mesh of the default fractal. Prints one JSON line with what was made, so the clean-room test
can compare a run inside a minimal Debian root with the same run on the build machine.

Usage: python3 bake_with_native.py ADDON_DIR WORK_DIR [RESOLUTION]
ADDON_DIR is the add-on's package folder from the zip (dqjulia/, holding native.py and lib/).
"""

import json
import os
import sys


sys.path.append(os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "common"))
from package_module import load_package_module  # noqa: E402 (beside this script in a root; tests/common here)


def load_native(addon_dir):
    # As in Blender: native.py finds its _buildinfo.py (the version it was built for) beside it.
    return load_package_module(os.path.join(addon_dir, "native.py"), "dqjulia_addon")


def main():
    addon_dir, work = sys.argv[1], sys.argv[2]
    resolution = int(sys.argv[3]) if len(sys.argv) > 3 else 96
    native = load_native(addon_dir)
    os.environ.pop(native.LIBRARY_ENV, None)
    error = native.load_error()
    if error is not None:
        print("cannot load the library: %s" % error, file=sys.stderr)
        return 1
    os.makedirs(work, exist_ok=True)
    vdb = os.path.join(work, "cleanroom.vdb")
    ply = os.path.join(work, "cleanroom.ply")
    with native.Context() as context:
        # An error inside the library comes back as a message (a C++ exception unwound and
        # caught inside it: the static unwinder works on this system).
        try:
            context.set_params_json('{"fractal": {"iterations": "many"}}')
        except native.NativeError as error:
            rejected = error.message
        else:
            print("a bad parameter document was accepted", file=sys.stderr)
            return 1
        context.set_bake_resolution(resolution)
        context.bake_vdb(vdb)
        bake = context.bake_stats()
        context.mesh_compute()
        vertices, triangles = context.mesh_sizes()
        context.mesh_write(ply)
    print(
        json.dumps(
            {
                "version": native.version()[1],
                "library": native.library_path(),
                "vdb_bytes": os.path.getsize(vdb),
                "active_voxels": bake.active_voxels,
                "voxels_evaluated": bake.voxels_evaluated,
                "mesh_vertices": vertices,
                "mesh_triangles": triangles,
                "ply_bytes": os.path.getsize(ply),
                "error_message": rejected,
            },
            sort_keys=True,
        )
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""The viewport preview's shaders without a window, in a bpy wheel 5.2+ (Blender as a Python
module starts its GPU backend headless: gpu.init(), on Mesa's llvmpipe through EGL here):

  VENV/bin/python tests/blender/gpu_preview_test.py -- --zip build/dist/dqjulia_blender.zip \\
      --work DIR --cli build/bin/dqjulia --backend OPENGL|VULKAN

The bpy module ignores Preferences > System > GPU Backend (it is read before any script runs,
from the factory settings) and takes the first backend that starts: Vulkan from 5.3 where a
Vulkan driver is installed (Mesa's lavapipe, Debian's mesa-vulkan-drivers, here), else OpenGL;
5.2.4 starts OpenGL whatever is installed. So --backend OPENGL hides the Vulkan drivers from
Vulkan's loader (VK_DRIVER_FILES and VK_ICD_FILENAMES naming no file), and the test checks that
Blender runs on the backend asked for rather than on a fallback. Then the add-on, installed from
the zip as an extension, draws its preview into a GPUOffScreen and preview_compare.py compares it
with the core's render: silhouette IoU and mean colour in two scenes, and no lone dark pixels.
"""

import os
import sys

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common  # noqa: E402
import preview_compare  # noqa: E402
from common import check, report  # noqa: E402


def extra_arguments(parser):
    parser.add_argument("--backend", choices=("OPENGL", "VULKAN"), default="OPENGL")
    preview_compare.add_arguments(parser)


ARGS = common.arguments(extra_arguments)
check(common.blender_kind() == "bpy module", "this runs in a bpy wheel (%s)" % common.blender_kind())

import gpu  # noqa: E402  (the bpy module's; importable once bpy is)

if ARGS.backend == "OPENGL":
    for name in ("VK_DRIVER_FILES", "VK_ICD_FILENAMES"):
        os.environ[name] = os.path.join(ARGS.work, "no-vulkan-driver.json")
try:
    gpu.init()
except SystemError as error:
    check(False, "gpu.init() starts the GPU without a window: %s" % error)
    common.finish()
backend = gpu.platform.backend_type_get()
report(
    "Blender %s: GPU backend %s, %s, %s, %s"
    % (
        bpy.app.version_string,
        backend,
        gpu.platform.vendor_get(),
        gpu.platform.renderer_get(),
        gpu.platform.version_get(),
    )
)
check(backend == ARGS.backend, "the GPU runs on the chosen backend %s (%s)" % (ARGS.backend, backend))

dqjulia = common.install_addon(ARGS.zip, os.path.join(ARGS.work, "cache"))
preview_compare.setup(dqjulia, ARGS)
for obj in list(bpy.data.objects):
    bpy.data.objects.remove(obj)
check(bpy.ops.object.dqjulia_add() == {"FINISHED"}, "Add DQ Julia")
obj = bpy.context.view_layer.objects.active
preview_compare.compare_with_core(obj)
preview_compare.check_speckles(obj)
report("results: %s" % preview_compare.RESULTS)
common.finish()

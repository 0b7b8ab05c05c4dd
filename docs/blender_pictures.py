"""The documentation's renders of the Blender add-on's results (docs/make-pictures.sh runs this in
Debian's Blender in a window under xvfb-run: the viewport preview needs a GPU, which -b lacks):

  xvfb-run -a -s "-screen 0 1280x800x24" blender --factory-startup --python docs/blender_pictures.py -- \
      --zip build/dist/dqjulia_blender.zip --work DIR --out DIR --vdb FRACTAL.vdb --resolution 256

Writes into --out:
  blender-default-preview.png  the factory scene with Add DQ Julia, seen by its camera: the GLSL
                               preview over the world's colour
  blender-default-volume.png   the same with a default Bake Volume (the Surface look), Cycles
  blender-default-mesh.png     the same with a default Bake Mesh, Cycles
  baked-blender.png            --vdb (the default fractal as `dqjulia bake -r RESOLUTION` wrote it)
                               as the add-on's volume in the Surface look, Frame Camera, Studio, Cycles
Cycles on the CPU with --samples samples, no denoiser (Debian's Blender has none); the view
transform is Standard, the colours `dqjulia render` writes. The exit status is 0 only if every
picture was made.
"""

import os
import sys
import traceback

import bpy

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), os.pardir, "tests", "blender"))
import common  # noqa: E402
import preview_compare  # noqa: E402
from common import check, report  # noqa: E402


def extra_arguments(parser):
    parser.add_argument("--out", required=True, help="the folder the pictures go into")
    parser.add_argument("--vdb", required=True, help="the default fractal baked by `dqjulia bake`")
    parser.add_argument("--resolution", type=int, required=True, help="the resolution --vdb was baked at")
    parser.add_argument("--samples", type=int, default=128, help="Cycles samples a pixel")


ARGS = common.arguments(extra_arguments)
dqjulia = common.install_addon(ARGS.zip, os.path.join(ARGS.work, "cache"))
preview_compare.setup(dqjulia, ARGS)
bakes = common.submodule(dqjulia, "bakes")


def window_override(obj):
    window = bpy.context.window_manager.windows[0]
    area = next(area for area in window.screen.areas if area.type == "VIEW_3D")
    region = next(region for region in area.regions if region.type == "WINDOW")
    return bpy.context.temp_override(window=window, area=area, region=region, active_object=obj, object=obj)


def render_settings(width, height):
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = ARGS.samples
    scene.cycles.use_denoising = False
    scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = width, height, 100
    scene.render.film_transparent = False
    scene.view_settings.view_transform = "Standard"
    settings = scene.render.image_settings
    settings.file_format, settings.color_mode, settings.color_depth = "PNG", "RGB", "8"


def render(obj, shown, name):
    """F12 with only the bake of kind `shown` of obj's bakes rendering; saved as name in --out."""
    for child in obj.children:
        child.hide_render = child.get("dqjulia_bake") != shown
    scene = bpy.context.scene
    scene.render.filepath = os.path.join(ARGS.out, name)
    bpy.ops.render.render(write_still=True)
    check(os.path.getsize(scene.render.filepath) > 0, "rendered %s" % scene.render.filepath)


def default_scene_pictures(obj):
    """The factory scene's camera and light on the default object: the preview, then Cycles
    renders of its default volume and mesh bakes."""
    width, height = 480, 270
    scene = bpy.context.scene
    render_settings(width, height)
    world = tuple(scene.world.node_tree.nodes["Background"].inputs[0].default_value[:3])
    camera = scene.camera
    view = camera.matrix_world.inverted()
    projection = camera.calc_matrix_camera(bpy.context.evaluated_depsgraph_get(), x=width, y=height)
    drew, rgba, _mask = preview_compare.offscreen_preview(obj, view, projection, width, height)
    check(drew, "the preview drew the object")
    for index in range(width * height):  # over the world's colour, as the viewport shows it
        alpha = rgba[4 * index + 3]
        for channel in range(3):
            rgba[4 * index + channel] += (1.0 - alpha) * world[channel]
        rgba[4 * index + 3] = 1.0
    image = bpy.data.images.new("preview", width, height, alpha=False, float_buffer=True)
    image.pixels.foreach_set(rgba)
    image.save_render(os.path.join(ARGS.out, "blender-default-preview.png"), scene=scene)
    bpy.data.images.remove(image)
    for kind, operator in (("volume", bpy.ops.dqjulia.bake_volume), ("mesh", bpy.ops.dqjulia.bake_mesh)):
        with window_override(obj):
            result = operator(synchronous=True)
        check(result == {"FINISHED"}, "default %s bake: %s" % (kind, result))
        render(obj, kind, "blender-default-%s.png" % kind)


def cli_bake_picture(obj):
    """The command's bake as the add-on's volume (the object's look), framed and lit as a user's
    first render is: Frame Camera, then Studio (the factory light off)."""
    obj.dqjulia.bake_resolution = ARGS.resolution  # the Surface look's edge is a voxel deep
    obj.dqjulia.volume_look = "SURFACE"
    volume = bakes.build_volume(bpy.context, obj, os.path.abspath(ARGS.vdb))
    check(volume.get("dqjulia_bake") == "volume", "the command's VDB is the object's volume")
    for light in [o for o in bpy.context.scene.objects if o.type == "LIGHT"]:
        light.hide_render = True
    render_settings(560, 420)
    for operator in (bpy.ops.dqjulia.frame_camera, bpy.ops.dqjulia.studio):
        with window_override(obj):
            result = operator()
        check(result == {"FINISHED"}, "%s: %s" % (operator.idname_py(), result))
    render(obj, "volume", "baked-blender.png")


def make_pictures():
    os.makedirs(ARGS.out, exist_ok=True)
    for obj in list(bpy.data.objects):
        if obj.type == "MESH":  # the factory cube
            bpy.data.objects.remove(obj)
    with window_override(None):
        check(bpy.ops.object.dqjulia_add() == {"FINISHED"}, "Add DQ Julia")
    obj = bpy.context.view_layer.objects.active
    default_scene_pictures(obj)
    cli_bake_picture(obj)


def _run():
    try:
        make_pictures()
        failures = common.failures()
        report("%d check(s) failed: %s" % (len(failures), "; ".join(failures)) if failures else "all pictures made")
        code = 1 if failures else 0
    except Exception:
        traceback.print_exc()
        code = 1
    sys.stdout.flush()
    os._exit(code)


# From a timer: the window (and its GPU context) exists once the event loop runs.
bpy.app.timers.register(_run, first_interval=1.0)

"""The viewport preview drawn offscreen and compared with the core's render: shared by
preview_test.py (Debian's Blender in a window under xvfb-run) and gpu_preview_test.py (the bpy
wheels 5.2+, whose module starts the GPU without a window: gpu.init()).

  compare_with_core(obj)  the GLSL preview, drawn into a GPUOffScreen with the camera of a core
                          render, against that render (the core's dqj_render_rgba8, which `dqjulia
                          render` calls; and the CLI itself when --cli is given), in two scenes:
                          the silhouettes' overlap (IoU >= --min-iou) and the mean linear colour
                          of the pixels both cover, preview against core (occlusion and shadows
                          off, which the preview does not draw; normals by central differences,
                          as the preview's), within --max-colour-difference per channel
  check_speckles(obj)     no lone dark pixels on the default fractal at 640 x 480

setup(package, args) first: the installed add-on's package and the parsed arguments
(add_arguments(parser) adds --min-iou and --max-colour-difference). RESULTS collects the
measured values.
"""

import array
import json
import os
import subprocess

import bpy

import common
from common import check, report

WIDTH, HEIGHT = 320, 240
RESULTS = {}
ARGS = None
native = preview = props = None


def add_arguments(parser):
    parser.add_argument("--min-iou", type=float, default=0.98)
    # The preview marches, takes normals and shades in float on the GPU, the core in double, so
    # single pixels may differ where the surface has fine detail; the mean colour of the two
    # pictures differed by 1e-4 (linear RGB, per channel) under llvmpipe, so 0.005 leaves room for
    # other drivers while a wrong palette, trap scale or Phong term (0.02 and more) fails.
    parser.add_argument("--max-colour-difference", type=float, default=0.005)


def setup(package, args):
    global ARGS, native, preview, props
    ARGS = args
    native, preview, props = (common.submodule(package, name) for name in ("native", "preview", "props"))


def look_at(eye, target, up):
    from mathutils import Matrix, Vector

    eye, target, up = Vector(eye), Vector(target), Vector(up)
    forward = (target - eye).normalized()
    right = forward.cross(up).normalized()
    true_up = right.cross(forward)
    return Matrix(
        (
            (right.x, right.y, right.z, -right.dot(eye)),
            (true_up.x, true_up.y, true_up.z, -true_up.dot(eye)),
            (-forward.x, -forward.y, -forward.z, forward.dot(eye)),
            (0.0, 0.0, 0.0, 1.0),
        )
    )


def perspective(fov_degrees, aspect, near, far):
    import math
    from mathutils import Matrix

    f = 1.0 / math.tan(math.radians(fov_degrees) / 2.0)
    return Matrix(
        (
            (f / aspect, 0.0, 0.0, 0.0),
            (0.0, f, 0.0, 0.0),
            (0.0, 0.0, (far + near) / (near - far), 2.0 * far * near / (near - far)),
            (0.0, 0.0, -1.0, 0.0),
        )
    )


def offscreen_preview(obj, view, projection, width, height):
    """The preview drawn offscreen: (RGBA floats bottom-up, coverage mask top-down). Half floats,
    so the linear colour is not rounded to 8 bits."""
    import gpu

    try:
        offscreen = gpu.types.GPUOffScreen(width, height, format="RGBA16F")
    except (TypeError, ValueError):
        offscreen = gpu.types.GPUOffScreen(width, height)
    try:
        with offscreen.bind():
            framebuffer = gpu.state.active_framebuffer_get()
            framebuffer.clear(color=(0.0, 0.0, 0.0, 0.0), depth=1.0)
            with gpu.matrix.push_pop():
                gpu.matrix.load_matrix(view)
                gpu.matrix.load_projection_matrix(projection)
                drew = preview.draw_object(obj, view, projection, height)
            buffer = framebuffer.read_color(0, 0, width, height, 4, 0, "FLOAT")
    finally:
        offscreen.free()
    buffer.dimensions = width * height * 4
    rgba = array.array("f", buffer)
    mask = []
    for row in range(height - 1, -1, -1):  # top-down, as images are
        for column in range(width):
            mask.append(rgba[4 * (row * width + column) + 3] > 0.5)
    return drew, rgba, mask


def save_mask(path, mask, width, height):
    image = bpy.data.images.new(os.path.basename(path), width, height, alpha=False)
    pixels = array.array("f", [0.0]) * (4 * width * height)
    for index, inside in enumerate(mask):
        row, column = divmod(index, width)
        base = 4 * ((height - 1 - row) * width + column)
        value = 1.0 if inside else 0.0
        pixels[base : base + 4] = array.array("f", [value, value, value, 1.0])
    image.pixels.foreach_set(pixels)
    image.filepath_raw = path
    image.file_format = "PNG"
    image.save()
    bpy.data.images.remove(image)


def core_render(document, width, height):
    """The core renderer's coverage (alpha > 0.5) for the document, top-down, and its pixels
    (RGBA8, sRGB colour)."""
    with native.Context(document) as context:
        pixels, _warning = context.render_rgba8(width, height)
    return [pixels[4 * i + 3] > 127 for i in range(width * height)], pixels


def srgb_to_linear(value):
    """An 8-bit sRGB value (0..255) as linear colour: the inverse of the core's linearToSrgb8."""
    encoded = value / 255.0
    return encoded / 12.92 if encoded <= 0.04045 else ((encoded + 0.055) / 1.055) ** 2.4


def mean_colours(preview_rgba, core_pixels, preview_mask, core_mask, width, height):
    """Mean linear RGB of the preview and of the core over the pixels both cover, and how many."""
    preview_sum = [0.0, 0.0, 0.0]
    core_sum = [0.0, 0.0, 0.0]
    count = 0
    for index in range(width * height):
        if not (preview_mask[index] and core_mask[index]):
            continue
        row, column = divmod(index, width)
        base = 4 * ((height - 1 - row) * width + column)  # the preview's rows are bottom-up
        for channel in range(3):
            preview_sum[channel] += preview_rgba[base + channel]
            core_sum[channel] += srgb_to_linear(core_pixels[4 * index + channel])
        count += 1
    count_or_one = max(1, count)
    return [x / count_or_one for x in preview_sum], [x / count_or_one for x in core_sum], count


def cli_mask(document, width, height):
    """The same through the dqjulia command, if given: rendered flat white on black (ambient
    light only, no occlusion) into a PNG, so a pixel is white exactly where its ray hit."""
    if not ARGS.cli or not os.path.isfile(ARGS.cli):
        return None
    flat = json.loads(json.dumps(document))
    flat["material"].update(
        {
            "coloring": "solid",
            "color": [1.0, 1.0, 1.0],
            "ambient": 1.0,
            "diffuse": 0.0,
            "specular": 0.0,
            "occlusion": 0.0,
            "shadows": False,
        }
    )
    flat["render"]["background"] = [0.0, 0.0, 0.0]
    params = os.path.join(ARGS.work, "cli_params.json")
    output = os.path.join(ARGS.work, "cli_render_%d.png" % len(os.listdir(ARGS.work)))
    with open(params, "w") as file:
        json.dump(flat, file)
    command = [ARGS.cli, "render", "-q", "-p", params, "-W", str(width), "-H", str(height), "-s", "1", "-o", output]
    result = subprocess.run(command, capture_output=True, text=True)
    if not check(result.returncode == 0, "`dqjulia render` ran (%s)" % (result.stderr.strip()[:200] or "ok")):
        return None
    image = bpy.data.images.load(output)
    pixels = array.array("f", [0.0]) * (4 * width * height)
    image.pixels.foreach_get(pixels)
    bpy.data.images.remove(image)
    mask = []
    for row in range(height - 1, -1, -1):  # Blender's pixels are bottom-up
        for column in range(width):
            mask.append(pixels[4 * (row * width + column)] > 0.5)
    return mask


def compare_with_core(obj):
    cases = [
        ("default (paper, N=15, trap colouring)", {}),
        (
            "dual, N=30, turned slice, iterations colouring",
            {
                "variant": "dual",
                "iterations": 30,
                "c_a": (-0.2, 0.6, 0.2, 0.0),
                "c_b": (0.0, 0.0, 0.0, 0.0),
                "rotation": ("a.j", "a.k", 35.0),
                "coloring": "iterations",
            },
        ),
    ]
    s = obj.dqjulia
    for name, change in cases:
        with native.Context() as context:
            props.from_document(s, context.params())
        for key in ("variant", "iterations", "c_a", "c_b", "coloring"):
            if key in change:
                setattr(s, key, change[key])
        # The preview draws no occlusion or shadows, and takes normals by central differences
        # (the core's "auto" takes analytic ones for dual: 2.5% brighter on average here).
        s.occlusion, s.shadows, s.normals = 0.0, False, "central"
        if "rotation" in change:
            rotation = s.rotations.add()
            rotation.first, rotation.second, rotation.degrees = change["rotation"]
        eye, target, up, fov = (2.3, 1.9, 3.9), (0.0, 0.0, 0.0), (0.0, 1.0, 0.0), 40.0
        s.camera_use_position = s.camera_use_target = True
        s.camera_position, s.camera_target, s.camera_up, s.camera_fov = eye, target, up, fov
        s.width, s.height, s.samples = WIDTH, HEIGHT, 1
        s.preview_max_steps = s.max_steps  # the preview marches as far as the core
        document = props.to_document(s)
        expected, core_pixels = core_render(document, WIDTH, HEIGHT)
        # The core's camera is in the slice's (the object's local) coordinates; the viewport's in
        # the world's: the object is turned (Add DQ Julia's y-up convention).
        view = look_at(eye, target, up) @ obj.matrix_world.inverted()
        projection = perspective(fov, WIDTH / HEIGHT, 0.05, 100.0)
        drew, rgba, drawn = offscreen_preview(obj, view, projection, WIDTH, HEIGHT)
        check(drew, "%s: the preview shader compiled and drew (%s)" % (name, preview.shader_error() or "no error"))
        value = common.iou(drawn, expected)
        RESULTS["iou " + name] = value
        check(sum(expected) > 0.05 * WIDTH * HEIGHT, "%s: the core render covers %d pixels" % (name, sum(expected)))
        check(
            value >= ARGS.min_iou,
            "%s: preview vs core render silhouette IoU %.4f (>= %.2f)" % (name, value, ARGS.min_iou),
        )
        preview_mean, core_mean, both = mean_colours(rgba, core_pixels, drawn, expected, WIDTH, HEIGHT)
        difference = max(abs(a - b) for a, b in zip(preview_mean, core_mean))
        RESULTS["colour difference " + name] = difference
        check(
            both > 0.05 * WIDTH * HEIGHT and difference <= ARGS.max_colour_difference,
            "%s: mean colour over %d pixels, preview (%.4f, %.4f, %.4f) vs core (%.4f, %.4f, %.4f): largest "
            "channel difference %.4f (<= %.3f)"
            % ((name, both) + tuple(preview_mean) + tuple(core_mean) + (difference, ARGS.max_colour_difference)),
        )
        slug = name.split(" ")[0].strip(",")
        save_mask(os.path.join(ARGS.work, "mask_preview_%s.png" % slug), drawn, WIDTH, HEIGHT)
        save_mask(os.path.join(ARGS.work, "mask_core_%s.png" % slug), expected, WIDTH, HEIGHT)
        from_cli = cli_mask(document, WIDTH, HEIGHT)
        if from_cli is not None:
            value = common.iou(drawn, from_cli)
            RESULTS["iou cli " + name] = value
            check(value >= ARGS.min_iou, "%s: preview vs `dqjulia render` silhouette IoU %.4f" % (name, value))
        else:
            report("note %s: no CLI given (--cli), compared with dqj_render_rgba8 only" % name)
        s.rotations.clear()
    with native.Context() as context:
        props.from_document(s, context.params())


def isolated_dark_pixels(rgba, mask, width, height, ratio=0.25):
    """Speckles: covered pixels darker than `ratio` times the median of their 8 neighbours, with
    no other pixel of their 5 x 5 neighbourhood darker than half that median and all of it
    covered. A crease or an occluding edge is a line of dark pixels (dotted at one ray a pixel)
    and a rim lies beside the background, so neither counts; a lone pixel on a surface does."""
    luminance = [0.0] * (width * height)
    for index in range(width * height):
        row, column = divmod(index, width)
        base = 4 * ((height - 1 - row) * width + column)  # the preview's rows are bottom-up
        luminance[index] = (rgba[base] + rgba[base + 1] + rgba[base + 2]) / 3.0
    ring = [(dy, dx) for dy in range(-2, 3) for dx in range(-2, 3) if dy or dx]
    found = []
    for row in range(2, height - 2):
        for column in range(2, width - 2):
            index = row * width + column
            if not mask[index]:
                continue
            around = [index + dy * width + dx for dy, dx in ring]
            if not all(mask[k] for k in around):
                continue
            near = sorted(luminance[index + dy * width + dx] for dy, dx in ring if abs(dy) <= 1 and abs(dx) <= 1)
            median = near[len(near) // 2]
            if luminance[index] < ratio * median and min(luminance[k] for k in around) >= 0.5 * median:
                found.append((column, row))
    return found


def check_speckles(obj):
    """The default fractal at 640 x 480, one ray a pixel: no lone dark pixels on lit surfaces.
    (Their cause was the normal's turn towards the eye: a grazing normal tipped past
    perpendicular was mirrored, which lit the pixel from behind; it is now bent onto the
    silhouette, in the preview as in the core.)"""
    width, height = 640, 480
    s = obj.dqjulia
    with native.Context() as context:
        props.from_document(s, context.params())
    eye, target, up, fov = (1.5, 1.2, 2.5), (0.0, 0.0, 0.0), (0.0, 1.0, 0.0), 40.0
    view = look_at(eye, target, up) @ obj.matrix_world.inverted()
    projection = perspective(fov, width / height, 0.05, 100.0)
    _drew, rgba, mask = offscreen_preview(obj, view, projection, width, height)
    covered = sum(mask)
    speckles = isolated_dark_pixels(rgba, mask, width, height)
    RESULTS["speckles"] = len(speckles)
    image = bpy.data.images.new("speckles", width, height, alpha=False)
    image.pixels.foreach_set(rgba)
    image.filepath_raw = os.path.join(ARGS.work, "speckles.png")
    image.file_format = "PNG"
    image.save()
    bpy.data.images.remove(image)
    # Measured here: 31 before the fix, 0 after (llvmpipe); the limit leaves a driver one in 40,000.
    check(
        covered > 0.1 * width * height and len(speckles) <= covered // 40000,
        "the default preview at %dx%d: %d lone dark pixels among %d covered (at most %d)%s"
        % (width, height, len(speckles), covered, covered // 40000, (": %s" % speckles[:8]) if speckles else ""),
    )

"""The viewport preview: the set ray-marched by a GLSL shader inside each DQ Julia object's
bounds, drawn from a SpaceView3D draw handler, updating live as parameters change.

The shader is shaders/dqjulia_de.glsl (the DE and sphere tracer) and shaders/dqjulia_shading.glsl
(the core's colouring and Phong terms, coloring.hpp), the code the test suite compiles as C++
and compares with the core, followed by shaders/preview_frag.glsl; its interface is
shaders/preview.interface. What the shader cannot compute cheaply comes from the
core, once per change of parameters (core_state.py's `state_for`): validation of the document,
the bounds, whether the slice is provably empty (and why), r_K and the slice's 8-D axes.
Marching costs one ray per pixel of the cube around the bounds; the result is kept per viewport
in textures (colour and depth) and put back by a blit shader (shaders/blit_*) until the view or
a previewed object changes, so Blender's many other redraws of the viewport stay cheap.
"""

import ctypes
import math
import os

import bpy

from . import core_state, native

SHADER_DIR = os.path.join(os.path.dirname(os.path.abspath(__file__)), "shaders")

_shader = None
_shader_error = None
_handler = None
draw_count = 0  # previews drawn by the draw handler (tests read it)


def shader_sources(program="preview"):
    """(interface declarations, vertex source, fragment source) of shaders/<program>.*,
    assembled as glsl_standalone.cmake assembles them for glslangValidator."""

    def read(name):
        with open(os.path.join(SHADER_DIR, name)) as file:
            return file.read()

    interface = []
    fragment_prefix = ""
    for line in read(program + ".interface").splitlines():
        line = line.strip()
        if not line or line.startswith("#"):
            continue
        parts = tuple(line.split())
        if parts[0] == "typedef":
            parts = ("typedef", read(parts[1]), "")
        elif parts[0] == "prepend_fragment":
            fragment_prefix += read(parts[1]) + "\n"
            continue
        interface.append(parts)
    return interface, read(program + "_vert.glsl"), fragment_prefix + read(program + "_frag.glsl")


def _create_shader(program, depth_write):
    import gpu

    interface, vertex, fragment = shader_sources(program)
    info = gpu.types.GPUShaderCreateInfo()
    stage = gpu.types.GPUStageInterfaceInfo("dqj_%s_iface" % program)
    location = 0
    slot = 0
    for kind, type_name, name in interface:
        if kind == "typedef":
            info.typedef_source(type_name)
        elif kind == "uniform_buf":
            info.uniform_buf(0, type_name, name)
        elif kind == "sampler":
            info.sampler(slot, type_name, name)
            slot += 1
        elif kind == "vertex_in":
            info.vertex_in(location, type_name, name)
            location += 1
        elif kind == "push":
            info.push_constant(type_name, name)
        elif kind == "smooth":
            stage.smooth(type_name, name)
        elif kind == "fragment_out":
            info.fragment_out(0, type_name, name)
    info.vertex_out(stage)
    if depth_write and hasattr(info, "depth_write"):  # Blender 4.x: the shader writes gl_FragDepth
        info.depth_write("ANY")
    info.vertex_source(vertex)
    info.fragment_source(fragment)
    return gpu.shader.create_from_info(info)


_blit_shader = None


def shader():
    """The compiled preview shader (created once); raises RuntimeError if it cannot be."""
    global _shader, _shader_error
    if _shader is not None:
        return _shader
    if _shader_error is not None:
        raise RuntimeError(_shader_error)
    try:
        _shader = _create_shader("preview", True)
    except Exception as error:  # a driver that rejects the shader: say so once, stop trying
        _shader_error = "the preview shader could not be compiled: %s" % error
        raise RuntimeError(_shader_error)
    return _shader


def blit_shader():
    global _blit_shader, _shader_error
    if _blit_shader is None:
        try:
            _blit_shader = _create_shader("blit", True)
        except Exception as error:
            _shader_error = "the preview's blit shader could not be compiled: %s" % error
            raise RuntimeError(_shader_error)
    return _blit_shader


def shader_error():
    return _shader_error


# -------------------------------------------------------------------------------------------
# Drawing


class PreviewParams(ctypes.Structure):
    """shaders/preview_params.glsl in std140: 16-byte members, matrices column by column."""

    _fields_ = [
        ("slice_a", ctypes.c_float * 16),
        ("slice_b", ctypes.c_float * 16),
        ("palette", ctypes.c_float * 16),
        ("lights", ctypes.c_float * 16),
        ("ca", ctypes.c_float * 4),
        ("cb", ctypes.c_float * 4),
        ("bounds", ctypes.c_float * 4),
        ("marching", ctypes.c_float * 4),
        ("color", ctypes.c_float * 4),
        ("phong", ctypes.c_float * 4),
        ("ints", ctypes.c_int32 * 4),
        ("floats", ctypes.c_float * 4),
    ]


def _columns(columns):
    """4 columns of 4 numbers -> 16 floats, column-major."""
    flat = []
    for column in columns:
        flat += [float(x) for x in column]
    return (ctypes.c_float * 16)(*flat)


_CUBE_TRIANGLES = (
    # outward-facing, counter-clockwise seen from outside
    (0, 2, 1),
    (0, 3, 2),
    (4, 5, 6),
    (4, 6, 7),
    (0, 1, 5),
    (0, 5, 4),
    (2, 3, 7),
    (2, 7, 6),
    (1, 2, 6),
    (1, 6, 5),
    (0, 4, 7),
    (0, 7, 3),
)


def _cube(center, radius):
    r = radius * 1.0001
    cx, cy, cz = center
    return [
        (cx - r, cy - r, cz - r),
        (cx + r, cy - r, cz - r),
        (cx + r, cy + r, cz - r),
        (cx - r, cy + r, cz - r),
        (cx - r, cy - r, cz + r),
        (cx + r, cy - r, cz + r),
        (cx + r, cy + r, cz + r),
        (cx - r, cy + r, cz + r),
    ]


def uniforms(obj, state, view_matrix, projection_matrix, viewport_height):
    """(push constants {name: value}, PreviewParams, mirrored) for drawing `obj` with this view."""
    from mathutils import Vector

    s = obj.dqjulia
    document = state.document
    model_view = view_matrix @ obj.matrix_world
    mvp = projection_matrix @ model_view
    inverse = model_view.inverted_safe()
    perspective = abs(projection_matrix[3][3]) < 1e-9
    pixel = 2.0 / (abs(projection_matrix[1][1]) * max(1, viewport_height))
    if perspective:
        eye = inverse @ Vector((0.0, 0.0, 0.0))
        eye4 = (eye.x, eye.y, eye.z, 1.0)
        footprint = (pixel, 0.0)
    else:
        direction = inverse.to_3x3() @ Vector((0.0, 0.0, -1.0))
        scale = max(1e-12, direction.length)
        direction = direction / scale
        eye4 = (direction.x, direction.y, direction.z, 0.0)
        footprint = (0.0, pixel * scale)  # the pixel's size in object units

    fractal = document["fractal"]
    render = document["render"]
    material = document["material"]
    params = PreviewParams()
    origin, axes = state.origin, state.axes
    params.slice_a = _columns([origin[0:4]] + [axis[0:4] for axis in axes])
    params.slice_b = _columns([origin[4:8]] + [axis[4:8] for axis in axes])
    palette = [list(colour) + [1.0] for colour in material["palette"]][:4] or [[1.0, 1.0, 1.0, 1.0]]
    palette_size = len(palette)
    palette += [palette[-1]] * (4 - len(palette))
    params.palette = _columns(palette)
    lights = []
    for light in document["lights"][:2]:
        direction = Vector(light["direction"])
        if direction.length == 0.0:
            continue
        direction.normalize()
        lights += [tuple(direction) + (0.0,), tuple(x * light["intensity"] for x in light["color"]) + (0.0,)]
    while len(lights) < 4:
        lights += [(0.0, 0.0, 1.0, 0.0), (0.0, 0.0, 0.0, 0.0)]
    params.lights = _columns(lights)
    c = fractal["c"]
    params.ca = (ctypes.c_float * 4)(*c[:4])
    params.cb = (ctypes.c_float * 4)(*c[4:])
    center, radius, clipped = state.bounds
    params.bounds = (ctypes.c_float * 4)(center[0], center[1], center[2], radius)
    max_steps = min(int(render["max_steps"]), int(s.preview_max_steps))
    params.marching = (ctypes.c_float * 4)(
        float(render["step_factor"]),
        float(render["max_step"]),
        float(max_steps),
        float(render["detail"]) * float(s.preview_detail),
    )
    params.color = (ctypes.c_float * 4)(*(list(material["color"]) + [1.0]))
    params.phong = (ctypes.c_float * 4)(
        material["ambient"], material["diffuse"], material["specular"], material["shininess"]
    )
    params.ints = (ctypes.c_int32 * 4)(
        native.VARIANTS.index(fractal["variant"]),
        int(fractal["iterations"]),
        ["solid", "iterations", "trap"].index(material["coloring"]),
        palette_size,
    )
    params.floats = (ctypes.c_float * 4)(
        float(fractal["bailout"]), float(state.stretch), state.containment_radius, 1.0 if clipped else 0.0
    )
    push = {"dqj_mvp": mvp, "dqj_eye": eye4, "dqj_footprint": footprint}
    return push, params, model_view.determinant() < 0.0


def draw_object(obj, view_matrix, projection_matrix, viewport_height):
    """Draws one object's preview with the given view into the bound framebuffer.
    Returns False (and draws nothing) if the object's parameters are not drawable."""
    import gpu
    from gpu_extras.batch import batch_for_shader

    state = core_state.state_for(obj)
    if not state.drawable:
        return False
    program = shader()
    push, params, mirrored = uniforms(obj, state, view_matrix, projection_matrix, viewport_height)
    buffer = gpu.types.GPUUniformBuf(gpu.types.Buffer("UBYTE", ctypes.sizeof(params), params))
    program.bind()
    for name, value in push.items():
        program.uniform_float(name, value)
    program.uniform_block("dqj", buffer)
    center, radius, _clipped = state.bounds
    batch = batch_for_shader(program, "TRIS", {"pos": _cube(center, radius)}, indices=_CUBE_TRIANGLES)
    gpu.state.depth_test_set("LESS_EQUAL")
    gpu.state.depth_mask_set(True)
    gpu.state.blend_set("NONE")
    gpu.state.face_culling_set("BACK" if mirrored else "FRONT")  # march from the far faces
    batch.draw(program)
    gpu.state.face_culling_set("NONE")
    gpu.state.depth_mask_set(False)
    gpu.state.depth_test_set("NONE")
    return True


def _bounds_outline(center, radius, segments=64):
    lines = []
    for axis in range(3):
        previous = None
        for index in range(segments + 1):
            angle = 2.0 * math.pi * index / segments
            u, v = radius * math.cos(angle), radius * math.sin(angle)
            point = [0.0, 0.0, 0.0]
            point[(axis + 1) % 3] = u
            point[(axis + 2) % 3] = v
            point = (center[0] + point[0], center[1] + point[1], center[2] + point[2])
            if previous is not None:
                lines += [previous, point]
            previous = point
    return lines


def _uniform_color_shader():
    import gpu

    for name in ("UNIFORM_COLOR", "3D_UNIFORM_COLOR"):
        try:
            return gpu.shader.from_builtin(name)
        except (ValueError, TypeError):
            continue
    return None


def draw_outline(obj, colour):
    """The bounding sphere as three circles, in the object's frame (uses gpu.matrix)."""
    import gpu
    from gpu_extras.batch import batch_for_shader

    state = core_state.state_for(obj)
    if state.bounds is None:
        return
    program = _uniform_color_shader()
    if program is None:
        return
    center, radius, _clipped = state.bounds
    batch = batch_for_shader(program, "LINES", {"pos": _bounds_outline(center, radius)})
    with gpu.matrix.push_pop():
        gpu.matrix.multiply_matrix(obj.matrix_world)
        program.bind()
        program.uniform_float("color", colour)
        gpu.state.depth_test_set("LESS_EQUAL")
        gpu.state.blend_set("ALPHA")
        batch.draw(program)
        gpu.state.blend_set("NONE")
        gpu.state.depth_test_set("NONE")


def preview_objects(context):
    view_layer = context.view_layer
    for obj in context.scene.objects:
        settings = getattr(obj, "dqjulia", None)
        if settings is None or not settings.enabled:
            continue
        try:
            visible = obj.visible_get(view_layer=view_layer)
        except (TypeError, RuntimeError):
            visible = not obj.hide_get()
        if visible:
            yield obj


class _ViewCache:
    """The preview of one viewport region, kept in textures (colour and depth) until the view,
    the viewport's size or a previewed object changes. Blender redraws a viewport far more
    often than that (Workbench accumulates its anti-aliasing over several redraws, overlays
    change); those redraws then only blit the textures."""

    def __init__(self):
        self.key = None
        self.size = None
        self.color = None
        self.depth = None
        self.framebuffer = None

    def ensure(self, width, height):
        import gpu

        if self.size != (width, height):
            self.color = gpu.types.GPUTexture((width, height), format="RGBA16F")
            self.depth = gpu.types.GPUTexture((width, height), format="DEPTH_COMPONENT32F")
            self.framebuffer = gpu.types.GPUFrameBuffer(depth_slot=self.depth, color_slots=self.color)
            self.size = (width, height)
            self.key = None


_view_caches = {}  # region pointer -> _ViewCache
render_count = 0  # previews ray-marched into a cache (tests read it)


def _matrix_key(matrix):
    return tuple(round(x, 7) for row in matrix for x in row)


def draw_cached(region_key, objects, view, projection, width, height):
    """Draws the objects' previews through the region's cache; returns True if it marched."""
    global render_count
    import gpu
    from gpu_extras.batch import batch_for_shader

    scale = max(1, max(obj.dqjulia.preview_resolution for obj in objects))
    cache_width, cache_height = max(1, width // scale), max(1, height // scale)
    # What the pixels depend on: the size and, per object, the exact shader inputs (so a change
    # the preview does not show, such as the bake resolution, keeps the cache).
    key = [cache_width, cache_height]
    for obj in objects:
        push, params, mirrored = uniforms(obj, core_state.state_for(obj), view, projection, cache_height)
        key += [bytes(params), mirrored] + [
            _matrix_key(value) if hasattr(value, "row") else tuple(value) for value in push.values()
        ]
    key = tuple(key)
    cache = _view_caches.get(region_key)
    if cache is None:
        cache = _view_caches[region_key] = _ViewCache()
    cache.ensure(cache_width, cache_height)
    marched = False
    if cache.key != key:
        viewport = gpu.state.viewport_get()
        with cache.framebuffer.bind():
            gpu.state.viewport_set(0, 0, cache_width, cache_height)
            cache.framebuffer.clear(color=(0.0, 0.0, 0.0, 0.0), depth=1.0)
            for obj in objects:
                draw_object(obj, view, projection, cache_height)
        gpu.state.viewport_set(*viewport)
        cache.key = key
        render_count += 1
        marched = True
    program = blit_shader()
    quad = batch_for_shader(program, "TRI_FAN", {"pos": ((-1, -1), (1, -1), (1, 1), (-1, 1))})
    program.bind()
    program.uniform_sampler("dqj_image", cache.color)
    program.uniform_sampler("dqj_depth", cache.depth)
    gpu.state.depth_test_set("LESS_EQUAL")
    gpu.state.depth_mask_set(True)
    gpu.state.blend_set("NONE")
    quad.draw(program)
    gpu.state.depth_mask_set(False)
    gpu.state.depth_test_set("NONE")
    return marched


def _draw_handler():
    global draw_count
    import gpu

    context = bpy.context
    if native.load_error() is not None or _shader_error is not None:
        return
    view = gpu.matrix.get_model_view_matrix()
    projection = gpu.matrix.get_projection_matrix()
    _x, _y, width, height = gpu.state.viewport_get()
    objects = list(preview_objects(context))
    try:
        shown = [obj for obj in objects if obj.dqjulia.show_preview and core_state.state_for(obj).drawable]
        if shown:
            region = context.region
            draw_cached(region.as_pointer() if region else 0, shown, view, projection, width, height)
            draw_count += 1
        for obj in objects:
            if obj.dqjulia.show_bounds:
                selected = obj.select_get()
                draw_outline(obj, (1.0, 0.6, 0.2, 0.8) if selected else (0.6, 0.6, 0.6, 0.35))
    except RuntimeError:
        return  # a shader could not be made; the panel says why


@bpy.app.handlers.persistent
def _forget_views(*_args):
    """A file was loaded: its viewports are new, drop the old ones' cached pictures."""
    _view_caches.clear()


def register():
    global _handler
    if _handler is None:
        _handler = bpy.types.SpaceView3D.draw_handler_add(_draw_handler, (), "WINDOW", "POST_VIEW")
    if _forget_views not in bpy.app.handlers.load_post:
        bpy.app.handlers.load_post.append(_forget_views)


def unregister():
    global _handler, _shader, _blit_shader, _shader_error
    if _forget_views in bpy.app.handlers.load_post:
        bpy.app.handlers.load_post.remove(_forget_views)
    if _handler is not None:
        bpy.types.SpaceView3D.draw_handler_remove(_handler, "WINDOW")
        _handler = None
    _shader = None
    _blit_shader = None
    _shader_error = None
    _view_caches.clear()

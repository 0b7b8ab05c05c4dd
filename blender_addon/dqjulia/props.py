"""The parameters on the object: a PropertyGroup (Object.dqjulia) holding everything the
parameter file holds, and the two-way mapping between it and the file's JSON document.

Every value is an ordinary Blender property, so it can be keyframed, driven and edited in
the UI. The file's format belongs to the core: documents are always validated by the library
(native.Context.set_params) and read back complete from it (Context.params), so this module
only maps names. Sections of a file this version does not model are kept verbatim in
`extra_json` and written back on export.
"""

import json
import struct

import bpy
from bpy.props import (BoolProperty, CollectionProperty, EnumProperty, FloatProperty, FloatVectorProperty,
                       IntProperty, PointerProperty, StringProperty)

from .slicing import AXIS_NAMES

FORMAT_VERSION = 1
# Top-level keys mapped to properties; anything else is kept verbatim (extra_json).
MODELED_SECTIONS = ("version", "description", "fractal", "slice", "bounds", "camera", "lights", "material",
                    "render", "output", "bake", "animation")

VARIANT_ITEMS = [
    ("paper", "Paper", "The paper's rule a^2 + b^2 eps: real and dual parts iterate independently; "
                       "escape when |a| > R or |b| > R"),
    ("paper-coupled", "Paper, coupled", "The paper's rule with one 8-D norm for escape and distance estimate"),
    ("dual", "Dual", "The true dual-quaternion algebra a^2 + (ab + ba) eps; escape on |a|"),
]
AXIS_ITEMS = [(name, name, "%s part, %s component" % ("real" if name[0] == "a" else "dual", name[2]))
              for name in AXIS_NAMES]
AXES_MODE_ITEMS = [
    ("NAMES", "Axis names", "Each of x, y, z runs along one 8-D coordinate axis"),
    ("VECTORS", "Vectors", "Each of x, y, z runs along an 8-D vector"),
]
COLORING_ITEMS = [
    ("solid", "Solid", "The material colour"),
    ("iterations", "Iterations", "The smooth escape count through the palette"),
    ("trap", "Orbit trap", "The orbit's closest approach to 0 through the palette"),
]
NORMALS_ITEMS = [
    ("auto", "Auto", "Analytic for the dual variant, central differences otherwise"),
    ("central", "Central differences", "Differences of the distance estimate"),
    ("analytic", "Analytic", "Exact, from the dual part (dual variant only)"),
]
FORMAT_ITEMS = [
    ("AUTO", "From extension", "From the output path's extension"),
    ("png8", "PNG 8-bit", ""),
    ("png16", "PNG 16-bit", ""),
    ("exr", "OpenEXR", "Premultiplied linear RGBA, depth and normals"),
]
GRID_ITEMS = [
    ("surface", "Surface", "Narrow-band level set of the surface"),
    ("density", "Density", "Fog volume: 1 inside, 0 outside (what Blender renders)"),
    ("color", "Color", "Linear RGB from the material's colouring"),
    ("trap", "Trap", "The orbit trap value"),
    ("iterations", "Iterations", "The smooth escape count"),
]


def _redraw(_self, context):
    """Property update: redraw the 3-D views so the preview follows."""
    screen = getattr(context, "screen", None)
    if screen is None:
        return
    for area in screen.areas:
        if area.type in {"VIEW_3D", "PROPERTIES"}:
            area.tag_redraw()


def _vector(name, size, default, description, soft=2.0, hard=100.0, subtype="NONE", update=_redraw):
    return FloatVectorProperty(name=name, size=size, default=default, description=description, soft_min=-soft,
                               soft_max=soft, min=-hard, max=hard, precision=5, step=1, subtype=subtype,
                               update=update)


def _color(name, default, description=""):
    return FloatVectorProperty(name=name, size=3, default=default, min=0.0, soft_max=1.0, max=1000.0,
                               subtype="COLOR", description=description, update=_redraw)


class DQJRotation(bpy.types.PropertyGroup):
    """A rotation of the slice's axes in a plane of the 8-D space (slice.rotations[])."""
    first: EnumProperty(name="From", items=AXIS_ITEMS, default="a.j", update=_redraw,
                        description="The rotation turns this axis towards the other")
    second: EnumProperty(name="To", items=AXIS_ITEMS, default="b.s", update=_redraw)
    degrees: FloatProperty(name="Degrees", default=0.0, min=-36000.0, max=36000.0, soft_min=-180.0, soft_max=180.0,
                           update=_redraw, description="Angle of the rotation (animatable)")


class DQJLight(bpy.types.PropertyGroup):
    """A directional light of the core's renderer and the preview (lights[])."""
    direction: _vector("Direction", 3, (0.6, 0.8, 0.7), "Towards the light, in the object's coordinates",
                       hard=1e9)
    color: _color("Color", (1.0, 1.0, 1.0), "Linear RGB")
    intensity: FloatProperty(name="Intensity", default=1.0, min=0.0, max=1000.0, soft_max=4.0, update=_redraw)


class DQJColor(bpy.types.PropertyGroup):
    color: _color("Color", (1.0, 1.0, 1.0))


class DQJuliaSettings(bpy.types.PropertyGroup):
    """Everything the parameter file holds (README "Parameter file"), plus the preview's options."""
    enabled: BoolProperty(name="DQ Julia object", default=False,
                          description="This object shows a dual-quaternion Julia set inside its bounds")
    description: StringProperty(name="Description", description="Free text, kept in the parameter file")

    # fractal
    c_a: _vector("Constant a", 4, (-0.39054, -0.58679, 0.0, 0.0),
                 "Real part of the constant c, (s, i, j, k) scalar first")
    c_b: _vector("Constant b", 4, (0.0, 0.5632, 0.0, 0.05), "Dual part of the constant c, (s, i, j, k)")
    variant: EnumProperty(name="Variant", items=VARIANT_ITEMS, default="paper", update=_redraw)
    iterations: IntProperty(name="Iterations", default=15, min=1, max=100000, soft_max=200, update=_redraw,
                            description="N, the iteration count (the paper uses 6 to 15)")
    bailout: FloatProperty(name="Bailout", default=4.0, min=1.0, soft_max=20.0, precision=4, update=_redraw,
                           description="R, at least the containment radius r_K of the constant")

    # slice
    axes_mode: EnumProperty(name="Axes", items=AXES_MODE_ITEMS, default="NAMES", update=_redraw)
    axis_x: EnumProperty(name="x", items=AXIS_ITEMS, default="a.s", update=_redraw)
    axis_y: EnumProperty(name="y", items=AXIS_ITEMS, default="a.i", update=_redraw)
    axis_z: EnumProperty(name="z", items=AXIS_ITEMS, default="a.j", update=_redraw)
    axis_x_vector: _vector("x axis", 8, (1, 0, 0, 0, 0, 0, 0, 0), "Where x goes in 8-D", hard=1e9)
    axis_y_vector: _vector("y axis", 8, (0, 1, 0, 0, 0, 0, 0, 0), "Where y goes in 8-D", hard=1e9)
    axis_z_vector: _vector("z axis", 8, (0, 0, 1, 0, 0, 0, 0, 0), "Where z goes in 8-D", hard=1e9)
    origin: _vector("Origin", 8, (0.0,) * 8, "The 8-D point at x = y = z = 0 (a's s, i, j, k, then b's)", hard=1e9)
    rotations: CollectionProperty(type=DQJRotation, name="Rotations")
    active_rotation: IntProperty(name="Active rotation", default=0, min=0)

    # bounds
    bounds_auto: BoolProperty(name="Automatic bounds", default=True, update=_redraw,
                              description="The smallest sphere holding the slice's share of the containment region")
    bounds_center: _vector("Center", 3, (0.0, 0.0, 0.0), "Centre of the bounding sphere", hard=1e9)
    bounds_radius: FloatProperty(name="Radius", default=2.0, min=1e-6, max=1e6, soft_max=10.0, update=_redraw)

    # camera (for renders by the core; the preview uses Blender's view)
    camera_use_position: BoolProperty(name="Camera position", default=False)
    camera_position: _vector("Position", 3, (0.0, 0.0, 5.0), "", hard=1e9, update=None)
    camera_use_target: BoolProperty(name="Camera target", default=False)
    camera_target: _vector("Target", 3, (0.0, 0.0, 0.0), "", hard=1e9, update=None)
    camera_direction: _vector("Direction", 3, (0.55, 0.45, 1.0), "From the target towards the camera", hard=1e9,
                              update=None)
    camera_up: _vector("Up", 3, (0.0, 1.0, 0.0), "", hard=1e9, update=None)
    camera_fov: FloatProperty(name="Field of view", default=40.0, min=0.001, max=169.999)

    lights: CollectionProperty(type=DQJLight, name="Lights")

    # material
    color: _color("Color", (0.85, 0.62, 0.35), "Base colour for solid colouring (linear RGB)")
    coloring: EnumProperty(name="Coloring", items=COLORING_ITEMS, default="trap", update=_redraw)
    palette: CollectionProperty(type=DQJColor, name="Palette")
    ambient: FloatProperty(name="Ambient", default=0.15, min=0.0, max=100.0, soft_max=1.0, update=_redraw)
    diffuse: FloatProperty(name="Diffuse", default=0.8, min=0.0, max=100.0, soft_max=1.0, update=_redraw)
    specular: FloatProperty(name="Specular", default=0.35, min=0.0, max=100.0, soft_max=1.0, update=_redraw)
    shininess: FloatProperty(name="Shininess", default=24.0, min=0.0, max=10000.0, soft_max=200.0, update=_redraw)
    occlusion: FloatProperty(name="Occlusion", default=0.8, min=0.0, max=1.0)
    shadows: BoolProperty(name="Shadows", default=True)
    shadow_softness: FloatProperty(name="Shadow softness", default=12.0, min=0.001, max=1000.0)

    # render (the core's renderer; step settings also drive the preview)
    width: IntProperty(name="Width", default=640, min=1, max=16384)
    height: IntProperty(name="Height", default=480, min=1, max=16384)
    samples: IntProperty(name="Samples", default=2, min=1, max=16)
    step_factor: FloatProperty(name="Step factor", default=0.9, min=0.001, max=1.0, update=_redraw)
    max_step: FloatProperty(name="Max step", default=0.25, min=1e-6, max=1e6, soft_max=1.0, update=_redraw)
    max_steps: IntProperty(name="Max steps", default=400, min=1, max=1000000, soft_max=2000, update=_redraw)
    detail: FloatProperty(name="Detail", default=1.0, min=0.001, max=1000.0, soft_max=8.0, update=_redraw,
                          description="Hit threshold in pixel footprints (smaller = finer)")
    normals: EnumProperty(name="Normals", items=NORMALS_ITEMS, default="auto")
    background_top: _color("Background top", (0.3, 0.36, 0.45))
    background_bottom: _color("Background bottom", (0.06, 0.06, 0.08))

    # output
    output_path: StringProperty(name="Output", default="out/dqjulia.png", subtype="FILE_PATH")
    output_format: EnumProperty(name="Format", items=FORMAT_ITEMS, default="AUTO")

    # bake
    bake_resolution: IntProperty(name="Resolution", default=128, min=8, max=16384, soft_max=1024,
                                 description="Voxels across the largest side of the bake bounds")
    bake_bounds_auto: BoolProperty(name="Automatic bake bounds", default=True,
                                   description="The cube around the bounding sphere, clipped to the sphere")
    bake_bounds_min: _vector("Min", 3, (-1.0, -1.0, -1.0), "", hard=1e6, update=None)
    bake_bounds_max: _vector("Max", 3, (1.0, 1.0, 1.0), "", hard=1e6, update=None)
    bake_band_width: FloatProperty(name="Band width", default=3.0, min=1.0, max=32.0,
                                   description="Half width of the level set's narrow band, in voxels")
    bake_grids: EnumProperty(name="Grids", items=GRID_ITEMS, options={"ENUM_FLAG"}, default={"surface", "density"})
    bake_adaptivity: FloatProperty(name="Adaptivity", default=0.0, min=0.0, max=1.0,
                                   description="Mesh adaptivity: 0 = uniform triangles, more = fewer triangles")
    bake_mesh_colors: BoolProperty(name="Vertex colours", default=True)

    # the preview (not in the file)
    show_preview: BoolProperty(name="Preview", default=True, update=_redraw,
                               description="Ray-march the set in the viewport (GLSL)")
    show_bounds: BoolProperty(name="Bounds", default=True, update=_redraw,
                              description="Draw the bounding sphere as three circles")
    preview_resolution: IntProperty(name="Preview pixel size", default=1, min=1, max=8, update=_redraw,
                                    description="March one ray per N x N viewport pixels (faster on slow GPUs)")
    preview_max_steps: IntProperty(name="Preview steps", default=160, min=8, max=100000, soft_max=1000,
                                   update=_redraw, description="Most steps a preview ray takes (cost)")
    preview_detail: FloatProperty(name="Preview detail", default=1.0, min=0.01, max=100.0, soft_max=8.0,
                                  update=_redraw, description="Hit threshold in pixels for the preview")

    # sections of an imported file this version does not model, written back on export
    extra_json: StringProperty(name="Other sections", default="{}", options={"HIDDEN"})


CLASSES = (DQJRotation, DQJLight, DQJColor, DQJuliaSettings)


# -------------------------------------------------------------------------------------------
# JSON <-> properties


def _number(value):
    """The shortest decimal that gives back the same 32-bit float (what Blender stores)."""
    value = float(value)
    single = struct.unpack("f", struct.pack("f", value))[0]
    for digits in range(6, 10):
        text = "%.*g" % (digits, single)
        if struct.unpack("f", struct.pack("f", float(text)))[0] == single:
            return float(text)
    return single


def _numbers(values):
    return [_number(x) for x in values]


def _value(settings, path, values):
    """A property's value, from `values` (per-frame overrides) when given there."""
    if values is not None and path in values:
        return values[path]
    return getattr(settings, path)


def to_document(settings, values=None, with_animation=None):
    """The parameter document of these properties (a dict, not yet validated by the core).

    values: optional {property name: value} overrides (used to take a frame's values).
    with_animation: an "animation" dict to include (see animation.py), or None for none.
    """
    s = settings
    c = list(_value(s, "c_a", values)) + list(_value(s, "c_b", values))
    document = {"version": FORMAT_VERSION}
    if s.description:
        document["description"] = s.description
    document["fractal"] = {
        "c": _numbers(c),
        "variant": s.variant,
        "iterations": int(_value(s, "iterations", values)),
        "bailout": _number(_value(s, "bailout", values)),
    }
    if s.axes_mode == "NAMES":
        axes = ",".join((s.axis_x, s.axis_y, s.axis_z))
    else:
        axes = [_numbers(s.axis_x_vector), _numbers(s.axis_y_vector), _numbers(s.axis_z_vector)]
    rotations = []
    for index, rotation in enumerate(s.rotations):
        degrees = _value(s, "rotations[%d].degrees" % index, values) if values else rotation.degrees
        rotations.append({"plane": "%s,%s" % (rotation.first, rotation.second), "degrees": _number(degrees)})
    document["slice"] = {"axes": axes, "origin": _numbers(_value(s, "origin", values)), "rotations": rotations}
    if s.bounds_auto:
        document["bounds"] = "auto"
    else:
        document["bounds"] = {"center": _numbers(s.bounds_center), "radius": _number(s.bounds_radius)}
    camera = {}
    if s.camera_use_position:
        camera["position"] = _numbers(s.camera_position)
    if s.camera_use_target:
        camera["target"] = _numbers(s.camera_target)
    camera.update({"direction": _numbers(s.camera_direction), "up": _numbers(s.camera_up),
                   "fov": _number(s.camera_fov)})
    document["camera"] = camera
    document["lights"] = [{"direction": _numbers(light.direction), "color": _numbers(light.color),
                           "intensity": _number(light.intensity)} for light in s.lights]
    document["material"] = {
        "color": _numbers(s.color), "coloring": s.coloring,
        "palette": [_numbers(entry.color) for entry in s.palette] or [_numbers(s.color)],
        "ambient": _number(s.ambient), "diffuse": _number(s.diffuse), "specular": _number(s.specular),
        "shininess": _number(s.shininess), "occlusion": _number(s.occlusion), "shadows": bool(s.shadows),
        "shadow_softness": _number(s.shadow_softness),
    }
    document["render"] = {
        "width": s.width, "height": s.height, "samples": s.samples, "step_factor": _number(s.step_factor),
        "max_step": _number(s.max_step), "max_steps": s.max_steps, "detail": _number(s.detail),
        "normals": s.normals,
        "background": {"top": _numbers(s.background_top), "bottom": _numbers(s.background_bottom)},
    }
    output = {"path": s.output_path}
    if s.output_format != "AUTO":
        output["format"] = s.output_format
    document["output"] = output
    grids = [name for name, _label, _description in GRID_ITEMS if name in s.bake_grids]
    document["bake"] = {
        "resolution": s.bake_resolution,
        "bounds": "auto" if s.bake_bounds_auto else {"min": _numbers(s.bake_bounds_min),
                                                     "max": _numbers(s.bake_bounds_max)},
        "band_width": _number(s.bake_band_width),
        "grids": grids or ["surface", "density"],
        "adaptivity": _number(s.bake_adaptivity),
        "mesh_colors": bool(s.bake_mesh_colors),
    }
    if with_animation:
        document["animation"] = with_animation
    try:
        extra = json.loads(s.extra_json or "{}")
    except ValueError:
        extra = {}
    for key, value in extra.items():
        if key not in MODELED_SECTIONS:
            document[key] = value
    return document


def from_document(settings, document):
    """Sets the properties from a complete document (as the core returns it). The "animation"
    section is not applied here (animation.py turns it into keyframes)."""
    s = settings
    s.description = document.get("description", "")
    fractal = document["fractal"]
    s.c_a = fractal["c"][:4]
    s.c_b = fractal["c"][4:]
    s.variant = fractal["variant"]
    s.iterations = int(fractal["iterations"])
    s.bailout = fractal["bailout"]

    slice_doc = document["slice"]
    axes = slice_doc["axes"]
    if isinstance(axes, str):
        s.axes_mode = "NAMES"
        s.axis_x, s.axis_y, s.axis_z = [name.strip() for name in axes.split(",")]
        vectors = []
        for name in (s.axis_x, s.axis_y, s.axis_z):
            vector = [0.0] * 8
            vector[AXIS_NAMES.index(name)] = 1.0
            vectors.append(vector)
    else:
        s.axes_mode = "VECTORS"
        vectors = axes
    s.axis_x_vector, s.axis_y_vector, s.axis_z_vector = vectors
    s.origin = slice_doc["origin"]
    s.rotations.clear()
    for rotation in slice_doc["rotations"]:
        item = s.rotations.add()
        item.first, item.second = [name.strip() for name in rotation["plane"].split(",")]
        item.degrees = rotation["degrees"]
    s.active_rotation = max(0, min(s.active_rotation, len(s.rotations) - 1))

    bounds = document["bounds"]
    s.bounds_auto = bounds == "auto"
    if not s.bounds_auto:
        s.bounds_center = bounds["center"]
        s.bounds_radius = bounds["radius"]

    camera = document["camera"]
    s.camera_use_position = "position" in camera
    if s.camera_use_position:
        s.camera_position = camera["position"]
    s.camera_use_target = "target" in camera
    if s.camera_use_target:
        s.camera_target = camera["target"]
    s.camera_direction = camera["direction"]
    s.camera_up = camera["up"]
    s.camera_fov = camera["fov"]

    s.lights.clear()
    for light in document["lights"]:
        item = s.lights.add()
        item.direction = light["direction"]
        item.color = light["color"]
        item.intensity = light["intensity"]

    material = document["material"]
    s.color = material["color"]
    s.coloring = material["coloring"]
    s.palette.clear()
    for colour in material["palette"]:
        s.palette.add().color = colour
    for key in ("ambient", "diffuse", "specular", "shininess", "occlusion", "shadows"):
        setattr(s, key, material[key])
    s.shadow_softness = material["shadow_softness"]

    render = document["render"]
    for key in ("width", "height", "samples", "step_factor", "max_step", "max_steps", "detail", "normals"):
        setattr(s, key, render[key])
    background = render["background"]
    if isinstance(background, dict):
        s.background_top = background["top"]
        s.background_bottom = background["bottom"]
    else:
        s.background_top = s.background_bottom = background

    output = document["output"]
    s.output_path = output["path"]
    s.output_format = output.get("format", "AUTO")

    bake = document.get("bake")
    if bake:
        s.bake_resolution = bake["resolution"]
        s.bake_bounds_auto = bake["bounds"] == "auto"
        if not s.bake_bounds_auto:
            s.bake_bounds_min = bake["bounds"]["min"]
            s.bake_bounds_max = bake["bounds"]["max"]
        s.bake_band_width = bake["band_width"]
        s.bake_grids = set(bake["grids"])
        s.bake_adaptivity = bake["adaptivity"]
        s.bake_mesh_colors = bake["mesh_colors"]

    s.extra_json = json.dumps({key: value for key, value in document.items() if key not in MODELED_SECTIONS})


def register():
    for cls in CLASSES:
        bpy.utils.register_class(cls)
    bpy.types.Object.dqjulia = PointerProperty(type=DQJuliaSettings, name="DQ Julia")


def unregister():
    del bpy.types.Object.dqjulia
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)

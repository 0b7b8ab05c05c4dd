"""The parameters on the object: a PropertyGroup (Object.dqjulia) holding everything the
parameter file holds, and the two-way mapping between it and the file's JSON document.

The properties are built from the core's parameter schema (schema.json in the add-on, written
by `dqjulia schema` when the add-on is packaged: every key's type, label, help, default and
range, once, in the core). Each key becomes one property, named by one rule (prop_name); this
module only adds what the file has no key for (the slice axes' two forms, the preview's own
settings) and the few shapes that need two controls (c as a and b, "auto" objects, optional
values). Every value is an ordinary Blender property, so it can be keyframed, driven and edited
in the UI. Documents are always validated by the library (native.Context.set_params) and read
back complete from it (Context.params). Sections of a file this version does not model are
kept verbatim in `extra_json` and written back on export.
"""

import json
import os
import struct

import bpy
from bpy.props import (
    BoolProperty,
    CollectionProperty,
    EnumProperty,
    FloatProperty,
    FloatVectorProperty,
    IntProperty,
    PointerProperty,
    StringProperty,
)

from .slicing import AXIS_NAMES

SCHEMA_PATH = os.path.join(os.path.dirname(__file__), "schema.json")
with open(SCHEMA_PATH, encoding="utf-8") as _file:
    SCHEMA = json.load(_file)
FIELDS = {field["key"]: field for field in SCHEMA["fields"]}
FORMAT_VERSION = SCHEMA["format_version"]
# Top-level keys mapped to properties; anything else is kept verbatim (extra_json).
MODELED_SECTIONS = ("version",) + tuple(key for key in FIELDS if "." not in key and "[" not in key)
# Sections whose keys are properties without the section's name ("fractal.iterations" -> iterations).
_BARE_SECTIONS = ("fractal", "slice", "material", "render")
_FLOAT_MAX = 3.0e38  # Blender stores single-precision floats


def prop_name(key):
    """The property of a schema key: "fractal.iterations" -> "iterations", "bake.band_width" ->
    "bake_band_width", "lights[].color" -> "color" (on the list's item)."""
    if "[]" in key:
        return key.rsplit("[]", 1)[1].lstrip(".") or "color"
    section, _, rest = key.partition(".")
    if section in _BARE_SECTIONS and rest:
        key = rest
    return key.replace(".", "_")


def use_name(key):
    """The toggle of an optional vector: "camera.position" -> "camera_use_position"."""
    section, _, leaf = key.rpartition(".")
    return "%s_use_%s" % (section.replace(".", "_"), leaf)


def choice_items(key):
    field = FIELDS[key]
    items = [(choice["name"], choice["label"], choice["help"]) for choice in field["choices"]]
    if field.get("optional"):
        items.insert(0, ("AUTO", "Automatic", field["help"]))
    return items


VARIANT_ITEMS = choice_items("fractal.variant")
COLORING_ITEMS = choice_items("material.coloring")
GRID_ITEMS = choice_items("bake.grids")
AXIS_ITEMS = [
    (name, name, "%s part, %s component" % ("real" if name[0] == "a" else "dual", name[2])) for name in AXIS_NAMES
]
# The groups a variation may change (native.GROUPS, `dqjulia explore --lock`'s names).
VARIATION_GROUP_ITEMS = [
    ("a", "a", "The constant's real part a"),
    ("b", "b", "The constant's dual part b"),
    ("orientation", "Orientation", "The slice's rotations"),
    ("origin", "Origin", "The slice's origin"),
    ("iterations", "Iterations", "N and the bailout R"),
    ("variant", "Variant", "The variant (changed only from strength large on)"),
]
AXES_MODE_ITEMS = [
    ("NAMES", "Axis names", "Each of x, y, z runs along one 8-D coordinate axis"),
    ("VECTORS", "Vectors", "Each of x, y, z runs along an 8-D vector"),
]


def _redraw(_self, context):
    """Property update: redraw the 3-D views so the preview follows."""
    screen = getattr(context, "screen", None)
    if screen is None:
        return
    for area in screen.areas:
        if area.type in {"VIEW_3D", "PROPERTIES"}:
            area.tag_redraw()


def _limits(field):
    """Blender's min, max, soft_min and soft_max for a field (exclusive limits nudged inside)."""
    low, high = field["min"], field["max"]
    nudge = 1e-3 if high - low <= 1000 else 1e-6
    if field.get("min_exclusive"):
        low += nudge
    if field.get("max_exclusive"):
        high -= nudge
    low, high = max(low, -_FLOAT_MAX), min(high, _FLOAT_MAX)
    return {"min": low, "max": high, "soft_min": max(low, field["soft_min"]), "soft_max": min(high, field["soft_max"])}


def _initial(field):
    """The value a property starts from: the default, or for optional keys and "auto" objects
    the value the core suggests when they are turned on."""
    value = field.get("default")
    if value is None or value == "auto":
        value = field.get("initial", value)
    return value


def make_property(key, **overrides):
    """The Blender property of a schema key (not for lists, objects or axes)."""
    field = FIELDS[key]
    kind = field["type"]
    options = {"name": field["label"], "description": field["help"]}
    if not field.get("image_only"):
        options["update"] = _redraw
    value = _initial(field)
    if kind == "boolean":
        return BoolProperty(default=bool(value), **options, **overrides)
    if kind == "integer":
        limits = {name: int(limit) for name, limit in _limits(field).items()}
        return IntProperty(default=int(value), **limits, **options, **overrides)
    if kind == "number":
        return FloatProperty(default=float(value), precision=4, **_limits(field), **options, **overrides)
    if kind == "string":
        subtype = "FILE_PATH" if key.endswith("path") else "NONE"
        return StringProperty(default=value or "", subtype=subtype, **options, **overrides)
    if kind == "choice":
        return EnumProperty(items=choice_items(key), default=field["default"] or "AUTO", **options, **overrides)
    if kind == "choice_set":
        return EnumProperty(items=choice_items(key), options={"ENUM_FLAG"}, default=set(value), **options, **overrides)
    if kind in ("vec3", "color", "vec8"):
        size = 8 if kind == "vec8" else 3
        subtype = "COLOR" if kind == "color" else "NONE"
        return FloatVectorProperty(
            size=size,
            default=tuple(value),
            subtype=subtype,
            precision=5,
            step=1,
            **_limits(field),
            **options,
            **overrides,
        )
    raise ValueError("no property for schema key %s (%s)" % (key, kind))


def _quaternion_halves(key):
    """fractal.c as two 4-vectors "<name>_a" (real part) and "<name>_b" (dual part)."""
    field = FIELDS[key]
    halves = {}
    for suffix, part, values in (("a", "real", field["default"][:4]), ("b", "dual", field["default"][4:])):
        halves["%s_%s" % (prop_name(key), suffix)] = FloatVectorProperty(
            name="%s %s" % (field["label"], suffix),
            size=4,
            default=tuple(values),
            precision=3,  # four to a row fit the sidebar's default width (the value keeps every digit)
            step=1,
            description="%s: %s part (s, i, j, k)" % (field["help"], part),
            update=_redraw,
            **_limits(field),
        )
    return halves


def _value_keys(prefix=""):
    """The schema's value keys directly under `prefix`, in file order (not lists' items)."""
    for key, field in FIELDS.items():
        if (
            key.startswith(prefix)
            and "[]" not in key[len(prefix) :]
            and (prefix or "[]" not in key)
            and field["type"] not in ("object", "list", "color_list", "animation")
        ):
            yield key, field


def _annotations(prefix):
    """The properties of every value key under `prefix` ("lights[]." for a light's)."""
    annotations = {}
    for key, field in _value_keys(prefix):
        kind = field["type"]
        if kind == "dual_quaternion":
            annotations.update(_quaternion_halves(key))
        elif kind in ("axes", "axis_pair"):
            continue  # two controls each, below
        else:
            annotations[prop_name(key)] = make_property(key)
            if field.get("optional") and kind != "choice":
                annotations[use_name(key)] = BoolProperty(
                    name=field["label"], default=False, description="Set: " + field["help"]
                )
    return annotations


def _auto_toggles():
    """For each "auto" object ("bounds"), the toggle "<name>_auto" (on = "auto")."""
    return {
        prop_name(key) + "_auto": BoolProperty(
            name="Automatic " + field["label"].lower(), default=True, update=_redraw, description=field["help"]
        )
        for key, field in FIELDS.items()
        if field.get("auto")
    }


def _group(name, doc, annotations):
    return type(name, (bpy.types.PropertyGroup,), {"__annotations__": annotations, "__doc__": doc})


_first, _second = FIELDS["slice.rotations[].plane"]["default"].split(",")
DQJRotation = _group(
    "DQJRotation",
    "A rotation of the slice's axes in a plane of the 8-D space (slice.rotations[]).",
    {
        "first": EnumProperty(
            name="From",
            items=AXIS_ITEMS,
            default=_first,
            update=_redraw,
            description=FIELDS["slice.rotations[].plane"]["help"],
        ),
        "second": EnumProperty(name="To", items=AXIS_ITEMS, default=_second, update=_redraw),
        **_annotations("slice.rotations[]."),
    },
)
DQJLight = _group(
    "DQJLight", "A directional light of the core's renderer and the preview (lights[]).", _annotations("lights[].")
)
DQJColor = _group("DQJColor", "A palette colour (material.palette[]).", {"color": make_property("material.palette[]")})

VOLUME_LOOK_ITEMS = [
    ("SURFACE", "Surface", "An opaque, shaded surface at the set's edge, as `dqjulia render` and the mesh show it"),
    ("CLOUD", "Cloud", "The fog as baked: a soft, translucent glow"),
]


# What re-makes an object's baked volumes in a new look: bakes.apply_volume_look, set by bakes.py
# when it registers (bakes imports core_state, which imports this module, so this module cannot
# import bakes).
volume_look_changed = None


def _volume_look_changed(settings, _context):
    if volume_look_changed is not None:
        volume_look_changed(settings.id_data)


_axes = FIELDS["slice.axes"]["default"].split(",")
_settings = {
    "enabled": BoolProperty(
        name="DQ Julia object",
        default=False,
        description="This object shows a dual-quaternion Julia set inside its bounds",
    ),
    **_annotations(""),
    **_auto_toggles(),
    # slice.axes: names or vectors
    "axes_mode": EnumProperty(name="Axes", items=AXES_MODE_ITEMS, default="NAMES", update=_redraw),
    "rotations": CollectionProperty(type=DQJRotation, name=FIELDS["slice.rotations"]["label"]),
    "active_rotation": IntProperty(name="Active rotation", default=0, min=0),
    "lights": CollectionProperty(type=DQJLight, name=FIELDS["lights"]["label"]),
    "palette": CollectionProperty(type=DQJColor, name=FIELDS["material.palette"]["label"]),
    # the preview (not in the file)
    "show_preview": BoolProperty(
        name="Preview", default=True, update=_redraw, description="Ray-march the set in the viewport (GLSL)"
    ),
    "show_bounds": BoolProperty(
        name="Bounds", default=True, update=_redraw, description="Draw the bounding sphere as three circles"
    ),
    "preview_resolution": IntProperty(
        name="Preview pixel size",
        default=1,
        min=1,
        max=8,
        update=_redraw,
        description="March one ray per N x N viewport pixels (faster on slow GPUs)",
    ),
    "preview_max_steps": IntProperty(
        name="Preview steps",
        default=160,
        min=8,
        max=100000,
        soft_max=1000,
        update=_redraw,
        description="Most steps a preview ray takes (cost)",
    ),
    "preview_detail": FloatProperty(
        name="Preview detail",
        default=1.0,
        min=0.01,
        max=100.0,
        soft_max=8.0,
        update=_redraw,
        description="Hit threshold in pixels for the preview",
    ),
    # how a baked volume renders (not in the file; bakes.py)
    "volume_look": EnumProperty(
        name="Volume look",
        items=VOLUME_LOOK_ITEMS,
        default="SURFACE",
        update=_volume_look_changed,
        description="How baked volumes render: an opaque, shaded surface, as `dqjulia render` and the mesh show it, "
        "or the soft, translucent cloud of the fog",
    ),
    # the Variations panel's settings (not in the file; variations.py)
    "variation_strength": FloatProperty(
        name="Strength",
        default=0.3,
        min=0.0,
        max=1.0,
        step=1,
        precision=2,
        description="How far the variations go: 0.05 tiny (details move a little), 0.15 small (a close relative), "
        "0.3 medium (a sibling), 0.6 large (a cousin), 1 huge (a stranger); the library takes 0.01 to 1",
    ),
    "variation_locks": EnumProperty(
        name="Keep",
        items=VARIATION_GROUP_ITEMS,
        options={"ENUM_FLAG"},
        default={"variant"},
        description="The groups the variations keep as they are, bit for bit",
    ),
    "variation_seed": IntProperty(
        name="Seed",
        default=1,
        min=0,
        description="The variations' random seed: the same seed, strength and locks give the same variations "
        "(Refresh moves to the next)",
    ),
    # sections of an imported file this version does not model, written back on export
    "extra_json": StringProperty(name="Other sections", default="{}", options={"HIDDEN"}),
}
for _index, _axis in enumerate("xyz"):
    _settings["axis_" + _axis] = EnumProperty(name=_axis, items=AXIS_ITEMS, default=_axes[_index], update=_redraw)
    _unit = [0.0] * 8
    _unit[AXIS_NAMES.index(_axes[_index])] = 1.0
    _settings["axis_%s_vector" % _axis] = FloatVectorProperty(
        name="%s axis" % _axis,
        size=8,
        default=tuple(_unit),
        precision=5,
        step=1,
        update=_redraw,
        description="Where %s goes in 8-D" % _axis,
        **_limits(FIELDS["slice.axes"]),
    )
DQJuliaSettings = _group(
    "DQJuliaSettings",
    'Everything the parameter file holds (docs/parameter-file.md), plus the preview\'s options.',
    _settings,
)

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


def _json_value(field, value):
    """A property's value as the document writes it."""
    kind = field["type"]
    if kind == "boolean":
        return bool(value)
    if kind == "integer":
        return int(value)
    if kind == "number":
        return _number(value)
    if kind in ("vec3", "color", "vec8"):
        return _numbers(value)
    if kind == "choice_set":
        return [name for name, _label, _help in choice_items(field["key"]) if name in value]
    return value


def _put(document, key, value):
    """document["a"]["b"] = value for key "a.b"."""
    *sections, leaf = key.split(".")
    for section in sections:
        document = document.setdefault(section, {})
    document[leaf] = value


def _get(document, key):
    """document["a"]["b"] for key "a.b", or None where absent."""
    for part in key.split("."):
        if not isinstance(document, dict) or part not in document:
            return None
        document = document[part]
    return document


def _inside_auto(key):
    """The "auto" object a key belongs to ("bounds.center" -> "bounds"), or None."""
    for other, field in FIELDS.items():
        if field.get("auto") and key.startswith(other + "."):
            return other
    return None


def _item(item, prefix):
    """A list item's document from its properties (a light, a rotation)."""
    return {
        key[len(prefix) :]: _json_value(field, getattr(item, prop_name(key)))
        for key, field in _value_keys(prefix)
        if field["type"] != "axis_pair"
    }


def to_document(settings, values=None, with_animation=None):
    """The parameter document of these properties (a dict, not yet validated by the core).

    values: optional {property name: value} overrides (used to take a frame's values).
    with_animation: an "animation" dict to include (see animation.py), or None for none.
    """
    s = settings
    document = {"version": FORMAT_VERSION}
    for key, field in _value_keys():
        kind, name = field["type"], prop_name(key)
        auto = _inside_auto(key)
        if auto and getattr(s, prop_name(auto) + "_auto"):
            document_value = None
        elif kind == "dual_quaternion":
            document_value = _numbers(list(_value(s, name + "_a", values)) + list(_value(s, name + "_b", values)))
        elif kind == "axes":
            if s.axes_mode == "NAMES":
                document_value = ",".join((s.axis_x, s.axis_y, s.axis_z))
            else:
                document_value = [_numbers(s.axis_x_vector), _numbers(s.axis_y_vector), _numbers(s.axis_z_vector)]
        elif field.get("optional") and kind != "choice" and not getattr(s, use_name(key)):
            document_value = None
        else:
            document_value = _json_value(field, _value(s, name, values))
            if kind == "choice" and document_value == "AUTO":
                document_value = None
            if key == "description" and not document_value:
                document_value = None
        if document_value is not None:
            _put(document, key, document_value)
    for key, field in FIELDS.items():
        if field.get("auto") and getattr(s, prop_name(key) + "_auto"):
            _put(document, key, "auto")
    rotations = []
    for index, rotation in enumerate(s.rotations):
        item = _item(rotation, "slice.rotations[].")
        item["plane"] = "%s,%s" % (rotation.first, rotation.second)
        if values:
            item["degrees"] = _number(_value(s, "rotations[%d].degrees" % index, values))
        rotations.append(item)
    _put(document, "slice.rotations", rotations)
    document["lights"] = [_item(light, "lights[].") for light in s.lights]
    _put(document, "material.palette", [_numbers(entry.color) for entry in s.palette] or [_numbers(s.color)])
    if not document["bake"].get("grids"):
        document["bake"]["grids"] = FIELDS["bake.grids"]["default"]
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


def _set_item(item, prefix, document):
    for key, field in _value_keys(prefix):
        if field["type"] != "axis_pair":
            setattr(item, prop_name(key), document[key[len(prefix) :]])


def from_document(settings, document):
    """Sets the properties from a complete document (as the core returns it). The "animation"
    section is not applied here (animation.py turns it into keyframes)."""
    s = settings
    for key, field in _value_keys():
        kind, name = field["type"], prop_name(key)
        value = _get(document, key)
        auto = _inside_auto(key)
        if auto:
            auto_on = _get(document, auto) == "auto"
            setattr(s, prop_name(auto) + "_auto", auto_on)
            if auto_on:
                continue
        if kind == "dual_quaternion":
            setattr(s, name + "_a", value[:4])
            setattr(s, name + "_b", value[4:])
        elif kind == "axes":
            if isinstance(value, str):
                s.axes_mode = "NAMES"
                s.axis_x, s.axis_y, s.axis_z = [axis.strip() for axis in value.split(",")]
                vectors = []
                for axis in (s.axis_x, s.axis_y, s.axis_z):
                    vector = [0.0] * 8
                    vector[AXIS_NAMES.index(axis)] = 1.0
                    vectors.append(vector)
            else:
                s.axes_mode = "VECTORS"
                vectors = value
            s.axis_x_vector, s.axis_y_vector, s.axis_z_vector = vectors
        elif field.get("optional") and kind != "choice":
            setattr(s, use_name(key), value is not None)
            if value is not None:
                setattr(s, name, value)
        elif kind == "choice_set":
            setattr(s, name, set(value))
        elif value is None:
            setattr(s, name, "AUTO" if kind == "choice" else _initial(field))
        else:
            setattr(s, name, value)
    s.rotations.clear()
    for rotation in _get(document, "slice.rotations"):
        item = s.rotations.add()
        item.first, item.second = [name.strip() for name in rotation["plane"].split(",")]
        _set_item(item, "slice.rotations[].", rotation)
    s.active_rotation = max(0, min(s.active_rotation, len(s.rotations) - 1))
    s.lights.clear()
    for light in document["lights"]:
        _set_item(s.lights.add(), "lights[].", light)
    s.palette.clear()
    for colour in _get(document, "material.palette"):
        s.palette.add().color = colour
    s.extra_json = json.dumps({key: value for key, value in document.items() if key not in MODELED_SECTIONS})


def draw_fields(layout, settings, keys):
    """One row per schema key, labelled and explained by the schema (panels.py)."""
    for key in keys:
        field = FIELDS[key]
        if field.get("optional") and field["type"] != "choice":
            layout.prop(settings, use_name(key))
            if not getattr(settings, use_name(key)):
                continue
        layout.prop(settings, prop_name(key))


def section_keys(section, exclude=()):
    """The scalar value keys of a section in file order (for draw_fields)."""
    return [
        key
        for key, field in _value_keys(section + ".")
        if key not in exclude
        and not _inside_auto(key)
        and field["type"] in ("boolean", "integer", "number", "string", "choice", "vec3", "color")
    ]


def register():
    for cls in CLASSES:
        bpy.utils.register_class(cls)
    bpy.types.Object.dqjulia = PointerProperty(type=DQJuliaSettings, name="DQ Julia")


def unregister():
    del bpy.types.Object.dqjulia
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)

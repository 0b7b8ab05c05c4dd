"""Keyframes: Blender's F-curves on Object.dqjulia <-> the parameter file's "animation".

In Blender every property of a DQ Julia object can be keyframed. Bake Sequence takes each
frame's values from Blender itself (scene.frame_set, so F-curves, drivers and NLA all apply),
and bakes a document holding that frame's values. The parameter file animates four things
(docs/baking.md, "Animation"): fractal.c, fractal.iterations, fractal.bailout and
slice.rotations[i].degrees; export writes the keys of those F-curves, import makes F-curves
from the file's keys. Interpolation: the file's "linear" is Blender's LINEAR; its "smooth"
(a monotone cubic, never overshooting) is written for and read as Blender's BEZIER with
auto-clamped handles, which also never overshoot; the curves agree at the keys and differ
slightly between them.
"""

import re

from . import props

PREFIX = "dqjulia."
_ROTATION = re.compile(r"^dqjulia\.rotations\[(\d+)\]\.degrees$")


def action_fcurves(obj, create=False):
    """The F-curve collection that animates `obj` in its action, or None.

    Blender 3.4 - 4.3: Action.fcurves. 4.4+: layered actions, whose F-curves live in the
    channelbag of the object's action slot (Action.fcurves is deprecated in 4.4 and gone in 5.0).
    `create`: make the channelbag if the slot has none yet (keyframe_insert makes it anyway)."""
    animation_data = obj.animation_data
    action = animation_data.action if animation_data else None
    if action is None:
        return None
    slot = getattr(animation_data, "action_slot", None)
    if hasattr(action, "layers") and slot is not None:
        from bpy_extras import anim_utils

        channelbag = anim_utils.action_get_channelbag_for_slot(action, slot)
        if channelbag is None and create and hasattr(anim_utils, "action_ensure_channelbag_for_slot"):
            channelbag = anim_utils.action_ensure_channelbag_for_slot(action, slot)
        if channelbag is not None:
            return channelbag.fcurves
        if not hasattr(action, "fcurves"):
            return None
    return getattr(action, "fcurves", None)


def dqjulia_fcurves(obj):
    fcurves = action_fcurves(obj)
    if fcurves is None:
        return []
    return [curve for curve in fcurves if curve.data_path.startswith(PREFIX)]


def is_animated(obj):
    return bool(dqjulia_fcurves(obj))


def _interpolation(curve, frame):
    for point in curve.keyframe_points:
        if abs(point.co.x - frame) < 1e-6:
            return "linear" if point.interpolation in {"LINEAR", "CONSTANT"} else "smooth"
    return "smooth"


def animation_section(obj):
    """(the file's "animation" dict, [names of animated properties the file cannot hold])."""
    curves = dqjulia_fcurves(obj)
    settings = obj.dqjulia
    section = {}
    skipped = []
    constant_curves = {}
    for curve in curves:
        path = curve.data_path
        if path in ("dqjulia.c_a", "dqjulia.c_b"):
            offset = 0 if path.endswith("c_a") else 4
            constant_curves[offset + curve.array_index] = curve
        elif path in ("dqjulia.iterations", "dqjulia.bailout"):
            key = "fractal." + path[len(PREFIX) :]
            keys = []
            for point in sorted(curve.keyframe_points, key=lambda p: p.co.x):
                value = int(round(point.co.y)) if key == "fractal.iterations" else props._number(point.co.y)
                keys.append(
                    {"frame": float(point.co.x), "value": value, "interpolation": _interpolation(curve, point.co.x)}
                )
            if keys:
                section[key] = keys
        elif _ROTATION.match(path):
            index = int(_ROTATION.match(path).group(1))
            keys = [
                {
                    "frame": float(point.co.x),
                    "value": props._number(point.co.y),
                    "interpolation": _interpolation(curve, point.co.x),
                }
                for point in sorted(curve.keyframe_points, key=lambda p: p.co.x)
            ]
            if keys:
                section["slice.rotations[%d].degrees" % index] = keys
        else:
            name = path[len(PREFIX) :]
            if name not in skipped:
                skipped.append(name)
    if constant_curves:
        frames = sorted({round(point.co.x, 6) for curve in constant_curves.values() for point in curve.keyframe_points})
        static = list(settings.c_a) + list(settings.c_b)
        keys = []
        for frame in frames:
            value = [
                props._number(constant_curves[i].evaluate(frame)) if i in constant_curves else props._number(static[i])
                for i in range(8)
            ]
            interpolation = next(
                (
                    _interpolation(curve, frame)
                    for curve in constant_curves.values()
                    if any(abs(p.co.x - frame) < 1e-6 for p in curve.keyframe_points)
                ),
                "smooth",
            )
            keys.append({"frame": float(frame), "value": value, "interpolation": interpolation})
        section["fractal.c"] = keys
    return section, skipped


def clear(obj):
    fcurves = action_fcurves(obj)
    if fcurves is None:
        return
    for curve in [curve for curve in fcurves if curve.data_path.startswith(PREFIX)]:
        fcurves.remove(curve)


def _set_interpolation(obj, data_path, index, frame, interpolation):
    fcurves = action_fcurves(obj)
    curve = fcurves.find(data_path, index=index) if fcurves is not None else None
    if curve is None:
        return
    for point in curve.keyframe_points:
        if abs(point.co.x - frame) < 1e-6:
            if interpolation == "linear":
                point.interpolation = "LINEAR"
            else:
                point.interpolation = "BEZIER"
                point.handle_left_type = "AUTO_CLAMPED"
                point.handle_right_type = "AUTO_CLAMPED"
    curve.update()


def apply_section(obj, section):
    """Replaces the object's dqjulia keyframes by the file's "animation" section."""
    clear(obj)
    settings = obj.dqjulia
    for key, keys in section.items():
        for item in keys:
            frame = float(item["frame"])
            value = item["value"]
            interpolation = item.get("interpolation", "linear")
            if key == "fractal.c":
                settings.c_a = value[:4]
                settings.c_b = value[4:]
                for name in ("c_a", "c_b"):
                    for index in range(4):
                        obj.keyframe_insert(PREFIX + name, index=index, frame=frame, group="DQ Julia")
                        _set_interpolation(obj, PREFIX + name, index, frame, interpolation)
            elif key in ("fractal.iterations", "fractal.bailout"):
                name = key.split(".")[1]
                setattr(settings, name, int(value) if name == "iterations" else value)
                obj.keyframe_insert(PREFIX + name, frame=frame, group="DQ Julia")
                _set_interpolation(obj, PREFIX + name, 0, frame, interpolation)
            else:
                match = re.match(r"^slice\.rotations\[(\d+)\]\.degrees$", key)
                if not match or int(match.group(1)) >= len(settings.rotations):
                    continue
                index = int(match.group(1))
                settings.rotations[index].degrees = value
                path = "%srotations[%d].degrees" % (PREFIX, index)
                obj.keyframe_insert(path, frame=frame, group="DQ Julia")
                _set_interpolation(obj, path, 0, frame, interpolation)


def frame_documents(obj, scene, frames):
    """The object's parameter document at each frame, as Blender evaluates it (main thread)."""
    current, subframe = scene.frame_current, scene.frame_subframe
    documents = []
    try:
        for frame in frames:
            scene.frame_set(int(frame))
            documents.append(props.to_document(obj.dqjulia))
    finally:
        scene.frame_set(current, subframe=subframe)
    return documents

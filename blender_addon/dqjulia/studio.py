"""A first render that shows the set: Frame Camera and Studio.

Frame Camera aims the scene's camera at a DQ Julia object's bounds as `dqjulia render` frames
them (core/src/render/camera.cpp: from the document's camera.direction, with its up, the bounding
sphere fitted in the narrower field of view with 8 % margin); with no camera it makes one, with
the document's field of view, in the studio's collection. Studio adds a light rig (key, fill and
rim sun lights, placed about the camera's view) and a soft grey world, all in the collection
"DQ Julia Studio" and tagged, so running it again re-aims the same lights instead of adding more;
the user's own lights and world are left as they are (the scene just uses the studio's world,
and Ctrl-Z or choosing the old world in the World properties returns to it).
"""

import math

import bpy
from mathutils import Matrix, Vector

from . import core_state, operators, props

STUDIO_KEY = "dqjulia_studio"  # custom property on the studio's collection, lights, camera and world
COLLECTION_NAME = "DQ Julia Studio"
WORLD_NAME = "DQ Julia Studio"
MARGIN = 1.08  # as the core's frameCamera

# The rig, in the camera's frame (right, up, towards the camera): where each sun comes from,
# its strength (W/m^2), its colour. A warm key from the upper left in front, a cool fill from the
# right, a rim from behind above that outlines the silhouette.
RIG = (
    ("Key", (-0.7, 0.8, 0.9), 4.0, (1.0, 0.96, 0.9)),
    ("Fill", (0.9, 0.1, 0.6), 1.2, (0.85, 0.9, 1.0)),
    ("Rim", (0.3, 0.9, -1.0), 3.0, (1.0, 1.0, 1.0)),
)
WORLD_COLOR = (0.18, 0.19, 0.21)  # the background and the ambient light it gives
WORLD_STRENGTH = 1.0


class FrameError(Exception):
    """Why an object cannot be framed (no bounds: the slice is empty or invalid)."""


def world_bounds(obj):
    """The object's bounding sphere in world space: (centre, radius); FrameError without one."""
    state = core_state.state_for(obj)
    if state.error is not None:
        raise FrameError(state.error)
    if state.bounds is None:
        raise FrameError("the object has no bounds to frame: %s" % (state.empty_reason or "the slice is empty"))
    center, radius, _clipped = state.bounds
    matrix = obj.matrix_world
    return matrix @ Vector(center), radius * max(abs(s) for s in matrix.to_scale())


def _world_direction(obj, vector):
    """A direction of the slice's frame (the object's local one) in world space, unit length."""
    direction = obj.matrix_world.to_3x3() @ Vector(vector)
    return direction.normalized() if direction.length > 0.0 else Vector((0.0, 0.0, 1.0))


def tan_half_fovs(camera, aspect):
    """tan of half the camera's horizontal and vertical fields of view at image aspect w/h,
    following Blender's sensor fit."""
    if camera.sensor_fit == "VERTICAL" or (camera.sensor_fit == "AUTO" and aspect < 1.0):
        sensor = camera.sensor_height if camera.sensor_fit == "VERTICAL" else camera.sensor_width
        vertical = 0.5 * sensor / camera.lens
        return vertical * aspect, vertical
    horizontal = 0.5 * camera.sensor_width / camera.lens
    return horizontal, horizontal / aspect


def image_aspect(scene):
    render = scene.render
    return (render.resolution_x * render.pixel_aspect_x) / max(1e-9, render.resolution_y * render.pixel_aspect_y)


def studio_collection(scene):
    """The studio's collection in the scene, made and linked if missing (found by its tag, so a
    user's collection of the same name is never used)."""
    for collection in scene.collection.children_recursive:
        if collection.get(STUDIO_KEY):
            return collection
    collection = bpy.data.collections.new(COLLECTION_NAME)
    collection[STUDIO_KEY] = True
    scene.collection.children.link(collection)
    return collection


def frame_camera(context, obj):
    """Aims the scene's camera (made if there is none) at the object's bounds; returns it.
    Raises FrameError if the object has no bounds."""
    scene = context.scene
    center, radius = world_bounds(obj)
    camera_settings = props.to_document(obj.dqjulia)["camera"]
    camera = scene.camera
    if camera is None or camera.type != "CAMERA":
        data = bpy.data.cameras.new("DQ Julia Camera")
        data.sensor_fit = "VERTICAL"
        data.angle_y = math.radians(float(camera_settings["fov"]))  # the core's fov is vertical
        camera = bpy.data.objects.new("DQ Julia Camera", data)
        camera[STUDIO_KEY] = "camera"
        studio_collection(scene).objects.link(camera)
        scene.camera = camera
    data = camera.data
    aspect = image_aspect(scene)
    up = _world_direction(obj, camera_settings["up"])
    if "position" in camera_settings:
        eye = obj.matrix_world @ Vector(camera_settings["position"])
        target = obj.matrix_world @ Vector(camera_settings["target"]) if "target" in camera_settings else center
    else:
        target = obj.matrix_world @ Vector(camera_settings["target"]) if "target" in camera_settings else center
        away = _world_direction(obj, camera_settings["direction"])
        if data.type == "ORTHO":
            data.ortho_scale = 2.0 * radius * MARGIN * max(aspect, 1.0 / aspect)
            distance = 4.0 * radius
        elif data.type == "PERSP":
            tan_x, tan_y = tan_half_fovs(data, aspect)
            distance = radius / math.sin(math.atan(min(tan_x, tan_y))) * MARGIN
        else:
            raise FrameError("the scene's camera is panoramic: Frame Camera fits perspective and orthographic ones")
        eye = target + away * distance
    forward = target - eye
    forward = forward.normalized() if forward.length > 0.0 else Vector((0.0, 0.0, -1.0))
    if forward.cross(up).length <= 1e-9:
        up = min((Vector(axis) for axis in ((1, 0, 0), (0, 1, 0), (0, 0, 1))), key=lambda a: abs(a.dot(forward)))
    right = forward.cross(up).normalized()
    up = right.cross(forward)
    # A camera looks along its -Z with +Y up: its columns are right, up, backwards.
    rotation = Matrix((right, up, -forward)).transposed().to_4x4()
    camera.matrix_world = Matrix.Translation(eye) @ rotation
    distance = (eye - center).length
    data.clip_start = min(data.clip_start, max(1e-4, 0.5 * (distance - radius)), 0.01 * distance)
    data.clip_end = max(data.clip_end, 2.0 * (distance + radius))
    return camera


def _view_frame(scene, center):
    """(right, up, back) of the scene camera's view, or of a default view towards the centre."""
    if scene.camera is not None:
        rotation = scene.camera.matrix_world.to_3x3().normalized()
        return rotation.col[0], rotation.col[1], rotation.col[2]
    back = Vector((0.55, -1.0, 0.45)).normalized()
    right = Vector((0.0, 0.0, 1.0)).cross(back).normalized()
    return right, back.cross(right), back


def _studio_world():
    world = next((w for w in bpy.data.worlds if w.get(STUDIO_KEY)), None)
    if world is None:
        world = bpy.data.worlds.new(WORLD_NAME)
        world[STUDIO_KEY] = True
    if bpy.app.version < (5, 0, 0):
        world.use_nodes = True
    tree = world.node_tree
    background = next((node for node in tree.nodes if node.type == "BACKGROUND"), None)
    if background is None:
        background = tree.nodes.new("ShaderNodeBackground")
        output = next((node for node in tree.nodes if node.type == "OUTPUT_WORLD"), None)
        if output is None:
            output = tree.nodes.new("ShaderNodeOutputWorld")
        tree.links.new(background.outputs["Background"], output.inputs["Surface"])
    background.inputs["Color"].default_value = list(WORLD_COLOR) + [1.0]
    background.inputs["Strength"].default_value = WORLD_STRENGTH
    world.color = WORLD_COLOR
    return world


def studio(context, obj):
    """Adds (or re-aims) the studio's lights about the object and the camera's view and makes
    the studio's world the scene's; returns the lights. Raises FrameError without bounds."""
    scene = context.scene
    center, radius = world_bounds(obj)
    collection = studio_collection(scene)
    right, up, back = _view_frame(scene, center)
    lights = []
    for role, (x, y, z), strength, colour in RIG:
        light = next((o for o in collection.objects if o.get(STUDIO_KEY) == role.lower()), None)
        if light is None or light.type != "LIGHT" or light.data.type != "SUN":
            data = bpy.data.lights.new("DQ Julia %s" % role, "SUN")
            light = bpy.data.objects.new("DQ Julia %s" % role, data)
            light[STUDIO_KEY] = role.lower()
            collection.objects.link(light)
        light.data.energy = strength
        light.data.color = colour
        light.data.angle = math.radians(3.0)  # slightly soft shadows
        towards_light = (x * right + y * up + z * back).normalized()
        # A sun shines along its -Z: point -Z away from the light, i.e. +Z towards it.
        rotation = towards_light.to_track_quat("Z", "Y").to_matrix().to_4x4()
        light.matrix_world = Matrix.Translation(center + 3.0 * radius * towards_light) @ rotation
        lights.append(light)
    scene.world = _studio_world()
    return lights


class _StudioOperator(operators._NeedsDQJuliaObject):
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context):
        obj = operators.dqjulia_object(context)
        try:
            self.act(context, obj)
        except FrameError as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        return {"FINISHED"}


class DQJULIA_OT_frame_camera(_StudioOperator, bpy.types.Operator):
    """Aim the scene's camera at the object's bounds as `dqjulia render` frames them (a camera is
    made, in the "DQ Julia Studio" collection, if the scene has none)"""

    bl_idname = "dqjulia.frame_camera"
    bl_label = "Frame Camera"

    def act(self, context, obj):
        camera = frame_camera(context, obj)
        self.report({"INFO"}, "%s frames %s" % (camera.name, obj.name))


class DQJULIA_OT_studio(_StudioOperator, bpy.types.Operator):
    """Light the object with a studio rig (key, fill and rim suns about the camera's view) and a
    soft grey world, in the "DQ Julia Studio" collection; running it again re-aims the same lights.
    Your own lights and world stay as they are"""

    bl_idname = "dqjulia.studio"
    bl_label = "Studio"

    def act(self, context, obj):
        lights = studio(context, obj)
        self.report({"INFO"}, "%d studio lights and the studio world light %s" % (len(lights), obj.name))


CLASSES = (DQJULIA_OT_frame_camera, DQJULIA_OT_studio)


def register():
    for cls in CLASSES:
        bpy.utils.register_class(cls)


def unregister():
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)

"""The OSL volume: shaders/dqjulia_density.osl in a Cycles Script node, on a cube over the
bounds, so Cycles computes the set while it renders (no bake). Needs a Blender built with
OSL (bpy.app.build_options.cycles_osl); Debian's Blender has none, and then the add-on says
so instead of failing. The script's inputs take the object's parameters (slice rotations
applied); a frame-change handler keeps them in step with keyframes.
"""

import os

import bpy
from bpy.app.handlers import persistent

from . import bakes, core_state

SCRIPT_PATH = os.path.join(os.path.dirname(os.path.abspath(__file__)), "shaders", "dqjulia_density.osl")
TEXT_NAME = "dqjulia_density.osl"
SOURCE_KEY = bakes.OSL_SOURCE  # custom property: the OSL volume's source object

UNAVAILABLE_MESSAGE = (
    "This Blender was built without Open Shading Language (bpy.app.build_options.cycles_osl "
    "is False; Debian's Blender is), so Cycles cannot run the DQ Julia OSL script. Use Bake "
    "Volume or Bake Mesh, or a Blender from blender.org; 'OSL Script to Text' still loads "
    "the script to read or copy."
)


def available():
    return bool(getattr(bpy.app.build_options, "cycles_osl", False))


def shader_text():
    """The OSL source as a text block (made or refreshed)."""
    text = bpy.data.texts.get(TEXT_NAME) or bpy.data.texts.new(TEXT_NAME)
    with open(SCRIPT_PATH, encoding="utf-8") as file:
        source = file.read()
    if text.as_string() != source:
        text.clear()
        text.write(source)
    return text


def input_values(obj):
    """The Script node's input values for the object's current parameters."""
    state = core_state.state_for(obj)
    if state.error:
        raise RuntimeError(state.error)
    if state.bounds is None:
        raise RuntimeError(state.empty_reason or "the slice has no bounds")
    fractal = state.document["fractal"]
    c = fractal["c"]
    origin, axes = state.origin, state.axes
    values = {
        "CaS": c[0],
        "CaV": c[1:4],
        "CbS": c[4],
        "CbV": c[5:8],
        "Variant": ["paper", "paper-coupled", "dual"].index(fractal["variant"]),
        "Iterations": int(fractal["iterations"]),
        "Bailout": float(fractal["bailout"]),
        "OriginAS": origin[0],
        "OriginAV": origin[1:4],
        "OriginBS": origin[4],
        "OriginBV": origin[5:8],
        "Stretch": state.stretch,
        "BoundsCenter": state.bounds[0],
        "BoundsRadius": state.bounds[1],
    }
    for name, axis in zip("XYZ", axes):
        values[name + "AS"] = axis[0]
        values[name + "AV"] = axis[1:4]
        values[name + "BS"] = axis[4]
        values[name + "BV"] = axis[5:8]
    return values


def sync_node(node, obj):
    for name, value in input_values(obj).items():
        socket = node.inputs.get(name)
        if socket is None:
            continue
        if hasattr(value, "__len__"):
            if tuple(socket.default_value) != tuple(value):
                socket.default_value = value
        elif socket.default_value != value:
            socket.default_value = value


def use_cycles_osl(scene):
    """Cycles on the CPU with Open Shading Language: what the Script node needs to run."""
    scene.render.engine = "CYCLES"
    cycles = getattr(scene, "cycles", None)
    if cycles is not None:
        cycles.shading_system = True
        cycles.device = "CPU"  # OSL runs on the CPU (and OptiX) only


def node_tree_of(material):
    """The material's node tree, or None. Blender 5.0 deprecates Material.use_nodes (always on;
    reading it warns each time): there, the tree alone says."""
    if material is None:
        return None
    if bpy.app.version < (5, 0, 0) and not material.use_nodes:
        return None
    return material.node_tree


def add_volume(context, source):
    """A cube over the bounds with the OSL volume material, parented to the source."""
    values = input_values(source)
    center, radius = values["BoundsCenter"], values["BoundsRadius"]
    mesh = bpy.data.meshes.new("%s OSL Volume" % source.name)
    corners = [
        (center[0] + sx * radius, center[1] + sy * radius, center[2] + sz * radius)
        for sx in (-1, 1)
        for sy in (-1, 1)
        for sz in (-1, 1)
    ]
    faces = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    mesh.from_pydata(corners, [], faces)  # 8 corners: the mesh bakes use foreach_set
    mesh.update()
    # Blender compiles a Script node's OSL (and gives it its sockets) only when the scene
    # already renders with Cycles and OSL on: switch first, then assign the script.
    use_cycles_osl(context.scene)
    material, volume = bakes.principled_volume_material("%s OSL" % source.name)
    tree = material.node_tree
    script = tree.nodes.new("ShaderNodeScript")
    script.location = (-350, 0)
    script.mode = "INTERNAL"
    script.script = shader_text()
    if "Density" not in script.outputs:
        bpy.data.materials.remove(material)
        bpy.data.meshes.remove(mesh)
        raise RuntimeError("Cycles did not compile the OSL script (no outputs); see the console")
    # The same density scale as a baked volume's material, so both render alike.
    scale = tree.nodes.new("ShaderNodeMath")
    scale.operation = "MULTIPLY"
    scale.location = (-150, 0)
    scale.inputs[1].default_value = bakes.volume_density(source)
    tree.links.new(script.outputs["Density"], scale.inputs[0])
    tree.links.new(scale.outputs["Value"], volume.inputs["Density"])
    sync_node(script, source)
    mesh.materials.append(material)
    obj = bpy.data.objects.new(mesh.name, mesh)
    (source.users_collection or (context.scene.collection,))[0].objects.link(obj)
    obj.parent = source
    obj.matrix_parent_inverse.identity()
    obj.matrix_basis.identity()
    obj[SOURCE_KEY] = source.name
    return obj


@persistent
def _sync_all(scene, _depsgraph=None):
    """Frame change: keep every OSL volume's inputs at its source's (keyframed) values."""
    for obj in scene.objects:
        name = obj.get(SOURCE_KEY)
        source = scene.objects.get(name) if name else None
        if source is None or obj.type != "MESH":
            continue
        for slot in obj.material_slots:
            tree = node_tree_of(slot.material)
            if tree is None:
                continue
            for node in tree.nodes:
                if node.bl_idname == "ShaderNodeScript":
                    try:
                        sync_node(node, source)
                    except RuntimeError:
                        pass


def register():
    if _sync_all not in bpy.app.handlers.frame_change_post:
        bpy.app.handlers.frame_change_post.append(_sync_all)


def unregister():
    if _sync_all in bpy.app.handlers.frame_change_post:
        bpy.app.handlers.frame_change_post.remove(_sync_all)

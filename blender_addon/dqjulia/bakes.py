"""Where bakes go, and the Blender objects made from them (main thread only).

Bakes belong to the .blend: by default their files go beside it, into
//dqjulia_cache/<blend name>/<object>/, and the volumes store that path relative to the .blend,
so a project folder moved or copied elsewhere renders its own bakes. Volumes need a saved
.blend (the operators say so); the add-on's preferences may name another cache folder (an
absolute one is stored absolute, e.g. a farm's shared drive). Blender's External Data tools
(Make Paths Relative/Absolute, Report/Find Missing Files, Pack Resources for single files)
work on them as on any file.

A bake never deletes a file a saved .blend may use: a re-bake writes new file names and
removes the replaced bake's files only if they were made since the .blend was last saved or
opened (so no saved file can refer to them). Objects are built only from a finished bake; if
building fails, whatever was made is removed again, so no half-made object remains. A missing
bake file is reported in the panel and in the render log (missing_bakes).
"""

import array
import os
import shutil
import sys
import uuid

import bpy
from bpy.app.handlers import persistent

from . import core_state, props

ADDON_DIR = os.path.dirname(os.path.abspath(__file__))
BAKE_KIND = "dqjulia_bake"  # custom property on baked objects: "volume", "mesh", "sequence"
BAKE_FILES = "dqjulia_files"  # custom property: the files or folder the baked object reads (as stored)
# The volume material's density: light falls to e^-4 (2 %) within the colour grid's depth
# (bake.color_depth of the bake's side), so a render shows the colours, not the black beneath.
VISIBLE_OPTICAL_DEPTH = 4.0
DEFAULT_CACHE = "//dqjulia_cache"  # beside the .blend

# The bake files made since the .blend was last saved or opened (absolute, normalised): the
# only ones a re-bake may delete.
_made_since_save = set()


def _package():
    return __package__ or "dqjulia"


def preferences(context=None):
    context = context or bpy.context
    addon = context.preferences.addons.get(_package())
    return addon.preferences if addon else None


def chosen_cache(context=None):
    """The cache folder as the user gave it: the preferences' folder, or //dqjulia_cache."""
    prefs = preferences(context)
    return (getattr(prefs, "cache_dir", "") if prefs else "") or DEFAULT_CACHE


def cache_root(context=None):
    """The cache folder, absolute. ValueError when it is relative to an unsaved .blend, or
    inside the add-on's folder (which Blender replaces on updates)."""
    chosen = chosen_cache(context)
    if chosen.startswith("//") and not bpy.data.filepath:
        raise ValueError(
            "save the .blend file first: volume bakes are stored beside it (in %s/), so they travel "
            "with the project (or choose an absolute cache folder in the add-on's preferences)" % chosen
        )
    root = os.path.abspath(bpy.path.abspath(chosen))
    if os.path.commonpath([root, ADDON_DIR]) == ADDON_DIR:
        raise ValueError(
            "the cache folder %s is inside the add-on's folder, which Blender replaces on updates; "
            "choose another in the add-on's preferences" % root
        )
    return root


def stored_path(path):
    """How a bake file's path is stored: relative to the .blend ("//...") when the cache folder
    was given relative to it, else absolute."""
    if bpy.data.filepath and chosen_cache().startswith("//"):
        return bpy.path.relpath(path)
    return os.path.abspath(path)


def _absolute(path):
    return os.path.normpath(os.path.abspath(bpy.path.abspath(path)))


def _safe(name):
    return "".join(ch if ch.isalnum() or ch in "-_." else "_" for ch in name) or "object"


def object_cache_dir(obj, context=None):
    blend = bpy.data.filepath
    project = os.path.splitext(os.path.basename(blend))[0] if blend else "untitled"
    return os.path.join(cache_root(context), _safe(project), _safe(obj.name))


def new_volume_path(obj, context=None):
    return os.path.join(object_cache_dir(obj, context), "%s_volume_%s.vdb" % (_safe(obj.name), uuid.uuid4().hex[:8]))


def new_sequence_dir(obj, context=None):
    return os.path.join(object_cache_dir(obj, context), "%s_sequence_%s" % (_safe(obj.name), uuid.uuid4().hex[:8]))


def sequence_frame_path(directory, obj, frame):
    """name_0001.vdb: the numbered files Blender plays back as a volume sequence."""
    return os.path.join(directory, "%s_%04d.vdb" % (_safe(obj.name), frame))


def remove_files(paths):
    for path in paths:
        path = _absolute(path)
        _made_since_save.discard(path)
        try:
            if os.path.isdir(path):
                shutil.rmtree(path)
            elif os.path.exists(path):
                os.remove(path)
        except OSError:
            pass


# -------------------------------------------------------------------------------------------
# Objects


def _find_baked(source, kind):
    for child in source.children:
        if child.get(BAKE_KIND) == kind:
            return child
    return None


def _link(context, source, obj):
    collections = source.users_collection or (context.scene.collection,)
    collections[0].objects.link(obj)
    obj.parent = source
    obj.matrix_parent_inverse.identity()
    obj.matrix_basis.identity()  # the bake is in the slice's (= the source's local) coordinates


def _replace(context, source, kind, name, data, files):
    """Puts `data` into the source's baked object of this kind (made if missing); returns it and
    removes the files of the bake it replaces."""
    obj = _find_baked(source, kind)
    old_files = []
    if obj is None:
        obj = bpy.data.objects.new(name, data)
        _link(context, source, obj)
    else:
        old_data = obj.data
        old_files = list(obj.get(BAKE_FILES, []))
        obj.data = data
        if old_data is not None and old_data.users == 0:
            if isinstance(old_data, bpy.types.Volume):
                bpy.data.volumes.remove(old_data)
            elif isinstance(old_data, bpy.types.Mesh):
                bpy.data.meshes.remove(old_data)
    obj[BAKE_KIND] = kind
    obj[BAKE_FILES] = [stored_path(path) for path in files]
    _made_since_save.update(_absolute(path) for path in files)
    # Only files no saved .blend can refer to (made since the last save or open) are removed.
    kept = {_absolute(path) for path in files}
    remove_files([path for path in old_files if _absolute(path) not in kept and _absolute(path) in _made_since_save])
    return obj


def new_node_material(name):
    """A new material with its node tree. Blender 5.0 deprecates Material.use_nodes (materials
    always use nodes there, and touching the property warns): set it only before 5.0."""
    material = bpy.data.materials.new(name)
    if bpy.app.version < (5, 0, 0):
        material.use_nodes = True
    return material


def principled_volume_material(name):
    """A new node material of one Principled Volume wired to the output: (material, volume node)."""
    material = new_node_material(name)
    tree = material.node_tree
    tree.nodes.clear()
    output = tree.nodes.new("ShaderNodeOutputMaterial")
    output.location = (300, 0)
    volume = tree.nodes.new("ShaderNodeVolumePrincipled")
    volume.location = (0, 0)
    tree.links.new(volume.outputs["Volume"], output.inputs["Volume"])
    return material, volume


def bake_side(source):
    """The longest side of the object's bake box (its bounding sphere's diameter when automatic)."""
    s = source.dqjulia
    if s.bake_bounds_auto:
        bounds = core_state.state_for(source).bounds
        side = 2.0 * (bounds[1] if bounds else 1.0)
    else:
        side = max(high - low for low, high in zip(s.bake_bounds_min, s.bake_bounds_max))
    return side


def volume_density(source):
    """The density scale of a DQ Julia object's volume material (and its OSL volume's): the fog
    is 0..1; this makes light fall to e^-4 within bake.color_depth of the bake's side."""
    return VISIBLE_OPTICAL_DEPTH / max(1e-6, source.dqjulia.bake_color_depth * bake_side(source))


# The volume looks (props "volume_look"). "SURFACE": where the fog passes SURFACE_LEVEL (just inside
# the set's edge: the fog ramps from 0 at the surface to 1 across the band's inner half), light
# falls to e^-4 within SURFACE_VOXELS voxels of the bake, so the volume renders as an opaque,
# shaded surface like the mesh and `dqjulia render`; "CLOUD": the fog as it is, at volume_density
# (a soft, translucent glow).
SURFACE_LEVEL = 0.02
SURFACE_VOXELS = 1.0


def surface_density(source):
    """The "SURFACE" look's density scale: opaque within SURFACE_VOXELS of the bake's voxels."""
    voxel = bake_side(source) / max(1, source.dqjulia.bake_resolution)
    return VISIBLE_OPTICAL_DEPTH / max(1e-6, SURFACE_VOXELS * voxel)


def _math_node(tree, operation, label, source, value, location):
    """A Math node of `operation` on (the socket `source`, the constant `value`)."""
    node = tree.nodes.new("ShaderNodeMath")
    node.operation = operation
    node.label = label
    node.inputs[1].default_value = value
    node.location = location
    tree.links.new(source, node.inputs[0])
    return node


def volume_material(name, grid_names, density=10.0, colour=(0.5, 0.5, 0.5), ambient=0.15, surface_level=None):
    """A Principled Volume: the "density" grid times `density`, coloured by the "color" grid when
    there is one (else the flat `colour`), which is also its scattering albedo. A dense volume
    lit by one light scatters about a sixth of what a surface of its colour reflects, so it also
    glows with `ambient` times its colour where it is dense (the emission is per unit of density:
    a thick part shows ambient * colour), as the preview's and the renderer's ambient term does.
    With `surface_level`, only fog above that level is dense (the "SURFACE" look: a hard edge)."""
    material, volume = principled_volume_material(name)
    tree = material.node_tree
    volume.inputs["Density"].default_value = density
    if "Density Attribute" in volume.inputs:
        volume.inputs["Density Attribute"].default_value = "density"
    if "color" in grid_names:
        # Through the Color input only: the node's "Color Attribute" would multiply it again
        # (it did: the colours came out squared, a murky brown).
        attribute = tree.nodes.new("ShaderNodeAttribute")
        attribute.attribute_name = "color"
        attribute.location = (-300, 150)
        tree.links.new(attribute.outputs["Color"], volume.inputs["Color"])
        tree.links.new(attribute.outputs["Color"], volume.inputs["Emission Color"])
    else:
        volume.inputs["Color"].default_value = list(colour) + [1.0]
        volume.inputs["Emission Color"].default_value = list(colour) + [1.0]
    fog = tree.nodes.new("ShaderNodeAttribute")
    fog.attribute_name = "density"
    fog.location = (-700, -150)
    glow = tree.nodes.new("ShaderNodeMath")
    glow.operation = "MULTIPLY"
    glow.label = "Ambient glow"
    glow.location = (-300, -150)
    if surface_level is None:
        tree.links.new(fog.outputs["Fac"], glow.inputs[0])
        glow.inputs[1].default_value = ambient * density
    else:
        # The density is `density` where the fog exceeds the level, else 0: not the fog times it
        # (an attribute name Cycles does not find multiplies by nothing), so the edge is sharp.
        if "Density Attribute" in volume.inputs:
            volume.inputs["Density Attribute"].default_value = ""
        edge = _math_node(tree, "GREATER_THAN", "Surface edge", fog.outputs["Fac"], surface_level, (-500, 0))
        scale = _math_node(tree, "MULTIPLY", "Surface density", edge.outputs["Value"], density, (-300, 0))
        tree.links.new(scale.outputs["Value"], volume.inputs["Density"])
        tree.links.new(scale.outputs["Value"], glow.inputs[0])
        glow.inputs[1].default_value = ambient
    tree.links.new(glow.outputs["Value"], volume.inputs["Emission Strength"])
    return material


def look_material(source, name, grid_names):
    """The volume material of a DQ Julia object's bake in the object's chosen look."""
    s = source.dqjulia
    if s.volume_look == "CLOUD":
        return volume_material(name, grid_names, volume_density(source), tuple(s.color), s.ambient)
    return volume_material(
        name, grid_names, surface_density(source), tuple(s.color), s.ambient, surface_level=SURFACE_LEVEL
    )


def apply_volume_look(source):
    """Gives the object's baked volumes (and sequences) a new material in its chosen look."""
    for child in source.children:
        if child.get(BAKE_KIND) not in ("volume", "sequence") or child.type != "VOLUME":
            continue
        names = [grid.name for grid in child.data.grids] if child.data.grids.load() else ["density"]
        old = list(child.data.materials)
        child.data.materials.clear()
        child.data.materials.append(look_material(source, child.data.name, names))
        for material in old:
            if material is not None and material.users == 0:
                bpy.data.materials.remove(material)


def grid_names(path):
    """The grids Blender reads from a VDB file; RuntimeError if it cannot read it."""
    probe = bpy.data.volumes.new("dqjulia probe")
    try:
        probe.filepath = path
        if not probe.grids.load():
            raise RuntimeError("Blender could not read %s: %s" % (path, probe.grids.error_message or "unknown error"))
        return [grid.name for grid in probe.grids]
    finally:
        bpy.data.volumes.remove(probe)


def build_volume(context, source, path, sequence=None):
    """A Volume object reading `path` (the first file of a sequence when `sequence` is
    (first frame, frame count, folder)); raises RuntimeError, leaving nothing, if Blender
    cannot read the file or it lacks the "density" grid."""
    kind = "sequence" if sequence else "volume"
    name = "%s %s" % (source.name, "Volume Sequence" if sequence else "Volume")
    names = grid_names(path)
    if "density" not in names:
        raise RuntimeError('%s has no "density" grid (grids: %s)' % (path, ", ".join(names) or "none"))
    volume = bpy.data.volumes.new(name)
    material = None
    try:
        volume.filepath = stored_path(path)
        if sequence:
            # Blender plays file number (scene frame - frame_start + 1 + frame_offset): with the
            # offset below, file name_0007.vdb is scene frame 7.
            first, count, _folder = sequence
            volume.is_sequence = True
            volume.frame_start = first
            volume.frame_duration = count
            volume.frame_offset = first - 1
            volume.sequence_mode = "CLIP"
        material = look_material(source, name, names)
        volume.materials.append(material)
        files = [sequence[2]] if sequence else [path]
        return _replace(context, source, kind, name, volume, files)
    except Exception:
        if material is not None:
            bpy.data.materials.remove(material)
        bpy.data.volumes.remove(volume)
        raise


def mesh_material(name, with_colors):
    material = new_node_material(name)
    tree = material.node_tree
    bsdf = next((node for node in tree.nodes if node.type == "BSDF_PRINCIPLED"), None)
    if bsdf is not None and with_colors:
        attribute = tree.nodes.new("ShaderNodeAttribute")
        attribute.attribute_name = "Col"
        attribute.location = (-300, 200)
        tree.links.new(attribute.outputs["Color"], bsdf.inputs["Base Color"])
    return material


def build_mesh(context, source, data):
    """A mesh object from MeshData, filled with foreach_set (no per-vertex Python calls),
    with the core's normals as custom split normals and its colours as a colour attribute."""
    name = "%s Mesh" % source.name
    mesh = bpy.data.meshes.new(name)
    material = None
    try:
        vertices, quads, triangles = data.vertex_count, data.quad_count, data.triangle_count
        faces = quads + triangles
        mesh.vertices.add(vertices)
        mesh.vertices.foreach_set("co", data.positions)
        mesh.loops.add(4 * quads + 3 * triangles)
        mesh.loops.foreach_set("vertex_index", data.quads + data.triangles)
        mesh.polygons.add(faces)
        # The core's quads stay quads (then its triangles). loop_total is read-only since 3.6:
        # Blender derives it from the next face's loop_start.
        starts = array.array("i", range(0, 4 * quads, 4))
        starts.extend(range(4 * quads, 4 * quads + 3 * triangles, 3))
        mesh.polygons.foreach_set("loop_start", starts)
        if not bpy.types.MeshPolygon.bl_rna.properties["loop_total"].is_readonly:  # Blender 3.4 - 3.5
            mesh.polygons.foreach_set("loop_total", array.array("i", [4]) * quads + array.array("i", [3]) * triangles)
        mesh.polygons.foreach_set("use_smooth", array.array("b", [1]) * faces)
        mesh.update(calc_edges=True)
        if hasattr(mesh, "use_auto_smooth"):  # Blender < 4.1: custom normals need auto smooth
            mesh.use_auto_smooth = True
        normals = data.normals
        mesh.normals_split_custom_set_from_vertices([normals[i : i + 3] for i in range(0, len(normals), 3)])
        if data.colors is not None and vertices:
            rgba = array.array("f", [1.0]) * (4 * vertices)
            for channel in range(3):
                rgba[channel::4] = data.colors[channel::3]
            attribute = mesh.color_attributes.new("Col", "FLOAT_COLOR", "POINT")
            attribute.data.foreach_set("color", rgba)
        material = mesh_material(name, data.colors is not None)
        mesh.materials.append(material)
        return _replace(context, source, "mesh", name, mesh, [])
    except Exception:
        if material is not None:
            bpy.data.materials.remove(material)
        bpy.data.meshes.remove(mesh)
        raise


# -------------------------------------------------------------------------------------------
# Missing bakes


def missing_bakes(objects):
    """(object, path) for each baked volume among `objects` whose file is not there."""
    missing = []
    for obj in objects:
        if obj.get(BAKE_KIND) in ("volume", "sequence") and obj.type == "VOLUME" and obj.data is not None:
            if obj.data.packed_file is None and not os.path.isfile(bpy.path.abspath(obj.data.filepath)):
                missing.append((obj, obj.data.filepath))
    return missing


OSL_SOURCE = "dqjulia_osl_source"  # custom property of an OSL volume (osl.py): its source object


def renders_nothing(scene_objects, source):
    """True when a DQ Julia object has nothing a renderer shows: no baked volume or mesh among
    its children and no OSL volume (the preview is viewport only)."""
    if any(child.get(BAKE_KIND) for child in source.children):
        return False
    return not any(obj.get(OSL_SOURCE) == source.name for obj in scene_objects)


def unrendered_sources(scene):
    return [
        obj
        for obj in scene.objects
        if getattr(obj, "dqjulia", None) is not None
        and obj.dqjulia.enabled
        and not obj.hide_render
        and renders_nothing(scene.objects, obj)
    ]


@persistent
def _saved_or_opened(*_args):
    _made_since_save.clear()


@persistent
def _report_missing_at_render(scene, *_args):
    """Render log: a baked volume whose file is missing renders empty; say so."""
    for obj, path in missing_bakes(scene.objects):
        print(
            "dqjulia: WARNING: %s renders empty: its bake file %s (%s) is missing; bake it again, or find it "
            "with File > External Data > Find Missing Files" % (obj.name, path, bpy.path.abspath(path)),
            file=sys.stderr,
            flush=True,
        )
    for obj in unrendered_sources(scene):
        print(
            "dqjulia: WARNING: %s renders nothing: the DQ Julia object is drawn in the viewport only; bake a "
            "volume or a mesh (DQ Julia > Bake), or add an OSL volume (Cycles with OSL)" % obj.name,
            file=sys.stderr,
            flush=True,
        )


_HANDLERS = (
    ("save_post", _saved_or_opened),
    ("load_post", _saved_or_opened),
    ("render_init", _report_missing_at_render),
)


def register():
    for name, handler in _HANDLERS:
        getattr(bpy.app.handlers, name).append(handler)
    props.volume_look_changed = apply_volume_look


def unregister():
    props.volume_look_changed = None
    for name, handler in _HANDLERS:
        handlers = getattr(bpy.app.handlers, name)
        if handler in handlers:
            handlers.remove(handler)

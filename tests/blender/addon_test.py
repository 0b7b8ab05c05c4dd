"""The add-on in the real Blender, in background mode:

  blender -b --factory-startup --python-exit-code 1 --python tests/blender/addon_test.py -- \
      --zip build/dist/dqjulia_blender.zip --work DIR --examples examples

Installs the zip as a user would, then: the library loads and its version is checked (and a
missing or mismatched library is explained, not a crash); parameters on the object, validated
by the core; presets; import/export round trips of the CLI's parameter files, keyframes
included; the Python slice against the core's; Bake Volume, Bake Mesh and Bake Sequence run
synchronously and their objects, grids, counts and files are checked; a cancelled or failed
bake leaves nothing behind; a bake in a worker thread leaves the main thread free; the OSL
volume says why it is unavailable on a Blender without OSL.
"""

import array
import json
import os
import sys
import time

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common  # noqa: E402
from common import check, report  # noqa: E402

ARGS = common.arguments()
CACHE = os.path.join(ARGS.work, "cache")
dqjulia = common.install_addon(ARGS.zip, CACHE)
from dqjulia import animation, bakes, jobs, native, osl, preview, props, slicing  # noqa: E402

ADDON_DIR = os.path.dirname(dqjulia.__file__)
EXAMPLES = ARGS.examples or os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "examples")


def files_under(folder):
    result = set()
    for root, _dirs, names in os.walk(folder):
        result |= {os.path.join(root, name) for name in names}
    return result


def new_dqjulia(preset=""):
    result = bpy.ops.object.dqjulia_add(preset=preset)
    check(result == {"FINISHED"}, "Add DQ Julia%s" % (" (%s)" % preset if preset else ""))
    return bpy.context.view_layer.objects.active


def core_document(path=None):
    with native.Context() as context:
        if path:
            context.load_params_file(path)
        return context.params()


# -------------------------------------------------------------------------------------------
report("== the library")
check(native.load_error() is None, "the native library loads: %s" % native.load_error())
number, text = native.version()
check(number == native.EXPECTED_VERSION, "library version %s is the one the add-on expects (%s)"
      % (text, native.version_text(native.EXPECTED_VERSION)))
check(native.library_path().startswith(ADDON_DIR) and os.path.isfile(native.library_path())
      and not os.path.islink(native.library_path()), "the library is a real file inside the installed add-on")
for name in ("dqj_bake_vdb", "dqj_mesh_compute", "dqj_mesh_get_sizes", "dqj_mesh_copy"):
    check(native.has(name), "the library has %s" % name)

report("== the cache folder")
default_root = bakes.default_cache_root()
check(os.path.commonpath([os.path.abspath(default_root), ADDON_DIR]) != ADDON_DIR,
      "the default cache folder %s is outside the add-on's folder" % default_root)
check(bakes.cache_root() == os.path.abspath(CACHE), "the preferences' cache folder is used")

report("== a missing or mismatched library is explained")
saved_expected = native.EXPECTED_VERSION
os.environ[native.LIBRARY_ENV] = os.path.join(ARGS.work, "no-such-libdqjulia.so")
native.reset()
preview.clear_cache()
message = native.load_error() or ""
check("missing" in message and "reinstall" in message, "missing library: %r" % message[:120])
result, error = common.call(bpy.ops.object.dqjulia_add)
check(result == {"CANCELLED"} and "missing" in error, "Add DQ Julia is refused, saying why")
del os.environ[native.LIBRARY_ENV]
native.EXPECTED_VERSION = (saved_expected // 10000 + 1) * 10000
native.reset()
message = native.load_error() or ""
check("version" in message and native.version_text(native.EXPECTED_VERSION) in message,
      "wrong version: %r" % message[:160])
native.EXPECTED_VERSION = saved_expected
native.reset()
check(native.load_error() is None, "the right library loads again")

report("== parameters on the object")
for obj in list(bpy.data.objects):
    bpy.data.objects.remove(obj)
obj = new_dqjulia()
defaults = core_document()
mine = core_document()
with native.Context() as context:
    context.set_params(props.to_document(obj.dqjulia))
    mine = context.params()
defaults.pop("output", None)
mine.pop("output", None)
check(mine == defaults, "a new object holds the core's defaults (every key of the parameter file)")
state = preview.state_for(obj)
check(state.error is None and state.bounds is not None, "its parameters validate; bounds %s" % (state.bounds,))
check(abs(obj.empty_display_size - state.bounds[1]) < 1e-5, "the empty shows the bounds' radius")
obj.dqjulia.bailout = 1.2
state = preview.state_for(obj)
check(state.error is not None and "fractal.bailout" in state.error,
      "an invalid value is reported with the core's message: %r" % (state.error or "")[:100])
obj.dqjulia.bailout = 4.0
check(preview.state_for(obj).error is None, "and the valid value clears it")

report("== presets, import and export")
presets = sorted(name[:-5] for name in os.listdir(os.path.join(ADDON_DIR, "presets")) if name.endswith(".json"))
examples = sorted(name[:-5] for name in os.listdir(EXAMPLES) if name.endswith(".json"))
check(presets == examples, "the zip ships every example as a preset (%d)" % len(presets))
result = bpy.ops.dqjulia.load_preset(preset="paper-test2-1")
check(result == {"FINISHED"}, "load preset paper-test2-1")
state = preview.state_for(obj)
check("escapes" in state.empty_reason and not state.drawable,
      "the empty slice of paper-test2-1 is explained: %r" % state.empty_reason[:90])
def without_animated_base_values(document):
    """A keyframed value's own entry is overridden by its track at every frame (the file's
    base value and Blender's current value may differ): compare the tracks, not those."""
    animated = document.get("animation") or {}
    for key in animated:
        if key.startswith("fractal."):
            document["fractal"].pop(key.split(".")[1], None)
        elif key.startswith("slice.rotations["):
            index = int(key[len("slice.rotations["):].split("]")[0])
            document["slice"]["rotations"][index].pop("degrees", None)
    return document


for name in examples:
    path = os.path.join(EXAMPLES, name + ".json")
    result = bpy.ops.dqjulia.import_params(filepath=path)
    exported = os.path.join(ARGS.work, "export-%s.json" % name)
    result2 = bpy.ops.dqjulia.export_params(filepath=exported)
    expected = without_animated_base_values(core_document(path))
    got = without_animated_base_values(core_document(exported))
    check(result == result2 == {"FINISHED"} and got == expected,
          "%s: import then export gives the same document" % name)
with open(os.path.join(ARGS.work, "bad.json"), "w") as file:
    file.write('{"fractal": {"iteratons": 8}}')
result, error = common.call(bpy.ops.dqjulia.import_params, filepath=os.path.join(ARGS.work, "bad.json"))
check(result == {"CANCELLED"} and "did you mean" in error, "a bad file is refused with the core's message: %s"
      % error[:110])

report("== the slice: Python's rotations against the core's")
obj.dqjulia.axes_mode = "NAMES"
obj.dqjulia.axis_x, obj.dqjulia.axis_y, obj.dqjulia.axis_z = "a.i", "a.j", "b.s"
obj.dqjulia.origin = (0.1, 0, 0, 0.05, 0, 0.02, 0, 0)
obj.dqjulia.rotations.clear()
for first, second, degrees in (("a.j", "b.s", 30.0), ("a.s", "b.i", -20.0)):
    rotation = obj.dqjulia.rotations.add()
    rotation.first, rotation.second, rotation.degrees = first, second, degrees
document = props.to_document(obj.dqjulia)
origin, axes = slicing.effective_slice(document)
points = [(-1.2, 0.3, 0.7), (0.0, 0.0, 0.0), (0.5, -0.9, -0.4), (1.1, 1.0, 0.2)]
with native.Context(document) as context:
    through_core = context.evaluate_slice_points(points)
    through_python = context.evaluate_points([slicing.map_point(origin, axes, p) for p in points])
worst = max(abs(a.de - b.de) / max(1e-300, abs(a.de)) if a.de else abs(b.de)
            for a, b in zip(through_core, through_python))
check(all(a.n == b.n for a, b in zip(through_core, through_python)) and worst < 1e-6,
      "same escape counts and DE (max relative difference %.2g)" % worst)
largest, smallest = slicing.stretch(axes)
check(abs(largest - 1.0) < 1e-6 and abs(smallest - 1.0) < 1e-6, "rotations keep the stretch 1")

report("== keyframes <-> the file's animation")
obj = new_dqjulia()
s = obj.dqjulia
s.bake_resolution = 40
rotation = s.rotations.add()
rotation.first, rotation.second, rotation.degrees = "a.j", "a.k", 0.0
s.iterations = 8
obj.keyframe_insert("dqjulia.iterations", frame=1)
obj.keyframe_insert("dqjulia.rotations[0].degrees", frame=1)
s.iterations = 14
rotation.degrees = 60.0
obj.keyframe_insert("dqjulia.iterations", frame=3)
obj.keyframe_insert("dqjulia.rotations[0].degrees", frame=3)
obj.keyframe_insert("dqjulia.c_a", frame=1)
s.c_a[0] = -0.3
obj.keyframe_insert("dqjulia.c_a", frame=3)
path = os.path.join(ARGS.work, "animated.json")
result = bpy.ops.dqjulia.export_params(filepath=path)
with open(path) as file:
    section = json.load(file)["animation"]
check(sorted(section) == ["fractal.c", "fractal.iterations", "slice.rotations[0].degrees"],
      "export writes the animation tracks: %s" % sorted(section))
check([key["value"] for key in section["fractal.iterations"]] == [8, 14], "iterations keys 8 -> 14")
other = new_dqjulia()
bpy.ops.dqjulia.import_params(filepath=path)
curves = sorted({curve.data_path for curve in animation.dqjulia_fcurves(other)})
check(curves == ["dqjulia.c_a", "dqjulia.c_b", "dqjulia.iterations", "dqjulia.rotations[0].degrees"],
      "import makes F-curves: %s" % curves)
documents = animation.frame_documents(other, bpy.context.scene, [1, 2, 3])
check([d["fractal"]["iterations"] for d in documents][::2] == [8, 14]
      and abs(documents[2]["slice"]["rotations"][0]["degrees"] - 60.0) < 1e-4,
      "each frame's values come from the keyframes (iterations %s)" % [d["fractal"]["iterations"] for d in documents])
bpy.data.objects.remove(other)

report("== Bake Volume (synchronous)")
bpy.context.view_layer.objects.active = obj
obj.select_set(True)
bpy.context.scene.frame_set(1)
objects_before = set(bpy.data.objects.keys())
result = bpy.ops.dqjulia.bake_volume(synchronous=True)
check(result == {"FINISHED"}, "Bake Volume finished")
volume = next((child for child in obj.children if child.get(bakes.BAKE_KIND) == "volume"), None)
check(volume is not None and volume.type == "VOLUME" and volume.parent == obj, "a Volume object, child of the source")
first_file = None
if volume is not None:
    first_file = volume.data.filepath
    check(os.path.isfile(first_file) and first_file.startswith(CACHE) and not first_file.startswith(ADDON_DIR),
          "its VDB is in the cache folder: %s" % first_file)
    volume.data.grids.load()
    names = sorted(grid.name for grid in volume.data.grids)
    check("density" in names and "surface" in names, "grids %s include density and surface" % names)
    material = volume.data.materials[0] if volume.data.materials else None
    node = material and next((n for n in material.node_tree.nodes if n.type == "PRINCIPLED_VOLUME"), None)
    check(node is not None and node.inputs["Density Attribute"].default_value == "density",
          "a Principled Volume material reads the density grid")
    check(volume.matrix_world == obj.matrix_world, "the volume sits in the source's frame")
result = bpy.ops.dqjulia.bake_volume(synchronous=True)
again = next((child for child in obj.children if child.get(bakes.BAKE_KIND) == "volume"), None)
check(result == {"FINISHED"} and again == volume and again.data.filepath != first_file
      and not os.path.exists(first_file or ""), "a second bake replaces the first (object kept, old file removed)")

report("== Bake Mesh (synchronous)")
s.bake_resolution = 48
result = bpy.ops.dqjulia.bake_mesh(synchronous=True)
check(result == {"FINISHED"}, "Bake Mesh finished")
mesh_object = next((child for child in obj.children if child.get(bakes.BAKE_KIND) == "mesh"), None)
check(mesh_object is not None and mesh_object.type == "MESH", "a mesh object, child of the source")
if mesh_object is not None:
    mesh = mesh_object.data
    with native.Context(props.to_document(s)) as context:
        context.mesh_compute()
        vertex_count, triangle_count = context.mesh_sizes()
        positions, normals, _colors, _triangles = context.mesh_copy()
    check(len(mesh.vertices) == vertex_count > 100 and len(mesh.polygons) == triangle_count > 100,
          "%d vertices and %d triangles, as the core's mesh" % (len(mesh.vertices), len(mesh.polygons)))
    check(all(len(p.vertices) == 3 for p in mesh.polygons[:1000]), "all faces are triangles")
    check(mesh.has_custom_normals, "it carries the core's normals (custom split normals)")
    if hasattr(mesh, "calc_normals_split"):
        mesh.calc_normals_split()
    loop_normals = array.array("f", [0.0]) * (3 * len(mesh.loops))
    mesh.loops.foreach_get("normal", loop_normals)
    loop_vertices = array.array("i", [0]) * len(mesh.loops)
    mesh.loops.foreach_get("vertex_index", loop_vertices)
    worst = 1.0
    for loop in range(0, len(mesh.loops), 7):
        v = loop_vertices[loop]
        dot = sum(loop_normals[3 * loop + k] * normals[3 * v + k] for k in range(3))
        worst = min(worst, dot)
    check(worst > 0.99, "loop normals follow the core's normals (worst cosine %.4f)" % worst)
    check("Col" in mesh.color_attributes, "vertex colours from the material's colouring")
    co = array.array("f", [0.0]) * (3 * len(mesh.vertices))
    mesh.vertices.foreach_get("co", co)
    check(max(abs(a - b) for a, b in zip(co, positions)) < 1e-6, "positions are the core's")

report("== Bake Sequence (synchronous)")
scene = bpy.context.scene
scene.frame_start, scene.frame_end = 1, 3
s.bake_resolution = 40
result = bpy.ops.dqjulia.bake_sequence(synchronous=True)
check(result == {"FINISHED"}, "Bake Sequence finished")
sequence = next((child for child in obj.children if child.get(bakes.BAKE_KIND) == "sequence"), None)
check(sequence is not None and sequence.data.is_sequence and sequence.data.frame_duration == 3,
      "a Volume sequence of 3 frames")
if sequence is not None:
    folder = os.path.dirname(sequence.data.filepath)
    names = sorted(os.listdir(folder))
    check(len(names) == 3 and all(n.endswith("_%04d.vdb" % f) for n, f in zip(names, (1, 2, 3))),
          "files name_0001.vdb ... name_0003.vdb: %s" % names)
    sizes = []
    for frame in (1, 2, 3):
        scene.frame_set(frame)
        grids = sequence.evaluated_get(bpy.context.evaluated_depsgraph_get()).data.grids
        grids.load()
        check(grids.frame == frame and grids.frame_filepath.endswith("_%04d.vdb" % frame)
              and "density" in [grid.name for grid in grids],
              "frame %d plays %s" % (frame, os.path.basename(grids.frame_filepath)))
        sizes.append(os.path.getsize(grids.frame_filepath))
    check(len(set(sizes)) > 1, "the frames differ (keyframed iterations and rotation): sizes %s" % sizes)

report("== a cancelled or failed bake leaves nothing")
objects_before = set(bpy.data.objects.keys())
files_before = files_under(CACHE)
document = props.to_document(s)
job = jobs.Job("test", [jobs.VolumeTask(document, os.path.join(CACHE, "cancelled.vdb"))])
job.cancel()
check(job.run() == jobs.Job.CANCELLED, "a job cancelled before it starts reports cancelled")
s.bake_resolution = 640  # long enough to watch on a fast machine; cancelled half-way
document = props.to_document(s)
job = jobs.Job("threaded", [jobs.VolumeTask(document, os.path.join(CACHE, "threaded.vdb"))])
job.start()
loops, fractions, started = 0, set(), time.monotonic()
while not job.finished_running:
    loops += 1  # the main thread keeps running Python while the worker bakes
    fractions.add(round(job.fraction, 3))
    if job.fraction > 0.5 and not job.cancel_requested:
        cancelled_at = time.monotonic()
        job.cancel()
    time.sleep(0.01)
job.join()
check(job.state == jobs.Job.CANCELLED, "a threaded bake cancelled at %.0f%% stops (%.2f s after cancel)"
      % (100 * max(fractions), job.finished - cancelled_at) if job.cancel_requested else "never cancelled")
check(loops > 10 and len(fractions) >= 3,  # at least 0, one fraction in between, and > 50 %
      "the main thread ran %d loops meanwhile and saw %d progress values"
      % (loops, len(fractions)))
check(files_under(CACHE) == files_before and set(bpy.data.objects.keys()) == objects_before,
      "no file and no object remain")
prefs = bpy.context.preferences.addons["dqjulia"].preferences
blocker = os.path.join(ARGS.work, "not-a-folder")
with open(blocker, "w") as file:
    file.write("x")
prefs.cache_dir = blocker
s.bake_resolution = 32
result, error = common.call(bpy.ops.dqjulia.bake_volume, synchronous=True)
check(result == {"CANCELLED"} and error, "a bake into an unusable folder fails, saying why: %s" % error[:110])
check(set(bpy.data.objects.keys()) == objects_before, "and adds no object")
prefs.cache_dir = CACHE

report("== OSL")
check(osl.available() == bool(bpy.app.build_options.cycles_osl), "OSL availability follows the build")
if not osl.available():
    result, error = common.call(bpy.ops.dqjulia.add_osl_volume)
    check(result == {"CANCELLED"} and "without Open Shading Language" in error,
          "Add OSL Volume says why it cannot run: %s" % error[:80])
result = bpy.ops.dqjulia.open_osl_text()
check(result == {"FINISHED"} and "shader dqjulia_density" in bpy.data.texts[osl.TEXT_NAME].as_string(),
      "the OSL script is available as a text block")

report("== disable")
result = bpy.ops.preferences.addon_disable(module="dqjulia")
check(result == {"FINISHED"} and not hasattr(bpy.types.Object, "dqjulia"), "the add-on unregisters cleanly")
common.finish()

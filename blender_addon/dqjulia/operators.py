"""Operators: add a DQ Julia object, presets, import/export of parameter files, the bakes
(volume, mesh, sequence) and the OSL volume.

Bakes are modal: the work runs in a worker thread (jobs.py), a window-manager timer polls it,
the cursor and the status bar show progress, Esc cancels. Scripts and tests get the same work
synchronously with `synchronous=True` (automatic in background mode, where there are no
events); the objects are built the same way in both paths.
"""

import json
import math
import os
import tempfile
import time

import bpy
from bpy.props import BoolProperty, EnumProperty, StringProperty
from bpy_extras.io_utils import ExportHelper, ImportHelper

from . import animation, bakes, core_state, jobs, native, osl, props
from .modal_job import ModalJob

PRESET_DIR = os.path.join(os.path.dirname(os.path.abspath(__file__)), "presets")


def dqjulia_object(context):
    obj = getattr(context, "object", None) or getattr(context, "active_object", None)
    if obj is not None and getattr(obj, "dqjulia", None) is not None and obj.dqjulia.enabled:
        return obj
    return None


def preset_names():
    if not os.path.isdir(PRESET_DIR):
        return []
    return sorted(os.path.splitext(name)[0] for name in os.listdir(PRESET_DIR) if name.endswith(".json"))


# Blender keeps only pointers to the strings a dynamic EnumProperty's items callback returns:
# Python must keep them alive, or menus show garbage or crash (bpy.props.EnumProperty's docs).
# The list is made once per set of preset files and kept here.
_PRESET_ITEMS = {"names": None, "items": [("", "(no presets)", "")]}


def _preset_items(_self, _context):
    names = tuple(preset_names())
    if names != _PRESET_ITEMS["names"]:
        _PRESET_ITEMS["names"] = names
        _PRESET_ITEMS["items"] = [(name, name, "examples/%s.json" % name) for name in names] or [
            ("", "(no presets)", "")
        ]
    return _PRESET_ITEMS["items"]


def load_params_into(obj, path):
    """Reads a parameter file through the core (which validates it) into the object's
    properties, keyframes included. Raises native.NativeError with the core's message."""
    with native.Context() as context:
        context.load_params_file(path)
        document = context.params()
    props.from_document(obj.dqjulia, document)
    animation.apply_section(obj, document.get("animation") or {})
    return document


def document_for_file(obj):
    """The object's complete document, keyframes included, as the core writes it (validated);
    and the names of animated properties the file cannot hold."""
    section, skipped = animation.animation_section(obj)
    document = props.to_document(obj.dqjulia, with_animation=section)
    with native.Context() as context:
        context.set_params(document)
        return context.params_json(), skipped


def write_text_atomically(path, text):
    directory = os.path.dirname(os.path.abspath(path))
    os.makedirs(directory, exist_ok=True)
    handle, temporary = tempfile.mkstemp(prefix=".dqjulia-", suffix=".json", dir=directory)
    try:
        with os.fdopen(handle, "w", encoding="utf-8") as file:
            file.write(text)
        os.replace(temporary, path)
    except BaseException:
        if os.path.exists(temporary):
            os.remove(temporary)
        raise


def _library_ready(operator):
    error = native.load_error()
    if error is not None:
        operator.report({"ERROR"}, error)
        return False
    return True


def _read_params(operator, context, path, done_message):
    """Reads a parameter file into the active DQ Julia object; a bad file is reported, not raised."""
    if not _library_ready(operator):
        return {"CANCELLED"}
    try:
        load_params_into(dqjulia_object(context), path)
    except (native.NativeError, OSError) as error:
        operator.report({"ERROR"}, str(error))
        return {"CANCELLED"}
    operator.report({"INFO"}, done_message)
    return {"FINISHED"}


class _NeedsDQJuliaObject:
    """For operators that act on the active DQ Julia object: unavailable without one."""

    @classmethod
    def poll(cls, context):
        return dqjulia_object(context) is not None


# The one orientation convention: the slice's y is up, as in `dqjulia render`'s pictures, the
# paper's figures and the files the command writes (OBJ, PLY, VDB: y-up, as Houdini's). Blender
# is z-up, so a new DQ Julia object is turned +90 degrees about x: its local (x, y, z) = the
# slice's, and the slice's y lies along Blender's Z. Preview, baked volumes and meshes and the OSL
# volume all sit in the object's frame, so they share it.
SLICE_TO_BLENDER_ROTATION = (math.pi / 2.0, 0.0, 0.0)


def new_object(name, path=""):
    """A new DQ Julia object (an empty showing the set's bounds, turned so the slice's y is up),
    in no collection yet: the parameter file at `path`, or the core's defaults. Raises
    native.NativeError (a bad file, with the core's message) or OSError, leaving nothing."""
    obj = bpy.data.objects.new(name, None)
    obj.empty_display_type = "SPHERE"
    obj.rotation_euler = SLICE_TO_BLENDER_ROTATION
    try:
        obj.dqjulia.enabled = True
        if path:
            load_params_into(obj, path)
        else:
            with native.Context() as native_context:  # the core's defaults, so they never drift
                props.from_document(obj.dqjulia, native_context.params())
    except BaseException:
        action = obj.animation_data.action if obj.animation_data else None
        bpy.data.objects.remove(obj)
        if action is not None and action.users == 0:
            bpy.data.actions.remove(action)
        raise
    state = core_state.state_for(obj)
    if state.bounds is not None:
        obj.empty_display_size = state.bounds[1]
    return obj


class DQJULIA_OT_add(bpy.types.Operator):
    """Add a DQ Julia object: the set ray-marched in the viewport inside its bounds"""

    bl_idname = "object.dqjulia_add"
    bl_label = "DQ Julia"
    bl_options = {"REGISTER", "UNDO"}

    preset: StringProperty(name="Preset", default="", description="A preset name or a parameter file to start from")

    def execute(self, context):
        if not _library_ready(self):
            return {"CANCELLED"}
        if context.mode != "OBJECT" and bpy.ops.object.mode_set.poll():
            bpy.ops.object.mode_set(mode="OBJECT")
        try:
            path = ""
            if self.preset:
                path = self.preset if os.path.isfile(self.preset) else os.path.join(PRESET_DIR, self.preset + ".json")
            obj = new_object("DQ Julia", path)
        except (native.NativeError, native.NativeUnavailable, OSError) as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        obj.location = context.scene.cursor.location
        context.collection.objects.link(obj)
        for other in context.selected_objects:
            other.select_set(False)
        obj.select_set(True)
        context.view_layer.objects.active = obj
        return {"FINISHED"}


class DQJULIA_OT_load_preset(_NeedsDQJuliaObject, bpy.types.Operator):
    """Load one of the example parameter files into the active DQ Julia object"""

    bl_idname = "dqjulia.load_preset"
    bl_label = "Load Preset"
    bl_options = {"REGISTER", "UNDO"}

    preset: EnumProperty(name="Preset", items=_preset_items)

    def execute(self, context):
        return _read_params(
            self, context, os.path.join(PRESET_DIR, self.preset + ".json"), "Loaded preset %s" % self.preset
        )


class DQJULIA_OT_import_params(_NeedsDQJuliaObject, bpy.types.Operator, ImportHelper):
    """Read a dqjulia parameter file (the JSON the command-line tool reads) into the active DQ Julia object"""

    bl_idname = "dqjulia.import_params"
    bl_label = "Import Parameters"
    bl_options = {"REGISTER", "UNDO"}

    filename_ext = ".json"
    filter_glob: StringProperty(default="*.json", options={"HIDDEN"})

    def execute(self, context):
        return _read_params(self, context, self.filepath, "Read %s" % self.filepath)


class DQJULIA_OT_export_params(_NeedsDQJuliaObject, bpy.types.Operator, ExportHelper):
    """Write the active DQ Julia object's parameters (and keyframes) as a dqjulia parameter file"""

    bl_idname = "dqjulia.export_params"
    bl_label = "Export Parameters"

    filename_ext = ".json"
    filter_glob: StringProperty(default="*.json", options={"HIDDEN"})

    def execute(self, context):
        if not _library_ready(self):
            return {"CANCELLED"}
        try:
            text, skipped = document_for_file(dqjulia_object(context))
            write_text_atomically(self.filepath, text)
        except (native.NativeError, OSError) as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        if skipped:
            self.report(
                {"WARNING"},
                "Wrote %s; the file cannot hold the keyframes of %s (it animates the constant, "
                "iterations, bailout and rotation angles)" % (self.filepath, ", ".join(skipped)),
            )
        else:
            self.report({"INFO"}, "Wrote %s" % self.filepath)
        return {"FINISHED"}


class DQJULIA_OT_collection_edit(_NeedsDQJuliaObject, bpy.types.Operator):
    """Add or remove an entry of a list (rotations, lights, palette)"""

    bl_idname = "dqjulia.collection_edit"
    bl_label = "Edit List"
    bl_options = {"REGISTER", "UNDO", "INTERNAL"}

    collection: EnumProperty(
        items=[("rotations", "Rotations", ""), ("lights", "Lights", ""), ("palette", "Palette", "")]
    )
    action: EnumProperty(items=[("ADD", "Add", ""), ("REMOVE", "Remove", "")])
    index: bpy.props.IntProperty(default=-1)

    def execute(self, context):
        settings = dqjulia_object(context).dqjulia
        items = getattr(settings, self.collection)
        if self.action == "ADD":
            item = items.add()
            if self.collection == "rotations":
                item.degrees = 30.0
                settings.active_rotation = len(items) - 1
        else:
            index = self.index if self.index >= 0 else len(items) - 1
            if 0 <= index < len(items):
                items.remove(index)
            settings.active_rotation = max(0, min(settings.active_rotation, len(items) - 1))
        props._redraw(None, context)
        return {"FINISHED"}


# -------------------------------------------------------------------------------------------
# Bakes


class _BakeOperator(ModalJob):
    """Shared by the bake operators: make the job, run it (modal_job.py), build the result on
    the main thread."""

    bl_options = {"REGISTER", "UNDO"}

    synchronous: BoolProperty(
        name="Synchronous",
        default=False,
        options={"SKIP_SAVE", "HIDDEN"},
        description="Bake in the calling thread and return when done (scripts, tests)",
    )

    _source_name = ""
    _cleanup = ()

    @classmethod
    def poll(cls, context):
        return dqjulia_object(context) is not None and not jobs.active_jobs(dqjulia_object(context).name)

    # to override ------------------------------------------------------------------------
    def make_job(self, context, obj):
        raise NotImplementedError

    def build(self, context, obj, job):
        raise NotImplementedError

    # -------------------------------------------------------------------------------------
    def _check_document(self, document):
        with native.Context() as context:
            context.set_params(document)

    def execute(self, context):
        if not _library_ready(self):
            return {"CANCELLED"}
        if not native.has("dqj_bake_vdb"):
            self.report(
                {"ERROR"},
                "the dqjulia library %s cannot bake (no dqj_bake_vdb): install the add-on zip "
                "from a build with OpenVDB baking" % native.version()[1],
            )
            return {"CANCELLED"}
        obj = dqjulia_object(context)
        try:
            job = self.make_job(context, obj)
        except (native.NativeError, ValueError, OSError) as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        self._source_name = obj.name
        return self.run_job(context, job)

    def invoke(self, context, _event):
        return self.execute(context)

    def job_started(self, context):
        context.window_manager.progress_begin(0, 100)
        self._status(context, self._job.status_text() + " (Esc to cancel)")

    def job_ticked(self, context):
        job = self._job
        context.window_manager.progress_update(int(100 * job.fraction))
        if job.cancel_requested:
            self._status(context, "%s: cancelling..." % job.label)
        else:
            self._status(context, job.status_text() + " (Esc to cancel)")
        _redraw_progress(context)

    def job_ended(self, context):
        context.window_manager.progress_end()
        self._status(context, None)

    def job_closed(self, _context):
        bakes.remove_files(self._cleanup)

    @staticmethod
    def _status(context, text):
        workspace = getattr(context, "workspace", None)
        if workspace is not None:
            workspace.status_text_set(text)

    def job_finished(self, context):
        job = self._job
        obj = bpy.data.objects.get(self._source_name)
        if job.state == jobs.Job.DONE and obj is None:
            job.state, job.error = jobs.Job.FAILED, "the object %s was deleted during the bake" % self._source_name
        if job.state == jobs.Job.DONE:
            try:
                message = self.build(context, obj, job)
            except Exception as error:
                bakes.remove_files(self._cleanup)
                self.report({"ERROR"}, "%s failed: %s" % (job.label, error))
                return {"CANCELLED"}
            for warning in dict.fromkeys(job.warnings):
                self.report({"WARNING"}, warning)
            self.report({"INFO"}, "%s (%.1f s)" % (message, job.finished - job.started))
            return {"FINISHED"}
        bakes.remove_files(self._cleanup)
        if job.state == jobs.Job.CANCELLED:
            self.report({"WARNING"}, "%s cancelled; nothing was added" % job.label)
        else:
            self.report({"ERROR"}, "%s failed: %s" % (job.label, job.error))
        return {"CANCELLED"}


def _redraw_progress(context):
    """Redraw where the progress text is (the sidebar and the properties), not the 3-D view
    itself: its preview is the expensive part of a redraw."""
    for area in context.screen.areas if context.screen else ():
        if area.type == "PROPERTIES":
            area.tag_redraw()
        elif area.type == "VIEW_3D":
            for region in area.regions:
                if region.type == "UI":
                    region.tag_redraw()


def _bake_document(obj, need_density=False):
    document = props.to_document(obj.dqjulia)
    if need_density and "density" not in document["bake"]["grids"]:
        document["bake"]["grids"].append("density")  # Blender renders the "density" grid
    return document


class DQJULIA_OT_bake_volume(_BakeOperator, bpy.types.Operator):
    """Bake the set at this frame to an OpenVDB file and add a Volume object that renders it"""

    bl_idname = "dqjulia.bake_volume"
    bl_label = "Bake Volume"

    def make_job(self, context, obj):
        document = _bake_document(obj, need_density=True)
        self._check_document(document)
        path = bakes.new_volume_path(obj, context)
        self._cleanup = (path,)
        return jobs.Job("Bake volume", [jobs.VolumeTask(document, path)], owner=obj.name)

    def build(self, context, obj, job):
        path = job.results[0]
        volume = bakes.build_volume(context, obj, path)
        return "Baked %s (%s)" % (volume.name, path)


# A mesh above these asks first (Bake Mesh's dialog): it takes minutes and gigabytes, and Blender
# holds the mesh again once added.
LARGE_MESH_BYTES = 1e9
LARGE_MESH_FACES = 5e6


class DQJULIA_OT_bake_mesh(_BakeOperator, bpy.types.Operator):
    """Mesh the set's surface at this frame and add it as a mesh object with normals and colours"""

    bl_idname = "dqjulia.bake_mesh"
    bl_label = "Bake Mesh"

    _estimate = ""

    def invoke(self, context, _event):
        """The core's estimate first (the classification alone): a mesh that cannot fit is refused
        with the core's reason before any work; a large one asks, showing memory, slabs and faces."""
        obj = dqjulia_object(context)
        if context.window is None or obj is None or native.load_error() or not native.has("dqj_mesh_estimate"):
            return self.execute(context)
        try:
            with native.Context() as core:
                core.set_params(_bake_document(obj))
                size, slabs, faces = core.mesh_estimate()
        except (native.NativeError, native.NativeUnavailable, ValueError, OSError) as error:
            self.report({"ERROR"}, "Bake mesh: %s" % error)
            return {"CANCELLED"}
        self._estimate = jobs.describe_mesh_estimate(size, slabs, faces)
        if slabs <= 1 and size < LARGE_MESH_BYTES and faces < LARGE_MESH_FACES:
            return self.execute(context)
        return context.window_manager.invoke_props_dialog(self, width=460)

    def draw(self, context):
        layout = self.layout
        layout.label(text="Mesh at %d voxels?" % dqjulia_object(context).dqjulia.bake_resolution, icon="QUESTION")
        layout.label(text=self._estimate[:1].upper() + self._estimate[1:])
        layout.label(text="Progress shows in the status bar; Esc cancels at any slab.")

    def make_job(self, context, obj):
        document = _bake_document(obj)
        self._check_document(document)
        self._cleanup = ()
        return jobs.Job("Bake mesh", [jobs.MeshTask(document, colors=obj.dqjulia.bake_mesh_colors)], owner=obj.name)

    def build(self, context, obj, job):
        data = job.results[0]
        if data.face_count == 0:
            raise RuntimeError(
                "the surface has no faces at this resolution%s" % ("; " + job.warnings[0] if job.warnings else "")
            )
        mesh = bakes.build_mesh(context, obj, data)
        return "Baked %s: %d vertices, %d quads, %d triangles" % (
            mesh.name,
            data.vertex_count,
            data.quad_count,
            data.triangle_count,
        )


def estimate_sequence(document, frames, folder):
    """(bytes, seconds) a sequence bake of `frames` frames of `document` will take, from sample
    bakes of its first frame at two small resolutions (the cost grows between the square and the
    cube of the resolution: the fitted power, kept in [2, 3], carries it to the full one)."""
    resolution = document["bake"]["resolution"]
    samples = sorted({min(resolution, 24), min(resolution, 48)})
    measured = []
    os.makedirs(folder, exist_ok=True)
    with native.Context() as context:
        for index, sample in enumerate(samples):
            probe = json.loads(json.dumps(document))
            probe["bake"]["resolution"] = sample
            context.set_params(probe)
            path = os.path.join(folder, "estimate-%d.vdb" % index)
            started = time.monotonic()
            try:
                context.bake_vdb(path)
                measured.append((sample, os.path.getsize(path), time.monotonic() - started))
            finally:
                bakes.remove_files([path])
    if len(measured) == 1:
        _sample, size, seconds = measured[0]
        return size * len(frames), seconds * len(frames)
    (r1, s1, t1), (r2, s2, t2) = measured
    scale = resolution / r2

    def extrapolate(low, high):
        power = max(2.0, min(3.0, math.log(max(high, 1e-9) / max(low, 1e-9)) / math.log(r2 / r1)))
        return high * scale**power

    return extrapolate(s1, s2) * len(frames), extrapolate(t1, t2) * len(frames)


def sequence_tasks(obj, scene, frames, directory):
    """The volume bakes of `frames` as Blender evaluates them (keyframes, drivers), each checked
    by the core, into `directory`/NAME_0001.vdb, ... (Bake Sequence's, and farm.py's)."""
    documents = animation.frame_documents(obj, scene, frames)
    for frame, document in zip(frames, documents):
        if "density" not in document["bake"]["grids"]:
            document["bake"]["grids"].append("density")
        try:
            with native.Context() as context:
                context.set_params(document)
        except native.NativeError as error:
            raise ValueError("frame %d: %s" % (frame, error.message)) from None
    return [
        jobs.VolumeTask(document, bakes.sequence_frame_path(directory, obj, frame), frame=frame)
        for frame, document in zip(frames, documents)
    ]


class DQJULIA_OT_bake_sequence(_BakeOperator, bpy.types.Operator):
    """Bake a volume for every frame of the scene's frame range (the keyframed values of each frame) and add a Volume object that plays them back"""

    bl_idname = "dqjulia.bake_sequence"
    bl_label = "Bake Sequence"

    _estimate = ""

    def invoke(self, context, _event):
        """Asks first: the frame count, and the disk space and time a quick sample predicts."""
        obj = dqjulia_object(context)
        scene = context.scene
        frames = list(range(scene.frame_start, scene.frame_end + 1))
        if context.window is None or not frames or obj is None:
            return self.execute(context)
        try:
            folder = os.path.join(bakes.cache_root(context), ".estimate")
            size, seconds = estimate_sequence(_bake_document(obj, need_density=True), frames, folder)
        except (native.NativeError, native.NativeUnavailable, ValueError, OSError) as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        self._estimate = "%d frames (%d-%d) at %d voxels: about %s on disk and %s" % (
            len(frames),
            frames[0],
            frames[-1],
            obj.dqjulia.bake_resolution,
            jobs.format_bytes(size),
            jobs.format_duration(seconds),
        )
        return context.window_manager.invoke_props_dialog(self, width=420)

    def draw(self, _context):
        layout = self.layout
        layout.label(text="Bake a volume for every frame?", icon="QUESTION")
        layout.label(text=self._estimate)
        layout.label(text="(estimated from sample bakes of the first frame)")

    def make_job(self, context, obj):
        scene = context.scene
        frames = list(range(scene.frame_start, scene.frame_end + 1))
        if not frames:
            raise ValueError("the scene's frame range is empty")
        directory = bakes.new_sequence_dir(obj, context)
        self._cleanup = (directory,)
        self._frames = frames
        self._directory = directory
        return jobs.Job("Bake sequence", sequence_tasks(obj, scene, frames, directory), owner=obj.name)

    def build(self, context, obj, job):
        frames = self._frames
        volume = bakes.build_volume(context, obj, job.results[0], sequence=(frames[0], len(frames), self._directory))
        return "Baked %s: frames %d-%d in %s" % (volume.name, frames[0], frames[-1], self._directory)


class DQJULIA_OT_cancel_bakes(bpy.types.Operator):
    """Cancel the running bakes (same as Esc)"""

    bl_idname = "dqjulia.cancel_bakes"
    bl_label = "Cancel Bakes"

    def execute(self, _context):
        jobs.cancel_all()
        return {"FINISHED"}


class DQJULIA_OT_add_osl_volume(_NeedsDQJuliaObject, bpy.types.Operator):
    """Add a cube over the bounds with a Cycles OSL volume material that computes the set while rendering (needs a Blender built with OSL)"""

    bl_idname = "dqjulia.add_osl_volume"
    bl_label = "Add OSL Volume"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context):
        if not osl.available():
            self.report({"ERROR"}, osl.UNAVAILABLE_MESSAGE)
            return {"CANCELLED"}
        try:
            obj = osl.add_volume(context, dqjulia_object(context))
        except (RuntimeError, native.NativeError) as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        self.report({"INFO"}, "Added %s (render with Cycles, Open Shading Language on)" % obj.name)
        return {"FINISHED"}


class DQJULIA_OT_open_osl_text(bpy.types.Operator):
    """Load the OSL shader source into a text block (to read, or to use on a Blender with OSL)"""

    bl_idname = "dqjulia.open_osl_text"
    bl_label = "OSL Script to Text"

    def execute(self, _context):
        text = osl.shader_text()
        self.report({"INFO"}, "The OSL source is in the text block %s" % text.name)
        return {"FINISHED"}


CLASSES = (
    DQJULIA_OT_add,
    DQJULIA_OT_load_preset,
    DQJULIA_OT_import_params,
    DQJULIA_OT_export_params,
    DQJULIA_OT_collection_edit,
    DQJULIA_OT_bake_volume,
    DQJULIA_OT_bake_mesh,
    DQJULIA_OT_bake_sequence,
    DQJULIA_OT_cancel_bakes,
    DQJULIA_OT_add_osl_volume,
    DQJULIA_OT_open_osl_text,
)


def menu_add(self, _context):
    self.layout.operator(DQJULIA_OT_add.bl_idname, text="DQ Julia", icon="OUTLINER_OB_VOLUME")


def register():
    for cls in CLASSES:
        bpy.utils.register_class(cls)
    bpy.types.VIEW3D_MT_add.append(menu_add)


def unregister():
    bpy.types.VIEW3D_MT_add.remove(menu_add)
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)

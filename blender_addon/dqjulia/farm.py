"""Farm bakes: an object's volume sequence baked from a saved .blend by a render farm's Blender
tasks, headless and blocking, many machines at once:

  blender -b scene.blend --addons dqjulia --python-exit-code 1 \\
      --python-expr "import bpy; bpy.ops.dqjulia.farm_bake(object='DQ Julia', frame_start=1, frame_end=24)"

(in Blender 4.2+ the add-on is the extension bl_ext.user_default.dqjulia, enabled in the farm's
user preferences). Every task writes into one folder, the object's cache folder's
NAME_farm/ (or `directory`), as NAME_0001.vdb, ..., and skips the frames whose file exists (a
file gets its name only when complete), so chunks of a range run on many machines and a task
run again redoes only what is missing. Tasks change nothing in the .blend; a last one with
attach=True adds the Volume object that plays the scene's frame range and saves the .blend.
The frames' values and the bakes are Bake Sequence's (operators.sequence_tasks, jobs.Job.run).
A failure is an error report, which bpy.ops raises as RuntimeError: Blender then exits 1 with
--python-exit-code 1. Cost: the bakes; the tasks share nothing but the folder.
"""

import os

import bpy
from bpy.props import BoolProperty, IntProperty, StringProperty

from . import bakes, jobs, native, operators


def farm_dir(obj, context=None):
    """The folder farm tasks of `obj` share: NAME_farm/ in the object's cache folder."""
    return os.path.join(bakes.object_cache_dir(obj, context), "%s_farm" % bakes._safe(obj.name))


class DQJULIA_OT_farm_bake(bpy.types.Operator):
    """Bake frames of a DQ Julia object's sequence into a shared folder, blocking (farm tasks; skips finished ones)"""

    bl_idname = "dqjulia.farm_bake"
    bl_label = "Farm Bake"
    bl_options = {"REGISTER"}

    object: StringProperty(name="Object", default="", description="The DQ Julia object (default: the active one)")
    frame_start: IntProperty(name="First frame", default=-1, description="Default (-1): the scene's first frame")
    frame_end: IntProperty(name="Last frame", default=-1, description="Default (-1): the scene's last frame")
    directory: StringProperty(
        name="Folder", default="", subtype="DIR_PATH", description="Default: NAME_farm/ in the object's cache folder"
    )
    skip_existing: BoolProperty(name="Skip existing", default=True, description="Keep the frames whose file exists")
    attach: BoolProperty(
        name="Attach",
        default=False,
        description="After baking, add the Volume object that plays the scene's frame range and save the .blend",
    )

    def execute(self, context):
        error = native.load_error()
        if error is not None:
            self.report({"ERROR"}, error)
            return {"CANCELLED"}
        obj = bpy.data.objects.get(self.object) if self.object else operators.dqjulia_object(context)
        if obj is None or getattr(obj, "dqjulia", None) is None or not obj.dqjulia.enabled:
            self.report({"ERROR"}, "no DQ Julia object %s" % repr(self.object) if self.object else "no DQ Julia object")
            return {"CANCELLED"}
        scene = context.scene
        first = scene.frame_start if self.frame_start < 0 else self.frame_start
        last = scene.frame_end if self.frame_end < 0 else self.frame_end
        try:
            directory = os.path.abspath(bpy.path.abspath(self.directory)) if self.directory else farm_dir(obj, context)
            frames = [
                frame
                for frame in range(first, last + 1)
                if not (self.skip_existing and os.path.isfile(bakes.sequence_frame_path(directory, obj, frame)))
            ]
            job = jobs.Job("Farm bake", operators.sequence_tasks(obj, scene, frames, directory), owner=obj.name)
        except (native.NativeError, ValueError, OSError) as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        if job.run() != jobs.Job.DONE:
            self.report({"ERROR"}, "Farm bake of %s failed: %s" % (obj.name, job.error))
            return {"CANCELLED"}
        message = "Baked %d of frames %d-%d of %s into %s" % (len(frames), first, last, obj.name, directory)
        if self.attach:
            whole = range(scene.frame_start, scene.frame_end + 1)
            missing = [f for f in whole if not os.path.isfile(bakes.sequence_frame_path(directory, obj, f))]
            if missing or not whole:
                self.report({"ERROR"}, "cannot attach %s: frames %s are not baked" % (directory, missing or "(none)"))
                return {"CANCELLED"}
            try:
                path = bakes.sequence_frame_path(directory, obj, whole[0])
                volume = bakes.build_volume(context, obj, path, sequence=(whole[0], len(whole), directory))
            except RuntimeError as error:
                self.report({"ERROR"}, str(error))
                return {"CANCELLED"}
            bpy.ops.wm.save_mainfile()
            message += "; %s plays frames %d-%d, saved %s" % (volume.name, whole[0], whole[-1], bpy.data.filepath)
        print("dqjulia: %s" % message, flush=True)  # the farm task's log
        self.report({"INFO"}, message)
        return {"FINISHED"}


CLASSES = (DQJULIA_OT_farm_bake,)
register, unregister = bpy.utils.register_classes_factory(CLASSES)

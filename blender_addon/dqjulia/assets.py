"""Keep what you find: DQ Julia objects as Blender assets, and the shipped presets as an asset
library.

Mark as Asset (mark()) makes the object an asset (Blender's ID.asset_mark) with its metadata (a
description: the parameters' own, else one of the values; one typed in the Asset Browser is
kept; the tags "DQ Julia", the variant and the colouring) and its preview: the library's
own render of the object's parameters in the object's own look (jobs.render_thumbnail, the
Variations grid's thumbnails), PREVIEW_SIZE pixels square, with an ICON_SIZE icon rendered the
same way. No GPU and never Blender's generic icon: Blender keeps a preview set from Python
(ImagePreview.is_image_custom) and saves it in the .blend. The parameters live in the object's
own properties (Object.dqjulia), which an append or a drop from the Asset Browser carries: the
dropped object is a DQ Julia object like any other (preview, bakes, variations). The asset's
custom property THUMBNAIL_OF keeps the values its preview shows, so the panel can tell when the
object changed since (Update Thumbnail). Blender's own Mark as Asset gives an empty no preview:
a timer (give_thumbnails()) gives a DQ Julia asset without THUMBNAIL_OF the library's thumbnail.

The preset library (write_preset_library(), register_library()): every preset the add-on ships
(the examples and the paper's figures) made an asset in one .blend, LIBRARY_FILE, written by
the library installed (so its thumbnails are that version's renders) into a folder of the
user's: the extension's own user folder in Blender 4.2+ (bpy.utils.extension_path_user, which an
update keeps), else Blender's user datafiles folder. Not the add-on's folder: an extension's
files are replaced on update and may be read-only (a system repository). The folder is then
registered as the asset library LIBRARY_NAME in the preferences, on the user's request (the
preferences' and the panel's button), never behind their back.
"""

import json
import os

import bpy

from . import core_state, jobs, native, operators, props

PREVIEW_SIZE = 256  # pixels, square: the Asset Browser's picture of the asset
ICON_SIZE = 32  # its small icon (lists, menus)
TAG = "DQ Julia"
THUMBNAIL_OF = "dqjulia_thumbnail_of"  # asset_data: the values (JSON) its preview shows
DESCRIBED = "dqjulia_description"  # asset_data: the description mark() wrote (one typed since is kept)
LIBRARY_NAME = "DQ Julia"
LIBRARY_FILE = "dqjulia-presets.blend"
_LABELS = {name: label for name, label, _help in props.VARIANT_ITEMS + props.COLORING_ITEMS}


def values_text(obj):
    """The object's values as the asset records them (sorted JSON of props.to_document)."""
    return json.dumps(props.to_document(obj.dqjulia), sort_keys=True)


def describe(document):
    """A description from the values: the variant, the constant, the iterations."""
    fractal = document["fractal"]
    c = fractal["c"]
    return "DQ Julia set, %s variant: c = (%s) + (%s)\u03b5, %d iterations" % (
        _LABELS.get(fractal.get("variant"), fractal.get("variant", "")),
        ", ".join("%.4g" % x for x in c[:4]),
        ", ".join("%.4g" % x for x in c[4:]),
        fractal["iterations"],
    )


def render_previews(document):
    """(image pixels, icon pixels), each RGBA8 rows top-down: the library's renders of the
    document. Raises ValueError with why (nothing to see, the render failed)."""
    state = core_state.state_for_document(document)
    if state.error:
        raise ValueError(state.error)
    if state.empty_reason:
        raise ValueError("nothing to show in its thumbnail: " + state.empty_reason)
    pictures = []
    with native.Context() as context:
        for size in (PREVIEW_SIZE, ICON_SIZE):
            pixels, error = jobs.render_thumbnail(context, document, size)
            if pixels is None:
                raise ValueError("its thumbnail failed to render: " + error)
            pictures.append(pixels)
    return pictures[0], pictures[1]


def mark(obj, tags=()):
    """Makes the DQ Julia object an asset with its metadata and the library's thumbnail (also
    to update an asset after its values changed). Raises ValueError (the object unchanged)
    when there is nothing to show or the render fails; native errors pass through."""
    document = props.to_document(obj.dqjulia)
    with native.Context() as context:  # the complete document, as the core reads it
        context.set_params(document)
        complete = context.params()
    image, icon = render_previews(complete)
    obj.asset_mark()
    data = obj.asset_data
    if not data.description or data.description == data.get(DESCRIBED):  # never one typed in the browser
        data.description = (complete.get("description") or "").strip() or describe(complete)
        data[DESCRIBED] = data.description
    fractal, material = complete["fractal"], complete["material"]
    wanted = [TAG, _LABELS.get(fractal["variant"], fractal["variant"])]
    wanted.append(_LABELS.get(material["coloring"], material["coloring"]))
    wanted.extend(tags)
    for tag in list(data.tags):  # a variant or colouring the object no longer has
        if tag.name in _LABELS.values() and tag.name not in wanted:
            data.tags.remove(tag)
    for name in wanted:
        if name not in data.tags:
            data.tags.new(name)
    data[THUMBNAIL_OF] = values_text(obj)
    preview = obj.preview_ensure()
    preview.image_size = (PREVIEW_SIZE, PREVIEW_SIZE)
    preview.image_pixels = jobs.preview_ints(image, PREVIEW_SIZE, PREVIEW_SIZE)
    preview.icon_size = (ICON_SIZE, ICON_SIZE)
    preview.icon_pixels = jobs.preview_ints(icon, ICON_SIZE, ICON_SIZE)


def give_thumbnails():
    """DQ Julia objects made assets another way (Blender's own Mark as Asset, which gives an
    empty no preview) get the library's thumbnail and metadata, as mark() gives them. Linked
    objects are left alone; one whose thumbnail cannot be made is tried again only once its
    values change. Returns how many were given one."""
    given = 0
    for obj in bpy.data.objects:
        data = obj.asset_data
        if data is None or obj.library is not None or data.get(THUMBNAIL_OF) is not None:
            continue
        settings = getattr(obj, "dqjulia", None)
        if settings is None or not settings.enabled:
            continue
        values = values_text(obj)
        if _failed.get(obj.name) == values:
            continue
        try:
            mark(obj)
            given += 1
        except (ValueError, native.NativeError, native.NativeUnavailable):
            _failed[obj.name] = values
    return given


_failed = {}  # object name -> the values whose thumbnail could not be made
POLL_SECONDS = 1.0  # how often give_thumbnails() looks (a timer: Blender has no handler for marking)


def _poll():
    if native.load_error() is None:
        give_thumbnails()
    return POLL_SECONDS


def thumbnail_stale(obj):
    """Whether the object is an asset whose thumbnail shows other values than it has now."""
    data = obj.asset_data
    return data is not None and data.get(THUMBNAIL_OF) != values_text(obj)


# -------------------------------------------------------------------------------------------
# The preset library


def library_folder(create=True):
    """The folder of the preset library (made if missing, when `create`): the extension's user
    folder in Blender 4.2+ (kept across updates), else <user datafiles>/dqjulia/assets."""
    package = __package__ or "dqjulia"
    if package.startswith("bl_ext.") and hasattr(bpy.utils, "extension_path_user"):
        return bpy.utils.extension_path_user(package, path="assets", create=create)
    return bpy.utils.user_resource("DATAFILES", path=os.path.join("dqjulia", "assets"), create=create)


def _remove(objects):
    """Removes objects made here, and the keyframes' actions only they used."""
    for obj in objects:
        action = obj.animation_data.action if obj.animation_data else None
        bpy.data.objects.remove(obj)
        if action is not None and action.users == 0:
            bpy.data.actions.remove(action)


def write_preset_library(folder, on_progress=None):
    """Writes every shipped preset as an asset into folder/LIBRARY_FILE (replacing it whole, never
    half-written). Returns (path, the presets written, [(a preset left out, why)]). The objects
    are made in the open file for the writing only and removed after: it is left as it was (an
    object of it that has a preset's name lends it for the while, so the asset has that name).
    on_progress(fraction) is called after each preset."""
    made, left_out, aside = [], [], {}  # aside: the open file's objects renamed for the while
    path = os.path.join(folder, LIBRARY_FILE)
    temporary = path + ".partial"  # not a .blend: the Asset Browser never lists a half-written file
    names = operators.preset_names()
    try:
        for index, name in enumerate(names):
            if on_progress is not None:
                on_progress(index / len(names))
            try:
                obj = operators.new_object(name, os.path.join(operators.PRESET_DIR, name + ".json"))
            except (native.NativeError, OSError) as error:
                left_out.append((name, str(error)))
                continue
            made.append(obj)
            if obj.name != name:  # an object of the open file has the preset's name: lend it
                other = next(o for o in bpy.data.objects if o.name == name and o.library is None)
                other.name = "dqjulia-aside-%d" % index
                aside[other] = name
                obj.name = name
            try:
                mark(obj, tags=("paper figure" if name.startswith("paper-") else "preset",))
            except (ValueError, native.NativeError) as error:
                left_out.append((name, str(error)))
        assets = [obj for obj in made if obj.asset_data is not None]
        if not assets:
            raise ValueError("no preset could be made an asset: %s" % "; ".join("%s: %s" % item for item in left_out))
        written = sorted(obj.name for obj in assets)
        os.makedirs(folder, exist_ok=True)
        bpy.data.libraries.write(temporary, set(assets), fake_user=True, compress=True)
        os.replace(temporary, path)
    finally:
        _remove(made)
        for other, name in aside.items():
            other.name = name
        if os.path.exists(temporary):
            os.remove(temporary)
    return path, written, left_out


def _same_folder(a, b):
    return os.path.normcase(os.path.abspath(bpy.path.abspath(a))).rstrip(os.sep) == os.path.normcase(
        os.path.abspath(b)
    ).rstrip(os.sep)


def registered_library(context, folder):
    """The preferences' asset library of `folder`, or None."""
    for library in context.preferences.filepaths.asset_libraries:
        if _same_folder(library.path, folder):
            return library
    return None


def register_library(context, folder):
    """Adds `folder` to the preferences' asset libraries as LIBRARY_NAME (once), appending its
    assets on a drop (editable objects, not links) where Blender offers the choice (3.5+)."""
    library = registered_library(context, folder)
    if library is None:
        result = bpy.ops.preferences.asset_library_add(directory=folder)
        library = registered_library(context, folder)
        if result != {"FINISHED"} or library is None:
            raise ValueError("Blender did not add the asset library %s" % folder)
        library.name = LIBRARY_NAME
    if hasattr(library, "import_method"):
        library.import_method = "APPEND"
    context.preferences.is_dirty = True  # saved with the preferences (auto-save, or Save Preferences)
    return library


# -------------------------------------------------------------------------------------------
# Operators


class DQJULIA_OT_mark_asset(bpy.types.Operator):
    bl_description = (
        "Mark the DQ Julia object as an asset, with its parameters and a thumbnail the library renders "
        "in the object's own look (again: update the thumbnail)"
    )

    bl_idname = "dqjulia.mark_asset"
    bl_label = "Mark as Asset"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return operators.dqjulia_object(context) is not None

    def execute(self, context):
        obj = operators.dqjulia_object(context)
        if obj.library is not None:
            self.report({"ERROR"}, "%s is linked from a library: mark it in its own file" % obj.name)
            return {"CANCELLED"}
        try:
            mark(obj)
        except (ValueError, native.NativeError, native.NativeUnavailable) as error:
            self.report({"ERROR"}, "%s is not marked as an asset: %s" % (obj.name, error))
            return {"CANCELLED"}
        self.report({"INFO"}, "%s is an asset (Asset Browser: Current File)" % obj.name)
        return {"FINISHED"}


class DQJULIA_OT_preset_library(bpy.types.Operator):
    bl_description = (
        "Write the shipped presets and the paper's figures as assets, with the library's thumbnails, "
        'into your user folder and add it to the asset libraries as "DQ Julia"'
    )

    bl_idname = "dqjulia.preset_library"
    bl_label = "Add Preset Asset Library"

    def execute(self, context):
        if native.load_error() is not None:
            self.report({"ERROR"}, native.load_error())
            return {"CANCELLED"}
        wm = context.window_manager
        wm.progress_begin(0.0, 1.0)  # the cursor shows it: a few seconds, one render a preset
        try:
            folder = library_folder()
            path, written, left_out = write_preset_library(folder, wm.progress_update)
            library = register_library(context, folder)
        except (ValueError, OSError, RuntimeError, native.NativeError, native.NativeUnavailable) as error:
            self.report({"ERROR"}, "The preset asset library was not made: %s" % error)
            return {"CANCELLED"}
        finally:
            wm.progress_end()
        message = '%d presets in the asset library "%s" (%s)' % (len(written), library.name, path)
        if left_out:
            message += "; left out: %s" % "; ".join("%s (%s)" % item for item in left_out)
        self.report({"INFO"}, message)
        return {"FINISHED"}


CLASSES = (DQJULIA_OT_mark_asset, DQJULIA_OT_preset_library)


def register():
    for cls in CLASSES:
        bpy.utils.register_class(cls)
    if not bpy.app.timers.is_registered(_poll):
        bpy.app.timers.register(_poll, first_interval=POLL_SECONDS, persistent=True)


def unregister():
    if bpy.app.timers.is_registered(_poll):
        bpy.app.timers.unregister(_poll)
    _failed.clear()
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)

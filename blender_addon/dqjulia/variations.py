"""The Variations panel's work: a grid of variations of a DQ Julia object, their thumbnails as
image previews, and the picks.

The library does the finding and the drawing (jobs.VariationsTask: dqj_variations_compute, then
each variation's thumbnail rendered by the core in the object's own look); a worker thread runs
it (jobs.Job) and the Refresh operator, modal, copies each thumbnail into a
`bpy.utils.previews` image as it arrives, so the grid fills in while Blender stays responsive;
Esc stops it. Clicking a thumbnail applies that variation's document to the object in one undo
step (or to a copy, leaving the original as it was), records it in the object's history of
picks (Back, Forward) and varies around it next.

What is kept here lives for the session only, by object name: each object's Grid (the centre it
varies, its thumbnails, the message to show) and its History. Nothing of it goes into the .blend
but the settings on the object (props.py: strength, locks, seed).
"""

import json

import bpy
from bpy.props import BoolProperty, IntProperty

from . import animation, core_state, jobs, native, operators, props
from .modal_job import ModalJob

COUNT = 9  # a 3 x 3 grid
MIN_STRENGTH = 0.01  # the library's range of strengths: 0.01 to 1
GROUP_BITS = {name: native.GROUPS[name] for name, _label, _help in props.VARIATION_GROUP_ITEMS}
STRENGTH_WORDS = (  # docs/examples.md "Variations of a fractal you like", docs/variations.md
    (0.05, "tiny", "details move"),
    (0.15, "small", "a close relative"),
    (0.3, "medium", "a sibling"),
    (0.6, "large", "a cousin"),
    (1.0, "huge", "a stranger"),
)


def strength_words(strength):
    """The named strength nearest to `strength`: "medium: a sibling ..."."""
    value, name, words = min(STRENGTH_WORDS, key=lambda entry: abs(entry[0] - strength))
    return "%s%s: %s" % (name, "" if abs(value - strength) < 1e-6 else " (about)", words)


def document_text(document):
    """A document as the grid and the history compare them: the core's complete JSON."""
    with native.Context() as context:
        context.set_params(document)
        return context.params_json()


class Grid:
    """One object's variations: around which document (JSON text), with which settings, the
    thumbnails that have arrived (jobs.Thumbnail), their previews, and what to say."""

    generation = 0  # numbers every grid, so their previews never share a name

    def __init__(self, source, seed, strength):
        Grid.generation += 1
        self.key = "g%d" % Grid.generation
        self.source = source  # the object's values it varies, as props.to_document gave them
        self.centre = ""  # the same as the core's complete document
        self.seed = seed
        self.strength = strength
        self.thumbnails = []
        self.icons = {}  # slot index -> preview icon id (0 in background mode)
        self.message = ""  # an error to show in the panel
        self.summary = ""  # how many candidates the search took, and what it rejected
        self.job = None
        self.running = False

    def preview_name(self, index):
        return "%s-%d" % (self.key, index)


class History:
    """The documents an object's grid was centred on, oldest first, and where it is."""

    def __init__(self, first):
        self.entries = [first]
        self.index = 0

    def push(self, text):
        """A new pick: it follows the current entry, and what came after is dropped."""
        del self.entries[self.index + 1 :]
        if text != self.entries[-1]:
            self.entries.append(text)
        self.index = len(self.entries) - 1

    def visit(self, text):
        """The object's values now: an entry of the history (after Ctrl-Z, say) becomes the
        current one; other values (edited by hand) are pushed as a pick."""
        if text == self.entries[self.index]:
            return
        if text in self.entries:
            self.index = len(self.entries) - 1 - self.entries[::-1].index(text)
        else:
            self.push(text)

    def can_step(self, step):
        return 0 <= self.index + step < len(self.entries)


_grids = {}  # object name -> Grid
_histories = {}  # object name -> History
_previews = None  # the bpy.utils.previews collection of every grid's thumbnails


def grid_for(obj):
    return _grids.get(obj.name)


def history_for(obj):
    return _histories.get(obj.name)


def _collection():
    global _previews
    if _previews is None:
        import bpy.utils.previews

        _previews = bpy.utils.previews.new()
    return _previews


def _forget_previews(grid):
    if _previews is None:
        return
    for index in range(COUNT):
        name = grid.preview_name(index)
        if name in _previews:
            del _previews[name]
    grid.icons.clear()


def fill_previews(grid):
    """Copies the thumbnails that arrived since the last call into image previews; returns
    how many it added. Main thread only."""
    added = 0
    size = jobs.THUMBNAIL_SIZE
    for thumbnail in list(grid.thumbnails):
        if thumbnail.index in grid.icons or thumbnail.pixels is None:
            continue
        preview = _collection().new(grid.preview_name(thumbnail.index))
        preview.image_size = (size, size)
        preview.image_pixels = jobs.preview_ints(thumbnail.pixels, size, size)
        grid.icons[thumbnail.index] = preview.icon_id
        added += 1
    return added


def preview_of(grid, index):
    """The image preview of slot `index`, or None while it has none."""
    if _previews is None:
        return None
    return _previews.get(grid.preview_name(index))


PLACEHOLDER = "placeholder"  # the grey square of a slot whose thumbnail has not come (or failed)


def placeholder_icon():
    """The icon id of a grey square the size of a thumbnail (made once)."""
    import array

    collection = _collection()
    preview = collection.get(PLACEHOLDER)
    if preview is None:
        preview = collection.new(PLACEHOLDER)
        size = jobs.THUMBNAIL_SIZE
        preview.image_size = (size, size)
        grey = array.array("i")
        grey.frombytes(bytes((48, 48, 48, 255)) * (size * size))
        preview.image_pixels = grey
    return preview.icon_id


def _locks_bits(settings):
    return sum(GROUP_BITS[name] for name in settings.variation_locks)


def new_grid(obj):
    """A new grid around the object's current values, replacing (and stopping) its last one,
    with its job made for the Refresh operator to run. Returns the Grid; its `message` says what
    went wrong before any work (it has no job then)."""
    settings = obj.dqjulia
    document = props.to_document(settings)
    old = _grids.get(obj.name)
    if old is not None:
        if old.job is not None:
            old.job.cancel()
        _forget_previews(old)
    source = json.dumps(document, sort_keys=True)
    # The strength as the panel shows it (Blender keeps a float: 0.15 is 0.1500000059...).
    strength = round(settings.variation_strength, 4)
    grid = Grid(source, settings.variation_seed, strength)
    _grids[obj.name] = grid
    state = core_state.state_for(obj)
    if state.error or state.empty_reason:
        grid.message = state.error or "Nothing to vary: " + state.empty_reason
        return grid
    if not MIN_STRENGTH <= grid.strength <= 1.0:
        grid.message = "Strength %.3g is out of range: from %g (the details move) to 1 (anything)" % (
            grid.strength,
            MIN_STRENGTH,
        )
        return grid
    if len(settings.variation_locks) == len(GROUP_BITS):
        grid.message = "Every group is kept as it is, so nothing can vary: unlock at least one"
        return grid
    try:
        grid.centre = document_text(document)
    except (native.NativeError, native.NativeUnavailable) as error:
        grid.message = str(error)
        return grid
    _histories.setdefault(obj.name, History(grid.centre)).visit(grid.centre)
    task = jobs.VariationsTask(json.loads(grid.centre), grid.seed, grid.strength, _locks_bits(settings), count=COUNT)
    grid.thumbnails = task.thumbnails
    grid.job = jobs.Job("Variations", [task])
    grid.running = True
    return grid


def conclude(grid):
    """After the job: the last previews, the summary, the message. Main thread."""
    job = grid.job
    task = job.tasks[0]
    fill_previews(grid)
    grid.running = False
    found = task.summary
    if found:
        rejected = ", ".join("%s %d" % (name, count) for name, count in found["rejected"].items() if count)
        grid.summary = "%d of %d candidates kept%s" % (
            found["count"],
            found["candidates"],
            " (rejected: %s)" % rejected if rejected else "",
        )
    if job.state == jobs.Job.FAILED:
        grid.message = job.error
    elif job.state == jobs.Job.CANCELLED:
        grid.message = "Stopped: %d of %d thumbnails made. Refresh for a new grid." % (
            len(grid.thumbnails),
            COUNT,
        )


def slot_error(grid, index):
    thumbnail = next((t for t in grid.thumbnails if t.index == index), None)
    return thumbnail.error if thumbnail is not None else ""


def stale(obj, grid):
    """Whether the object's values are no longer the ones its grid varies (edited, undone)."""
    return json.dumps(props.to_document(obj.dqjulia), sort_keys=True) != grid.source


def apply_text(obj, text):
    """Sets the object's properties to a complete document (JSON text), as Import does:
    every value of the file, and its keyframes (a variation has none: they are cleared)."""
    document = json.loads(text)
    props.from_document(obj.dqjulia, document)
    animation.apply_section(obj, document.get("animation") or {})


def copy_beside(context, obj):
    """A copy of the DQ Julia object (its settings, not its bakes) beside it, active."""
    copy = obj.copy()
    if copy.animation_data is not None:
        copy.animation_data_clear()
    for collection in obj.users_collection:
        collection.objects.link(copy)
    state = core_state.state_for(obj)
    radius = state.bounds[1] if state.bounds else 1.0
    copy.location.x += 2.2 * radius * max(obj.scale)
    for other in context.selected_objects:
        other.select_set(False)
    copy.select_set(True)
    context.view_layer.objects.active = copy
    return copy


# -------------------------------------------------------------------------------------------
# Operators

_dqjulia_object = operators.dqjulia_object
_redraw_panels = operators._redraw_progress  # the sidebar and the properties, not the viewport


def unavailable():
    """Why the loaded library cannot make variations, or None."""
    error = native.load_error()
    if error is not None:
        return error
    if not native.has_feature(native.FEATURE_VARIATIONS):
        return "the dqjulia library %s has no variations (feature %r): install the add-on from a newer build" % (
            native.version()[1],
            native.FEATURE_VARIATIONS,
        )
    return None


class DQJULIA_OT_variations_refresh(ModalJob, bpy.types.Operator):
    """Find variations of the active DQ Julia object and render their thumbnails in the background (Esc stops)"""

    bl_idname = "dqjulia.variations_refresh"
    bl_label = "Refresh"

    next_seed: BoolProperty(
        name="Next seed",
        default=True,
        options={"SKIP_SAVE"},
        description="Move to the next seed first: a new set of variations",
    )
    synchronous: BoolProperty(
        name="Synchronous",
        default=False,
        options={"SKIP_SAVE", "HIDDEN"},
        description="Work in the calling thread and return when done (scripts, tests)",
    )

    timer_step = 0.05
    _grid = None
    _name = ""

    @classmethod
    def poll(cls, context):
        return _dqjulia_object(context) is not None

    def execute(self, context):
        obj = _dqjulia_object(context)
        why = unavailable()
        if why is not None:
            self.report({"ERROR"}, why)
            return {"CANCELLED"}
        if self.next_seed and obj.name in _grids:
            obj.dqjulia.variation_seed += 1
        self._grid, self._name = new_grid(obj), obj.name
        if self._grid.job is None:
            return self.job_finished(context)
        return self.run_job(context, self._grid.job)

    def invoke(self, context, _event):
        return self.execute(context)

    def job_superseded(self):
        return _grids.get(self._name) is not self._grid

    def job_ticked(self, context):
        if fill_previews(self._grid):
            _redraw_panels(context)

    def job_finished(self, context):
        grid = self._grid
        if grid.job is not None:
            conclude(grid)
            _redraw_panels(context)
        if grid.message and (grid.job is None or grid.job.state == jobs.Job.FAILED):
            self.report({"ERROR"}, grid.message)
            return {"CANCELLED"}
        if grid.job.state == jobs.Job.CANCELLED:
            self.report({"WARNING"}, grid.message)
            return {"CANCELLED"}
        failed = sum(1 for thumbnail in grid.thumbnails if thumbnail.error)
        self.report({"INFO"}, "Variations: %s%s" % (grid.summary, "; %d failed to render" % failed if failed else ""))
        return {"FINISHED"}


def _refresh_around(context, obj):
    """After a pick: the next grid around the object's new values (in the background where
    there is a window)."""
    # The object named, not the context's: the properties editor may still show the original.
    with context.temp_override(object=obj, active_object=obj):
        bpy.ops.dqjulia.variations_refresh("INVOKE_DEFAULT", next_seed=False)


class DQJULIA_OT_variation_apply(bpy.types.Operator):
    """Apply this variation to the object (Ctrl-Z returns to the original); the next variations vary it"""

    bl_idname = "dqjulia.variation_apply"
    bl_label = "Apply Variation"
    bl_options = {"REGISTER", "UNDO", "INTERNAL"}

    index: IntProperty(name="Variation", default=0, min=0, options={"SKIP_SAVE"})
    copy: BoolProperty(
        name="Apply to a copy",
        default=False,
        options={"SKIP_SAVE"},
        description="Apply the variation to a copy of the object beside it, leaving the original as it is",
    )
    refresh: BoolProperty(
        name="Vary around it",
        default=True,
        options={"SKIP_SAVE", "HIDDEN"},
        description="Start the next variations around the pick",
    )

    @classmethod
    def poll(cls, context):
        return _dqjulia_object(context) is not None

    @classmethod
    def description(cls, context, properties):
        if properties.copy:
            text = "Apply this variation to a copy of the object beside it (the original stays as it is)"
        else:
            text = "Apply this variation to the object (Ctrl-Z returns to the original)"
        text += "; it becomes the centre of the next variations"
        obj = _dqjulia_object(context)
        grid = _grids.get(obj.name) if obj is not None else None
        thumbnail = next((t for t in grid.thumbnails if t.index == properties.index), None) if grid else None
        return "%s.\n%s" % (text, thumbnail.description) if thumbnail is not None else text

    def execute(self, context):
        obj = _dqjulia_object(context)
        grid = _grids.get(obj.name)
        thumbnail = None
        if grid is not None:
            thumbnail = next((t for t in grid.thumbnails if t.index == self.index), None)
        if thumbnail is None:
            self.report({"ERROR"}, "variation %d is not there (yet): Refresh the variations" % (self.index + 1))
            return {"CANCELLED"}
        try:
            # Back returns to the values the object has now (after an undo or an edit too).
            current = document_text(props.to_document(obj.dqjulia))
            target = obj
            if self.copy:
                target = copy_beside(context, obj)
                _histories[target.name] = History(current)
            history = _histories.setdefault(target.name, History(current))
            history.visit(current)
            apply_text(target, thumbnail.text)
            history.push(document_text(props.to_document(target.dqjulia)))
        except (native.NativeError, native.NativeUnavailable) as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        self.report({"INFO"}, "Applied variation %d to %s" % (self.index + 1, target.name))
        if self.refresh:
            _refresh_around(context, target)
        return {"FINISHED"}


class DQJULIA_OT_variations_history(bpy.types.Operator):
    """Go back (or forward) through the picks of this object: its values as they were at that pick"""

    bl_idname = "dqjulia.variations_history"
    bl_label = "Variations History"
    bl_options = {"REGISTER", "UNDO", "INTERNAL"}

    step: IntProperty(name="Step", default=-1, options={"SKIP_SAVE"})
    refresh: BoolProperty(name="Vary around it", default=True, options={"SKIP_SAVE", "HIDDEN"})

    @classmethod
    def poll(cls, context):
        obj = _dqjulia_object(context)
        return obj is not None and obj.name in _histories

    @classmethod
    def description(cls, _context, properties):
        return "Back to the previous pick" if properties.step < 0 else "Forward to the next pick"

    def execute(self, context):
        obj = _dqjulia_object(context)
        history = _histories.get(obj.name)
        if history is None or not history.can_step(self.step):
            self.report({"WARNING"}, "no %s pick" % ("earlier" if self.step < 0 else "later"))
            return {"CANCELLED"}
        history.index += self.step
        apply_text(obj, history.entries[history.index])
        if self.refresh:
            _refresh_around(context, obj)
        return {"FINISHED"}


CLASSES = (DQJULIA_OT_variations_refresh, DQJULIA_OT_variation_apply, DQJULIA_OT_variations_history)


def forget_all():
    """Stops every grid's work and forgets the grids, the histories and their previews."""
    global _previews
    for grid in _grids.values():
        if grid.job is not None:
            grid.job.cancel()
    _grids.clear()
    _histories.clear()
    if _previews is not None:
        import bpy.utils.previews

        bpy.utils.previews.remove(_previews)
        _previews = None


@bpy.app.handlers.persistent
def _forget_on_load(*_args):
    """Another .blend was loaded: its objects have no grids yet."""
    forget_all()


def register():
    for cls in CLASSES:
        bpy.utils.register_class(cls)
    if _forget_on_load not in bpy.app.handlers.load_post:
        bpy.app.handlers.load_post.append(_forget_on_load)


def unregister():
    if _forget_on_load in bpy.app.handlers.load_post:
        bpy.app.handlers.load_post.remove(_forget_on_load)
    forget_all()
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)

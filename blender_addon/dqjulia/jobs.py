"""Background work: bakes and variations run in a worker thread, never on Blender's main thread.

A Job is a list of tasks (a VDB bake, a mesh: one native call each; a grid of variations: the
variations, then a thumbnail of each) run one after another in a thread. ctypes releases the
GIL for the whole native call, so Blender stays responsive; the core reports progress through
a ctypes callback (native.Progress), which records the fraction and returns 1 once cancel() was
asked, and the call then ends with DQJ_ERROR_CANCELLED. Nothing here touches bpy: the worker
only fills plain Python objects, and the operator that owns the job (operators.py,
variations.py) polls it from a modal timer on the main thread, shows its progress, and builds
Blender objects only when it has succeeded.

Typed (scripts/check-style.sh runs mypy on it, for Python 3.9 as native.py; Blender's Pythons are newer).
"""

from __future__ import annotations

import array
import ctypes
import json
import os
import threading
import time
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

from . import native

_active: List[Job] = []  # running jobs and held ones (Job.hold), for the panels
_lock = threading.Lock()


class MeshData:
    """A mesh copied out of the core: flat arrays ready for foreach_set (no bpy). Faces as the
    core made them: quads first, then triangles."""

    def __init__(
        self,
        positions: array.array[float],
        normals: array.array[float],
        colors: Optional[array.array[float]],
        quads: array.array[int],
        triangles: array.array[int],
    ) -> None:
        self.positions = positions  # array('f'), 3 a vertex
        self.normals = normals  # array('f'), 3 a vertex
        self.colors = colors  # array('f'), 3 a vertex, or None
        self.quads = quads  # array('i'), 4 a quad
        self.triangles = triangles  # array('i'), 3 a triangle

    @property
    def vertex_count(self) -> int:
        return len(self.positions) // 3

    @property
    def quad_count(self) -> int:
        return len(self.quads) // 4

    @property
    def triangle_count(self) -> int:
        return len(self.triangles) // 3

    @property
    def face_count(self) -> int:
        return self.quad_count + self.triangle_count


def _as_array(typecode: str, ctypes_array: ctypes.Array[Any]) -> array.array[Any]:
    result: array.array[Any] = array.array(typecode)
    result.frombytes(memoryview(ctypes_array).cast("B"))
    return result


class _TaskBase:
    """What every task has: its document, the warning its native call gave, `part`, the
    share of the task's progress its current native call covers (start, width): a task of
    several native calls moves it before each; and `note`, what the status shows of it ("" or
    "about 1.2 GB of memory, 3 slabs")."""

    kind = ""

    def __init__(self, document: Dict[str, Any]) -> None:
        self.document = document
        self.warning = ""
        self.note = ""
        self.part: Tuple[float, float] = (0.0, 1.0)


class VolumeTask(_TaskBase):
    """Bakes one document to a VDB file (grids "surface" and "density" at least)."""

    kind = "volume"

    def __init__(self, document: Dict[str, Any], path: str, frame: Optional[int] = None) -> None:
        super().__init__(document)
        self.path = path
        self.frame = frame

    def run(self, context: native.Context, progress: native.Progress) -> str:
        directory = os.path.dirname(self.path)
        if directory:
            os.makedirs(directory, exist_ok=True)
        self.warning = context.bake_vdb(self.path, progress)
        return self.path


class MeshTask(_TaskBase):
    """Meshes one document's surface and copies the mesh out of the core. First the estimate
    (dqj_mesh_estimate, the classification alone: the first 5 % of the progress): a mesh that
    cannot fit the memory limit even slab by slab fails then, with the core's reason, and the
    status shows the memory, slabs and faces to come. `memory_limit` (bytes, 0: the core's
    default, half the available memory) is the limit the core slabs under."""

    kind = "mesh"

    def __init__(self, document: Dict[str, Any], colors: bool = True, memory_limit: int = 0) -> None:
        super().__init__(document)
        self.colors = colors
        self.memory_limit = memory_limit
        self.estimate: Optional[Tuple[int, int, int]] = None  # (bytes, slabs, faces)

    def run(self, context: native.Context, progress: native.Progress) -> MeshData:
        context.set_memory_limit(self.memory_limit)
        if native.has("dqj_mesh_estimate"):
            self.part = (0.0, 0.05)
            self.estimate = context.mesh_estimate(progress)
            self.note = describe_mesh_estimate(*self.estimate)
            self.part = (0.05, 0.95)
        self.warning = context.mesh_compute(progress)
        positions, normals, colors, quads, triangles = context.mesh_faces(colors=self.colors)
        return MeshData(
            _as_array("f", positions),
            _as_array("f", normals),
            _as_array("f", colors) if colors is not None else None,
            _as_array("i", quads),
            _as_array("i", triangles),
        )


THUMBNAIL_SIZE = 128  # pixels, square: a variation's picture in the grid


def render_thumbnail(
    context: native.Context, document: Dict[str, Any], size: int, progress: Optional[native.Progress] = None
) -> Tuple[Optional[bytes], str]:
    """A document's picture as the core renders it in the document's own look (its material,
    palette and lights; one sample a pixel), `size` pixels square, RGBA8 sRGB, rows top-down:
    (pixels, "") or (None, why). A cancel is raised, any other failure kept. The Variations
    grid's thumbnails and the assets' previews (assets.py) are these."""
    document = dict(document)
    document["render"] = dict(document.get("render") or {}, samples=1)
    try:
        context.set_params(document)
        pixels, _warning = context.render_rgba8(size, size, progress)
        return pixels, ""
    except native.NativeError as error:
        if error.cancelled or (progress is not None and progress.cancelled):
            raise
        return None, error.message
    except native.NativeUnavailable as error:
        return None, str(error)


def preview_ints(pixels: bytes, width: int, height: int) -> array.array[int]:
    """The core's RGBA8 rows (top-down) as Blender's ImagePreview.image_pixels (or icon_pixels)
    take them: one int a pixel (its four bytes), rows bottom-up."""
    stride = 4 * width
    packed: array.array[int] = array.array("i")
    packed.frombytes(b"".join(pixels[stride * row : stride * (row + 1)] for row in range(height - 1, -1, -1)))
    return packed


class Thumbnail:
    """One slot of a grid of variations, filled by the worker: the variation's complete document
    (JSON text, as the core gives it), then its picture (RGBA8, sRGB, rows top-down) or why it
    has none."""

    def __init__(self, index: int, text: str, description: str) -> None:
        self.index = index
        self.text = text
        self.description = description
        self.pixels: Optional[bytes] = None
        self.error = ""

    @property
    def done(self) -> bool:
        return self.pixels is not None or bool(self.error)


class VariationsTask(_TaskBase):
    """Variations of one document (dqj_variations_compute: `count` documents, each proven
    non-empty, not dust, not a ball, not tiny, no two alike), then each one's thumbnail rendered
    by the core in the document's own look (its material, palette and lights; one sample a
    pixel). `thumbnails` grows as the worker goes: the main thread may read it at any time (a
    slot appears complete, its picture or its error set before it is appended). A thumbnail
    that fails to render keeps its reason and the others go on; the variations failing (a
    strength out of range, every group locked, an empty start, too few found) fail the task
    with the core's message."""

    kind = "variations"
    COMPUTE_SHARE = 0.3  # of the progress: the search; the thumbnails share the rest

    def __init__(
        self, document: Dict[str, Any], seed: int, strength: float, locked_groups: int, count: int = 9
    ) -> None:
        super().__init__(document)
        self.seed = seed
        self.strength = strength
        self.locked_groups = locked_groups
        self.count = count
        self.summary: Dict[str, Any] = {}
        self.thumbnails: List[Thumbnail] = []

    def run(self, context: native.Context, progress: native.Progress) -> List[Thumbnail]:
        self.part = (0.0, self.COMPUTE_SHARE)
        self.warning = context.variations_compute(self.seed, self.strength, self.locked_groups, self.count, progress)
        self.summary = context.variations()
        texts = [context.variation_params_json(index) for index in range(self.summary["count"])]
        described = self.summary["variations"]
        share = (1.0 - self.COMPUTE_SHARE) / max(1, len(texts))
        for index, text in enumerate(texts):
            self.part = (self.COMPUTE_SHARE + index * share, share)
            slot = Thumbnail(index, text, str(described[index].get("description", "")))
            slot.pixels, slot.error = render_thumbnail(context, json.loads(text), THUMBNAIL_SIZE, progress)
            self.thumbnails.append(slot)
        return self.thumbnails


# One task of a Job: native calls with a document.
Task = Union[VolumeTask, MeshTask, VariationsTask]


def format_duration(seconds: float) -> str:
    """12 s, 4 min, 2.5 h."""
    if seconds < 90:
        return "%d s" % max(1, round(seconds))
    if seconds < 5400:
        return "%d min" % round(seconds / 60.0)
    return "%.1f h" % (seconds / 3600.0)


def describe_mesh_estimate(size: int, slabs: int, faces: int) -> str:
    """ "about 1.2 GB of memory in 3 slabs, about 4.1 million faces": a mesh estimate as the
    status and the Bake Mesh dialog show it."""
    where = "in one piece" if slabs <= 1 else "in %d slabs" % slabs
    count = "%.1f million" % (faces / 1e6) if faces >= 1e6 else "%d" % faces
    return "about %s of memory %s, about %s faces" % (format_bytes(size), where, count)


def format_bytes(count: float) -> str:
    for unit in ("bytes", "KB", "MB", "GB"):
        if count < 1000 or unit == "GB":
            return ("%d %s" if unit == "bytes" else "%.1f %s") % (count, unit)
        count /= 1000.0
    return "%.1f TB" % count


class Job:
    """Tasks run in order in one worker thread (or synchronously with run())."""

    RUNNING, DONE, FAILED, CANCELLED = "running", "done", "failed", "cancelled"

    def __init__(self, label: str, tasks: Sequence[Task], owner: str = "") -> None:
        self.label = label
        self.owner = owner  # the object's name, for the panel
        self.tasks = list(tasks)
        self.results: List[Union[str, MeshData, List[Thumbnail]]] = []  # each task's: a VDB's path, a mesh, ...
        self.state = Job.RUNNING
        self.error = ""
        self.warnings: List[str] = []
        self.index = 0  # the task under way
        self._task_fraction = 0.0
        self._progress: Optional[native.Progress] = None
        self._cancel = threading.Event()
        self._thread: Optional[threading.Thread] = None
        self.started = time.monotonic()
        self.finished: Optional[float] = None

    # progress ------------------------------------------------------------------------------

    @property
    def fraction(self) -> float:
        if not self.tasks:
            return 1.0
        return min(1.0, (self.index + self._task_fraction) / len(self.tasks))

    def _on_progress(self, fraction: float) -> None:
        if self.index < len(self.tasks):
            start, width = self.tasks[self.index].part
            fraction = start + width * fraction
        self._task_fraction = fraction

    def status_text(self) -> str:
        """ "Bake sequence: 12 of 250 frames done, 4% (about 23 min left)"."""
        text = "%s: %d%%" % (self.label, round(100.0 * self.fraction))
        if len(self.tasks) > 1:
            text = "%s: %d of %d %s done, %d%%" % (
                self.label,
                min(self.index, len(self.tasks)),
                len(self.tasks),
                "frames" if self.tasks[0].kind == "volume" else "parts",
                round(100.0 * self.fraction),
            )
        left = self.seconds_left()
        if left is not None:
            text += " (about %s left)" % format_duration(left)
        if len(self.tasks) == 1 and self.tasks[0].note:
            text += "; " + self.tasks[0].note
        return text

    def seconds_left(self) -> Optional[float]:
        """The time left at the pace so far; None until there is a pace to go by."""
        fraction = self.fraction
        elapsed = time.monotonic() - self.started
        if fraction < 0.02 or elapsed < 2.0 or fraction >= 1.0:
            return None
        return elapsed * (1.0 - fraction) / fraction

    # control -------------------------------------------------------------------------------

    def cancel(self) -> None:
        """Asks the work to stop; safe from any thread. The native call returns at its next
        progress report; a held job that never started is cancelled at once."""
        self._cancel.set()
        with _lock:
            if self._thread is None and self in _active:  # held, never started
                _active.remove(self)
                self.state, self.error, self.finished = Job.CANCELLED, "cancelled", time.monotonic()
        progress = self._progress
        if progress is not None:
            progress.cancel()

    @property
    def cancel_requested(self) -> bool:
        return self._cancel.is_set()

    @property
    def finished_running(self) -> bool:
        return self.state != Job.RUNNING

    def run(self) -> str:
        """Runs every task in the calling thread (the worker, or the main thread for scripts)."""
        self.started = time.monotonic()
        try:
            context = native.Context()
            try:
                for index, task in enumerate(self.tasks):
                    self.index = index
                    self._task_fraction = 0.0
                    if self._cancel.is_set():
                        raise native.NativeError(native.ERROR_CANCELLED, "cancelled")
                    progress = native.Progress(self._on_progress)
                    self._progress = progress
                    if self._cancel.is_set():
                        progress.cancel()
                    context.set_params(task.document)  # a frame's values: no keyframes in it
                    self.results.append(task.run(context, progress))
                    if task.warning:
                        self.warnings.append(task.warning)
                    self._task_fraction = 1.0
                self.index = len(self.tasks)
                self._task_fraction = 0.0
                self.state = Job.DONE
            finally:
                self._progress = None
                context.close()
        except native.NativeError as error:
            if error.cancelled or self._cancel.is_set():
                self.state = Job.CANCELLED
                self.error = "cancelled"
            else:
                self.state = Job.FAILED
                self.error = error.message
        except native.NativeUnavailable as error:
            self.state = Job.FAILED
            self.error = str(error)
        except OSError as error:  # e.g. the cache folder cannot be made
            self.state = Job.FAILED
            self.error = str(error)
        except Exception as error:  # report anything else rather than lose it in a thread
            self.state = Job.FAILED
            self.error = "%s: %s" % (type(error).__name__, error)
        finally:
            self.finished = time.monotonic()
        return self.state

    def hold(self) -> None:
        """Counts the job as active (active_jobs, the panels, cancel_all) before its worker
        starts: a modal operator starts it at its first timer tick (modal_job.py says why)."""
        with _lock:
            if self not in _active:
                _active.append(self)

    def start(self) -> None:
        """Runs the tasks in a worker thread; poll finished_running from the main thread. A
        cancelled job does not start."""
        with _lock:
            if self.state != Job.RUNNING or self._thread is not None:
                return
            if self not in _active:
                _active.append(self)
            thread = threading.Thread(target=self._thread_main, name="dqjulia-" + self.label, daemon=True)
            self._thread = thread
        thread.start()

    def _thread_main(self) -> None:
        try:
            self.run()
        finally:
            with _lock:
                if self in _active:
                    _active.remove(self)

    def join(self, timeout: Optional[float] = None) -> None:
        if self._thread is not None:
            self._thread.join(timeout)


def active_jobs(owner: Optional[str] = None) -> List[Job]:
    with _lock:
        return [job for job in _active if owner is None or job.owner == owner]


def cancel_all() -> None:
    for job in active_jobs():
        job.cancel()

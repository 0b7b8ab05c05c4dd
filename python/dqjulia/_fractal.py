"""The Python API's Fractal: one parameter set and the work done with it, over one dqj_context
of the C ABI (through _native, the package's ctypes bindings). NumPy is imported only by the
functions that take or give arrays."""

from __future__ import annotations

import ctypes
import dataclasses
import json
import os
import signal
import threading
import warnings
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any, Callable, Optional, Union

from . import _native

if TYPE_CHECKING:
    import numpy

__all__ = [
    "BakeStats",
    "DqjuliaWarning",
    "Fractal",
    "Mesh",
    "ProgressCallback",
    "defaults",
    "has_feature",
    "library_version",
    "sample_dtype",
    "schema",
]

PathLike = Union[str, "os.PathLike[str]"]
ProgressCallback = Callable[[float], Optional[bool]]
"""Called with the fraction done (0 to 1) a few times a second, on the calling thread; returning
False cancels the work (CancelledError), and so does an exception, which is then raised."""


class DqjuliaWarning(UserWarning):
    """A warning of the library about a result that succeeded: for example that the slice is
    empty (and what to change), so a render shows only the background."""


@dataclasses.dataclass(frozen=True)
class BakeStats:
    """What a bake or mesh cost (dqj_bake_stats)."""

    voxels_evaluated: int
    """Fractal evaluations, including the block tests."""
    voxels_dense: int
    """Voxels of the whole grid: what a dense bake would evaluate."""
    active_voxels: int
    """Active voxels of the "surface" level set (bakes; 0 for meshes)."""
    estimated_bytes: int
    """The memory estimate checked against the memory limit."""
    seconds: float
    """Wall-clock time."""


@dataclasses.dataclass(frozen=True)
class Mesh:
    """A mesh of the surface as NumPy arrays (Fractal.mesh). Faces are counter-clockwise seen from
    outside; indices are into `vertices`."""

    vertices: numpy.ndarray
    """(V, 3) float32: x, y, z in the slice's coordinates."""
    normals: numpy.ndarray
    """(V, 3) float32: unit normals pointing out of the solid."""
    colors: numpy.ndarray | None
    """(V, 3) float32 linear RGB from the material's colouring, or None (bake.mesh_colors false)."""
    quads: numpy.ndarray
    """(Q, 4) uint32: the quads as the core made them (none when triangulated)."""
    triangles: numpy.ndarray
    """(T, 3) uint32: the triangles as the core made them, or every face as triangles when
    triangulated."""
    stats: BakeStats
    """What computing the mesh cost."""


def _numpy():
    try:
        import numpy
    except ImportError:
        raise ImportError(
            "this function of dqjulia takes or gives NumPy arrays: install NumPy (pip install numpy, "
            'or pip install "dqjulia[numpy]")'
        ) from None
    return numpy


def _pointer(array: Any, kind: Any) -> Any:
    return array.ctypes.data_as(ctypes.POINTER(kind))


def _stats(stats: _native.BakeStats) -> BakeStats:
    return BakeStats(
        voxels_evaluated=stats.voxels_evaluated,
        voxels_dense=stats.voxels_dense,
        active_voxels=stats.active_voxels,
        estimated_bytes=stats.estimated_bytes,
        seconds=stats.seconds,
    )


def _merge(base: dict, changes: Mapping) -> dict:
    merged = dict(base)
    for key, value in changes.items():
        if isinstance(value, Mapping) and isinstance(merged.get(key), dict):
            merged[key] = _merge(merged[key], value)
        else:
            merged[key] = value
    return merged


class Fractal:
    """A dual-quaternion Julia fractal: a parameter document (docs/parameter-file.md) and what
    is made from it: point evaluation, renders, OpenVDB bakes and meshes.

    The library validates every document and value; a rejected one raises ParameterError (a
    ValueError) with the library's message, which names the key, what was wrong and what is
    allowed, and leaves the previous parameters in place.

    One call at a time: a Fractal used from two threads at once raises BusyError in the second;
    separate Fractals may work in parallel. Long calls (render, bake, mesh) release the GIL, report
    progress and can be cancelled (their `progress` and `cancel` arguments; Ctrl-C cancels them
    too, raising KeyboardInterrupt). Files are written whole or not at all: after an error or a
    cancel an existing file is untouched and no partial file remains.

    Close it with close() or use it as a context manager (`with dqjulia.Fractal() as fractal:`);
    it is also closed when garbage-collected.
    """

    def __init__(self, params: Mapping[str, Any] | None = None) -> None:
        """A fractal with the parameters `params` (a dict of the parameter document, whole or in
        part: missing keys take their defaults), or the defaults."""
        self._context = _native.Context()
        self._frame = 1.0
        self._memory_limit = 0
        self.warning = ""
        """The library's warning from the last render, bake or mesh ("" if none); it is also
        issued as a DqjuliaWarning."""
        if params is not None:
            self.set_params(params)

    @classmethod
    def from_json(cls, text: str) -> Fractal:
        """A fractal from the JSON text of a parameter document."""
        fractal = cls()
        fractal.set_params(text)
        return fractal

    @classmethod
    def from_file(cls, path: PathLike) -> Fractal:
        """A fractal from a parameter file (JSON; docs/parameter-file.md)."""
        fractal = cls()
        fractal.load(path)
        return fractal

    # Life ---------------------------------------------------------------------------------

    def close(self) -> None:
        """Frees the native context; later calls raise InvalidHandleError. Closing twice is fine."""
        self._context.close()

    def __enter__(self) -> Fractal:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def __repr__(self) -> str:
        try:
            fractal = self.params["fractal"]
        except _native.DqjuliaError:
            return "<dqjulia.Fractal (closed)>"
        return "<dqjulia.Fractal variant=%s c=%s iterations=%d>" % (
            fractal["variant"],
            fractal["c"],
            fractal["iterations"],
        )

    # Parameters ---------------------------------------------------------------------------

    @property
    def params(self) -> dict[str, Any]:
        """The complete parameter document (every key, defaults filled in) as a dict. Setting it
        replaces the document (keys left out take their defaults)."""
        return self._context.params()

    @params.setter
    def params(self, params: Mapping[str, Any] | str) -> None:
        self.set_params(params)

    def set_params(self, params: Mapping[str, Any] | str) -> None:
        """Replaces the parameter document: a dict, or JSON text. Keys left out take their defaults."""
        if isinstance(params, str):
            self._context.set_params_json(params)
        elif isinstance(params, Mapping):
            self._context.set_params_json(json.dumps(params))
        else:
            raise TypeError("parameters are a dict or JSON text, not %s" % type(params).__name__)

    def update(self, changes: Mapping[str, Any]) -> None:
        """Changes some keys and keeps the rest: `changes` is merged into the current document
        (nested dicts key by key, other values replaced), e.g.
        `fractal.update({"fractal": {"iterations": 10}})`."""
        self.set_params(_merge(self.params, changes))

    def load(self, path: PathLike) -> None:
        """Replaces the parameter document with a parameter file's."""
        self._context.load_params_file(os.fspath(path))

    def to_json(self) -> str:
        """The complete parameter document as JSON text (what a parameter file holds)."""
        return self._context.params_json()

    def save(self, path: PathLike) -> None:
        """Writes the complete parameter document to a file, for `dqjulia --params`."""
        with open(path, "w", encoding="utf-8") as file:
            file.write(self.to_json())

    @property
    def frame(self) -> float:
        """The frame at which keyframed parameters ("animation") are taken by renders, bakes and
        meshes (default 1); without keyframes it changes nothing."""
        return self._frame

    @frame.setter
    def frame(self, frame: float) -> None:
        self._context.set_frame(frame)
        self._frame = float(frame)

    @property
    def memory_limit(self) -> int:
        """Bakes and meshes whose estimated memory exceeds this many bytes are refused before any
        heavy work (OutOfMemoryError, with the estimate); 0 (the default) means half of the memory
        available when the work starts."""
        return self._memory_limit

    @memory_limit.setter
    def memory_limit(self, limit: int) -> None:
        self._context.set_memory_limit(limit)
        self._memory_limit = int(limit)

    def inspect(self) -> dict[str, Any]:
        """What the constant and slice give: the equivalent complex constants, their Mandelbrot
        membership, bounds, inside fraction and, when the slice is empty, why (as `dqjulia inspect`)."""
        return self._context.inspect()

    # Evaluation ---------------------------------------------------------------------------

    def evaluate(self, points: Any) -> numpy.ndarray:
        """Evaluates 8-D points (a then b, s i j k each): an array-like of shape (..., 8). Returns a
        structured array of shape (...) with the fields n (escape iteration, 0 = did not escape),
        r (the escape norm at exit), ra and rb (the norms of a and b at exit) and de (distance estimate in
        8-D units). One call into the library for all points."""
        return self._evaluate(points, 8)

    def evaluate_slice(self, points: Any) -> numpy.ndarray:
        """Evaluates 3-D points (x, y, z) mapped through the slice: an array-like of shape (..., 3).
        Returns the structured array of evaluate(); de is in 8-D units (divide by the slice's
        largest stretch for a 3-D distance)."""
        return self._evaluate(points, 3)

    def _evaluate(self, points: Any, width: int) -> numpy.ndarray:
        numpy = _numpy()
        array = numpy.ascontiguousarray(points, dtype=numpy.float64)
        if array.ndim == 0 or array.shape[-1] != width:
            raise ValueError(
                "points need %d coordinates each (shape (..., %d)), got shape %s" % (width, width, array.shape)
            )
        shape = array.shape[:-1]
        out = numpy.empty(shape, dtype=sample_dtype())
        count = out.size
        if count:
            self._context.evaluate_into(
                _pointer(array, ctypes.c_double), count, _pointer(out, _native.Sample), slice_points=width == 3
            )
        return out

    # Rendering ----------------------------------------------------------------------------

    def render(
        self,
        width: int | None = None,
        height: int | None = None,
        *,
        progress: ProgressCallback | None = None,
        cancel: threading.Event | None = None,
    ) -> numpy.ndarray:
        """Renders the picture (the parameters' camera, lights, material) and returns it as a
        (height, width, 4) uint8 array, top row first: RGB is sRGB, the pixels of the PNG that
        render_to_file writes (the surface over the background), and A is the surface's coverage
        (0 where only the background shows). Width and height default to the parameters' render
        size."""
        numpy = _numpy()
        if width is None or height is None:
            size = self.params["render"]
            width = size["width"] if width is None else width
            height = size["height"] if height is None else height
        if width < 1 or height < 1:
            raise ValueError("width and height must be at least 1 (got %d x %d)" % (width, height))
        pixels = numpy.zeros((height, width, 4), dtype=numpy.uint8)
        self._run(
            lambda native_progress: self._context.render_rgba8_into(
                _pointer(pixels, ctypes.c_uint8), width, height, 4 * width, native_progress
            ),
            progress,
            cancel,
        )
        return pixels

    def render_to_file(
        self, path: PathLike, *, progress: ProgressCallback | None = None, cancel: threading.Event | None = None
    ) -> None:
        """Renders and writes an image file: .png (8-bit, or as the parameters' output.format says)
        or .exr (with depth and normals). An existing file is replaced once the new one is whole."""
        self._run(
            lambda native_progress: self._context.render_to_file(os.fspath(path), native_progress), progress, cancel
        )

    # Baking -------------------------------------------------------------------------------

    def bake(
        self,
        path: PathLike,
        *,
        resolution: int | None = None,
        progress: ProgressCallback | None = None,
        cancel: threading.Event | None = None,
    ) -> BakeStats:
        """Bakes an OpenVDB file: the level set "surface", the fog volume "density" and the grids
        the parameters' bake.grids asks for, at the parameters' bake resolution (or `resolution`,
        which sets bake.resolution: voxels across the largest side of the bounds). Returns what
        it cost."""
        return self._bake_work(
            resolution,
            lambda native_progress: self._context.bake_vdb(os.fspath(path), native_progress),
            progress,
            cancel,
        )

    def mesh(
        self,
        *,
        resolution: int | None = None,
        triangulate: bool = False,
        progress: ProgressCallback | None = None,
        cancel: threading.Event | None = None,
    ) -> Mesh:
        """Meshes the surface (bake resolution and bake.adaptivity, as `dqjulia mesh`) and returns
        it as NumPy arrays: quads and triangles as the core made them, or with `triangulate` every
        face as triangles. Vertex colours come with it unless the parameters' bake.mesh_colors is
        false."""
        numpy = _numpy()
        stats = self._bake_work(resolution, self._context.mesh_compute, progress, cancel)
        vertex_count, triangle_count = self._context.mesh_sizes()
        vertices = numpy.empty((vertex_count, 3), dtype=numpy.float32)
        normals = numpy.empty((vertex_count, 3), dtype=numpy.float32)
        colors = numpy.empty((vertex_count, 3), dtype=numpy.float32) if self.params["bake"]["mesh_colors"] else None
        color_pointer = None if colors is None else _pointer(colors, ctypes.c_float)
        float_pointers = (_pointer(vertices, ctypes.c_float), _pointer(normals, ctypes.c_float), color_pointer)
        if triangulate:
            quads = numpy.empty((0, 4), dtype=numpy.uint32)
            triangles = numpy.empty((triangle_count, 3), dtype=numpy.uint32)
            self._context.mesh_copy_into(
                *float_pointers, vertex_count, _pointer(triangles, ctypes.c_uint32), triangle_count
            )
        else:
            self._context.mesh_copy_into(*float_pointers, vertex_count)
            quad_count, triangle_count = self._context.mesh_face_counts()
            quads = numpy.empty((quad_count, 4), dtype=numpy.uint32)
            triangles = numpy.empty((triangle_count, 3), dtype=numpy.uint32)
            self._context.mesh_copy_faces_into(
                _pointer(quads, ctypes.c_uint32), quad_count, _pointer(triangles, ctypes.c_uint32), triangle_count
            )
        return Mesh(vertices=vertices, normals=normals, colors=colors, quads=quads, triangles=triangles, stats=stats)

    def mesh_to_file(
        self,
        path: PathLike,
        *,
        resolution: int | None = None,
        progress: ProgressCallback | None = None,
        cancel: threading.Event | None = None,
    ) -> BakeStats:
        """Meshes the surface and writes it, by the path's extension: .ply (binary, with normals and
        colours), .obj, .stl (binary, no colours) or .3mf (vertex colours), the file `dqjulia mesh`
        writes (in slice coordinates). Returns what it cost."""
        stats = self._bake_work(resolution, self._context.mesh_compute, progress, cancel)
        self._context.mesh_write(os.fspath(path))
        return stats

    # ----------------------------------------------------------------------------------------

    def _bake_work(
        self,
        resolution: int | None,
        call: Callable[[_native.Progress], str],
        progress: ProgressCallback | None,
        cancel: threading.Event | None,
    ) -> BakeStats:
        """A bake or mesh call at `resolution` (sets bake.resolution; None keeps it); what it cost."""
        if resolution is not None:
            self._context.set_bake_resolution(resolution)
        self._run(call, progress, cancel)
        return _stats(self._context.bake_stats())

    def _run(
        self,
        call: Callable[[_native.Progress], str],
        progress: ProgressCallback | None,
        cancel: threading.Event | None,
    ) -> None:
        """Runs a long call with a progress callback (always one: cancel and Ctrl-C are noticed at
        its reports, a few times a second); issues the library's warning.

        Ctrl-C: in the main thread with Python's own SIGINT handler, the call's handler cancels
        the work instead of raising inside the callback (which would unwind into C), and
        KeyboardInterrupt is raised once the call has returned."""
        native_progress: _native.Progress
        interrupted = []

        def report(fraction: float) -> None:
            cancelled = cancel is not None and cancel.is_set()
            if cancelled or (progress is not None and progress(fraction) is False):
                native_progress.cancel()

        def interrupt(_signal: int, _frame: object) -> None:
            interrupted.append(True)
            native_progress.cancel()

        native_progress = _native.Progress(report, cancel_on_error=True)
        previous = None
        main_thread = threading.current_thread() is threading.main_thread()
        if main_thread and signal.getsignal(signal.SIGINT) is signal.default_int_handler:
            previous = signal.signal(signal.SIGINT, interrupt)
        self.warning = ""
        try:
            self.warning = call(native_progress)
        except _native.CancelledError:
            if interrupted:
                raise KeyboardInterrupt from None
            raise
        finally:
            if previous is not None:
                signal.signal(signal.SIGINT, previous)
        if interrupted:
            raise KeyboardInterrupt
        if self.warning:
            warnings.warn(self.warning, DqjuliaWarning, stacklevel=3)


def sample_dtype() -> numpy.dtype:
    """The NumPy dtype of evaluate()'s results: dqj_sample's fields n (int32), r, ra, rb, de
    (float64), laid out as the C struct."""
    return _numpy().dtype(_native.Sample)


def library_version() -> str:
    """The version of the loaded native library ("1.0.0")."""
    return _native.version()[1]


def has_feature(name: str) -> bool:
    """Whether the loaded library has an optional feature: "vdb", "mesh" or "animation"."""
    _native.library()
    return _native.has_feature(name)


def schema() -> dict[str, Any]:
    """The parameter schema: every key of the parameter document with its type, label, help,
    default, range and choices (docs/parameter-file.md, "Parameter schema")."""
    with _native.Context() as context:
        return context.schema()


def defaults() -> dict[str, Any]:
    """The complete default parameter document."""
    with _native.Context() as context:
        return context.params()

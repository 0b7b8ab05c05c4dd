"""ctypes bindings of libdqjulia's C ABI (core/include/dqjulia/dqjulia.h).

The one module that talks to the native library. It is loaded lazily, on first use, so the
add-on registers (and its panels can explain the problem) even when the library is missing
or of the wrong version; `load_error()` gives that explanation in words a user can act on.

Every function is declared with its argtypes and restype. Functions the add-on can live
without (baking, keyframes) belong to optional features, which the library is asked for
(dqj_has_feature), never probed for symbols: `has_feature(name)` and `has(function)` say
whether the loaded library has them, and calling a missing one raises NativeUnavailable with
the reason.

No bpy here: the module is used from worker threads (ctypes releases the GIL during each
call) and by the tests outside Blender.
"""

import ctypes
import json
import os
import sys
import threading

try:
    from . import _buildinfo
except ImportError:  # running from the source tree, not from the built zip
    _buildinfo = None

# The C ABI version this add-on was built against (DQJ_VERSION_NUMBER = major*10000 +
# minor*100 + patch, from dqjulia.h at build time). A library loads if its major version is
# the same and it is not older: minor versions only add functions.
EXPECTED_VERSION = getattr(_buildinfo, "DQJ_VERSION_NUMBER", 100)

LIBRARY_ENV = "DQJULIA_LIBRARY"  # developers: load this file instead of the bundled one

# dqj_status
OK = 0
ERROR_INVALID_HANDLE = 1
ERROR_INVALID_ARGUMENT = 2
ERROR_PARAMETERS = 3
ERROR_IO = 4
ERROR_CANCELLED = 5
ERROR_OUT_OF_MEMORY = 6
ERROR_INTERNAL = 7
ERROR_BUSY = 8  # a call on the context is running (e.g. destroy from its own progress callback)

VARIANTS = ("paper", "paper-coupled", "dual")  # dqj_variant order

# The optional features this add-on knows (DQJ_FEATURE_*), for dqj_has_feature.
FEATURE_VDB = "vdb"
FEATURE_MESH = "mesh"
FEATURE_ANIMATION = "animation"
FEATURES = (FEATURE_VDB, FEATURE_MESH, FEATURE_ANIMATION)


class NativeUnavailable(RuntimeError):
    """The library could not be loaded (missing, wrong version, or lacks a function)."""


class NativeError(RuntimeError):
    """A call returned a status other than DQJ_OK; `status` and the context's message."""

    def __init__(self, status, message):
        self.status = status
        self.message = message
        super().__init__(message)

    @property
    def cancelled(self):
        return self.status == ERROR_CANCELLED


class Sample(ctypes.Structure):
    """dqj_sample: the result for one point."""

    _fields_ = [
        ("n", ctypes.c_int32),
        ("r", ctypes.c_double),
        ("ra", ctypes.c_double),
        ("rb", ctypes.c_double),
        ("de", ctypes.c_double),
    ]


class BakeStats(ctypes.Structure):
    """dqj_bake_stats: what the last bake or mesh cost. A growing struct: struct_size is set to
    this class's size before each call (Context.bake_stats does)."""

    _fields_ = [
        ("struct_size", ctypes.c_size_t),
        ("voxels_evaluated", ctypes.c_uint64),
        ("voxels_dense", ctypes.c_uint64),
        ("active_voxels", ctypes.c_uint64),
        ("estimated_bytes", ctypes.c_uint64),
        ("seconds", ctypes.c_double),
    ]


# typedef int (*dqj_progress_fn)(double fraction, void* user_data); non-zero goes on, 0 cancels.
PROGRESS_FN = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.c_double, ctypes.c_void_p)

_handle = ctypes.c_void_p
_status = ctypes.c_int
_size_p = ctypes.POINTER(ctypes.c_size_t)
_char_buffer = ctypes.c_char_p

_BAKE = (FEATURE_VDB, FEATURE_MESH)  # the calls bakes and meshes share

# name: (restype, argtypes, features): None for a function every library has, else the
# features of which any one brings it.
_SIGNATURES = {
    "dqj_version_number": (ctypes.c_uint, [], None),
    "dqj_version_string": (ctypes.c_char_p, [], None),
    "dqj_status_string": (ctypes.c_char_p, [ctypes.c_int], None),
    "dqj_has_feature": (ctypes.c_int, [ctypes.c_char_p], None),
    "dqj_context_create": (_status, [ctypes.POINTER(_handle)], None),
    "dqj_context_destroy": (_status, [_handle], None),
    "dqj_context_error": (ctypes.c_char_p, [_handle], None),
    "dqj_context_warning": (ctypes.c_char_p, [_handle], None),
    "dqj_context_load_params_file": (_status, [_handle, ctypes.c_char_p], None),
    "dqj_context_set_params_json": (_status, [_handle, ctypes.c_char_p], None),
    "dqj_context_get_params_json": (_status, [_handle, ctypes.c_void_p, ctypes.c_size_t, _size_p], None),
    "dqj_params_schema_json": (_status, [_handle, ctypes.c_void_p, ctypes.c_size_t, _size_p], None),
    "dqj_context_set_constant": (_status, [_handle, ctypes.POINTER(ctypes.c_double)], None),
    "dqj_context_set_variant": (_status, [_handle, ctypes.c_int], None),
    "dqj_context_set_iterations": (_status, [_handle, ctypes.c_int], None),
    "dqj_context_set_bailout": (_status, [_handle, ctypes.c_double], None),
    "dqj_context_set_slice_axes": (_status, [_handle, ctypes.c_char_p], None),
    "dqj_evaluate_points": (
        _status,
        [_handle, ctypes.POINTER(ctypes.c_double), ctypes.c_size_t, ctypes.POINTER(Sample)],
        None,
    ),
    "dqj_evaluate_slice_points": (
        _status,
        [_handle, ctypes.POINTER(ctypes.c_double), ctypes.c_size_t, ctypes.POINTER(Sample)],
        None,
    ),
    "dqj_render_rgba8": (
        _status,
        [
            _handle,
            ctypes.POINTER(ctypes.c_uint8),
            ctypes.c_uint32,
            ctypes.c_uint32,
            ctypes.c_size_t,
            PROGRESS_FN,
            ctypes.c_void_p,
        ],
        None,
    ),
    "dqj_render_to_file": (_status, [_handle, ctypes.c_char_p, PROGRESS_FN, ctypes.c_void_p], None),
    "dqj_inspect_json": (_status, [_handle, ctypes.c_void_p, ctypes.c_size_t, _size_p], None),
    # Optional: the add-on still previews and renders with a library without them.
    "dqj_context_set_bake_resolution": (_status, [_handle, ctypes.c_int], _BAKE),
    "dqj_context_set_frame": (_status, [_handle, ctypes.c_double], (FEATURE_ANIMATION,)),
    "dqj_context_set_memory_limit": (_status, [_handle, ctypes.c_uint64], _BAKE),
    "dqj_bake_vdb": (_status, [_handle, ctypes.c_char_p, PROGRESS_FN, ctypes.c_void_p], (FEATURE_VDB,)),
    "dqj_mesh_compute": (_status, [_handle, PROGRESS_FN, ctypes.c_void_p], (FEATURE_MESH,)),
    "dqj_mesh_get_sizes": (_status, [_handle, _size_p, _size_p], (FEATURE_MESH,)),
    "dqj_mesh_copy": (
        _status,
        [
            _handle,
            ctypes.POINTER(ctypes.c_float),
            ctypes.POINTER(ctypes.c_float),
            ctypes.POINTER(ctypes.c_float),
            ctypes.c_size_t,
            ctypes.POINTER(ctypes.c_uint32),
            ctypes.c_size_t,
        ],
        (FEATURE_MESH,),
    ),
    "dqj_mesh_get_face_counts": (_status, [_handle, _size_p, _size_p], (FEATURE_MESH,)),
    "dqj_mesh_copy_faces": (
        _status,
        [_handle, ctypes.POINTER(ctypes.c_uint32), ctypes.c_size_t, ctypes.POINTER(ctypes.c_uint32), ctypes.c_size_t],
        (FEATURE_MESH,),
    ),
    "dqj_mesh_write": (_status, [_handle, ctypes.c_char_p], (FEATURE_MESH,)),
    "dqj_bake_get_stats": (_status, [_handle, ctypes.POINTER(BakeStats)], _BAKE),
}

_lock = threading.Lock()
_library = None
_load_error = None
_library_path = None
_dll_directory = None  # Windows: the library's folder, added to the DLL search path while loaded
_features = frozenset()  # the FEATURES the loaded library has
_bound = frozenset()  # the functions of _SIGNATURES it offers


def version_text(number):
    return "%d.%d.%d" % (number // 10000, number // 100 % 100, number % 100)


# What the library needs of the system it runs on, by sys.platform (for the message when it does not load).
_REQUIREMENTS = {
    "win32": "64-bit Windows (x64) with its own system libraries",
    "linux": "Linux x86-64 with glibc 2.34 or newer (Debian 12, Ubuntu 22.04, RHEL 9 or later)",
}


def bundled_library_path():
    """Where the zip puts the library: lib/ beside this file (the zip made for this platform)."""
    names = {"win32": "dqjulia.dll", "darwin": "libdqjulia.dylib"}
    return os.path.join(os.path.dirname(os.path.abspath(__file__)), "lib", names.get(sys.platform, "libdqjulia.so"))


def library_path():
    return os.environ.get(LIBRARY_ENV) or bundled_library_path()


def _bind(library):
    """Declares the functions the library offers: every required one, and those of the
    optional features it says it has. Returns (features, function names)."""

    def declare(name, restype, argtypes):
        try:
            function = getattr(library, name)
        except AttributeError:
            raise NativeUnavailable(
                "the dqjulia library at %s has no function %s: it is not the library this add-on was "
                "built with; reinstall the add-on zip" % (_library_path, name)
            ) from None
        function.restype = restype
        function.argtypes = argtypes

    restype, argtypes, _ = _SIGNATURES["dqj_has_feature"]
    declare("dqj_has_feature", restype, argtypes)
    features = frozenset(name for name in FEATURES if library.dqj_has_feature(name.encode()) == 1)
    bound = set()
    for name, (restype, argtypes, needs) in _SIGNATURES.items():
        if needs is None or features.intersection(needs):
            declare(name, restype, argtypes)
            bound.add(name)
    return features, frozenset(bound)


def _load():
    global _library_path, _dll_directory
    path = library_path()
    _library_path = path
    if not os.path.isfile(path):
        raise NativeUnavailable(
            "the dqjulia native library is missing: expected %s. The add-on zip must be the one the build "
            "makes (build/dist/dqjulia_blender.zip), which holds the library; reinstall it" % path
        )
    try:
        if hasattr(os, "add_dll_directory") and _dll_directory is None:  # Windows: DLLs beside it are found
            _dll_directory = os.add_dll_directory(os.path.dirname(os.path.abspath(path)))
        library = ctypes.CDLL(path)
    except OSError as error:
        raise NativeUnavailable(
            "the dqjulia native library at %s could not be loaded (%s). It is self-contained and needs only "
            "%s; on another system, build the add-on there (README, Two commands)"
            % (path, error, _REQUIREMENTS.get(sys.platform, _REQUIREMENTS["linux"]))
        ) from error
    try:
        version_number = library.dqj_version_number
    except AttributeError:
        raise NativeUnavailable("%s is not the dqjulia library (no dqj_version_number)" % path) from None
    version_number.restype = ctypes.c_uint
    version_number.argtypes = []
    found = version_number()
    if found // 10000 != EXPECTED_VERSION // 10000 or found < EXPECTED_VERSION:
        raise NativeUnavailable(
            "the dqjulia library at %s is version %s, but this add-on needs %s (same major version, not "
            "older): install the add-on zip and the library from the same build"
            % (path, version_text(found), version_text(EXPECTED_VERSION))
        )
    return library, _bind(library)


def library():
    """The loaded library; raises NativeUnavailable (with the reason) if it cannot be used."""
    global _library, _load_error, _features, _bound
    with _lock:
        if _library is None and _load_error is None:
            try:
                _library, (_features, _bound) = _load()
            except NativeUnavailable as error:
                _load_error = str(error)
        if _library is None:
            raise NativeUnavailable(_load_error)
        return _library


def load_error():
    """None when the library is usable, else why not (for the UI)."""
    try:
        library()
        return None
    except NativeUnavailable as error:
        return str(error)


def reset():
    """Forget the loaded library and the last error, so the next use tries again (tests)."""
    global _library, _load_error, _features, _bound
    with _lock:
        _library = None
        _load_error = None
        _features = frozenset()
        _bound = frozenset()


def has_feature(name):
    """Whether the loaded library has this optional feature (FEATURE_*; False if it cannot be
    loaded or the add-on does not know the name)."""
    try:
        library()
    except NativeUnavailable:
        return False
    return name in _features


def has(name):
    """Whether the loaded library offers this function of _SIGNATURES (False if it cannot be
    loaded)."""
    try:
        library()
    except NativeUnavailable:
        return False
    return name in _bound


def version():
    """(number, text) of the loaded library."""
    lib = library()
    return lib.dqj_version_number(), lib.dqj_version_string().decode()


def status_text(status):
    return library().dqj_status_string(status).decode()


def _function(name):
    lib = library()
    if name not in _bound:
        raise NativeUnavailable(
            "the dqjulia library %s has no %s (it lacks the feature %s); this add-on needs a library that has it"
            % (version()[1], name, " or ".join(_SIGNATURES[name][2] or ()) if name in _SIGNATURES else "?")
        )
    return getattr(lib, name)


class Progress:
    """A progress callback for one native call: records the fraction, asks to cancel.

    `callback` is the ctypes function pointer to pass; keep this object alive during the call
    (ctypes does not). `cancel()` may be called from any thread; the native call then returns
    DQJ_ERROR_CANCELLED at its next progress report (a few times a second).
    """

    def __init__(self, on_progress=None):
        self.fraction = 0.0
        self._cancel = threading.Event()
        self._on_progress = on_progress
        self.callback = PROGRESS_FN(self._report)

    def _report(self, fraction, _user):
        try:
            self.fraction = max(0.0, min(1.0, float(fraction)))
            if self._on_progress is not None:
                self._on_progress(self.fraction)
        except Exception:  # an exception must never unwind into C
            pass
        return 0 if self._cancel.is_set() else 1  # dqj_progress_fn: non-zero goes on, 0 cancels

    def cancel(self):
        self._cancel.set()

    @property
    def cancelled(self):
        return self._cancel.is_set()


def _text(pointer):
    return pointer.decode("utf-8", "replace") if pointer else ""


class Context:
    """A dqj_context: a parameter set and the text of its last error. One thread at a time."""

    def __init__(self, params=None):
        self._lib = library()
        handle = _handle()
        status = self._lib.dqj_context_create(ctypes.byref(handle))
        if status != OK:
            raise NativeError(status, "dqj_context_create failed: %s" % status_text(status))
        self._handle = handle
        if params is not None:
            self.set_params(params)

    def close(self):
        """Destroys the native context. Raises NativeError (ERROR_BUSY) if one of its calls is
        still running, e.g. when called from that call's progress callback: cancel instead."""
        if getattr(self, "_handle", None):
            status = self._lib.dqj_context_destroy(self._handle)
            if status == ERROR_BUSY:
                raise NativeError(status, "the dqjulia context is busy (a call on it is running): cancel it first")
            self._handle = None

    def __del__(self):
        try:
            self.close()
        except Exception:
            pass

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    @property
    def handle(self):
        if not self._handle:
            raise NativeError(ERROR_INVALID_HANDLE, "the dqjulia context was closed")
        return self._handle

    def error(self):
        return _text(self._lib.dqj_context_error(self.handle))

    def warning(self):
        return _text(self._lib.dqj_context_warning(self.handle))

    def check(self, status, what):
        if status != OK:
            message = self.error() or status_text(status)
            raise NativeError(status, "%s: %s" % (what, message) if what else message)

    def _text_out(self, function_name):
        function = _function(function_name)
        size = ctypes.c_size_t(0)
        self.check(function(self.handle, None, 0, ctypes.byref(size)), function_name)
        buffer = ctypes.create_string_buffer(size.value)
        self.check(function(self.handle, buffer, size.value, ctypes.byref(size)), function_name)
        return buffer.value.decode("utf-8")

    # Parameters -------------------------------------------------------------------------

    def load_params_file(self, path):
        self.check(self._lib.dqj_context_load_params_file(self.handle, os.fsencode(path)), None)

    def set_params_json(self, text):
        self.check(self._lib.dqj_context_set_params_json(self.handle, text.encode("utf-8")), None)

    def set_params(self, document):
        """Sets the whole parameter document (a dict or JSON text); the core validates it."""
        self.set_params_json(document if isinstance(document, str) else json.dumps(document))

    def params_json(self):
        return self._text_out("dqj_context_get_params_json")

    def params(self):
        """The complete parameter document the core holds (every key), as a dict."""
        return json.loads(self.params_json())

    def schema(self):
        """The parameter schema (dqj_params_schema_json) as a dict: every key's type, label, help,
        default and range. props.py builds the properties from the packaged copy (schema.json)."""
        return json.loads(self._text_out("dqj_params_schema_json"))

    def inspect(self):
        """dqj_inspect_json as a dict: equivalent complex constants, bounds, emptiness and why."""
        return json.loads(self._text_out("dqj_inspect_json"))

    # Evaluation -------------------------------------------------------------------------

    def evaluate_points(self, points):
        """points: sequence of 8-number sequences. Returns a list of Sample."""
        return self._evaluate("dqj_evaluate_points", points, 8)

    def evaluate_slice_points(self, points):
        """points: sequence of (x, y, z) in the slice. Returns a list of Sample."""
        return self._evaluate("dqj_evaluate_slice_points", points, 3)

    def _evaluate(self, name, points, width):
        points = list(points)
        flat = (ctypes.c_double * (width * len(points)))()
        for index, point in enumerate(points):
            if len(point) != width:
                raise ValueError("each point needs %d numbers" % width)
            flat[width * index : width * index + width] = [float(x) for x in point]
        out = (Sample * max(1, len(points)))()
        self.check(getattr(self._lib, name)(self.handle, flat, len(points), out), name)
        return list(out[: len(points)])

    # Rendering --------------------------------------------------------------------------

    def render_rgba8(self, width, height, progress=None):
        """Renders with the core's renderer; returns (bytes RGBA8 sRGB rows top-down, warning)."""
        stride = 4 * width
        pixels = (ctypes.c_uint8 * (stride * height))()
        progress = progress or Progress()
        status = self._lib.dqj_render_rgba8(self.handle, pixels, width, height, stride, progress.callback, None)
        self.check(status, "render")
        return bytes(pixels), self.warning()

    def render_to_file(self, path, progress=None):
        progress = progress or Progress()
        self.check(self._lib.dqj_render_to_file(self.handle, os.fsencode(path), progress.callback, None), "render")
        return self.warning()

    # Baking -----------------------------------------------------------------------------

    def set_frame(self, frame):
        self.check(_function("dqj_context_set_frame")(self.handle, float(frame)), "frame")

    def set_bake_resolution(self, resolution):
        self.check(_function("dqj_context_set_bake_resolution")(self.handle, int(resolution)), "bake resolution")

    def set_memory_limit(self, limit_bytes):
        self.check(_function("dqj_context_set_memory_limit")(self.handle, int(limit_bytes)), "memory limit")

    def bake_vdb(self, path, progress=None):
        """Writes an OpenVDB file (grids "surface", "density" and bake.grids); all or nothing.
        Returns the context's warning ("" if none)."""
        progress = progress or Progress()
        function = _function("dqj_bake_vdb")
        self.check(function(self.handle, os.fsencode(path), progress.callback, None), "bake")
        return self.warning()

    def mesh_compute(self, progress=None):
        progress = progress or Progress()
        self.check(_function("dqj_mesh_compute")(self.handle, progress.callback, None), "mesh")
        return self.warning()

    def mesh_sizes(self):
        vertices, triangles = ctypes.c_size_t(0), ctypes.c_size_t(0)
        self.check(
            _function("dqj_mesh_get_sizes")(self.handle, ctypes.byref(vertices), ctypes.byref(triangles)), "mesh sizes"
        )
        return vertices.value, triangles.value

    def mesh_faces(self, colors=True):
        """The context's mesh with its faces as the core made them: (positions, normals, colors or
        None, quads, triangles) as ctypes arrays; 4 and 3 uint32 indices a face."""
        vertex_count, _triangle_count = self.mesh_sizes()
        positions = (ctypes.c_float * (3 * vertex_count))()
        normals = (ctypes.c_float * (3 * vertex_count))()
        colours = (ctypes.c_float * (3 * vertex_count))() if colors else None
        self.check(
            _function("dqj_mesh_copy")(self.handle, positions, normals, colours, vertex_count, None, 0), "mesh copy"
        )
        quad_count, triangle_count = ctypes.c_size_t(0), ctypes.c_size_t(0)
        self.check(
            _function("dqj_mesh_get_face_counts")(self.handle, ctypes.byref(quad_count), ctypes.byref(triangle_count)),
            "mesh face counts",
        )
        quads = (ctypes.c_uint32 * (4 * quad_count.value))()
        triangles = (ctypes.c_uint32 * (3 * triangle_count.value))()
        self.check(
            _function("dqj_mesh_copy_faces")(self.handle, quads, quad_count.value, triangles, triangle_count.value),
            "mesh faces",
        )
        return positions, normals, colours, quads, triangles

    def mesh_write(self, path):
        self.check(_function("dqj_mesh_write")(self.handle, os.fsencode(path)), "mesh write")

    def bake_stats(self):
        stats = BakeStats(struct_size=ctypes.sizeof(BakeStats))
        self.check(_function("dqj_bake_get_stats")(self.handle, ctypes.byref(stats)), "bake stats")
        return stats

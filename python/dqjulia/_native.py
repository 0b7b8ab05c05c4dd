"""ctypes bindings of libdqjulia's C ABI (core/include/dqjulia/dqjulia.h).

The one set of Python bindings of the library, written once: it is the Python package's
dqjulia/_native.py, under the public API of dqjulia/__init__.py, and the Blender add-on's
dqjulia/native.py, which the add-on's packaging copies from here unchanged (tests/python check
that both copies are this file). Where the two differ (what to reinstall, the version expected)
comes from the _buildinfo.py the build writes beside each copy.

The library is loaded lazily, on first use, so the add-on registers (and its panels can explain
the problem) and the package imports even when the library is missing or of the wrong version;
`load_error()` gives that explanation in words a user can act on. On Linux the C library is
checked first (glibc 2.34 or newer, `platform_problem()`), so an older system is told so instead
of meeting a loader error.

Every function is declared with its argtypes and restype. Functions a host can live without
(baking, keyframes) belong to optional features, which the library is asked for
(dqj_has_feature), never probed for symbols: `has_feature(name)` and `has(function)` say
whether the loaded library has them, and calling a missing one raises NativeUnavailable with
the reason.

Errors are one hierarchy: DqjuliaError, with LibraryUnavailableError (the library cannot be
used) and StatusError (a call returned a dqj_status other than DQJ_OK), whose subclasses follow
the status codes (ERROR_CLASSES). NativeError and NativeUnavailable are the add-on's names of
StatusError and LibraryUnavailableError.

No bpy and no NumPy here: the module is used from Blender's worker threads (ctypes releases the
GIL during each call), by the package and by the tests. Buffers are passed as ctypes objects or
pointers (the *_into methods), so callers can hand in NumPy arrays without a copy.

Typed (scripts/check-style.sh runs mypy on it, for Python 3.9): annotations are not evaluated at
run time (`from __future__ import annotations`), so they may use what 3.9 cannot evaluate.
"""

from __future__ import annotations

import ctypes
import json
import os
import re
import sys
import threading
from types import ModuleType
from typing import Any, Callable, Dict, FrozenSet, Iterable, List, Optional, Sequence, Tuple, Type, Union

_buildinfo: Optional[ModuleType]
try:
    from . import _buildinfo  # type: ignore[attr-defined, no-redef, unused-ignore]
except ImportError:  # running from the source tree, not from a built add-on zip or wheel
    _buildinfo = None

# A parameter document: a dict as the core's JSON, or that JSON's text.
Document = Union[Dict[str, Any], str]
# A buffer the caller hands in: a ctypes array or pointer of the right element type (a NumPy
# array's `ctypes.data_as(...)`), or None where the C function takes NULL.
Buffer = Any
# What a progress callback is told: the fraction done (0 to 1). Its result is not used.
OnProgress = Callable[[float], object]


def _source_tree_version() -> Optional[int]:
    """DQJ_VERSION_NUMBER of the source tree this file sits in (python/dqjulia/ under the
    project's VERSION file), or None: a copy without _buildinfo.py outside the source tree
    cannot know which library it belongs to, and then refuses to load one."""
    path = os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))), "VERSION")
    try:
        with open(path, encoding="utf-8") as handle:
            match = re.fullmatch(r"(\d+)\.(\d+)\.(\d+)", handle.read().strip())
    except OSError:
        return None
    return int(match.group(1)) * 10000 + int(match.group(2)) * 100 + int(match.group(3)) if match else None


# The C ABI version this copy was built against (DQJ_VERSION_NUMBER = major*10000 +
# minor*100 + patch, from dqjulia.h at build time; in the source tree, from its VERSION file).
# A library loads if its major version is the same and it is not older: minor versions only add
# functions. None: this copy cannot tell (no build info, no source tree), so no library loads.
EXPECTED_VERSION: Optional[int] = getattr(_buildinfo, "DQJ_VERSION_NUMBER", None) or _source_tree_version()
# What holds this copy ("the add-on", "the Python package dqjulia") and how a user gets the
# library back, for the messages below.
HOST: str = getattr(_buildinfo, "HOST", "dqjulia")
REINSTALL: str = getattr(_buildinfo, "REINSTALL", "reinstall dqjulia")

LIBRARY_ENV = "DQJULIA_LIBRARY"  # developers: load this file instead of the bundled one

# The oldest glibc the Linux library and command run on (their newest GLIBC_ symbol version,
# checked by tests/cleanroom/check_library.py).
GLIBC_FLOOR = (2, 34)

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

# The optional features this copy knows (DQJ_FEATURE_*), for dqj_has_feature.
FEATURE_VDB = "vdb"
FEATURE_MESH = "mesh"
FEATURE_ANIMATION = "animation"
FEATURE_VARIATIONS = "variations"
FEATURES = (FEATURE_VDB, FEATURE_MESH, FEATURE_ANIMATION, FEATURE_VARIATIONS)

# The groups a variation may change (DQJ_GROUP_*), by the names `dqjulia explore --lock` takes.
GROUP_A = 0x01
GROUP_B = 0x02
GROUP_SLICE_ORIENTATION = 0x04
GROUP_SLICE_ORIGIN = 0x08
GROUP_ITERATIONS = 0x10
GROUP_VARIANT = 0x20
GROUP_ALL = 0x3F
GROUPS: Dict[str, int] = {
    "a": GROUP_A,
    "b": GROUP_B,
    "orientation": GROUP_SLICE_ORIENTATION,
    "origin": GROUP_SLICE_ORIGIN,
    "iterations": GROUP_ITERATIONS,
    "variant": GROUP_VARIANT,
}
# The named strengths (DQJ_STRENGTH_*), tiny to huge.
STRENGTHS: Dict[str, float] = {"tiny": 0.05, "small": 0.15, "medium": 0.3, "large": 0.6, "huge": 1.0}


class DqjuliaError(RuntimeError):
    """Every error of dqjulia's library: it cannot be used (LibraryUnavailableError), or a call
    failed (StatusError and its subclasses, one a dqj_status)."""


class LibraryUnavailableError(DqjuliaError):
    """The library cannot be used: missing, of another version, built for another system, or
    lacking a function; the message says which and what to do."""


class StatusError(DqjuliaError):
    """A call returned a dqj_status other than DQJ_OK: `status` (the code), `message` (the
    library's own text, naming the key or file at fault)."""

    def __init__(self, status: int, message: str) -> None:
        self.status = status
        self.message = message
        super().__init__(message)

    @property
    def cancelled(self) -> bool:
        return self.status == ERROR_CANCELLED


class InvalidHandleError(StatusError):
    """DQJ_ERROR_INVALID_HANDLE: the context was closed (or never made)."""


class InvalidArgumentError(StatusError, ValueError):
    """DQJ_ERROR_INVALID_ARGUMENT: a value out of range, a buffer too small."""


class ParameterError(StatusError, ValueError):
    """DQJ_ERROR_PARAMETERS: the parameter document or a value was rejected; the message names
    the key, what was wrong and what is allowed."""


class FileError(StatusError, OSError):
    """DQJ_ERROR_IO: a file could not be read or written (nothing partial is left)."""


class CancelledError(StatusError):
    """DQJ_ERROR_CANCELLED: the work was cancelled (its progress callback asked to stop)."""


class OutOfMemoryError(StatusError, MemoryError):
    """DQJ_ERROR_OUT_OF_MEMORY: the work would need more memory than allowed (refused before it
    starts, with the estimate) or memory ran out."""


class InternalError(StatusError):
    """DQJ_ERROR_INTERNAL: a fault inside the library (please report it)."""


class BusyError(StatusError):
    """DQJ_ERROR_BUSY: another call on the same context is running; one call at a time."""


# dqj_status -> the class raised for it.
ERROR_CLASSES: Dict[int, Type[StatusError]] = {
    ERROR_INVALID_HANDLE: InvalidHandleError,
    ERROR_INVALID_ARGUMENT: InvalidArgumentError,
    ERROR_PARAMETERS: ParameterError,
    ERROR_IO: FileError,
    ERROR_CANCELLED: CancelledError,
    ERROR_OUT_OF_MEMORY: OutOfMemoryError,
    ERROR_INTERNAL: InternalError,
    ERROR_BUSY: BusyError,
}


def error_for(status: int, message: str) -> StatusError:
    """The exception for a status: its class of ERROR_CLASSES (StatusError for an unknown one)."""
    return ERROR_CLASSES.get(status, StatusError)(status, message)


# The add-on's names.
NativeError = StatusError
NativeUnavailable = LibraryUnavailableError


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
_uint64_p = ctypes.POINTER(ctypes.c_uint64)
_char_buffer = ctypes.c_char_p

_BAKE = (FEATURE_VDB, FEATURE_MESH)  # the calls bakes and meshes share

# name: (restype, argtypes, features): None for a function every library has, else the
# features of which any one brings it.
_SIGNATURES: Dict[str, Tuple[Any, List[Any], Optional[Tuple[str, ...]]]] = {
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
    "dqj_mesh_estimate": (
        _status,
        [_handle, _uint64_p, _uint64_p, _uint64_p, PROGRESS_FN, ctypes.c_void_p],
        (FEATURE_MESH,),
    ),
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
    "dqj_variations_compute": (
        _status,
        [_handle, ctypes.c_uint64, ctypes.c_double, ctypes.c_uint32, ctypes.c_uint32, PROGRESS_FN, ctypes.c_void_p],
        (FEATURE_VARIATIONS,),
    ),
    "dqj_variations_get_json": (
        _status,
        [_handle, ctypes.c_void_p, ctypes.c_size_t, _size_p],
        (FEATURE_VARIATIONS,),
    ),
    "dqj_variation_get_params_json": (
        _status,
        [_handle, ctypes.c_size_t, ctypes.c_void_p, ctypes.c_size_t, _size_p],
        (FEATURE_VARIATIONS,),
    ),
}

_lock = threading.Lock()
_library: Optional[ctypes.CDLL] = None
_load_error: Optional[str] = None
_library_path: Optional[str] = None
_dll_directory: Optional[object] = None  # Windows: the library's folder, added to the DLL search path while loaded
_features: FrozenSet[str] = frozenset()  # the FEATURES the loaded library has
_bound: FrozenSet[str] = frozenset()  # the functions of _SIGNATURES it offers


def version_text(number: int) -> str:
    return "%d.%d.%d" % (number // 10000, number // 100 % 100, number % 100)


_GLIBC_TEXT = "glibc %d.%d" % GLIBC_FLOOR
# What the library needs of the system it runs on, by sys.platform (for the message when it does not load).
_REQUIREMENTS = {
    "win32": "64-bit Windows (x64) with its own system libraries",
    "linux": "Linux x86-64 with %s or newer (Debian 12, Ubuntu 22.04, RHEL 9, Fedora 35 or later)" % _GLIBC_TEXT,
}


def platform_problem() -> Optional[str]:
    """None when this system can run dqjulia's native code as far as can be told without loading
    it, else why not in plain words. On Linux: the C library must be glibc at GLIBC_FLOOR or newer
    (asked with os.confstr, so nothing is loaded that would fail with a loader error)."""
    if not sys.platform.startswith("linux"):
        return None
    try:
        found = os.confstr("CS_GNU_LIBC_VERSION") or ""  # "glibc 2.36"
    except (AttributeError, ValueError, OSError):
        found = ""
    match = re.match(r"glibc (\d+)\.(\d+)", found)
    needs = "dqjulia's native code needs %s" % _REQUIREMENTS["linux"]
    if match is None:
        return "%s; this system's C library is not glibc (%s)" % (needs, found or "unknown")
    version = (int(match.group(1)), int(match.group(2)))
    if version < GLIBC_FLOOR:
        found = "glibc %d.%d" % version
        return "%s; this system has %s, older than %s. Use a newer system, or build dqjulia from source on it" % (
            needs,
            found,
            _GLIBC_TEXT,
        )
    return None


def bundled_file(folder: str, tree_folder: str, name: str) -> str:
    """A native file shipped with this code: FOLDER/NAME beside this file, where the add-on zip and
    the wheel put it. The package's modules alone in an install tree, as
    <prefix>/lib/python/dqjulia, use the tree's own file instead: <prefix>/TREE_FOLDER/NAME."""
    here = os.path.dirname(os.path.abspath(__file__))
    beside = os.path.join(here, folder, name)
    python_folder = os.path.dirname(here)
    if os.path.isfile(beside) or os.path.basename(python_folder) != "python":
        return beside
    in_tree = os.path.join(os.path.dirname(os.path.dirname(python_folder)), tree_folder, name)
    return in_tree if os.path.isfile(in_tree) else beside


def bundled_library_path() -> str:
    """Where the library is: lib/ beside this file (the one made for this platform), or an install
    tree's lib/libdqjulia.so or bin/dqjulia.dll (bundled_file)."""
    if sys.platform == "win32":
        return bundled_file("lib", "bin", "dqjulia.dll")
    return bundled_file("lib", "lib", {"darwin": "libdqjulia.dylib"}.get(sys.platform, "libdqjulia.so"))


def library_path() -> str:
    return os.environ.get(LIBRARY_ENV) or bundled_library_path()


def _bind(library: ctypes.CDLL) -> Tuple[FrozenSet[str], FrozenSet[str]]:
    """Declares the functions the library offers: every required one, and those of the
    optional features it says it has. Returns (features, function names)."""

    def declare(name: str, restype: Any, argtypes: List[Any]) -> None:
        try:
            function = getattr(library, name)
        except AttributeError:
            raise LibraryUnavailableError(
                "the dqjulia library at %s has no function %s: it is not the library %s was built with; %s"
                % (_library_path, name, HOST, REINSTALL)
            ) from None
        function.restype = restype
        function.argtypes = argtypes

    restype, argtypes, _ = _SIGNATURES["dqj_has_feature"]
    declare("dqj_has_feature", restype, argtypes)
    features = frozenset(name for name in FEATURES if library.dqj_has_feature(name.encode()) == 1)
    bound: set[str] = set()
    for name, (restype, argtypes, needs) in _SIGNATURES.items():
        if needs is None or features.intersection(needs):
            declare(name, restype, argtypes)
            bound.add(name)
    return features, frozenset(bound)


def _load() -> Tuple[ctypes.CDLL, Tuple[FrozenSet[str], FrozenSet[str]]]:
    global _library_path, _dll_directory
    path = library_path()
    _library_path = path
    problem = platform_problem()
    if problem is not None:
        raise LibraryUnavailableError(problem)
    if not os.path.isfile(path):
        raise LibraryUnavailableError(
            "the dqjulia native library is missing: expected %s, which %s holds; %s" % (path, HOST, REINSTALL)
        )
    try:
        if hasattr(os, "add_dll_directory") and _dll_directory is None:  # Windows: DLLs beside it are found
            _dll_directory = os.add_dll_directory(os.path.dirname(os.path.abspath(path)))
        library = ctypes.CDLL(path)
    except OSError as error:
        raise LibraryUnavailableError(
            "the dqjulia native library at %s could not be loaded (%s). It is self-contained and needs only "
            "%s; on another system, build dqjulia there (docs/developing.md, Two commands)"
            % (path, error, _REQUIREMENTS.get(sys.platform, _REQUIREMENTS["linux"]))
        ) from error
    try:
        version_number = library.dqj_version_number
    except AttributeError:
        raise LibraryUnavailableError("%s is not the dqjulia library (no dqj_version_number)" % path) from None
    version_number.restype = ctypes.c_uint
    version_number.argtypes = []
    found: int = version_number()
    if EXPECTED_VERSION is None:
        raise LibraryUnavailableError(
            "%s has no _buildinfo.py and is not in dqjulia's source tree, so it cannot tell which library "
            "version it was written for: %s" % (os.path.dirname(os.path.abspath(__file__)), REINSTALL)
        )
    if found // 10000 != EXPECTED_VERSION // 10000 or found < EXPECTED_VERSION:
        raise LibraryUnavailableError(
            "the dqjulia library at %s is version %s, but %s needs %s (same major version, not older): "
            "%s, so that it and its library come from the same build"
            % (path, version_text(found), HOST, version_text(EXPECTED_VERSION), REINSTALL)
        )
    return library, _bind(library)


def library() -> ctypes.CDLL:
    """The loaded library; raises LibraryUnavailableError (with the reason) if it cannot be used."""
    global _library, _load_error, _features, _bound
    with _lock:
        if _library is None and _load_error is None:
            try:
                _library, (_features, _bound) = _load()
            except LibraryUnavailableError as error:
                _load_error = str(error)
        if _library is None:
            raise LibraryUnavailableError(_load_error)
        return _library


def load_error() -> Optional[str]:
    """None when the library is usable, else why not (for the UI)."""
    try:
        library()
        return None
    except LibraryUnavailableError as error:
        return str(error)


def reset() -> None:
    """Forget the loaded library and the last error, so the next use tries again (tests)."""
    global _library, _load_error, _features, _bound
    with _lock:
        _library = None
        _load_error = None
        _features = frozenset()
        _bound = frozenset()


def has_feature(name: str) -> bool:
    """Whether the loaded library has this optional feature (FEATURE_*; False if it cannot be
    loaded or this copy does not know the name)."""
    try:
        library()
    except LibraryUnavailableError:
        return False
    return name in _features


def has(name: str) -> bool:
    """Whether the loaded library offers this function of _SIGNATURES (False if it cannot be
    loaded)."""
    try:
        library()
    except LibraryUnavailableError:
        return False
    return name in _bound


def version() -> Tuple[int, str]:
    """(number, text) of the loaded library."""
    lib = library()
    text: bytes = lib.dqj_version_string()
    return int(lib.dqj_version_number()), text.decode()


def status_text(status: int) -> str:
    text: bytes = library().dqj_status_string(status)
    return text.decode()


def _function(name: str) -> Callable[..., Any]:
    lib = library()
    if name not in _bound:
        raise LibraryUnavailableError(
            "the dqjulia library %s has no %s (it lacks the feature %s); %s needs a library that has it"
            % (version()[1], name, " or ".join(_SIGNATURES[name][2] or ()) if name in _SIGNATURES else "?", HOST)
        )
    function: Callable[..., Any] = getattr(lib, name)
    return function


class Progress:
    """A progress callback for one native call: records the fraction, asks to cancel.

    `callback` is the ctypes function pointer to pass; keep this object alive during the call
    (ctypes does not). `cancel()` may be called from any thread; the native call then returns
    DQJ_ERROR_CANCELLED at its next progress report (a few times a second).

    An exception never unwinds into C. One raised by `on_progress` cancels the work when
    `cancel_on_error` is set, and always when it is not an Exception (a KeyboardInterrupt from
    Ctrl-C, delivered while the callback runs Python code): it is kept in `error` and raised by
    `raise_error()` once the native call has returned. Otherwise it is ignored and the work goes on.
    """

    def __init__(self, on_progress: Optional[OnProgress] = None, cancel_on_error: bool = False) -> None:
        self.fraction = 0.0
        self.error: Optional[BaseException] = None
        self._cancel = threading.Event()
        self._on_progress = on_progress
        self._cancel_on_error = cancel_on_error
        self.callback = PROGRESS_FN(self._report)

    def _report(self, fraction: float, _user: Optional[int]) -> int:
        try:
            self.fraction = max(0.0, min(1.0, float(fraction)))
            if self._on_progress is not None:
                self._on_progress(self.fraction)
        except BaseException as error:  # an exception must never unwind into C
            if self._cancel_on_error or not isinstance(error, Exception):
                self.error = self.error or error
                self._cancel.set()
        return 0 if self._cancel.is_set() else 1  # dqj_progress_fn: non-zero goes on, 0 cancels

    def cancel(self) -> None:
        self._cancel.set()

    @property
    def cancelled(self) -> bool:
        return self._cancel.is_set()

    def raise_error(self) -> None:
        """Raises the exception the callback kept, if any (after the native call returned)."""
        if self.error is not None:
            error, self.error = self.error, None
            raise error


def _text(pointer: Optional[bytes]) -> str:
    return pointer.decode("utf-8", "replace") if pointer else ""


def _json_object(text: str) -> Dict[str, Any]:
    """The JSON object of a text the library wrote."""
    value: Dict[str, Any] = json.loads(text)
    return value


# A mesh's arrays as Context.mesh_faces gives them: positions, normals, colours (or None), quads
# and triangles.
MeshFaces = Tuple[
    "ctypes.Array[ctypes.c_float]",
    "ctypes.Array[ctypes.c_float]",
    "Optional[ctypes.Array[ctypes.c_float]]",
    "ctypes.Array[ctypes.c_uint32]",
    "ctypes.Array[ctypes.c_uint32]",
]


class Context:
    """A dqj_context: a parameter set and the text of its last error. One thread at a time."""

    def __init__(self, params: Optional[Document] = None) -> None:
        self._lib = library()
        handle = _handle()
        status = self._lib.dqj_context_create(ctypes.byref(handle))
        if status != OK:
            raise error_for(status, "dqj_context_create failed: %s" % status_text(status))
        self._handle: Optional[ctypes.c_void_p] = handle
        if params is not None:
            self.set_params(params)

    def close(self) -> None:
        """Destroys the native context. Raises BusyError if one of its calls is still running,
        e.g. when called from that call's progress callback: cancel instead."""
        if getattr(self, "_handle", None):
            status = self._lib.dqj_context_destroy(self._handle)
            if status == ERROR_BUSY:
                raise BusyError(status, "the dqjulia context is busy (a call on it is running): cancel it first")
            self._handle = None

    def __del__(self) -> None:
        try:
            self.close()
        except Exception:
            pass

    def __enter__(self) -> Context:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    @property
    def handle(self) -> ctypes.c_void_p:
        if not self._handle:
            raise InvalidHandleError(ERROR_INVALID_HANDLE, "the dqjulia context was closed")
        return self._handle

    def error(self) -> str:
        return _text(self._lib.dqj_context_error(self.handle))

    def warning(self) -> str:
        return _text(self._lib.dqj_context_warning(self.handle))

    def check(self, status: int, what: Optional[str]) -> None:
        if status != OK:
            message = self.error() or status_text(status)
            raise error_for(status, "%s: %s" % (what, message) if what else message)

    def _text_out(self, function_name: str) -> str:
        function = _function(function_name)
        size = ctypes.c_size_t(0)
        self.check(function(self.handle, None, 0, ctypes.byref(size)), function_name)
        buffer = ctypes.create_string_buffer(size.value)
        self.check(function(self.handle, buffer, size.value, ctypes.byref(size)), function_name)
        return buffer.value.decode("utf-8")

    def _indexed_text_out(self, function_name: str, index: int) -> str:
        function = _function(function_name)
        size = ctypes.c_size_t(0)
        self.check(function(self.handle, index, None, 0, ctypes.byref(size)), function_name)
        buffer = ctypes.create_string_buffer(size.value)
        self.check(function(self.handle, index, buffer, size.value, ctypes.byref(size)), function_name)
        return buffer.value.decode("utf-8")

    def _run(self, what: str, function: Callable[..., int], progress: Optional[Progress], *arguments: Any) -> str:
        """A call that reports progress: `function(handle, *arguments, callback, None)`. An error
        kept by the callback (an exception in on_progress, Ctrl-C) is raised in place of the
        cancel it caused."""
        progress = progress or Progress()
        status = function(self.handle, *arguments, progress.callback, None)
        progress.raise_error()
        self.check(status, what)
        return self.warning()

    # Parameters -------------------------------------------------------------------------

    def load_params_file(self, path: Union[str, os.PathLike[str]]) -> None:
        self.check(self._lib.dqj_context_load_params_file(self.handle, os.fsencode(path)), None)

    def set_params_json(self, text: str) -> None:
        self.check(self._lib.dqj_context_set_params_json(self.handle, text.encode("utf-8")), None)

    def set_params(self, document: Document) -> None:
        """Sets the whole parameter document (a dict or JSON text); the core validates it."""
        self.set_params_json(document if isinstance(document, str) else json.dumps(document))

    def params_json(self) -> str:
        return self._text_out("dqj_context_get_params_json")

    def params(self) -> Dict[str, Any]:
        """The complete parameter document the core holds (every key), as a dict."""
        return _json_object(self.params_json())

    def schema(self) -> Dict[str, Any]:
        """The parameter schema (dqj_params_schema_json) as a dict: every key's type, label, help,
        default and range. The add-on's props.py builds its properties from the packaged copy
        (schema.json)."""
        return _json_object(self._text_out("dqj_params_schema_json"))

    def inspect(self) -> Dict[str, Any]:
        """dqj_inspect_json as a dict: equivalent complex constants, bounds, emptiness and why."""
        return _json_object(self._text_out("dqj_inspect_json"))

    # Evaluation -------------------------------------------------------------------------

    def evaluate_points(self, points: Iterable[Sequence[float]]) -> List[Sample]:
        """points: sequence of 8-number sequences. Returns a list of Sample."""
        return self._evaluate(points, 8)

    def evaluate_slice_points(self, points: Iterable[Sequence[float]]) -> List[Sample]:
        """points: sequence of (x, y, z) in the slice. Returns a list of Sample."""
        return self._evaluate(points, 3)

    def _evaluate(self, points: Iterable[Sequence[float]], width: int) -> List[Sample]:
        listed = list(points)
        flat = (ctypes.c_double * (width * len(listed)))()
        for index, point in enumerate(listed):
            if len(point) != width:
                raise ValueError("each point needs %d numbers" % width)
            flat[width * index : width * index + width] = [float(x) for x in point]
        out = (Sample * max(1, len(listed)))()
        self.evaluate_into(flat, len(listed), out, slice_points=width == 3)
        return list(out[: len(listed)])

    def evaluate_into(self, points: Buffer, count: int, out: Buffer, slice_points: bool = False) -> None:
        """Evaluates `count` points from a buffer of doubles (8 a point, or 3 with slice_points)
        into a buffer of `count` Sample: ctypes arrays or pointers (a NumPy array's
        `ctypes.data_as(...)`), sized by the caller."""
        name = "dqj_evaluate_slice_points" if slice_points else "dqj_evaluate_points"
        self.check(getattr(self._lib, name)(self.handle, points, count, out), name)

    # Rendering --------------------------------------------------------------------------

    def render_rgba8(self, width: int, height: int, progress: Optional[Progress] = None) -> Tuple[bytes, str]:
        """Renders with the core's renderer; returns (bytes RGBA8 sRGB rows top-down, warning)."""
        stride = 4 * width
        pixels = (ctypes.c_uint8 * (stride * height))()
        warning = self.render_rgba8_into(pixels, width, height, stride, progress)
        return bytes(pixels), warning

    def render_rgba8_into(
        self, pixels: Buffer, width: int, height: int, stride: int, progress: Optional[Progress] = None
    ) -> str:
        """Renders into a caller's buffer of `height` rows of `stride` bytes (a ctypes array or
        pointer); returns the warning ("" if none)."""
        return self._run("render", self._lib.dqj_render_rgba8, progress, pixels, width, height, stride)

    def render_to_file(self, path: Union[str, os.PathLike[str]], progress: Optional[Progress] = None) -> str:
        return self._run("render", self._lib.dqj_render_to_file, progress, os.fsencode(path))

    # Baking -----------------------------------------------------------------------------

    def set_frame(self, frame: float) -> None:
        self.check(_function("dqj_context_set_frame")(self.handle, float(frame)), "frame")

    def set_bake_resolution(self, resolution: int) -> None:
        self.check(_function("dqj_context_set_bake_resolution")(self.handle, int(resolution)), "bake resolution")

    def set_memory_limit(self, limit_bytes: int) -> None:
        self.check(_function("dqj_context_set_memory_limit")(self.handle, int(limit_bytes)), "memory limit")

    def bake_vdb(self, path: Union[str, os.PathLike[str]], progress: Optional[Progress] = None) -> str:
        """Writes an OpenVDB file (grids "surface", "density" and bake.grids); all or nothing.
        Returns the context's warning ("" if none)."""
        return self._run("bake", _function("dqj_bake_vdb"), progress, os.fsencode(path))

    def mesh_compute(self, progress: Optional[Progress] = None) -> str:
        return self._run("mesh", _function("dqj_mesh_compute"), progress)

    def mesh_estimate(self, progress: Optional[Progress] = None) -> Tuple[int, int, int]:
        """(bytes, slabs, faces) mesh_compute would take with these parameters and memory limit,
        from the classification alone: the memory estimate checked against the limit, the slabs
        (1: one piece), about how many triangles. A mesh that cannot fit raises NativeError with
        the reason (status DQJ_ERROR_OUT_OF_MEMORY)."""
        size, slabs, faces = ctypes.c_uint64(0), ctypes.c_uint64(0), ctypes.c_uint64(0)
        self._run(
            "mesh estimate",
            _function("dqj_mesh_estimate"),
            progress,
            ctypes.byref(size),
            ctypes.byref(slabs),
            ctypes.byref(faces),
        )
        return size.value, slabs.value, faces.value

    def mesh_sizes(self) -> Tuple[int, int]:
        vertices, triangles = ctypes.c_size_t(0), ctypes.c_size_t(0)
        self.check(
            _function("dqj_mesh_get_sizes")(self.handle, ctypes.byref(vertices), ctypes.byref(triangles)), "mesh sizes"
        )
        return vertices.value, triangles.value

    def mesh_face_counts(self) -> Tuple[int, int]:
        """(quads, triangles) of the context's mesh as the core made it."""
        quads, triangles = ctypes.c_size_t(0), ctypes.c_size_t(0)
        self.check(
            _function("dqj_mesh_get_face_counts")(self.handle, ctypes.byref(quads), ctypes.byref(triangles)),
            "mesh face counts",
        )
        return quads.value, triangles.value

    def mesh_copy_into(
        self,
        positions: Buffer,
        normals: Buffer,
        colors: Buffer,
        vertex_capacity: int,
        triangles: Buffer = None,
        triangle_capacity: int = 0,
    ) -> None:
        """dqj_mesh_copy into caller buffers (ctypes arrays or pointers; normals, colors and
        triangles may be None)."""
        function = _function("dqj_mesh_copy")
        self.check(
            function(self.handle, positions, normals, colors, vertex_capacity, triangles, triangle_capacity),
            "mesh copy",
        )

    def mesh_copy_faces_into(
        self, quads: Buffer, quad_capacity: int, triangles: Buffer, triangle_capacity: int
    ) -> None:
        """dqj_mesh_copy_faces into caller buffers of 4 and 3 uint32 a face."""
        function = _function("dqj_mesh_copy_faces")
        self.check(function(self.handle, quads, quad_capacity, triangles, triangle_capacity), "mesh faces")

    def mesh_faces(self, colors: bool = True) -> MeshFaces:
        """The context's mesh with its faces as the core made them: (positions, normals, colors or
        None, quads, triangles) as ctypes arrays; 4 and 3 uint32 indices a face."""
        vertex_count, _triangle_count = self.mesh_sizes()
        positions = (ctypes.c_float * (3 * vertex_count))()
        normals = (ctypes.c_float * (3 * vertex_count))()
        colours = (ctypes.c_float * (3 * vertex_count))() if colors else None
        self.mesh_copy_into(positions, normals, colours, vertex_count)
        quad_count, triangle_count = self.mesh_face_counts()
        quads = (ctypes.c_uint32 * (4 * quad_count))()
        triangles = (ctypes.c_uint32 * (3 * triangle_count))()
        self.mesh_copy_faces_into(quads, quad_count, triangles, triangle_count)
        return positions, normals, colours, quads, triangles

    def mesh_write(self, path: Union[str, os.PathLike[str]]) -> None:
        self.check(_function("dqj_mesh_write")(self.handle, os.fsencode(path)), "mesh write")

    def bake_stats(self) -> BakeStats:
        stats = BakeStats(struct_size=ctypes.sizeof(BakeStats))
        self.check(_function("dqj_bake_get_stats")(self.handle, ctypes.byref(stats)), "bake stats")
        return stats

    # Variations -------------------------------------------------------------------------

    def variations_compute(
        self,
        seed: int,
        strength: float = STRENGTHS["medium"],
        locked_groups: int = GROUP_VARIANT,
        count: int = 9,
        progress: Optional[Progress] = None,
    ) -> str:
        """Computes `count` variations of the context's parameters (feature "variations") and
        keeps them in the context. `locked_groups`: GROUP_* bits that stay as they are. Raises
        InvalidArgumentError for a bad strength, count or lock, ParameterError for an empty start
        or when too few pass (the message says how to loosen the settings)."""
        return self._run(
            "variations",
            _function("dqj_variations_compute"),
            progress,
            ctypes.c_uint64(int(seed) & 0xFFFFFFFFFFFFFFFF),
            float(strength),
            int(locked_groups),
            int(count),
        )

    def variations(self) -> Dict[str, Any]:
        """dqj_variations_get_json as a dict: the candidates, the rejections by measure and each
        variation's measures and description."""
        return _json_object(self._text_out("dqj_variations_get_json"))

    def variation_params_json(self, index: int) -> str:
        """Variation `index` as a complete parameter document (JSON text), for set_params_json."""
        return self._indexed_text_out("dqj_variation_get_params_json", int(index))

    def variation_params(self, index: int) -> Dict[str, Any]:
        return _json_object(self.variation_params_json(index))

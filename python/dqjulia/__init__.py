"""dqjulia: dual-quaternion Julia fractals from Python.

A Python API over libdqjulia's C ABI (ctypes; the library ships inside the package) for
pipelines and notebooks::

    import dqjulia

    with dqjulia.Fractal.from_file("examples/paper-test2-2.json") as fractal:
        fractal.update({"fractal": {"iterations": 12}})      # validated by the library
        image = fractal.render(320, 240)                     # (240, 320, 4) uint8, sRGB RGBA
        fractal.render_to_file("out.png")
        samples = fractal.evaluate_slice([[0.1, 0.2, 0.3]])  # fields n, r, ra, rb, de
        stats = fractal.bake("out.vdb", resolution=128)      # OpenVDB: "surface", "density"
        mesh = fractal.mesh(resolution=128)                  # mesh.vertices, .quads, .triangles

Parameters come from a dict (`Fractal(params)`), JSON text (`Fractal.from_json`) or a file
(`Fractal.from_file`), in the format of the command's parameter files. Errors are exceptions of
one hierarchy under DqjuliaError, one class a status of the C ABI, carrying the library's
message. The functions that take or give arrays need NumPy (`pip install "dqjulia[numpy]"`);
the rest does not. The package also installs the `dqjulia` command (`command_path()` gives its
native program).

The native code needs Linux x86-64 with glibc 2.34 or newer, or 64-bit Windows: importing the
package on an older Linux raises ImportError saying so.
"""

from __future__ import annotations

import os
import sys

from . import _native

_problem = _native.platform_problem()
if _problem is not None:
    if os.path.basename(sys.argv[0] if sys.argv else "") == "dqjulia":
        # Imported by the `dqjulia` command's entry point: one line for a person, no traceback.
        sys.stderr.write("dqjulia: %s\n" % _problem)
        raise SystemExit(1)
    raise ImportError(_problem)

from ._cli import command_path
from ._fractal import (
    BakeStats,
    DqjuliaWarning,
    Fractal,
    Mesh,
    ProgressCallback,
    defaults,
    has_feature,
    library_version,
    sample_dtype,
    schema,
)
from ._native import (
    BusyError,
    CancelledError,
    DqjuliaError,
    FileError,
    InternalError,
    InvalidArgumentError,
    InvalidHandleError,
    LibraryUnavailableError,
    OutOfMemoryError,
    ParameterError,
    StatusError,
)

__version__: str = getattr(_native._buildinfo, "PROJECT_VERSION", "0+unknown")
"""The version of the package, which is the version of the library it carries."""

__all__ = [
    "BakeStats",
    "BusyError",
    "CancelledError",
    "DqjuliaError",
    "DqjuliaWarning",
    "FileError",
    "Fractal",
    "InternalError",
    "InvalidArgumentError",
    "InvalidHandleError",
    "LibraryUnavailableError",
    "Mesh",
    "OutOfMemoryError",
    "ParameterError",
    "ProgressCallback",
    "StatusError",
    "__version__",
    "command_path",
    "defaults",
    "has_feature",
    "library_version",
    "sample_dtype",
    "schema",
]

"""Run by wheel_install_test.py with the Python of a fresh venv that has the wheel and NumPy: the
package's API does what the command does, and writes what it made into WORK for the test to
compare with the build's command (it needs nothing but the package and NumPy).

Usage: python api_run.py PARAMS EMPTY_PARAMS POINTS8 POINTS3 WORK   (EMPTY_PARAMS: a file whose slice is empty)

Writes into WORK: api.png (render_to_file), api_render.rgba (render(): the array's bytes),
api.vdb (bake), api.ply, api.stl and api.3mf (mesh_to_file), api_mesh_*.bin (mesh(): each array's bytes), and
api.json: the shapes, the evaluations' values (repr, exact), the bake's stats, and the checks of
parameters from a dict, JSON text and a file, errors, progress and cancel.
"""

import json
import os
import sys
import threading
import warnings

import dqjulia
import numpy


def main():
    params_path, empty_path, points8_path, points3_path, work = sys.argv[1:6]
    result = {"checks": {}}
    checks = result["checks"]

    with open(params_path, encoding="utf-8") as file:
        document = json.load(file)
    from_file = dqjulia.Fractal.from_file(params_path)
    from_dict = dqjulia.Fractal(document)
    from_json = dqjulia.Fractal.from_json(json.dumps(document))
    checks["a dict, JSON text and the file give one document"] = (
        from_file.params == from_dict.params == from_json.params
    )
    for made in (from_file, from_dict, from_json):
        made.close()

    fractal = dqjulia.Fractal.from_file(params_path)
    result["version"] = [dqjulia.__version__, dqjulia.library_version()]
    result["numpy"] = numpy.__version__

    try:
        fractal.update({"fractal": {"iterations": -1}})
        checks["a bad value raises ParameterError"] = False
    except dqjulia.ParameterError as error:
        checks["a bad value raises ParameterError, a ValueError, naming the key: %s" % error] = (
            isinstance(error, ValueError) and "fractal.iterations" in str(error) and error.status == 3
        )
    checks["the rejected value left the parameters as they were"] = fractal.params == from_file_params(params_path)
    try:
        fractal.load(os.path.join(work, "no-such-file.json"))
        checks["a missing parameter file raises ParameterError"] = False
    except dqjulia.ParameterError as error:  # the library's status for a parameter file it cannot read
        checks["a missing parameter file raises ParameterError, saying so: %s" % error] = "cannot read" in str(error)
    try:
        fractal.render_to_file(os.path.join(work, "no-such-folder", "out.png"))
        checks["an unwritable output raises FileError"] = False
    except dqjulia.FileError as error:
        checks["an unwritable output raises FileError, an OSError: %s" % error] = isinstance(error, OSError)
    except dqjulia.DqjuliaError as error:
        checks["an unwritable output raises FileError, not %s: %s" % (type(error).__name__, error)] = False

    # Evaluation: one call for all points, arrays of any leading shape.
    points8 = numpy.loadtxt(points8_path, ndmin=2)
    points3 = numpy.loadtxt(points3_path, ndmin=2)
    samples8 = fractal.evaluate(points8)
    samples3 = fractal.evaluate_slice(points3)
    grid = fractal.evaluate_slice(points3[:6].reshape(2, 3, 3))
    checks["evaluate_slice keeps the leading shape (2, 3)"] = grid.shape == (2, 3) and bool(
        (grid.ravel() == samples3[:6]).all()
    )
    try:
        fractal.evaluate(points3)
        checks["points of the wrong width raise ValueError"] = False
    except ValueError:
        checks["points of the wrong width raise ValueError"] = True
    result["evaluate"] = [
        [repr(float(sample[name])) if name != "n" else int(sample[name]) for name in ("n", "r", "ra", "rb", "de")]
        for sample in samples8
    ]
    result["evaluate_slice"] = [
        [repr(float(sample[name])) if name != "n" else int(sample[name]) for name in ("n", "r", "ra", "rb", "de")]
        for sample in samples3
    ]

    # Rendering, with progress reports.
    fractions = []
    fractal.render_to_file(os.path.join(work, "api.png"), progress=fractions.append)
    checks["render_to_file reported progress from 0 to 1 (%d reports)" % len(fractions)] = (
        len(fractions) >= 2 and fractions[0] == 0.0 and fractions[-1] == 1.0
    )
    image = fractal.render()
    result["render_shape"] = list(image.shape)
    checks["render() gives uint8"] = image.dtype == numpy.uint8
    with open(os.path.join(work, "api_render.rgba"), "wb") as file:
        file.write(image.tobytes())

    # Cancel (an Event set before the call) and a callback returning False: CancelledError, no file.
    cancelled_path = os.path.join(work, "cancelled.vdb")
    stop = threading.Event()
    stop.set()
    try:
        fractal.bake(cancelled_path, cancel=stop)
        checks["a set cancel Event cancels the bake"] = False
    except dqjulia.CancelledError:
        checks["a set cancel Event cancels the bake, leaving no file"] = not os.path.exists(cancelled_path)
    try:
        fractal.render(progress=lambda fraction: False)
        checks["a progress callback returning False cancels the render"] = False
    except dqjulia.CancelledError as error:
        checks["a progress callback returning False cancels: %s" % error] = error.status == 5

    # Bake and mesh.
    stats = fractal.bake(os.path.join(work, "api.vdb"))
    result["bake_stats"] = {"active_voxels": stats.active_voxels, "voxels_evaluated": stats.voxels_evaluated}
    mesh = fractal.mesh()
    triangulated = fractal.mesh(triangulate=True)
    checks["triangulate gives every face as triangles"] = len(triangulated.quads) == 0 and len(
        triangulated.triangles
    ) == 2 * len(mesh.quads) + len(mesh.triangles)
    result["mesh_shapes"] = {}
    for name in ("vertices", "normals", "colors", "quads", "triangles"):
        array = getattr(mesh, name)
        result["mesh_shapes"][name] = [list(array.shape), str(array.dtype)]
        with open(os.path.join(work, "api_mesh_%s.bin" % name), "wb") as file:
            file.write(array.tobytes())
    for extension in ("ply", "stl", "3mf"):
        fractal.mesh_to_file(os.path.join(work, "api." + extension))

    # An empty slice: the library's warning as a DqjuliaWarning.
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        with dqjulia.Fractal.from_file(empty_path) as empty:
            empty.render(32, 24)
            checks["an empty slice warns (DqjuliaWarning): %s" % empty.warning[:60]] = bool(empty.warning) and any(
                issubclass(warning.category, dqjulia.DqjuliaWarning) for warning in caught
            )

    fractal.close()
    try:
        fractal.inspect()
        checks["a closed Fractal raises InvalidHandleError"] = False
    except dqjulia.InvalidHandleError:
        checks["a closed Fractal raises InvalidHandleError"] = True
    checks["schema() lists fractal.iterations"] = "fractal" in json.dumps(dqjulia.schema())
    checks["has_feature: vdb, mesh, animation"] = all(
        dqjulia.has_feature(name) for name in ("vdb", "mesh", "animation")
    )

    with open(os.path.join(work, "api.json"), "w", encoding="utf-8") as file:
        json.dump(result, file, indent=1)
    return 0


def from_file_params(path):
    with dqjulia.Fractal.from_file(path) as fractal:
        return fractal.params


if __name__ == "__main__":
    sys.exit(main())

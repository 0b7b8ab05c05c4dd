"""Every mesh format read back by independent readers: `dqjulia mesh` writes .ply, .obj, .stl and
.3mf of the default fractal at 64^3 and of the unit ball; trimesh reads each (its own PLY, OBJ, STL
and 3MF loaders, vertices merged by position) and finds it watertight with consistent winding, and
the test counts every edge itself: each undirected edge in exactly two triangles, each directed
edge in one (closed, edge-manifold, oriented). The triangle counts are the triangulated faces
`--stats` reports, the bounds agree across formats, the ball is a sphere within a voxel. lib3mf, the 3MF
Consortium's library, reads the 3MF: its counts, unit, manifold check, and the colour of every
triangle corner, which must be the PLY's colour of that vertex. `--units/--size` give each format
a least corner at 0 and a largest side of the size; nonsense sizes and units are refused (exit 2,
the reason named, no file).

Usage: MESHCHECK_PYTHON mesh_files_test.py DQJULIA WORK_DIR
(the venv of scripts/tool-env.sh meshcheck). Prints DQJ_TEST_SKIPPED without trimesh or lib3mf.
"""

import os
import shutil
import subprocess
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "common"))
from check_report import skip_or_fail  # noqa: E402 (tests/common/check_report.py)

try:
    import lib3mf
    import numpy
    import trimesh
except ImportError as error:
    skip_or_fail("trimesh or lib3mf is missing (scripts/tool-env.sh meshcheck makes their venv): %s" % error)

FORMATS = ("ply", "obj", "stl", "3mf")
BALL = ["--c", "0", "0", "0", "0", "0", "0", "0", "0", "--variant", "dual"]
BALL += ["--bounds-min", "-1.5", "-1.5", "-1.5", "--bounds-max", "1.5", "1.5", "1.5"]
SHAPES = {"default": ["-r", "64"], "ball": ["-r", "48", *BALL]}
LIB3MF_UNITS = {"mm": 1, "cm": 2, "in": 3, "m": 5}  # lib3mf's eModelUnit


def run(cli, *arguments):
    return subprocess.run([cli, "mesh", *arguments], capture_output=True, text=True)


def mesh_stats(cli, path, arguments):
    done = run(cli, "-f", "-q", "--stats", *arguments, "-o", path)
    if done.returncode != 0:
        raise SystemExit("dqjulia mesh %s failed: %s" % (" ".join(arguments), done.stderr))
    stats = {}
    for key, value in (line.split(None, 1) for line in done.stdout.splitlines()):
        try:
            stats[key] = float(value)
        except ValueError:  # a vector (print_island_1_size): not needed here
            stats[key] = value
    return stats


def edge_problems(faces):
    """Undirected edges not in exactly two triangles, directed edges in more than one."""
    directed = numpy.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    _, directed_counts = numpy.unique(directed, axis=0, return_counts=True)
    _, undirected_counts = numpy.unique(numpy.sort(directed, axis=1), axis=0, return_counts=True)
    return int((undirected_counts != 2).sum()), int((directed_counts != 1).sum())


def check_closed(failures, label, loaded, triangles):
    if len(loaded.faces) != triangles:
        failures.append("%s: %d triangles, --stats says %d" % (label, len(loaded.faces), triangles))
    open_edges, repeated = edge_problems(numpy.asarray(loaded.faces))
    if open_edges or repeated:
        failures.append("%s: %d edges not in two triangles, %d directed edges repeated" % (label, open_edges, repeated))
    if not (loaded.is_watertight and loaded.is_winding_consistent):
        failures.append(
            "%s: trimesh: watertight %s, winding consistent %s"
            % (label, loaded.is_watertight, loaded.is_winding_consistent)
        )


def read_3mf(path):
    wrapper = lib3mf.get_wrapper()
    model = wrapper.CreateModel()
    reader = model.QueryReader("3mf")
    reader.ReadFromFile(path)
    objects = model.GetMeshObjects()
    meshes = []
    while objects.MoveNext():
        meshes.append(objects.GetCurrentMeshObject())
    groups = model.GetColorGroups()
    colors = {}
    while groups.MoveNext():
        group = groups.GetCurrentColorGroup()
        for property_id in group.GetAllPropertyIDs():
            color = group.GetColor(property_id)
            colors[(group.GetResourceID(), property_id)] = (color.Red, color.Green, color.Blue)
    return model, reader.GetWarningCount(), meshes, colors


def check_3mf(failures, label, path, ply_path, stats, unit):
    model, warnings, meshes, colors = read_3mf(path)
    if warnings:
        failures.append("%s: lib3mf warned %d times" % (label, warnings))
    if model.GetUnit() != LIB3MF_UNITS[unit]:
        failures.append("%s: unit %s, expected %s" % (label, model.GetUnit(), unit))
    if len(meshes) != 1:
        failures.append("%s: %d mesh objects" % (label, len(meshes)))
        return
    mesh = meshes[0]
    if (mesh.GetVertexCount(), mesh.GetTriangleCount()) != (stats["vertices"], stats["triangulated"]):
        failures.append(
            "%s: lib3mf counts %d vertices, %d triangles; --stats %d, %d"
            % (label, mesh.GetVertexCount(), mesh.GetTriangleCount(), stats["vertices"], stats["triangulated"])
        )
    if not mesh.IsManifoldAndOriented():
        failures.append("%s: lib3mf: not manifold and oriented" % label)
    # Every corner's colour is the PLY's colour of that vertex (the same vertex order).
    ply = trimesh.load(ply_path, process=False)
    ply_colors = numpy.asarray(ply.visual.vertex_colors)[:, :3]
    indices = mesh.GetTriangleIndices()
    properties = mesh.GetAllTriangleProperties()
    wrong = 0
    for triangle, property in zip(indices, properties):
        for vertex, property_id in zip(triangle.Indices, property.PropertyIDs):
            if colors.get((property.ResourceID, property_id)) != tuple(ply_colors[vertex]):
                wrong += 1
    if len(colors) != stats["vertices"] or wrong:
        failures.append(
            "%s: %d colours for %d vertices, %d corners with another colour than the PLY's"
            % (label, len(colors), stats["vertices"], wrong)
        )


def check_shapes(cli, work, failures):
    for shape, arguments in SHAPES.items():
        bounds = {}
        for extension in FORMATS:
            path = os.path.join(work, "%s.%s" % (shape, extension))
            stats = mesh_stats(cli, path, arguments)
            label = "%s.%s" % (shape, extension)
            loaded = trimesh.load(path, force="mesh")  # process: vertices merged by position
            check_closed(failures, label, loaded, stats["triangulated"])
            bounds[extension] = loaded.bounds
            if shape == "ball":  # within a voxel (3/48) of the unit sphere, the volume its radius gives
                radii = numpy.linalg.norm(loaded.vertices, axis=1)
                sphere = 4 / 3 * numpy.pi * radii.mean() ** 3
                if abs(radii - 1).max() > 3 / 48 or abs(loaded.volume / sphere - 1) > 0.01:
                    failures.append(
                        "%s: radii %.4f to %.4f, volume %.4f (a sphere of the mean radius: %.4f)"
                        % (label, radii.min(), radii.max(), loaded.volume, sphere)
                    )
            if extension == "3mf":
                check_3mf(failures, label, path, os.path.join(work, shape + ".ply"), stats, "mm")
        for extension, box in bounds.items():
            if not numpy.allclose(box, bounds["ply"], atol=1e-5):
                failures.append(
                    "%s.%s: bounds %s, the PLY's %s" % (shape, extension, box.tolist(), bounds["ply"].tolist())
                )


def check_sizes(cli, work, failures):
    for unit, size in (("mm", 120.0), ("in", 4.5)):
        for extension in FORMATS:
            path = os.path.join(work, "sized-%s.%s" % (unit, extension))
            stats = mesh_stats(cli, path, ["-r", "48", "--units", unit, "--size", str(size)])
            label = "--units %s --size %g .%s" % (unit, size, extension)
            loaded = trimesh.load(path, force="mesh")
            check_closed(failures, label, loaded, stats["triangulated"])
            low, high = loaded.bounds
            if not (numpy.allclose(low, 0, atol=1e-6 * size) and abs(high.max() - size) <= 1e-5 * size):
                failures.append(
                    "%s: bounds %s, expected 0 to a largest side of %g" % (label, loaded.bounds.tolist(), size)
                )
            if extension == "3mf":
                check_3mf(failures, label, path, os.path.join(work, "sized-%s.ply" % unit), stats, unit)


def check_refusals(cli, work, failures):
    folder = os.path.join(work, "refused")
    os.makedirs(folder, exist_ok=True)
    cases = [
        (["--size", "120"], "needs --units"),
        (["--units", "ft"], '--units "ft": expected mm, cm, m or in'),
        (["--units", "MM", "--size", "1"], "expected mm, cm, m or in"),
        (["--units", "mm", "--size", "0"], "must be above 0"),
        (["--units", "mm", "--size", "-5"], "the size (-5 mm) must be above 0 and at most 1e+06 mm"),
        (["--units", "mm", "--size", "nan"], "must be above 0"),
        (["--units", "mm", "--size", "inf"], "must be above 0"),
        (["--units", "m", "--size", "2000"], "at most 1000 m (1 km)"),
        (["--units", "mm", "--size", "12cm"], '--size "12cm": expected a number'),
        (["--units", "mm", "--size", ""], "expected a number"),
    ]
    for extension in FORMATS:
        for arguments, message in cases:
            done = run(cli, "-r", "16", *arguments, "-o", os.path.join(folder, "m." + extension))
            if done.returncode != 2 or message not in done.stderr:
                failures.append(
                    "%s .%s: exit %d, %r (expected 2 and %r)"
                    % (" ".join(arguments), extension, done.returncode, done.stderr.strip(), message)
                )
    if os.listdir(folder):
        failures.append("refused runs left %s" % os.listdir(folder))


def main():
    cli, work = sys.argv[1], sys.argv[2]
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    failures = []
    check_shapes(cli, work, failures)
    check_sizes(cli, work, failures)
    check_refusals(cli, work, failures)
    if failures:
        print("\n".join(failures))
        sys.exit(1)
    print(
        "every format closed, edge-manifold and oriented; 3MF read by lib3mf %s with its colours; sizes and refusals"
        % ".".join(map(str, lib3mf.get_wrapper().GetLibraryVersion()))
    )


if __name__ == "__main__":
    main()

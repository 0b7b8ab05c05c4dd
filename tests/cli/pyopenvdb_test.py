"""A bake read by another OpenVDB: Debian's python3-openvdb (pyopenvdb, the shared libopenvdb10.0
with Debian's libblosc1) reads every grid of a Blosc-compressed `dqjulia bake`: the grids' names,
classes and compression, the surface's active voxels as `--stats` counts them, and the values'
ranges (the level set within its band with both signs, the fog volume 0 to 1).

Usage: /usr/bin/python3 pyopenvdb_test.py DQJULIA WORK_DIR
Prints DQJ_TEST_SKIPPED (the test is then skipped; under CI=true it fails) without pyopenvdb.
"""

import os
import subprocess
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "common"))
from check_report import skip_or_fail  # noqa: E402 (tests/common/check_report.py)

try:
    import numpy
    import pyopenvdb
except ImportError as error:
    skip_or_fail("pyopenvdb or numpy is missing (apt-get install python3-openvdb python3-numpy): %s" % error)


def main():
    cli, work = sys.argv[1], sys.argv[2]
    os.makedirs(work, exist_ok=True)
    path = os.path.join(work, "bake.vdb")
    grids = "surface,density,color,trap,iterations"
    command = [cli, "bake", "-r", "48", "--grids", grids, "-o", path, "-f", "-q", "--stats"]
    stats = dict(
        line.split(None, 1)
        for line in subprocess.run(command, check=True, capture_output=True, text=True).stdout.splitlines()
    )
    read, metadata = pyopenvdb.readAll(path)
    failures = []
    by_name = {grid.name: grid for grid in read}
    if sorted(by_name) != sorted(grids.split(",")):
        failures.append("grids %s, expected %s" % (sorted(by_name), grids))
    classes = {"surface": "level set", "density": "fog volume"}
    for name, grid in sorted(by_name.items()):
        compression = grid.metadata.get("file_compression")
        print("%s: %s, %d active voxels, %s" % (name, grid.gridClass, grid.activeVoxelCount(), compression))
        if compression != "blosc + active values":
            failures.append("%s: compression %r, expected 'blosc + active values'" % (name, compression))
        if grid.gridClass != classes.get(name, "unknown"):
            failures.append("%s: class %s" % (name, grid.gridClass))
        if grid.activeVoxelCount() < 1000:
            failures.append("%s: only %d active voxels" % (name, grid.activeVoxelCount()))
    if "dqjulia_parameters" not in metadata:
        failures.append("no dqjulia_parameters in the file's metadata")
    surface, density = by_name.get("surface"), by_name.get("density")
    if surface is not None and surface.activeVoxelCount() != int(stats["active_voxels"]):
        failures.append(
            "surface: %d active voxels, --stats says %s" % (surface.activeVoxelCount(), stats["active_voxels"])
        )
    if surface is not None and density is not None:
        low, high = surface.evalActiveVoxelBoundingBox()
        shape = tuple(b - a + 1 for a, b in zip(low, high))
        distances = numpy.zeros(shape, dtype=numpy.float32)
        surface.copyToArray(distances, ijk=low)
        band = surface.background
        fog = numpy.zeros(shape, dtype=numpy.float32)
        density.copyToArray(fog, ijk=low)
        print(
            "surface %g to %g (band %g); density %g to %g"
            % (distances.min(), distances.max(), band, fog.min(), fog.max())
        )
        if not (-band - 1e-6 <= distances.min() < 0 < distances.max() <= band + 1e-6):
            failures.append("surface values %g to %g, band %g" % (distances.min(), distances.max(), band))
        if not (fog.min() >= 0 and fog.max() == 1):
            failures.append("density values %g to %g" % (fog.min(), fog.max()))
    for failure in failures:
        print("FAIL:", failure)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())

"""Makes the hand-made VDB files in tests/fuzz/corpus/vdb/ (seeds of the VDB fuzzer, and read by
tests/robustness and tests/core): `make_vdb_seeds.py DIRECTORY`. Run it with /usr/bin/python3,
which loads Debian's python3-openvdb.

- bool-bytes.vdb: a valid file whose bools are stored as bytes other than 0 and 1, as a damaged
  or hostile file may hold them: a 16^3 block of density 1, a bool grid `flags` with one root
  tile (value byte 7, active byte 9) and the file metadata `flagged` (byte 2). OpenVDB reads
  these bytes straight into bools; scripts/patches/openvdb-10.0.1-read-bools.patch makes each
  read true, as it is meant.
- corner-cube.vdb and origin-cube.vdb: the same 8^3 cube of density 1, one at the far corner of
  the index space (its last voxel at the largest Int32 on every axis) and one at the origin,
  each placed by its transform at the world's origin: `render --voxels` draws the same picture
  of both (index arithmetic that passed the largest Int32 made the first never finish).
- far-apart-tiles.vdb: density tiles of 0.25 (below the solid threshold) at the two far corners of
  the index space, and one voxel of 0.25 at the origin: the active box spans 4e9 voxels a side,
  which `render --voxels` once stepped through ray by ray; its picture is empty.
"""

import os
import struct
import sys

import pyopenvdb as vdb

TILE = (12288, 20480, 28672)  # a root tile's origin, easy to find among the file's bytes
LARGEST = 2**31 - 1


def bool_bytes(out):
    density = vdb.FloatGrid()
    density.name = "density"
    density.fill((-8, -8, -8), (7, 7, 7), 1.0, active=True)
    density.transform = vdb.createLinearTransform(voxelSize=0.1)
    flags = vdb.BoolGrid()
    flags.name = "flags"
    flags.fill(TILE, tuple(x + 4095 for x in TILE), True, active=True)
    vdb.write(out, grids=[density, flags], metadata={"flagged": True})

    with open(out, "rb") as file:
        data = bytearray(file.read())
    # The root's tile: its origin (three int32), then its value and active flag, one byte each.
    # (The origin appears first in the grid's file_bbox_min metadata: the last match is the tile.)
    tile = data.rfind(struct.pack("<3i", *TILE)) + 12
    assert data[tile : tile + 2] == b"\x01\x01", data[tile : tile + 2]
    data[tile : tile + 2] = b"\x07\x09"
    # The metadata: name, type name "bool", size 1, the value byte.
    flagged = data.find(b"flagged\x04\x00\x00\x00bool\x01\x00\x00\x00") + 19
    assert data[flagged] == 1
    data[flagged] = 2
    with open(out, "wb") as file:
        file.write(bytes(data))


def cube(out, last):
    """An 8^3 cube of density 1 whose last voxel is (last, last, last), centred on the world's
    origin with voxels of 0.25. (Set voxel by voxel: OpenVDB's fill never ends at the corner.)"""
    grid = vdb.FloatGrid()
    grid.name = "density"
    accessor = grid.getAccessor()
    for x in range(last - 7, last + 1):
        for y in range(last - 7, last + 1):
            for z in range(last - 7, last + 1):
                accessor.setValueOn((x, y, z), 1.0)
    size = 0.25
    shift = -(last - 3.5) * size
    grid.transform = vdb.createLinearTransform(
        [[size, 0, 0, 0], [0, size, 0, 0], [0, 0, size, 0], [shift, shift, shift, 1]]
    )
    vdb.write(out, grids=[grid])


def far_apart_tiles(out):
    grid = vdb.FloatGrid()
    grid.name = "density"
    low, high = -(2**31), 2**31 - 2 * 4096  # root tiles' origins (the last one: OpenVDB's fill never ends)
    for corner in (low, high):
        grid.fill((corner,) * 3, (corner + 4095,) * 3, 0.25, active=True)
    grid.getAccessor().setValueOn((0, 0, 0), 0.25)
    vdb.write(out, grids=[grid])


def main(directory):
    bool_bytes(os.path.join(directory, "bool-bytes.vdb"))
    cube(os.path.join(directory, "corner-cube.vdb"), LARGEST)
    cube(os.path.join(directory, "origin-cube.vdb"), 7)
    far_apart_tiles(os.path.join(directory, "far-apart-tiles.vdb"))


if __name__ == "__main__":
    main(sys.argv[1])

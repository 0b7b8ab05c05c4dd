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
- twice-at-one-origin.vdb: a damaged file whose root has two child nodes at the origin (a
  density voxel at the origin and one at x = 4096, the second's origin then overwritten): the
  second replaced the first, which was never freed. Refused since
  scripts/patches/openvdb-10.0.1-read-failures.patch ("two tiles or child nodes at [0, 0, 0]").
- cut-in-a-child-mask.vdb and cut-in-a-value-mask.vdb: a level set of one voxel, cut short in
  the middle of its upper internal node's child mask or value mask (the grid's descriptor made
  to end there too, so only the read itself finds it). A read that failed there once left the
  node's child slots holding the background value, which its destructor freed as pointers.
  Refused since scripts/patches/openvdb-10.0.1-read-failures.patch ("a grid's data ends early").
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


def twice_at_one_origin(out):
    grid = vdb.FloatGrid()
    grid.name = "density"
    accessor = grid.getAccessor()
    accessor.setValueOn((0, 0, 0), 1.0)
    accessor.setValueOn((4096, 0, 0), 1.0)
    vdb.write(out, grids=[grid])

    with open(out, "rb") as file:
        data = bytearray(file.read())
    # The root's second child: its origin (three int32) before its own topology. (The origin
    # appears first in the grid's file_bbox_max metadata: the last match is the child.)
    child = data.rfind(struct.pack("<3i", 4096, 0, 0))
    data[child : child + 12] = struct.pack("<3i", 0, 0, 0)
    with open(out, "wb") as file:
        file.write(bytes(data))


def cut_in_a_node_mask(out, mask):
    """A level set of one voxel (background 0.3) at TILE, the origin of the root's only child,
    written and then cut in the middle of that child's child mask (`mask` 0) or value mask (1)."""
    grid = vdb.FloatGrid(0.3)
    grid.name = "surface"
    grid.getAccessor().setValueOn(TILE, -0.1)
    vdb.write(out, grids=[grid])

    with open(out, "rb") as file:
        data = bytearray(file.read())
    # The root's child: its origin (three int32), then its child mask and its value mask (4096
    # bytes each, 32^3 bits). (The origin appears first in the grid's file_bbox_min metadata:
    # the last match is the child.)
    masks = data.rfind(struct.pack("<3i", *TILE)) + 12
    cut = masks + 4096 * mask + 2048
    # The grid's descriptor: its name, type and (empty) instance parent, then the offsets of
    # the grid, of its data blocks and of its end, which must lie inside the file.
    name = b"\x07\x00\x00\x00surface\x10\x00\x00\x00Tree_float_5_4_3\x00\x00\x00\x00"
    offsets = data.find(name) + len(name)
    grid_start, block_start, end = struct.unpack_from("<3q", data, offsets)
    assert grid_start < masks and block_start > cut and end == len(data), (grid_start, block_start, end)
    struct.pack_into("<3q", data, offsets, grid_start, cut, cut)
    with open(out, "wb") as file:
        file.write(bytes(data[:cut]))


def main(directory):
    bool_bytes(os.path.join(directory, "bool-bytes.vdb"))
    cube(os.path.join(directory, "corner-cube.vdb"), LARGEST)
    cube(os.path.join(directory, "origin-cube.vdb"), 7)
    far_apart_tiles(os.path.join(directory, "far-apart-tiles.vdb"))
    twice_at_one_origin(os.path.join(directory, "twice-at-one-origin.vdb"))
    cut_in_a_node_mask(os.path.join(directory, "cut-in-a-child-mask.vdb"), 0)
    cut_in_a_node_mask(os.path.join(directory, "cut-in-a-value-mask.vdb"), 1)


if __name__ == "__main__":
    main(sys.argv[1])

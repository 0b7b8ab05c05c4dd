// grid_mesher.hpp - OpenVDB's mesher (tools::VolumeToMesh) of a sampled grid, its output owned by
// the caller, and at adaptivity 0 run step by step so the grid is let go as soon as it has been
// read (internal to libdqjulia; used by mesh_stream.cpp).
//
// VolumeToMesh holds its input grid (the sampled f) until it returns, beside its own trees of
// sign flags and point indices, the points and the polygons being built: at 512^3 the grid is a
// quarter of the peak. Its uniform path (adaptivity 0) is a fixed sequence of OpenVDB's own
// steps (volume_to_mesh_internal: the voxels the surface crosses, the sign flags and point
// indices, the points per leaf, the points, the polygons); the grid is read up to the points
// and not after. meshGrid takes those steps itself, in the same order with the same arguments
// (so the same points and polygons, bit for bit), and frees the grid before the polygons. With
// adaptivity above 0 (merged cells, relaxed triangles) VolumeToMesh runs as a whole.
#pragma once

#include <memory>

#include <openvdb/openvdb.h>
#include <openvdb/tools/VolumeToMesh.h>

namespace dqj {

/// The mesher's output, as VolumeToMesh gives it: points in index space of the grid's transform
/// (here: slice units), polygon pools one per leaf of the surface.
struct GridMesh {
    std::unique_ptr<openvdb::Vec3s[]> points;
    std::size_t pointCount = 0;
    openvdb::tools::PolygonPoolList pools;
    std::size_t poolCount = 0;
};

/// Meshes the zero level set of `grid` at `adaptivity` (0 to 1); `grid` is reset (its memory
/// freed) as soon as the mesher no longer reads it, and is empty on return.
GridMesh meshGrid(openvdb::FloatGrid::Ptr& grid, double adaptivity);

}  // namespace dqj

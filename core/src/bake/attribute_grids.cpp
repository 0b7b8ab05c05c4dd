// The bake's attribute grids (attribute_grids.hpp): the voxels they cover, the surface seeds and
// their values (one orbit each, through the SIMD kernel), each voxel's nearest seed.
#include "bake/attribute_grids.hpp"

#include <vector>

#include <openvdb/tools/Morphology.h>
#include <openvdb/tree/LeafManager.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "bake/attribute_reach.hpp"
#include "bake/level_set.hpp"
#include "bake/nearest_seed.hpp"
#include "dqjulia/batch.hpp"
#include "dqjulia/coloring.hpp"
#include "platform/thread_scratch.hpp"

namespace dqj {

namespace {

/// The voxels the attribute grids cover: the level set's narrow band and the inside below it to
/// bake.color_depth of the bake's largest side (`resolution` voxels), so a volume shows its
/// colours through the depth light reaches, not a thin shell over black.
openvdb::MaskTree attributeVoxels(const openvdb::FloatGrid& surface, const BakeSettings& bake) {
    openvdb::MaskTree mask(surface.tree(), false, openvdb::TopologyCopy());
    if (const int steps = attributeDilation(bake); steps > 0) {
        // 26-neighbour steps beyond the band: at least attributeDepth() voxels deep in every
        // direction (up to sqrt 3 times that along the diagonals).
        openvdb::tools::dilateActiveValues(mask, steps, openvdb::tools::NN_FACE_EDGE_VERTEX,
                                           openvdb::tools::IGNORE_TILES);
        // Keep the band, and of the rest only the inside (negative distance): never the air.
        std::vector<openvdb::MaskTree::LeafNodeType*> leaves;
        mask.getNodes(leaves);
        for (auto* leaf : leaves) {
            openvdb::tree::ValueAccessor<const openvdb::FloatTree> accessor(surface.tree());
            const auto on = leaf->getValueMask();  // a copy: voxels are switched off as they are visited
            for (auto bit = on.beginOn(); bit; ++bit) {
                const openvdb::Coord ijk = leaf->offsetToGlobalCoord(bit.pos());
                if (!accessor.isValueOn(ijk) && !(accessor.getValue(ijk) < 0.0f)) leaf->setValueOff(bit.pos());
            }
        }
    }
    return mask;
}

/// The seeds of the attribute grids: the level set's voxels next to a zero crossing (a face
/// neighbour of the other sign), each with the surface point nearest to it (index space: the
/// voxel moved by its distance against the gradient) and the attributes there.
struct SurfaceSeeds {
    std::vector<openvdb::Coord> voxels;
    std::vector<openvdb::Vec3f> points;
    std::vector<openvdb::Vec3s> colours;
    std::vector<float> traps, iterations;

    void append(const SurfaceSeeds& other) {
        voxels.insert(voxels.end(), other.voxels.begin(), other.voxels.end());
        points.insert(points.end(), other.points.begin(), other.points.end());
        colours.insert(colours.end(), other.colours.begin(), other.colours.end());
        traps.insert(traps.end(), other.traps.begin(), other.traps.end());
        iterations.insert(iterations.end(), other.iterations.begin(), other.iterations.end());
    }
};

/// The seeds of one leaf of the level set. One orbit per seed, kSurfaceColourOffset voxels
/// outside its surface point along the gradient, where the renderer takes its colours; the
/// leaf's seeds go through the SIMD kernel together.
void addLeafSeeds(const Params& params, const Slice& slice,
                  const openvdb::tree::ValueAccessor<const openvdb::FloatTree>& surface,
                  const openvdb::FloatTree::LeafNodeType& leaf, double voxelSize, BatchBuffer<double>& batch,
                  SurfaceSeeds& seeds) {
    batch.clear();
    for (auto on = leaf.cbeginValueOn(); on; ++on) {
        const openvdb::Coord ijk = on.getCoord();
        const bool inside = *on < 0.0f;
        double around[6];  // -x, +x, -y, +y, -z, +z
        bool crossing = false;
        for (int axis = 0; axis < 3; ++axis)
            for (int side = 0; side < 2; ++side) {
                openvdb::Coord next = ijk;
                next[axis] += side ? 1 : -1;
                const float value = surface.getValue(next);
                crossing = crossing || (value < 0.0f) != inside;
                around[2 * axis + side] = double(value);
            }
        if (!crossing) continue;
        glm::dvec3 normal(around[1] - around[0], around[3] - around[2], around[5] - around[4]);
        const double length = glm::length(normal);
        if (length > 0.0) normal /= length;
        // The bake's grid maps index to world by the voxel size alone.
        const glm::dvec3 point = glm::dvec3(ijk.x(), ijk.y(), ijk.z()) - double(*on) / voxelSize * normal;
        seeds.voxels.push_back(ijk);
        seeds.points.emplace_back(float(point.x), float(point.y), float(point.z));
        batch.add(slice.map((point + kSurfaceColourOffset * normal) * voxelSize));
    }
    if (seeds.voxels.empty()) return;
    batch.evaluate(params.fractal);
    for (std::size_t seed = 0; seed < seeds.voxels.size(); ++seed) {
        const Escape escape = batch.escape(seed);
        if (hasGrid(params.bake, BakeGrid::Color)) {
            const glm::dvec3 c = orbitColour(params.material, params.fractal, escape);
            seeds.colours.emplace_back(float(c.x), float(c.y), float(c.z));
        }
        if (hasGrid(params.bake, BakeGrid::Trap)) seeds.traps.push_back(float(escape.trap));
        if (hasGrid(params.bake, BakeGrid::Iterations))
            seeds.iterations.push_back(float(smoothIterations(params.fractal, escape)));
    }
}

/// The seeds of `surface`, in the order of its leaves (deterministic).
SurfaceSeeds surfaceSeeds(const Params& params, const openvdb::FloatGrid& surface) {
    std::vector<const openvdb::FloatTree::LeafNodeType*> leaves;
    surface.tree().getNodes(leaves);
    std::vector<SurfaceSeeds> perLeaf(leaves.size());
    const Slice slice = params.slice.effective();  // once, not per leaf
    ThreadScratch<BatchBuffer<double>> batches;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, leaves.size()),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                          const openvdb::tree::ValueAccessor<const openvdb::FloatTree> accessor(surface.tree());
                          for (std::size_t index = range.begin(); index != range.end(); ++index)
                              addLeafSeeds(params, slice, accessor, *leaves[index], surface.voxelSize()[0],
                                           batches.local(), perLeaf[index]);
                      });
    SurfaceSeeds seeds;
    for (const SurfaceSeeds& leaf : perLeaf) seeds.append(leaf);
    return seeds;
}

/// A grid of `ids`' topology holding, at each voxel, the value of its seed.
template <typename GridT>
typename GridT::Ptr seedValueGrid(const openvdb::Int32Tree& ids, const std::vector<typename GridT::ValueType>& values) {
    using TreeT = typename GridT::TreeType;
    auto tree = std::make_shared<TreeT>(ids, typename TreeT::ValueType(0), openvdb::TopologyCopy());
    openvdb::tree::LeafManager<TreeT> leaves(*tree);
    leaves.foreach ([&](typename TreeT::LeafNodeType& leaf, std::size_t) {
        const openvdb::Int32Tree::LeafNodeType* seeds = ids.probeConstLeaf(leaf.origin());
        for (auto on = leaf.beginValueOn(); on; ++on) on.setValue(values[std::size_t(seeds->getValue(on.pos()))]);
    });
    return GridT::create(tree);
}

}  // namespace

void addAttributeGrids(const Params& params, const openvdb::FloatGrid& surface, const openvdb::CoordBBox* kept,
                       const ProgressCallback& progress, BakeStats& stats, openvdb::GridPtrVec& grids) {
    const bool color = hasGrid(params.bake, BakeGrid::Color);
    const bool trap = hasGrid(params.bake, BakeGrid::Trap);
    const bool iterations = hasGrid(params.bake, BakeGrid::Iterations);
    if (!color && !trap && !iterations) return;
    if (progress && !progress(0.0)) throw Cancelled();
    SurfaceSeeds seeds = surfaceSeeds(params, surface);
    stats.evaluated += seeds.voxels.size();
    if (progress && !progress(0.3)) throw Cancelled();
    openvdb::Int32Tree::Ptr ids =
        nearestSeeds(attributeVoxels(surface, params.bake), seeds.voxels, seeds.points, attributeRounds(params.bake));
    seeds.voxels = {};
    seeds.points = {};
    if (progress && !progress(0.8)) throw Cancelled();
    auto name = [&](auto grid, const char* label) {
        if (kept) grid->tree().clip(*kept);
        grid->setTransform(surface.transform().copy());
        grid->setName(label);
        grid->setGridClass(openvdb::GRID_UNKNOWN);
        grids.push_back(grid);
        return grid;
    };
    if (color)
        name(seedValueGrid<openvdb::Vec3SGrid>(*ids, seeds.colours), "color")->setVectorType(openvdb::VEC_INVARIANT);
    if (trap) name(seedValueGrid<openvdb::FloatGrid>(*ids, seeds.traps), "trap");
    if (iterations) name(seedValueGrid<openvdb::FloatGrid>(*ids, seeds.iterations), "iterations");
    if (progress && !progress(1.0)) throw Cancelled();
}

}  // namespace dqj

// Baking to OpenVDB (bake.hpp): the level set, the fog volume, the attribute grids and the file.
#include "dqjulia/bake.hpp"
#include "dqjulia/version.h"
#include "dqjulia/batch.hpp"
#include "dqjulia/coloring.hpp"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#ifdef _WIN32
#include <windows.h>
#else
#include <sys/resource.h>
#include <unistd.h>
#endif

#include <openvdb/tools/LevelSetUtil.h>
#include <openvdb/tools/Morphology.h>
#include <openvdb/tree/LeafManager.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "files/atomic_file.hpp"
#include "bake/attribute_reach.hpp"
#include "bake/level_set.hpp"
#include "bake/mesh_distance.hpp"
#include "bake/nearest_seed.hpp"
#include "platform/parallel_progress.hpp"
#include "files/text_input.hpp"
#include "platform/thread_scratch.hpp"
#include "bake/tile_geometry.hpp"
#include "files/vdb_file.hpp"

namespace dqj {


namespace {

/// Memory per sampled 8^3 leaf beyond the sampled leaf itself: the rebuild's mesh and distance
/// grids, the level set, the fog volume; attribute grids on top. Measured on the default
/// fractal (peak RSS minus the 65 MB of a tiny bake, over sampled leaves: 4.3 kB at 256^3,
/// 5.2 kB at 512^3, 4.9 kB at 1024^3) and doubled for headroom. With the colour grid (its
/// seeds, their propagation and the grid) 7.7 kB at 512^3 and 9.8 kB at 1024^3 in all, so
/// about 5 kB more, doubled (the sweeps it replaced took 17 kB: 4.2 GB at 1024^3, above the
/// 12 kB this allowed).
MemoryModel bakeMemoryModel(const BakeSettings& bake) {
    MemoryModel model;
    model.fixedBytes = 96.0 * 1024 * 1024;
    model.bytesPerLeaf = 9.0 * 1024;
    if (hasGrid(bake, BakeGrid::Color)) model.bytesPerLeaf += 10.0 * 1024;
    if (hasGrid(bake, BakeGrid::Trap)) model.bytesPerLeaf += 4.0 * 1024;
    if (hasGrid(bake, BakeGrid::Iterations)) model.bytesPerLeaf += 4.0 * 1024;
    return model;
}

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

/// The attribute grids ("color", "trap", "iterations") on attributeVoxels(), within `kept` if
/// given (a tile's), each an extension field: every voxel holds the value at the surface point
/// nearest to it, so the inside shows, through the depth light reaches, the colour its surface
/// has, as the mesh's vertices and the preview do; a voxel's own orbit would give the inside's
/// colour instead (bounded orbits: the palette's far end). One fractal evaluation per surface
/// seed (surfaceSeeds), then each voxel takes its nearest seed (nearestSeeds, in at most
/// attributeRounds() rounds), one propagation for all the grids; colour and smooth count from
/// coloring.hpp. A tile works on all it baked, its halo included, and keeps its box, where every
/// voxel's seed is the whole bake's (tileHalo says why).
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

}  // namespace

openvdb::FloatGrid::Ptr densityFromSurface(const openvdb::FloatGrid& surface) {
    // Interior 1, a ramp to 0 across the inner half of the band, outside 0 (inactive).
    openvdb::FloatGrid::Ptr density = surface.deepCopy();
    openvdb::tools::sdfToFogVolume(*density);
    density->setName("density");
    density->setCreator("dqjulia");
    return density;
}

void initializeOpenVdb() {
    static std::once_flag once;
    std::call_once(once, [] { openvdb::initialize(); });
}

openvdb::FloatGrid::Ptr bakeLevelSet(const Params& params, const BakeOptions& options, const MemoryModel& memory,
                                     StagedProgress& progress, BakeStats& stats, double sampledAt, double rebuiltAt) {
    initializeOpenVdb();
    SampledSurface sampled = sampleSurface(params, options, memory, progress, 0.03, sampledAt);
    stats = sampled.stats;
    const float band = float(params.bake.bandWidth);
    openvdb::FloatGrid::Ptr surface;
    parallelForWithProgress(1, progress.stage(BakeStage::LevelSet, sampledAt, rebuiltAt),
                            [&](std::size_t, const std::atomic<bool>& stop) {
                                surface = levelSetOfMesh(std::move(sampled.grid), band, stop);
                            });
    sampled.grid.reset();
    surface->setName("surface");
    surface->setGridClass(openvdb::GRID_LEVEL_SET);
    surface->setCreator("dqjulia");
    stats.activeVoxels = surface->activeVoxelCount();
    return surface;
}

MemoryLimitError::MemoryLimitError(const std::string& message, std::uint64_t estimate, std::uint64_t limit)
    : ParamError("bake.resolution", "bake.resolution: " + message), estimate_(estimate), limit_(limit) {}

#ifdef _WIN32

// Windows: the limits a job object puts on this process and on its job (what ulimit and cgroups are
// on Linux; the job's less its peak use), and half of the physical memory available.
std::uint64_t processMemoryHeadroom() {
    JOBOBJECT_EXTENDED_LIMIT_INFORMATION job{};
    if (!::QueryInformationJobObject(nullptr, JobObjectExtendedLimitInformation, &job, sizeof job, nullptr))
        return UINT64_MAX;  // not in a job
    std::uint64_t result = UINT64_MAX;
    const DWORD flags = job.BasicLimitInformation.LimitFlags;
    if (flags & JOB_OBJECT_LIMIT_PROCESS_MEMORY) result = std::min<std::uint64_t>(result, job.ProcessMemoryLimit);
    if (flags & JOB_OBJECT_LIMIT_JOB_MEMORY)
        result = std::min<std::uint64_t>(result, job.JobMemoryLimit > job.PeakJobMemoryUsed
                                                     ? job.JobMemoryLimit - job.PeakJobMemoryUsed
                                                     : 0);
    return result;
}

std::uint64_t defaultMemoryLimit() {
    MEMORYSTATUSEX status{};
    status.dwLength = sizeof status;
    const std::uint64_t half = ::GlobalMemoryStatusEx(&status) ? status.ullAvailPhys / 2 : std::uint64_t(1) << 31;
    return std::min(half, processMemoryHeadroom());
}

#else

namespace {

/// The number a file holds ("max", no number and missing files: nullopt; a read error throws).
std::optional<std::uint64_t> readNumberFile(const std::string& path) {
    const std::optional<std::string> text = lineStartingWith(path, "");
    if (!text || text->empty() || !std::isdigit(static_cast<unsigned char>(text->front()))) return std::nullopt;
    return std::strtoull(text->c_str(), nullptr, 10);
}

/// "VmSize:  123 kB" from /proc/self/status, in bytes.
std::uint64_t statusBytes(const std::string& key) {
    const std::optional<std::string> value = lineStartingWith("/proc/self/status", key);
    return value ? std::strtoull(value->c_str(), nullptr, 10) * 1024 : 0;
}

std::uint64_t headroom(std::uint64_t limit, std::uint64_t used) { return limit > used ? limit - used : 0; }

}  // namespace

std::uint64_t processMemoryHeadroom() {
    std::uint64_t result = UINT64_MAX;
    struct rlimit limit {};
    if (::getrlimit(RLIMIT_AS, &limit) == 0 && limit.rlim_cur != RLIM_INFINITY)
        result = std::min(result, headroom(limit.rlim_cur, statusBytes("VmSize:")));
    if (::getrlimit(RLIMIT_DATA, &limit) == 0 && limit.rlim_cur != RLIM_INFINITY)
        result = std::min(result, headroom(limit.rlim_cur, statusBytes("VmData:")));
    // Every cgroup from ours up to the root may cap us ("0::/a/b" for v2, "N:memory:/a/b" for v1).
    const std::string cgroups = readSmallFile("/proc/self/cgroup", std::size_t(1) << 20).value_or("");
    for (std::size_t start = 0, end = 0; start < cgroups.size(); start = end + 1) {
        end = std::min(cgroups.find('\n', start), cgroups.size());
        const std::string line = cgroups.substr(start, end - start);
        const std::size_t first = line.find(':'), second = line.find(':', first + 1);
        if (first == std::string::npos || second == std::string::npos) continue;
        const std::string controllers = line.substr(first + 1, second - first - 1);
        std::string group = line.substr(second + 1);
        const bool v2 = controllers.empty();
        if (!v2 && controllers.find("memory") == std::string::npos) continue;
        const std::string root = v2 ? "/sys/fs/cgroup" : "/sys/fs/cgroup/memory";
        for (;;) {
            const std::string folder = root + (group == "/" ? "" : group);
            const auto max = readNumberFile(folder + (v2 ? "/memory.max" : "/memory.limit_in_bytes"));
            const auto used = readNumberFile(folder + (v2 ? "/memory.current" : "/memory.usage_in_bytes"));
            if (max && *max < (std::uint64_t(1) << 60)) result = std::min(result, headroom(*max, used.value_or(0)));
            if (group.empty() || group == "/") break;
            const std::size_t slash = group.rfind('/');
            group = slash == 0 || slash == std::string::npos ? "/" : group.substr(0, slash);
        }
    }
    return result;
}

std::uint64_t defaultMemoryLimit() {
    const std::optional<std::string> available = lineStartingWith("/proc/meminfo", "MemAvailable:");
    std::uint64_t half = available ? std::strtoull(available->c_str(), nullptr, 10) * 1024 / 2 : 0;
    if (half == 0) {
        const long pages = ::sysconf(_SC_AVPHYS_PAGES);
        const long pageSize = ::sysconf(_SC_PAGESIZE);
        half = pages > 0 && pageSize > 0 ? std::uint64_t(pages) * std::uint64_t(pageSize) / 2 : std::uint64_t(1) << 31;
    }
    return std::min(half, processMemoryHeadroom());
}

#endif

std::string formatBytes(std::uint64_t bytes) {
    char text[32];
    const double value = double(bytes);
    if (value >= 1e9)
        std::snprintf(text, sizeof text, "%.1f GB", value / 1e9);
    else if (value >= 1e6)
        std::snprintf(text, sizeof text, "%.0f MB", value / 1e6);
    else
        std::snprintf(text, sizeof text, "%.0f kB", value / 1e3);
    return text;
}

std::string_view bakeStageName(BakeStage stage) {
    switch (stage) {
        case BakeStage::Classifying: return "classifying";
        case BakeStage::Sampling: return "sampling";
        case BakeStage::LevelSet: return "level set";
        case BakeStage::Grids: return "grids";
        case BakeStage::Meshing: return "meshing";
        case BakeStage::Writing: return "writing";
    }
    return "working";
}

BakeStats bakeVdb(const Params& params, const std::string& path, const BakeOptions& options,
                  const ProgressCallback& progress) {
    const auto start = std::chrono::steady_clock::now();
    validate(params);
    if (AtomicFile::lowercaseExtension(path) != ".vdb")
        throw ParamError("output.path", "'" + inputExcerpt(path) + "' must end in .vdb");
    if (options.tile) checkTile(params, *options.tile);
    AtomicFile file(path, options.existing);  // fails now, before the work, if the folder is not writable
    StagedProgress staged(progress, options.monitor);
    BakeStats stats;
    openvdb::FloatGrid::Ptr surface =
        bakeLevelSet(params, options, bakeMemoryModel(params.bake), staged, stats, 0.7, 0.85);
    // A tile keeps what it owns; its file holds the surface (the merge needs it) and the
    // attribute grids, and the merge makes the density from the merged surface.
    std::optional<openvdb::CoordBBox> kept;
    if (options.tile) {
        const openvdb::CoordBBox full = bakeIndexBox(params);
        kept = keptBox(full, ownedBox(full, *options.tile));
    }

    // The attribute grids before the density, so that the density is not held while their
    // seeds and propagation are (the peak at 1024^3); the file keeps its order.
    openvdb::GridPtrVec attributes;
    addAttributeGrids(params, *surface, kept ? &*kept : nullptr, staged.stage(BakeStage::Grids, 0.85, 0.95), stats,
                      attributes);
    openvdb::GridPtrVec grids;
    if (hasGrid(params.bake, BakeGrid::Surface) || kept) grids.push_back(surface);
    if (hasGrid(params.bake, BakeGrid::Density) && !kept) grids.push_back(densityFromSurface(*surface));
    grids.insert(grids.end(), attributes.begin(), attributes.end());
    if (kept) {
        surface->tree().clip(*kept);
        stats.activeVoxels = surface->activeVoxelCount();
    }

    staged.stage(BakeStage::Writing, 0.95, 1.0);
    if (progress && !progress(0.95)) throw Cancelled();
    openvdb::MetaMap metadata;
    metadata.insertMeta("creator", openvdb::StringMetadata(std::string("dqjulia ") + DQJ_VERSION_STRING));
    const std::string document = toJson(params);
    metadata.insertMeta("dqjulia_parameters", openvdb::StringMetadata(document));
    metadata.insertMeta("dqjulia_voxel_size", openvdb::DoubleMetadata(stats.voxelSize));
    if (options.tile) {
        std::uint64_t gridBytes = 0;
        for (const openvdb::GridBase::Ptr& grid : grids) gridBytes += grid->memUsage();
        addTileMetadata(metadata, params, *options.tile, document, gridBytes);
    }
    writeVdbFile(file, grids, metadata);
    stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (progress) progress(1.0);
    return stats;
}

}  // namespace dqj

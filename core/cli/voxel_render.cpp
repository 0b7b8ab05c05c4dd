// Voxel rendering of a baked density grid (voxel_render.hpp).
#include "voxel_render.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include <glm/geometric.hpp>
#include <openvdb/openvdb.h>

#include "dqjulia/coloring.hpp"
#include "files/message_text.hpp"
#include "platform/parallel_progress.hpp"
#include "files/vdb_file.hpp"

namespace dqj {
namespace {

constexpr int kTileRows = 8;

openvdb::FloatGrid::ConstPtr readDensity(const std::string& path) {
    auto grid = openvdb::gridPtrCast<openvdb::FloatGrid>(findGrid(readVdbFile(path), "density"));
    if (!grid)
        throw std::runtime_error("'" + inputExcerpt(path) +
                                 "' has no float grid named \"density\" (bake it with dqjulia bake)");
    return grid;
}

/// The first solid voxel along a ray, in the grid's index space where voxel (i, j, k) covers
/// [i - 0.5, i + 0.5]^3. Returns the world distance and the face normal (index axes = world axes
/// up to the uniform voxel scale of a bake).
struct VoxelHit {
    bool hit = false;
    double t = 0.0;
    glm::dvec3 normal{0.0};
};

VoxelHit traverse(const openvdb::FloatGrid& grid, const openvdb::CoordBBox& box, const glm::dvec3& eye,
                  const glm::dvec3& direction) {
    const openvdb::math::Transform& transform = grid.transform();
    const openvdb::Vec3d origin = transform.worldToIndex(openvdb::Vec3d(eye.x, eye.y, eye.z));
    const openvdb::Vec3d ahead =
        transform.worldToIndex(openvdb::Vec3d(eye.x + direction.x, eye.y + direction.y, eye.z + direction.z));
    // Shift by half a voxel so voxel (i, j, k) covers [i, i + 1); t stays in world units.
    const glm::dvec3 o(origin.x() + 0.5, origin.y() + 0.5, origin.z() + 0.5);
    const glm::dvec3 d(ahead.x() - origin.x(), ahead.y() - origin.y(), ahead.z() - origin.z());
    // In double and 64-bit integers from here: a box may end at the largest Int32.
    const glm::dvec3 low(box.min().x(), box.min().y(), box.min().z());
    const glm::dvec3 high(box.max().x() + 1.0, box.max().y() + 1.0, box.max().z() + 1.0);
    // Slab test against the box.
    double tEnter = 0.0, tExit = std::numeric_limits<double>::infinity();
    int enterAxis = -1;
    for (int axis = 0; axis < 3; ++axis) {
        if (d[axis] == 0.0) {
            if (o[axis] < low[axis] || o[axis] >= high[axis]) return {};
            continue;
        }
        double t0 = (low[axis] - o[axis]) / d[axis], t1 = (high[axis] - o[axis]) / d[axis];
        if (t0 > t1) std::swap(t0, t1);
        if (t0 > tEnter) {
            tEnter = t0;
            enterAxis = axis;
        }
        tExit = std::min(tExit, t1);
    }
    if (tEnter >= tExit) return {};
    // Amanatides-Woo voxel stepping from parameter `from` on; restarted past empty tiles (the
    // steps and the distances between boundaries are the ray's own, set once).
    glm::i64vec3 cell, step;
    glm::dvec3 next, delta;
    for (int a = 0; a < 3; ++a) {
        step[a] = d[a] > 0 ? 1 : -1;
        delta[a] = d[a] != 0.0 ? std::abs(1.0 / d[a]) : std::numeric_limits<double>::infinity();
    }
    auto enterAt = [&](double from) {
        const glm::dvec3 start = o + d * (from + 1e-9);
        cell = glm::i64vec3(std::floor(start.x), std::floor(start.y), std::floor(start.z));
        for (int a = 0; a < 3; ++a) {
            const double boundary = d[a] > 0 ? cell[a] + 1.0 : cell[a];
            next[a] = d[a] != 0.0 ? from + (boundary - start[a]) / d[a] : std::numeric_limits<double>::infinity();
        }
    };
    enterAt(tEnter);
    // Edge of the region a value of each tree depth stands for (getValueDepth: -1 background,
    // 0 a root tile, 1 and 2 internal tiles, 3 a voxel): an empty tile is crossed in one step,
    // not voxel by voxel, so a file whose few voxels lie far apart cannot stall the render.
    using Root = openvdb::FloatTree::RootNodeType;
    using Upper = Root::ChildNodeType;
    using Lower = Upper::ChildNodeType;
    constexpr int kRegion[] = {int(Upper::DIM), int(Upper::DIM), int(Lower::DIM), int(Lower::ChildNodeType::DIM), 1};
    auto accessor = grid.getConstAccessor();
    double t = tEnter;
    int axis = enterAxis;
    while (t <= tExit) {
        const openvdb::Coord xyz(openvdb::Int32(cell.x), openvdb::Int32(cell.y), openvdb::Int32(cell.z));
        if (accessor.getValue(xyz) >= 0.5f) {
            VoxelHit result{true, t, glm::dvec3(0.0)};
            if (axis >= 0) result.normal[axis] = -step[axis];
            return result;
        }
        const int size = kRegion[accessor.getValueDepth(xyz) + 1];
        if (size > 1) {  // an empty tile: on to where the ray leaves it
            double leave = std::numeric_limits<double>::infinity();
            int leaveAxis = axis;
            for (int a = 0; a < 3; ++a) {
                if (d[a] == 0.0) continue;
                const std::int64_t low = cell[a] & ~std::int64_t(size - 1);  // tiles are aligned to their size
                const double boundary = double(d[a] > 0 ? low + size : low);
                const double at = (boundary - o[a]) / d[a];
                if (at < leave) {
                    leave = at;
                    leaveAxis = a;
                }
            }
            if (leave > t && leave < std::numeric_limits<double>::infinity()) {
                t = leave;
                axis = leaveAxis;
                enterAt(t);
                continue;
            }
        }
        axis = next.x < next.y ? (next.x < next.z ? 0 : 2) : (next.y < next.z ? 1 : 2);
        t = next[axis];
        next[axis] += delta[axis];
        cell[axis] += step[axis];
    }
    return {};
}

}  // namespace

RenderResult renderVoxels(const Params& params, const std::string& vdbPath, const ProgressCallback& progress) {
    validate(params);
    const auto started = std::chrono::steady_clock::now();
    const openvdb::FloatGrid::ConstPtr grid = readDensity(vdbPath);
    // The root's entries that can hold a solid voxel (a child, or a tile of density >= 0.5),
    // each within the active box: a ray is traversed only through them, so a file whose few
    // voxels or tiles lie far apart cannot stall the render (the empty space between them is
    // never stepped through).
    const openvdb::CoordBBox box = grid->evalActiveVoxelBoundingBox();
    std::vector<openvdb::CoordBBox> regions;
    const auto& root = grid->tree().root();
    for (auto child = root.cbeginChildOn(); child; ++child) regions.push_back(child->getNodeBoundingBox());
    for (auto tile = root.cbeginValueAll(); tile; ++tile)
        if (*tile >= 0.5f)
            regions.push_back(
                openvdb::CoordBBox::createCube(tile.getCoord(), openvdb::FloatTree::RootNodeType::ChildNodeType::DIM));
    for (openvdb::CoordBBox& region : regions) region.intersect(box);
    std::erase_if(regions, [](const openvdb::CoordBBox& region) { return region.empty(); });
    const CameraFrame camera = frameCamera(params, renderBounds(params));
    auto firstHit = [&](const glm::dvec3& direction) {
        VoxelHit first;
        for (const openvdb::CoordBBox& region : regions) {
            const VoxelHit hit = traverse(*grid, region, camera.eye, direction);
            if (hit.hit && (!first.hit || hit.t < first.t)) first = hit;
        }
        return first;
    };
    const RenderSettings& settings = params.render;
    const Material& material = params.material;

    RenderResult result;
    Image& image = result.image;
    image.width = camera.width;
    image.height = camera.height;
    const std::size_t pixels = std::size_t(image.width) * image.height;
    image.rgba.assign(4 * pixels, 0.0f);
    image.surface.assign(3 * pixels, 0.0f);
    image.depth.assign(pixels, std::numeric_limits<float>::infinity());
    image.normal.assign(3 * pixels, 0.0f);
    std::atomic<std::uint64_t> hitPixels{0};
    const int samples = settings.samples;
    const int bands = (image.height + kTileRows - 1) / kTileRows;
    parallelForWithProgress(std::size_t(bands), progress, [&](std::size_t band, const std::atomic<bool>&) {
        for (int y = int(band) * kTileRows; y < std::min(image.height, int(band + 1) * kTileRows); ++y) {
            for (int x = 0; x < image.width; ++x) {
                glm::dvec3 colour(0.0), surface(0.0);
                int hits = 0;
                const std::size_t pixel = std::size_t(y) * image.width + x;
                for (int sy = 0; sy < samples; ++sy)
                    for (int sx = 0; sx < samples; ++sx) {
                        const glm::dvec3 direction =
                            camera.rayDirection(x + (sx + 0.5) / samples, y + (sy + 0.5) / samples);
                        const VoxelHit hit = firstHit(direction);
                        if (!hit.hit) {
                            // The same vertical gradient as render()'s background.
                            const double height = glm::dot(direction, camera.up) / glm::dot(direction, camera.forward) /
                                                  camera.tanHalfFov;
                            const double mix = std::clamp(0.5 + 0.5 * height, 0.0, 1.0);
                            colour += settings.backgroundBottom * (1.0 - mix) + settings.backgroundTop * mix;
                            continue;
                        }
                        // The renderer's Phong terms (coloring.hpp) on the solid colour, without occlusion.
                        glm::dvec3 shaded = phongAmbient(material, material.color, 1.0);
                        for (const Light& light : params.lights)
                            shaded += phongLight(material, material.color, hit.normal, glm::normalize(light.direction),
                                                 -direction, light.color * light.intensity, 1.0);
                        colour += shaded;
                        surface += shaded;
                        ++hits;
                        image.depth[pixel] = std::min(image.depth[pixel], float(hit.t));
                        for (int axis = 0; axis < 3; ++axis) image.normal[3 * pixel + axis] = float(hit.normal[axis]);
                    }
                const double weight = 1.0 / (samples * samples);
                for (int channel = 0; channel < 3; ++channel) {
                    image.rgba[4 * pixel + channel] = float(colour[channel] * weight);
                    image.surface[3 * pixel + channel] = float(surface[channel] * weight);
                }
                image.rgba[4 * pixel + 3] = float(hits * weight);
                if (hits) ++hitPixels;
            }
        }
    });
    result.stats.rays = pixels * samples * samples;
    result.stats.hitPixels = hitPixels;
    result.stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    return result;
}

}  // namespace dqj

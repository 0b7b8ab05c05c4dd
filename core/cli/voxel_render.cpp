// Voxel rendering of a baked density grid (voxel_render.hpp).
#include "voxel_render.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>

#include <glm/geometric.hpp>
#include <openvdb/openvdb.h>

#include "dqjulia/coloring.hpp"
#include "parallel_progress.hpp"
#include "vdb_file.hpp"

namespace dqj {
namespace {

constexpr int kTileRows = 8;

openvdb::FloatGrid::ConstPtr readDensity(const std::string& path) {
    auto grid = openvdb::gridPtrCast<openvdb::FloatGrid>(findGrid(readVdbFile(path), "density"));
    if (!grid)
        throw std::runtime_error("'" + path + "' has no float grid named \"density\" (bake it with dqjulia bake)");
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
    const glm::dvec3 low(box.min().x(), box.min().y(), box.min().z());
    const glm::dvec3 high(box.max().x() + 1, box.max().y() + 1, box.max().z() + 1);
    // Slab test against the active box.
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
    const glm::dvec3 start = o + d * (tEnter + 1e-9);
    glm::ivec3 cell(std::floor(start.x), std::floor(start.y), std::floor(start.z));
    glm::ivec3 step;
    glm::dvec3 next, delta;
    for (int axis = 0; axis < 3; ++axis) {
        step[axis] = d[axis] > 0 ? 1 : -1;
        delta[axis] = d[axis] != 0.0 ? std::abs(1.0 / d[axis]) : std::numeric_limits<double>::infinity();
        const double boundary = d[axis] > 0 ? cell[axis] + 1.0 : cell[axis];
        next[axis] =
            d[axis] != 0.0 ? tEnter + (boundary - start[axis]) / d[axis] : std::numeric_limits<double>::infinity();
    }
    auto accessor = grid.getConstAccessor();
    double t = tEnter;
    int axis = enterAxis;
    while (t <= tExit) {
        if (accessor.getValue(openvdb::Coord(cell.x, cell.y, cell.z)) >= 0.5f) {
            VoxelHit result{true, t, glm::dvec3(0.0)};
            if (axis >= 0) result.normal[axis] = -step[axis];
            return result;
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
    const openvdb::CoordBBox box = grid->evalActiveVoxelBoundingBox();
    const CameraFrame camera = frameCamera(params, renderBounds(params));
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
                        const VoxelHit hit = box.empty() ? VoxelHit{} : traverse(*grid, box, camera.eye, direction);
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

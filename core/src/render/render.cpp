// The sphere-tracing renderer (render.hpp): the tile loop. The scene every ray reads
// (scene.hpp) and the camera (camera.hpp, camera.cpp); each ray's state machine and the
// evaluators that answer its points (ray_job.hpp).
//
// All geometry is in slice (3-D) coordinates. The distance estimate is in 8-D units; a 3-D
// step of length s moves at most stretch.max * s in 8-D, so DE / stretch.max is a safe 3-D step.
//
// Each camera ray is a RayJob: a state machine that asks for the points it needs evaluated
// (marching, bisection, normal and occlusion probes, shadow marches) and consumes their
// escapes. The packet engine runs the rays of a tile as a wavefront: each round the queries of
// every unfinished ray go through the SIMD batch kernel together and finished rays retire. The
// scalar engine answers each query with evaluate(), the reference; both run the same logic.
// The packet engine uses the float kernel (twice the lanes) where its derivative cannot
// overflow: the points it evaluates stay about a hit threshold (a fraction of a pixel) from
// the surface or more, where the float orbit's error, 2^-24 times the derivative (batch.hpp),
// moves the DE by a small fraction of that threshold.
//
// A tile goes through named phases: its rays prepared (prepareTileRays), the cone pre-pass
// (conePrePass), then passes of whole pixels: trace (tracePass), shared shading (shadePass) and
// the pixels written (writePixels).
#include "dqjulia/render.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <limits>
#include <vector>

#include <glm/geometric.hpp>

#include "dqjulia/inspect.hpp"
#include "platform/parallel_progress.hpp"
#include "platform/thread_scratch.hpp"
#include "render/camera.hpp"
#include "render/ray_job.hpp"
#include "render/scene.hpp"

namespace dqj {
namespace {

constexpr int kTileSize = 16;
constexpr int kRaysPerPass = 1024;  // rays traced together: whole pixels of a tile
constexpr int kConeBlock = 4;       // pixels per side of the blocks a cone pre-pass marches for

struct TileStats {
    std::uint64_t rays = 0;
    std::uint64_t steps = 0;
    std::uint64_t hitPixels = 0;
    std::uint64_t evaluations = 0;
};

/// A thread's buffers for its tiles, kept from tile to tile (no allocation once they have
/// grown): render() keeps one per thread in a ThreadScratch.
struct TileBuffers {
    Evaluator evaluator;
    std::vector<RayJob> jobs;
    std::vector<ShadowMarch> shadowSlots;     // the jobs' shadow marches (RayJob's `shadows`)
    std::vector<double> columnX;              // image plane x of the tile's sub-pixel columns
    std::vector<double> rowY;                 // and y of its rows
    std::vector<glm::dvec3> rowBackground;    // and the background of each row
    std::vector<glm::dvec3> pixelBackground;  // per pixel row: a pixel's colour if no sample hits
    std::vector<double> starts;               // per cone block: where its rays start (+inf: all miss)
    std::vector<std::size_t> firstJob;        // per pixel of the pass: its first job, or kNoJob
};

/// One tile of the image and how its pixels are sampled: S x S rays a pixel, their colours
/// weighted 1 / S^2.
struct TileRect {
    int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
    int samples = 1;
    int perPixel = 1;
    double weight = 1.0;

    int width() const { return x1 - x0; }
    int pixels() const { return (x1 - x0) * (y1 - y0); }
    int blocksX() const { return (width() + kConeBlock - 1) / kConeBlock; }
    int blocksY() const { return (y1 - y0 + kConeBlock - 1) / kConeBlock; }
};

/// A pixel of a pass whose rays are not traced (its cone left the bounds).
constexpr std::size_t kNoJob = std::numeric_limits<std::size_t>::max();

/// Tile rays: a regular grid of sub-pixel positions (with one sample, the pixel centre); their
/// image plane coordinates, per sub-pixel column and row of the tile, are worked out once, with
/// the background of each row and what a pixel whose cone misses comes to.
void prepareTileRays(const Scene& scene, const TileRect& tile, TileBuffers& buffers) {
    const CameraFrame& camera = scene.camera();
    const int samples = tile.samples;
    std::vector<double>& columnX = buffers.columnX;
    std::vector<double>& rowY = buffers.rowY;
    columnX.clear();
    rowY.clear();
    for (int x = tile.x0; x < tile.x1; ++x)
        for (int sx = 0; sx < samples; ++sx) columnX.push_back(screenX(camera, x + (sx + 0.5) / samples));
    for (int y = tile.y0; y < tile.y1; ++y)
        for (int sy = 0; sy < samples; ++sy) rowY.push_back(screenY(camera, y + (sy + 0.5) / samples));
    std::vector<glm::dvec3>& rowBackground = buffers.rowBackground;  // the background of each row
    rowBackground.clear();
    for (const double y : rowY) rowBackground.push_back(scene.backgroundAt(y));
    // What a pixel whose cone misses comes to, per pixel row: its samples' backgrounds summed
    // and weighted as its rays' colours would be (the same sums), worked out once a row.
    std::vector<glm::dvec3>& pixelBackground = buffers.pixelBackground;
    pixelBackground.clear();
    for (int y = tile.y0; y < tile.y1; ++y) {
        glm::dvec3 colour(0.0);
        for (int sample = 0; sample < tile.perPixel; ++sample)
            colour += rowBackground[static_cast<std::size_t>(y - tile.y0) * samples + sample / samples];
        pixelBackground.push_back(colour * tile.weight);
    }
}

/// The cone pre-pass: one cone around each block of kConeBlock^2 pixels finds how far all their
/// rays may go before they can come near the set (buffers.starts, per block; +inf: all miss).
void conePrePass(const Scene& scene, RenderEngine engine, const TileRect& tile, TileBuffers& buffers) {
    const CameraFrame& camera = scene.camera();
    std::vector<RayJob>& jobs = buffers.jobs;
    jobs.clear();
    for (int by = 0; by < tile.blocksY(); ++by) {
        for (int bx = 0; bx < tile.blocksX(); ++bx) {
            const int bx0 = tile.x0 + bx * kConeBlock, by0 = tile.y0 + by * kConeBlock;
            const int bx1 = std::min(tile.x1, bx0 + kConeBlock), by1 = std::min(tile.y1, by0 + kConeBlock);
            const glm::dvec3 axis = camera.rayDirection(0.5 * (bx0 + bx1), 0.5 * (by0 + by1));
            double spread = 0.0;  // the farthest corner: a ray at t is within spread * t of the axis
            for (const int cy : {by0, by1})
                for (const int cx : {bx0, bx1})
                    spread = std::max(spread, glm::length(camera.rayDirection(cx, cy) - axis));
            // Its rays meet the bounds only where the axis comes within radius + spread * t of
            // the centre: the axis through the sphere grown by its spread at the farthest t.
            Bounds grown = scene.bounds();
            grown.radius += spread * (glm::length(camera.eye - grown.center) + grown.radius);
            const Interval span = intersectSphere(camera.eye, axis, grown);
            const double near = span.valid ? span.near : kInfinity;
            const double far = span.valid ? span.far : kInfinity;
            jobs.push_back(RayJob::cone(scene, axis, 1.01 * spread, near, far));
        }
    }
    buffers.evaluator.run(scene, engine, jobs);
    buffers.starts.clear();
    for (const RayJob& job : jobs) buffers.starts.push_back(job.coneStart());
}

/// A trace pass: the rays of the tile's pixels [first, last), each pixel's S x S rays starting
/// where its cone proved the way free, traced until they finish or pause before shading
/// (buffers.jobs; buffers.firstJob: each pixel's first job, or kNoJob).
void tracePass(const Scene& scene, RenderEngine engine, const TileRect& tile, int first, int last,
               TileBuffers& buffers) {
    const CameraFrame& camera = scene.camera();
    const std::size_t lights = scene.lightCount();
    std::vector<RayJob>& jobs = buffers.jobs;
    std::vector<std::size_t>& firstJob = buffers.firstJob;
    auto sampleDirection = [&](int x, int y, int sx, int sy) {
        const int column = (x - tile.x0) * tile.samples + sx;
        const int row = (y - tile.y0) * tile.samples + sy;
        return screenDirection(camera, buffers.columnX[static_cast<std::size_t>(column)],
                               buffers.rowY[static_cast<std::size_t>(row)]);
    };
    jobs.clear();
    firstJob.clear();
    for (int index = first; index < last; ++index) {
        const int x = tile.x0 + index % tile.width();
        const int y = tile.y0 + index / tile.width();
        const std::size_t block =
            static_cast<std::size_t>((y - tile.y0) / kConeBlock) * tile.blocksX() + (x - tile.x0) / kConeBlock;
        const double start = buffers.starts[block];
        // A pixel whose cone left the bounds misses with every sample: no rays to trace.
        firstJob.push_back(start == kInfinity ? kNoJob : jobs.size());
        if (start == kInfinity) continue;
        for (int sy = 0; sy < tile.samples; ++sy)
            for (int sx = 0; sx < tile.samples; ++sx)
                jobs.emplace_back(scene, sampleDirection(x, y, sx, sy), start,
                                  buffers.shadowSlots.data() + jobs.size() * lights);
    }
    buffers.evaluator.run(scene, engine, jobs);
}

/// Shared shading: occlusion and shadows vary slowly over the surface, so the first sample of a
/// pixel to hit shades itself, and the pixel's others on the same piece of surface take its values.
void shadePass(const Scene& scene, RenderEngine engine, const TileRect& tile, int first, int last,
               TileBuffers& buffers) {
    std::vector<RayJob>& jobs = buffers.jobs;
    const std::vector<std::size_t>& firstJob = buffers.firstJob;
    bool paused = false;
    for (int index = first; index < last; ++index) {
        const std::size_t pixelJobs = firstJob[static_cast<std::size_t>(index - first)];
        for (int sample = 0; sample < tile.perPixel && pixelJobs != kNoJob; ++sample) {
            if (!jobs[pixelJobs + sample].paused()) continue;
            jobs[pixelJobs + sample].resumeShading();
            paused = true;
            break;
        }
    }
    if (!paused) return;
    buffers.evaluator.run(scene, engine, jobs);
    for (int index = first; index < last; ++index) {
        const std::size_t pixelJobs = firstJob[static_cast<std::size_t>(index - first)];
        if (pixelJobs == kNoJob) continue;
        const RayJob* leader = nullptr;
        for (int sample = 0; sample < tile.perPixel; ++sample) {
            RayJob& job = jobs[pixelJobs + sample];
            if (!job.paused()) {
                if (leader == nullptr && job.trace().hit) leader = &job;
                continue;
            }
            if (leader != nullptr && job.canShareShading(*leader)) {
                job.shareShading(*leader);
            } else {
                job.resumeShading();
            }
        }
    }
    buffers.evaluator.run(scene, engine, jobs);
}

/// The pixels [first, last) of the tile into the image: their rays' colours averaged, the
/// surface's colour, coverage, nearest depth and mean normal; the background where no ray ran.
void writePixels(const TileRect& tile, int first, int last, const TileBuffers& buffers, Image& image,
                 TileStats& stats) {
    const std::vector<RayJob>& jobs = buffers.jobs;
    for (int index = first; index < last; ++index) {
        const int x = tile.x0 + index % tile.width();
        const int y = tile.y0 + index / tile.width();
        const std::size_t pixel = static_cast<std::size_t>(y) * image.width + x;
        const std::size_t pixelJobs = buffers.firstJob[static_cast<std::size_t>(index - first)];
        if (pixelJobs == kNoJob) {  // the background, as its rays' jobs would give it
            stats.rays += tile.perPixel;
            const glm::dvec3& colour = buffers.pixelBackground[static_cast<std::size_t>(y - tile.y0)];
            std::fill_n(image.surface.begin() + 3 * pixel, 3, 0.0f);
            image.rgba[4 * pixel + 0] = static_cast<float>(colour.x);
            image.rgba[4 * pixel + 1] = static_cast<float>(colour.y);
            image.rgba[4 * pixel + 2] = static_cast<float>(colour.z);
            image.rgba[4 * pixel + 3] = 0.0f;
            image.depth[pixel] = std::numeric_limits<float>::infinity();
            std::fill_n(image.normal.begin() + 3 * pixel, 3, 0.0f);
            continue;
        }
        glm::dvec3 colour(0.0);
        glm::dvec3 surfaceColour(0.0);
        glm::dvec3 normalSum(0.0);
        double depth = kInfinity;
        int hits = 0;
        for (int sample = 0; sample < tile.perPixel; ++sample) {
            const RayJob& job = jobs[pixelJobs + sample];
            ++stats.rays;
            stats.steps += job.trace().steps;
            colour += job.colour();
            if (!job.trace().hit) continue;
            surfaceColour += job.colour();
            normalSum += job.normal();
            depth = std::min(depth, job.trace().t);
            ++hits;
        }
        colour *= tile.weight;
        surfaceColour *= tile.weight;
        for (int channel = 0; channel < 3; ++channel)
            image.surface[3 * pixel + channel] = static_cast<float>(surfaceColour[channel]);
        image.rgba[4 * pixel + 0] = static_cast<float>(colour.x);
        image.rgba[4 * pixel + 1] = static_cast<float>(colour.y);
        image.rgba[4 * pixel + 2] = static_cast<float>(colour.z);
        image.rgba[4 * pixel + 3] = static_cast<float>(hits * tile.weight);
        image.depth[pixel] = static_cast<float>(depth);
        const double length = glm::length(normalSum);
        const glm::dvec3 normal = length > 0.0 ? normalSum / length : glm::dvec3(0.0);
        for (int axis = 0; axis < 3; ++axis) image.normal[3 * pixel + axis] = static_cast<float>(normal[axis]);
        if (hits > 0) ++stats.hitPixels;
    }
}

/// One tile: its rays prepared, the cone pre-pass, then its pixels in passes of about
/// kRaysPerPass rays (whole pixels): trace, shared shading, the pixels written.
TileStats renderTile(const Scene& scene, RenderEngine engine, int x0, int y0, int x1, int y1, Image& image,
                     TileBuffers& buffers) {
    TileStats stats;
    TileRect tile;
    tile.x0 = x0;
    tile.y0 = y0;
    tile.x1 = x1;
    tile.y1 = y1;
    tile.samples = scene.samples();
    tile.perPixel = tile.samples * tile.samples;
    tile.weight = 1.0 / tile.perPixel;
    const int pixelsPerPass = std::max(1, kRaysPerPass / tile.perPixel);
    // Room for the shadow marches of a pass's rays: job k has the lights' slots from k * lights.
    std::vector<ShadowMarch>& shadowSlots = buffers.shadowSlots;
    shadowSlots.resize(
        std::max(shadowSlots.size(), static_cast<std::size_t>(pixelsPerPass) * tile.perPixel * scene.lightCount()));
    prepareTileRays(scene, tile, buffers);
    conePrePass(scene, engine, tile, buffers);
    for (int first = 0; first < tile.pixels(); first += pixelsPerPass) {
        const int last = std::min(tile.pixels(), first + pixelsPerPass);
        tracePass(scene, engine, tile, first, last, buffers);
        shadePass(scene, engine, tile, first, last, buffers);
        writePixels(tile, first, last, buffers, image, stats);
    }
    stats.evaluations = buffers.evaluator.takeEvaluations();
    return stats;
}

}  // namespace

RenderResult render(const Params& params, const ProgressCallback& progress, RenderEngine engine) {
    validate(params);
    const auto start = std::chrono::steady_clock::now();
    const std::string provenEmpty = provenEmptyReason(params);
    const Scene scene(params, !provenEmpty.empty());

    RenderResult result;
    Image& image = result.image;
    image.width = scene.camera().width;
    image.height = scene.camera().height;
    const std::size_t pixels = static_cast<std::size_t>(image.width) * image.height;
    image.rgba.assign(4 * pixels, 0.0f);
    image.surface.assign(3 * pixels, 0.0f);
    image.depth.assign(pixels, std::numeric_limits<float>::infinity());
    image.normal.assign(3 * pixels, 0.0f);

    const int tilesX = (image.width + kTileSize - 1) / kTileSize;
    const int tilesY = (image.height + kTileSize - 1) / kTileSize;
    std::atomic<std::uint64_t> rays{0};
    std::atomic<std::uint64_t> steps{0};
    std::atomic<std::uint64_t> hitPixels{0};
    std::atomic<std::uint64_t> evaluations{0};
    ThreadScratch<TileBuffers> scratch;  // each thread's TileBuffers, reused from tile to tile
    parallelForWithProgress(static_cast<std::size_t>(tilesX) * tilesY, progress,
                            [&](std::size_t index, const std::atomic<bool>&) {
                                const int x0 = static_cast<int>(index % tilesX) * kTileSize;
                                const int y0 = static_cast<int>(index / tilesX) * kTileSize;
                                const TileStats tile =
                                    renderTile(scene, engine, x0, y0, std::min(x0 + kTileSize, image.width),
                                               std::min(y0 + kTileSize, image.height), image, scratch.local());
                                rays += tile.rays;
                                steps += tile.steps;
                                hitPixels += tile.hitPixels;
                                evaluations += tile.evaluations;
                            });

    result.stats.rays = rays;
    result.stats.steps = steps;
    result.stats.hitPixels = hitPixels;
    result.stats.evaluations = evaluations;
    result.stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (result.stats.hitPixels == 0)
        result.emptyReason = provenEmpty.empty() ? inspect(params).emptyReason : provenEmpty;
    return result;
}

}  // namespace dqj

// The C ABI: the only place that catches exceptions and turns them into status codes.
// Handles are numbers from a counter that never repeats, looked up in a table of live
// contexts: a stale or garbage handle gives DQJ_ERROR_INVALID_HANDLE instead of a crash, and
// cannot name a context created later at the same address. A context is marked busy while a
// call on it runs, so it cannot be destroyed or used again from inside that call.
#include "dqjulia/dqjulia.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <mutex>
#include <new>
#include <string>
#include <memory>
#include <system_error>
#include <unordered_map>

#include <nlohmann/json.hpp>

#include "dqjulia/bake.hpp"
#include "dqjulia/image.hpp"
#include "dqjulia/empty_result.hpp"
#include "dqjulia/inspect.hpp"
#include "dqjulia/mesh.hpp"
#include "dqjulia/params.hpp"
#include "dqjulia/render.hpp"
#include "dqjulia/variations.hpp"
#include "files/message_text.hpp"

struct dqj_context_t {
    dqj::Params params;
    std::string error;
    std::string warning;
    double frame = 1.0;             // where keyframed parameters are taken (dqj_context_set_frame)
    std::uint64_t memoryLimit = 0;  // 0 = dqj::defaultMemoryLimit()
    dqj::Mesh mesh;                 // from the last dqj_mesh_compute
    dqj::BakeStats bakeStats;       // of the last bake or mesh
    dqj::VariationResult variations;  // from the last dqj_variations_compute
};

namespace {

struct Entry {
    std::unique_ptr<dqj_context_t> context;
    bool busy = false;
};

std::mutex registryMutex;
std::uint64_t lastHandle = 0;  // under registryMutex
std::unordered_map<std::uintptr_t, Entry>& registry() {
    static auto* live = new std::unordered_map<std::uintptr_t, Entry>();  // never destroyed: safe at exit
    return *live;
}

std::uintptr_t handleValue(dqj_context handle) { return reinterpret_cast<std::uintptr_t>(handle); }

/// The live context behind a handle, or null. Its pointer stays valid while it is busy (a busy
/// context cannot be destroyed) or, for the readers of its texts, until it is destroyed.
dqj_context_t* lookUp(dqj_context handle) {
    if (!handle) return nullptr;
    std::lock_guard lock(registryMutex);
    const auto it = registry().find(handleValue(handle));
    return it == registry().end() ? nullptr : it->second.context.get();
}

constexpr const char* kInvalidHandleMessage = "invalid dqjulia context (null, unknown or already destroyed)";

/// Marks a context busy for the duration of one call.
class BusyScope {
public:
    explicit BusyScope(dqj_context handle) : handle_(handle) {
        if (!handle) return;
        std::lock_guard lock(registryMutex);
        const auto it = registry().find(handleValue(handle));
        if (it == registry().end()) return;
        if (it->second.busy) {
            busy_ = true;
            return;
        }
        it->second.busy = true;
        context_ = it->second.context.get();
    }
    ~BusyScope() {
        if (!context_) return;
        std::lock_guard lock(registryMutex);
        // find(), not at(): nothing may throw from a destructor (dqj_context_destroy refuses a busy context).
        const auto it = registry().find(handleValue(handle_));
        if (it != registry().end()) it->second.busy = false;
    }
    BusyScope(const BusyScope&) = delete;
    BusyScope& operator=(const BusyScope&) = delete;
    dqj_context_t* context() const { return context_; }
    bool busy() const { return busy_; }

private:
    dqj_context handle_;
    dqj_context_t* context_ = nullptr;
    bool busy_ = false;
};

/// The system refusing a thread or memory (ulimit -u, ulimit -v): not a file's fault.
bool refusedResources(const std::system_error& error) {
    return error.code() == std::errc::resource_unavailable_try_again || error.code() == std::errc::not_enough_memory;
}

/// Runs `body` for a live, idle context, mapping every exception to a status and a message.
template <typename Body>
dqj_status guarded(dqj_context handle, Body&& body) {
    const BusyScope scope(handle);
    if (scope.busy()) return DQJ_ERROR_BUSY;  // its own error text belongs to the running call
    if (!scope.context()) return DQJ_ERROR_INVALID_HANDLE;
    dqj_context_t* const context = scope.context();
    context->error.clear();
    context->warning.clear();
    try {
        return body(*context);
    } catch (const dqj::MemoryLimitError& error) {
        context->error = error.what();
        return DQJ_ERROR_OUT_OF_MEMORY;
    } catch (const dqj::ParamError& error) {
        context->error = error.what();
        return DQJ_ERROR_PARAMETERS;
    } catch (const dqj::Cancelled&) {
        context->error = "cancelled by the progress callback";
        return DQJ_ERROR_CANCELLED;
    } catch (const std::bad_alloc&) {
        context->error = "out of memory";
        return DQJ_ERROR_OUT_OF_MEMORY;
    } catch (const std::system_error& error) {
        context->error = dqj::exceptionMessage(error);
        return refusedResources(error) ? DQJ_ERROR_OUT_OF_MEMORY : DQJ_ERROR_IO;
    } catch (const std::exception& error) {
        context->error = error.what();
        return DQJ_ERROR_INTERNAL;
    } catch (...) {
        context->error = "unknown internal error";
        return DQJ_ERROR_INTERNAL;
    }
}

dqj_status invalidArgument(dqj_context_t& context, const std::string& message) {
    context.error = message;
    return DQJ_ERROR_INVALID_ARGUMENT;
}

/// Applies `change` to a copy of the parameters and keeps it only if it validates.
template <typename Change>
dqj_status changeParams(dqj_context_t& context, Change&& change) {
    dqj::Params candidate = context.params;
    change(candidate);
    dqj::validate(candidate);
    context.params = std::move(candidate);
    return DQJ_OK;
}

dqj_status copyText(dqj_context_t& context, const std::string& text, char* buffer, size_t capacity, size_t* outSize) {
    if (outSize) *outSize = text.size() + 1;
    if (!buffer) {
        if (capacity != 0) return invalidArgument(context, "buffer is NULL but capacity is not 0");
        return DQJ_OK;
    }
    if (capacity < text.size() + 1)
        return invalidArgument(context, "buffer too small: " + std::to_string(text.size() + 1) + " bytes needed, " +
                                            std::to_string(capacity) + " given");
    std::memcpy(buffer, text.c_str(), text.size() + 1);
    return DQJ_OK;
}

dqj::ProgressCallback wrapProgress(dqj_progress_fn progress, void* userData) {
    if (!progress) return {};
    return [progress, userData](double fraction) { return progress(fraction, userData) != 0; };  // 0 cancels
}

void fillSample(const dqj::Escape& escape, dqj_sample& sample) {
    sample.n = escape.n;
    sample.r = escape.r;
    sample.ra = escape.ra;
    sample.rb = escape.rb;
    sample.de = escape.de;
}

/// The context's parameters at its frame (keyframes applied), validated.
dqj::Params paramsNow(const dqj_context_t& context) { return dqj::validAtFrame(context.params, context.frame); }

/// Runs a bake step that writes a file: I/O failures (std::runtime_error that is neither a
/// parameter problem nor a cancel) become DQJ_ERROR_IO.
template <typename Work>
dqj_status withFileErrors(dqj_context_t& context, Work&& work) {
    try {
        work();
    } catch (const dqj::ParamError&) {
        throw;
    } catch (const dqj::Cancelled&) {
        throw;
    } catch (const std::system_error& error) {
        if (refusedResources(error)) throw;
        context.error = dqj::exceptionMessage(error);
        return DQJ_ERROR_IO;
    } catch (const std::runtime_error& error) {
        context.error = error.what();
        return DQJ_ERROR_IO;
    }
    return DQJ_OK;
}

/// After a bake or mesh: if there is no surface, say why (like noteEmptyRender).
void noteEmptyBake(dqj_context_t& context, const dqj::Params& params, dqj::EmptyResult kind, bool empty) {
    if (empty) context.warning = dqj::emptyResultMessage(kind, dqj::inspect(params).emptyReason);
}

/// After a render: if nothing was hit, say why on the context (a silent empty picture is a bug).
void noteEmptyRender(dqj_context_t& context, const dqj::RenderResult& result) {
    if (result.stats.hitPixels == 0)
        context.warning = dqj::emptyResultMessage(dqj::EmptyResult::Render, result.emptyReason);
}

}  // namespace

extern "C" {

unsigned dqj_version_number(void) { return DQJ_VERSION_NUMBER; }
const char* dqj_version_string(void) { return DQJ_VERSION_STRING; }

const char* dqj_status_string(dqj_status status) {
    switch (status) {
        case DQJ_OK: return "ok";
        case DQJ_ERROR_INVALID_HANDLE: return "invalid handle";
        case DQJ_ERROR_INVALID_ARGUMENT: return "invalid argument";
        case DQJ_ERROR_PARAMETERS: return "invalid parameters";
        case DQJ_ERROR_IO: return "input/output error";
        case DQJ_ERROR_CANCELLED: return "cancelled";
        case DQJ_ERROR_OUT_OF_MEMORY: return "out of memory";
        case DQJ_ERROR_INTERNAL: return "internal error";
        case DQJ_ERROR_BUSY: return "context busy (a call on it is running)";
    }
    return "unknown status";
}

int dqj_has_feature(const char* name) {
    if (!name) return 0;
    // Every build has them today; the names are for builds and hosts that may not.
    for (const char* feature : {DQJ_FEATURE_VDB, DQJ_FEATURE_MESH, DQJ_FEATURE_ANIMATION, DQJ_FEATURE_VARIATIONS})
        if (std::strcmp(name, feature) == 0) return 1;
    return 0;
}

dqj_status dqj_context_create(dqj_context* outContext) {
    if (!outContext) return DQJ_ERROR_INVALID_ARGUMENT;
    *outContext = nullptr;
    try {
        auto context = std::make_unique<dqj_context_t>();
        std::lock_guard lock(registryMutex);
        // Odd numbers from a 64-bit counter: never 0 (NULL), never an address, never reused.
        const std::uintptr_t handle = std::uintptr_t(2 * ++lastHandle + 1);
        registry()[handle].context = std::move(context);
        *outContext = reinterpret_cast<dqj_context>(handle);
        return DQJ_OK;
    } catch (const std::bad_alloc&) {
        return DQJ_ERROR_OUT_OF_MEMORY;
    } catch (...) {
        return DQJ_ERROR_INTERNAL;
    }
}

dqj_status dqj_context_destroy(dqj_context handle) {
    if (!handle) return DQJ_OK;
    std::unique_ptr<dqj_context_t> doomed;  // deleted after the lock is released
    {
        std::lock_guard lock(registryMutex);
        const auto it = registry().find(handleValue(handle));
        if (it == registry().end()) return DQJ_ERROR_INVALID_HANDLE;  // unknown or already destroyed: ignored
        if (it->second.busy) return DQJ_ERROR_BUSY;                   // from inside its own call: refused
        doomed = std::move(it->second.context);
        registry().erase(it);
    }
    return DQJ_OK;
}

const char* dqj_context_error(dqj_context handle) {
    const dqj_context_t* context = lookUp(handle);
    return context ? context->error.c_str() : kInvalidHandleMessage;
}

const char* dqj_context_warning(dqj_context handle) {
    const dqj_context_t* context = lookUp(handle);
    return context ? context->warning.c_str() : "";
}

dqj_status dqj_context_load_params_file(dqj_context context, const char* path) {
    return guarded(context, [&](dqj_context_t& self) {
        if (!path) return invalidArgument(self, "path is NULL");
        self.params = dqj::loadParams(path);
        return DQJ_OK;
    });
}

dqj_status dqj_context_set_params_json(dqj_context context, const char* json) {
    return guarded(context, [&](dqj_context_t& self) {
        if (!json) return invalidArgument(self, "json is NULL");
        self.params = dqj::parseParams(json, "parameters");
        return DQJ_OK;
    });
}

dqj_status dqj_context_get_params_json(dqj_context context, char* buffer, size_t capacity, size_t* outSize) {
    return guarded(context, [&](dqj_context_t& self) {
        return copyText(self, dqj::toJson(self.params), buffer, capacity, outSize);
    });
}

dqj_status dqj_params_schema_json(dqj_context context, char* buffer, size_t capacity, size_t* outSize) {
    return guarded(context, [&](dqj_context_t& self) {
        return copyText(self, dqj::schema::schemaJson(), buffer, capacity, outSize);
    });
}

dqj_status dqj_context_set_constant(dqj_context context, const double c[8]) {
    return guarded(context, [&](dqj_context_t& self) {
        if (!c) return invalidArgument(self, "c is NULL");
        dqj::Vec8 values;
        for (int index = 0; index < 8; ++index) {
            if (!std::isfinite(c[index]))
                return invalidArgument(self, "c[" + std::to_string(index) + "] is not a finite number");
            values[index] = c[index];
        }
        return changeParams(self, [&](dqj::Params& params) { params.fractal.c = dqj::toDualQuat(values); });
    });
}

dqj_status dqj_context_set_variant(dqj_context context, dqj_variant variant) {
    return guarded(context, [&](dqj_context_t& self) {
        dqj::Variant value;
        switch (variant) {
            case DQJ_VARIANT_PAPER: value = dqj::Variant::Paper; break;
            case DQJ_VARIANT_PAPER_COUPLED: value = dqj::Variant::PaperCoupled; break;
            case DQJ_VARIANT_DUAL: value = dqj::Variant::Dual; break;
            default: return invalidArgument(self, "variant must be DQJ_VARIANT_PAPER, _PAPER_COUPLED or _DUAL");
        }
        return changeParams(self, [&](dqj::Params& params) { params.fractal.variant = value; });
    });
}

dqj_status dqj_context_set_iterations(dqj_context context, int iterations) {
    return guarded(context, [&](dqj_context_t& self) {
        return changeParams(self, [&](dqj::Params& params) { params.fractal.iterations = iterations; });
    });
}

dqj_status dqj_context_set_bailout(dqj_context context, double bailout) {
    return guarded(context, [&](dqj_context_t& self) {
        return changeParams(self, [&](dqj::Params& params) { params.fractal.bailout = bailout; });
    });
}

dqj_status dqj_context_set_slice_axes(dqj_context context, const char* axes) {
    return guarded(context, [&](dqj_context_t& self) {
        if (!axes) return invalidArgument(self, "axes is NULL");
        dqj::Slice slice;
        try {
            slice = dqj::sliceFromAxisNames(axes);
        } catch (const std::invalid_argument& error) {
            return invalidArgument(self, std::string("slice axes: ") + error.what());
        }
        return changeParams(self, [&](dqj::Params& params) {
            slice.origin = params.slice.base.origin;
            params.slice.base = slice;
            params.slice.rotations.clear();
        });
    });
}

dqj_status dqj_evaluate_points(dqj_context context, const double* points, size_t count, dqj_sample* out) {
    return guarded(context, [&](dqj_context_t& self) {
        if (count == 0) return DQJ_OK;
        if (!points || !out) return invalidArgument(self, "points or out is NULL");
        for (size_t index = 0; index < count; ++index) {
            dqj::Vec8 point;
            std::copy(points + 8 * index, points + 8 * index + 8, point.begin());
            fillSample(dqj::evaluate(self.params.fractal, dqj::toDualQuat(point)), out[index]);
        }
        return DQJ_OK;
    });
}

dqj_status dqj_evaluate_slice_points(dqj_context context, const double* points, size_t count, dqj_sample* out) {
    return guarded(context, [&](dqj_context_t& self) {
        if (count == 0) return DQJ_OK;
        if (!points || !out) return invalidArgument(self, "points or out is NULL");
        const dqj::Slice slice = self.params.slice.effective();
        for (size_t index = 0; index < count; ++index) {
            const glm::dvec3 p(points[3 * index], points[3 * index + 1], points[3 * index + 2]);
            fillSample(dqj::evaluate(self.params.fractal, slice.map(p)), out[index]);
        }
        return DQJ_OK;
    });
}

dqj_status dqj_render_rgba8(dqj_context context, uint8_t* pixels, uint32_t width, uint32_t height, size_t stride,
                            dqj_progress_fn progress, void* userData) {
    return guarded(context, [&](dqj_context_t& self) {
        if (!pixels) return invalidArgument(self, "pixels is NULL");
        if (width == 0 || height == 0 || width > 16384 || height > 16384)
            return invalidArgument(self, "width and height must be from 1 to 16384");
        if (stride < size_t(width) * 4) return invalidArgument(self, "stride is smaller than 4 * width");
        dqj::Params params = paramsNow(self);
        params.render.width = int(width);
        params.render.height = int(height);
        const dqj::RenderResult result = dqj::render(params, wrapProgress(progress, userData));
        for (uint32_t y = 0; y < height; ++y) {
            uint8_t* row = pixels + y * stride;
            for (uint32_t x = 0; x < width; ++x) {
                const float* rgba = &result.image.rgba[(size_t(y) * width + x) * 4];
                for (int channel = 0; channel < 3; ++channel) row[4 * x + channel] = dqj::linearToSrgb8(rgba[channel]);
                row[4 * x + 3] = uint8_t(std::lround(std::clamp(rgba[3], 0.0f, 1.0f) * 255.0f));
            }
        }
        noteEmptyRender(self, result);
        return DQJ_OK;
    });
}

dqj_status dqj_render_to_file(dqj_context context, const char* path, dqj_progress_fn progress, void* userData) {
    return guarded(context, [&](dqj_context_t& self) {
        if (!path) return invalidArgument(self, "path is NULL");
        dqj::Params params = paramsNow(self);
        params.output.path = path;
        dqj::validate(params);
        try {
            dqj::checkWritable(path);  // before the work, not after it
        } catch (const std::exception& error) {
            self.error = error.what();
            return DQJ_ERROR_IO;
        }
        const dqj::RenderResult result = dqj::render(params, wrapProgress(progress, userData));
        try {
            dqj::writeImage(result.image, path, dqj::formatFor(params.output));
        } catch (const std::exception& error) {
            self.error = error.what();
            return DQJ_ERROR_IO;
        }
        noteEmptyRender(self, result);
        return DQJ_OK;
    });
}

dqj_status dqj_inspect_json(dqj_context context, char* buffer, size_t capacity, size_t* outSize) {
    return guarded(context, [&](dqj_context_t& self) {
        return copyText(self, dqj::reportJson(dqj::inspect(self.params)), buffer, capacity, outSize);
    });
}

dqj_status dqj_context_set_bake_resolution(dqj_context context, int resolution) {
    return guarded(context, [&](dqj_context_t& self) {
        return changeParams(self, [&](dqj::Params& params) { params.bake.resolution = resolution; });
    });
}

dqj_status dqj_context_set_frame(dqj_context context, double frame) {
    return guarded(context, [&](dqj_context_t& self) {
        if (!std::isfinite(frame) || std::abs(frame) > 1e6)
            return invalidArgument(self, "frame must be a finite number within +-1e6");
        self.frame = frame;
        return DQJ_OK;
    });
}

dqj_status dqj_context_set_memory_limit(dqj_context context, uint64_t bytes) {
    return guarded(context, [&](dqj_context_t& self) {
        self.memoryLimit = bytes;
        return DQJ_OK;
    });
}

dqj_status dqj_bake_vdb(dqj_context context, const char* path, dqj_progress_fn progress, void* userData) {
    return guarded(context, [&](dqj_context_t& self) {
        if (!path) return invalidArgument(self, "path is NULL");
        const dqj::Params params = paramsNow(self);
        dqj::BakeOptions options;
        options.memoryLimit = self.memoryLimit;
        dqj::BakeStats stats;
        const dqj_status status = withFileErrors(self, [&] {
            stats = dqj::bakeVdb(params, path, options, wrapProgress(progress, userData));
        });
        if (status != DQJ_OK) return status;
        self.bakeStats = stats;
        noteEmptyBake(self, params, dqj::EmptyResult::Bake, stats.activeVoxels == 0);
        return DQJ_OK;
    });
}

dqj_status dqj_mesh_compute(dqj_context context, dqj_progress_fn progress, void* userData) {
    return guarded(context, [&](dqj_context_t& self) {
        const dqj::Params params = paramsNow(self);
        dqj::BakeOptions options;
        options.memoryLimit = self.memoryLimit;
        dqj::BakeStats stats;
        dqj::Mesh mesh = dqj::bakeMesh(params, options, wrapProgress(progress, userData), &stats);
        if (mesh.positions.size() > UINT32_MAX) return invalidArgument(self, "the mesh has more than 2^32 vertices");
        self.mesh = std::move(mesh);
        self.bakeStats = stats;
        noteEmptyBake(self, params, dqj::EmptyResult::Mesh, self.mesh.positions.empty());
        return DQJ_OK;
    });
}

dqj_status dqj_mesh_estimate(dqj_context context, uint64_t* outBytes, uint64_t* outSlabs, uint64_t* outFaces,
                             dqj_progress_fn progress, void* userData) {
    return guarded(context, [&](dqj_context_t& self) {
        dqj::BakeOptions options;
        options.memoryLimit = self.memoryLimit;
        const dqj::MeshEstimate estimate =
            dqj::estimateMesh(paramsNow(self), options, wrapProgress(progress, userData));
        if (outBytes) *outBytes = estimate.bytes;
        if (outSlabs) *outSlabs = estimate.slabs;
        if (outFaces) *outFaces = estimate.faces;
        return DQJ_OK;
    });
}

dqj_status dqj_mesh_get_sizes(dqj_context context, size_t* outVertexCount, size_t* outTriangleCount) {
    return guarded(context, [&](dqj_context_t& self) {
        if (outVertexCount) *outVertexCount = self.mesh.positions.size();
        if (outTriangleCount) *outTriangleCount = self.mesh.triangleCount();
        return DQJ_OK;
    });
}

dqj_status dqj_mesh_copy(dqj_context context, float* positions, float* normals, float* colors, size_t vertexCapacity,
                         uint32_t* triangles, size_t triangleCapacity) {
    return guarded(context, [&](dqj_context_t& self) {
        const dqj::Mesh& mesh = self.mesh;
        const size_t vertices = mesh.positions.size();
        const bool vertexOnly = !triangles && triangleCapacity == 0;  // faces from dqj_mesh_copy_faces
        if (vertices != 0 && (!positions || (!triangles && !vertexOnly)))
            return invalidArgument(self, "positions or triangles is NULL");
        if (vertexCapacity < vertices || (!vertexOnly && triangleCapacity < mesh.triangleCount()))
            return invalidArgument(self, "buffers too small: the mesh has " + std::to_string(vertices) +
                                             " vertices and " + std::to_string(mesh.triangleCount()) +
                                             " triangles; capacities are " + std::to_string(vertexCapacity) + " and " +
                                             std::to_string(triangleCapacity));
        if (colors && mesh.colors.size() != vertices)
            return invalidArgument(self, "the mesh has no colours (bake.mesh_colors is false); pass colors = NULL");
        for (size_t index = 0; index < vertices; ++index) {
            for (int axis = 0; axis < 3; ++axis) {
                positions[3 * index + axis] = mesh.positions[index][axis];
                if (normals) normals[3 * index + axis] = mesh.normals[index][axis];
                if (colors) colors[3 * index + axis] = mesh.colors[index][axis];
            }
        }
        if (vertexOnly) return DQJ_OK;
        const std::vector<std::uint32_t> indices = mesh.triangulated();
        std::copy(indices.begin(), indices.end(), triangles);
        return DQJ_OK;
    });
}

dqj_status dqj_mesh_get_face_counts(dqj_context context, size_t* outQuadCount, size_t* outTriangleCount) {
    return guarded(context, [&](dqj_context_t& self) {
        if (outQuadCount) *outQuadCount = self.mesh.quads.size();
        if (outTriangleCount) *outTriangleCount = self.mesh.triangles.size();
        return DQJ_OK;
    });
}

dqj_status dqj_mesh_copy_faces(dqj_context context, uint32_t* quads, size_t quadCapacity, uint32_t* triangles,
                               size_t triangleCapacity) {
    return guarded(context, [&](dqj_context_t& self) {
        const dqj::Mesh& mesh = self.mesh;
        if ((!quads && !mesh.quads.empty()) || (!triangles && !mesh.triangles.empty()))
            return invalidArgument(self, "quads or triangles is NULL but the mesh has such faces");
        if (quadCapacity < mesh.quads.size() || triangleCapacity < mesh.triangles.size())
            return invalidArgument(self, "buffers too small: the mesh has " + std::to_string(mesh.quads.size()) +
                                             " quads and " + std::to_string(mesh.triangles.size()) +
                                             " triangles; capacities are " + std::to_string(quadCapacity) + " and " +
                                             std::to_string(triangleCapacity));
        for (std::size_t face = 0; face < mesh.quads.size(); ++face)
            std::copy(mesh.quads[face].begin(), mesh.quads[face].end(), quads + 4 * face);
        for (std::size_t face = 0; face < mesh.triangles.size(); ++face)
            std::copy(mesh.triangles[face].begin(), mesh.triangles[face].end(), triangles + 3 * face);
        return DQJ_OK;
    });
}

dqj_status dqj_mesh_write(dqj_context context, const char* path) {
    return guarded(context, [&](dqj_context_t& self) {
        if (!path) return invalidArgument(self, "path is NULL");
        if (self.mesh.positions.empty())
            return invalidArgument(self, "the context has no mesh: call dqj_mesh_compute first");
        return withFileErrors(self, [&] { dqj::writeMesh(self.mesh, path); });
    });
}

dqj_status dqj_bake_get_stats(dqj_context context, dqj_bake_stats* outStats) {
    return guarded(context, [&](dqj_context_t& self) {
        if (!outStats) return invalidArgument(self, "out_stats is NULL");
        // The first version of the struct ends with `seconds`; later fields are appended after it.
        constexpr size_t firstVersionSize = offsetof(dqj_bake_stats, seconds) + sizeof(double);
        const size_t given = outStats->struct_size;
        if (given < firstVersionSize)
            return invalidArgument(self, "out_stats->struct_size is " + std::to_string(given) +
                                             ": set it to sizeof(dqj_bake_stats) (DQJ_BAKE_STATS_INIT)");
        dqj_bake_stats stats{};
        stats.voxels_evaluated = self.bakeStats.evaluated;
        stats.voxels_dense = self.bakeStats.dense;
        stats.active_voxels = self.bakeStats.activeVoxels;
        stats.estimated_bytes = self.bakeStats.estimatedBytes;
        stats.seconds = self.bakeStats.seconds;
        stats.struct_size = std::min(given, sizeof stats);  // an older library fills less than a newer caller's size
        std::memcpy(outStats, &stats, stats.struct_size);
        return DQJ_OK;
    });
}

dqj_status dqj_variations_compute(dqj_context context, uint64_t seed, double strength, uint32_t lockedGroups,
                                  uint32_t count, dqj_progress_fn progress, void* userData) {
    static_assert(DQJ_GROUP_A == dqj::kGroupA && DQJ_GROUP_B == dqj::kGroupB &&
                  DQJ_GROUP_SLICE_ORIENTATION == dqj::kGroupSliceOrientation &&
                  DQJ_GROUP_SLICE_ORIGIN == dqj::kGroupSliceOrigin && DQJ_GROUP_ITERATIONS == dqj::kGroupIterations &&
                  DQJ_GROUP_VARIANT == dqj::kGroupVariant && DQJ_GROUP_ALL == dqj::kAllVariationGroups);
    return guarded(context, [&](dqj_context_t& self) {
        if (!(strength >= dqj::kMinStrength && strength <= dqj::kMaxStrength))
            return invalidArgument(self,
                                   "strength must be from 0.01 to 1 (DQJ_STRENGTH_TINY 0.05 ... DQJ_STRENGTH_HUGE 1)");
        if (count < 1 || count > 100) return invalidArgument(self, "count must be from 1 to 100");
        if (lockedGroups & ~DQJ_GROUP_ALL)
            return invalidArgument(self, "locked_groups has bits other than DQJ_GROUP_*");
        if (lockedGroups == DQJ_GROUP_ALL)
            return invalidArgument(self, "every group is locked: nothing may change; unlock at least one DQJ_GROUP_*");
        dqj::VariationOptions options;
        options.seed = seed;
        options.strength = strength;
        options.locked = lockedGroups;
        options.count = int(count);
        self.variations =
            dqj::vary(dqj::stillAtFrame(paramsNow(self), self.frame), options, wrapProgress(progress, userData));
        return DQJ_OK;
    });
}

dqj_status dqj_variations_get_json(dqj_context context, char* buffer, size_t capacity, size_t* outSize) {
    return guarded(context, [&](dqj_context_t& self) {
        const dqj::VariationResult& result = self.variations;
        nlohmann::ordered_json document;
        document["count"] = result.variations.size();
        document["candidates"] = result.candidates;
        for (int r = 0; r < dqj::kRejectionCount; ++r)
            document["rejected"][std::string(dqj::rejectionName(dqj::Rejection(r)))] = result.rejected[r];
        document["minimum_distance"] = result.minimumDistance;
        document["variations"] = nlohmann::ordered_json::array();
        for (const dqj::Variation& variation : result.variations)
            document["variations"].push_back({{"candidate", variation.candidate},
                                              {"coverage", variation.measures.coverage},
                                              {"roughness", variation.measures.roughness},
                                              {"distance", variation.measures.distance},
                                              {"connected", variation.measures.connected},
                                              {"description", variation.params.description}});
        return copyText(self, document.dump(2) + "\n", buffer, capacity, outSize);
    });
}

dqj_status dqj_variation_get_params_json(dqj_context context, size_t index, char* buffer, size_t capacity,
                                         size_t* outSize) {
    return guarded(context, [&](dqj_context_t& self) {
        const std::vector<dqj::Variation>& variations = self.variations.variations;
        if (index >= variations.size())
            return invalidArgument(self, "index " + std::to_string(index) + " is out of range: the context has " +
                                             std::to_string(variations.size()) + " variations");
        return copyText(self, dqj::toJson(variations[index].params), buffer, capacity, outSize);
    });
}

}  // extern "C"

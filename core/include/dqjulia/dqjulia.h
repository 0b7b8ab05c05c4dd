/* dqjulia/dqjulia.h - the C ABI of libdqjulia: dual-quaternion Julia fractals (implemented in
 * core/src/c_api.cpp).
 *
 * The one stable surface of the library, for C programs and for hosts that load it
 * at run time (the Blender add-on uses it through ctypes).
 *
 * Versions: from 1.0.0 on this ABI follows semantic versioning (DQJ_VERSION_*, the library's
 * file name libdqjulia.so.MAJOR). A program built against MAJOR.MINOR runs with any library of
 * the same MAJOR and the same or a later MINOR: within a major version functions, status codes,
 * feature names and fields at the end of growable structs are only added, never removed or
 * changed. Any incompatible change makes the next major version. (Before 1.0 a minor version
 * could break it.)
 *
 * - Opaque handles: a dqj_context holds a parameter set and the text of its last error.
 * - Every call returns a dqj_status; on failure dqj_context_error() tells why. There is
 *   no global error buffer, and no C++ exception ever crosses this boundary.
 * - Null pointers and unknown or destroyed handles give DQJ_ERROR_INVALID_HANDLE or
 *   DQJ_ERROR_INVALID_ARGUMENT, never a crash. A handle is a number that is never reused, so
 *   a destroyed handle stays invalid even after new contexts are created.
 * - A context is busy while one of its calls runs: another call on it (from its progress
 *   callback, or from another thread) and dqj_context_destroy() return DQJ_ERROR_BUSY.
 * - Buffers are the caller's: sizes are queried first, then filled.
 * - Result structs that may grow (dqj_bake_stats) start with `size_t struct_size`, which the
 *   caller sets to sizeof the struct it compiled against (the DQJ_*_INIT macros do). The library
 *   fills only what fits in that size, so a program built against an older header keeps
 *   working when fields are added at the end; a size below the first version's is refused
 *   (DQJ_ERROR_INVALID_ARGUMENT). Structs used as array elements (dqj_sample) are frozen.
 * - What an optional part of the library offers is asked with dqj_has_feature(), never by
 *   looking for symbols.
 * - Progress callbacks return non-zero to go on and 0 to cancel, as the C++ API's
 *   dqj::ProgressCallback returns true to go on and false to cancel.
 *
 * Thread safety: dqj_version*(), dqj_status_string() and dqj_has_feature() may be called from
 * any thread.
 * Separate contexts are independent and may be used from different threads at the same
 * time. One context is used by one call at a time (a second call meanwhile is refused with
 * DQJ_ERROR_BUSY, not queued); its progress callback runs on the thread that called dqj_render*(),
 * dqj_bake_vdb(), dqj_mesh_compute() or dqj_variations_compute().
 */
#ifndef DQJULIA_H
#define DQJULIA_H

#include <stddef.h>
#include <stdint.h>

#include "dqjulia/export.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Version of the header you compile against (DQJ_VERSION_MAJOR, _MINOR, _PATCH and
 * DQJ_VERSION_STRING, from the project's VERSION file); compare with dqj_version_number()
 * at run time. */
#include "dqjulia/version.h"
#define DQJ_VERSION_NUMBER (DQJ_VERSION_MAJOR * 10000 + DQJ_VERSION_MINOR * 100 + DQJ_VERSION_PATCH)

/* MAJOR*10000 + MINOR*100 + PATCH of the library actually loaded. */
DQJ_API unsigned dqj_version_number(void);
/* The loaded library's version as text, e.g. "1.0.0" */
DQJ_API const char* dqj_version_string(void);

typedef enum dqj_status {
    DQJ_OK = 0,
    DQJ_ERROR_INVALID_HANDLE = 1,   /* null, unknown or destroyed context */
    DQJ_ERROR_INVALID_ARGUMENT = 2, /* null pointer, size too small, value out of range */
    DQJ_ERROR_PARAMETERS = 3,       /* parameter file or value rejected; the message names the key */
    DQJ_ERROR_IO = 4,               /* a file could not be read or written */
    DQJ_ERROR_CANCELLED = 5,        /* the progress callback asked to stop */
    DQJ_ERROR_OUT_OF_MEMORY = 6,    /* over the memory limit (refused before the work), or memory or a thread refused */
    DQJ_ERROR_INTERNAL = 7,
    DQJ_ERROR_BUSY = 8 /* a call on this context is running (e.g. from its progress callback) */
} dqj_status;

/* A short English name for a status ("invalid handle"); never NULL. */
DQJ_API const char* dqj_status_string(dqj_status status);

/* Whether the loaded library has an optional feature: 1 if it has, 0 if not (and for NULL or
 * a name it does not know, such as one added by a later version). The functions of a feature
 * the library lacks may be missing from it or refuse to work; ask before using them. */
DQJ_API int dqj_has_feature(const char* name);
/* dqj_bake_vdb, with dqj_context_set_bake_resolution, dqj_context_set_memory_limit, dqj_bake_get_stats */
#define DQJ_FEATURE_VDB "vdb"
/* dqj_mesh_*, with the same three */
#define DQJ_FEATURE_MESH "mesh"
/* keyframes (the parameters' "animation") and dqj_context_set_frame */
#define DQJ_FEATURE_ANIMATION "animation"
/* dqj_variations_compute, dqj_variations_get_json, dqj_variation_get_params_json (since 1.1) */
#define DQJ_FEATURE_VARIATIONS "variations"

typedef enum dqj_variant {
    DQJ_VARIANT_PAPER = 0,         /* the paper's rule: a and b iterate independently */
    DQJ_VARIANT_PAPER_COUPLED = 1, /* the paper's rule with one 8-D norm */
    DQJ_VARIANT_DUAL = 2           /* the true dual-quaternion algebra */
} dqj_variant;

typedef struct dqj_context_t* dqj_context;

/* Creates a context holding the default parameters. */
DQJ_API dqj_status dqj_context_create(dqj_context* out_context);
/* Destroys a context; the handle is invalid afterwards. NULL, unknown and destroyed handles
 * are ignored (DQJ_ERROR_INVALID_HANDLE; DQJ_OK for NULL). While a call on the context runs
 * (destroying it from its own progress callback), nothing happens and DQJ_ERROR_BUSY is
 * returned: destroy it after the call returns. */
DQJ_API dqj_status dqj_context_destroy(dqj_context context);
/* The message of the context's last failed call ("" if none). Valid until the next call on
 * the context. For an invalid handle, a static text saying so. */
DQJ_API const char* dqj_context_error(dqj_context context);
/* A warning from the context's last successful call ("" if none): for example why a render,
 * bake or mesh found no surface ("the image shows no surface: " and why, or what to change). */
DQJ_API const char* dqj_context_warning(dqj_context context);

/* Parameters: the JSON document of the parameter file (docs/parameter-file.md), whole or in part;
 * missing keys take their defaults. */
DQJ_API dqj_status dqj_context_load_params_file(dqj_context context, const char* path);
DQJ_API dqj_status dqj_context_set_params_json(dqj_context context, const char* json);
/* The complete parameter document. Writes at most `capacity` bytes including the final NUL;
 * `*out_size` (if not NULL) receives the size needed including the NUL. Call with
 * buffer = NULL, capacity = 0 to query the size. */
DQJ_API dqj_status dqj_context_get_params_json(dqj_context context, char* buffer, size_t capacity, size_t* out_size);
/* The parameter schema: JSON describing every key of the parameter document once: its type,
 * label, help text, default, range (min, max, and the soft range a slider offers) and choices
 * (docs/parameter-file.md, "Parameter schema"). Front ends build their controls from it, as the Blender add-on
 * does. Same buffer convention as dqj_context_get_params_json; it does not depend on the
 * context's parameters. */
DQJ_API dqj_status dqj_params_schema_json(dqj_context context, char* buffer, size_t capacity, size_t* out_size);

/* Single values; each is validated like the parameter file. c: a's s,i,j,k then b's. */
DQJ_API dqj_status dqj_context_set_constant(dqj_context context, const double c[8]);
DQJ_API dqj_status dqj_context_set_variant(dqj_context context, dqj_variant variant);
DQJ_API dqj_status dqj_context_set_iterations(dqj_context context, int iterations);
DQJ_API dqj_status dqj_context_set_bailout(dqj_context context, double bailout);
/* Axis names such as "a.s,a.i,a.j" (origin kept, rotations cleared). */
DQJ_API dqj_status dqj_context_set_slice_axes(dqj_context context, const char* axes);

/* The result for one point, as math.md specifies. Frozen: it is an array element (the
 * evaluate functions fill `count` of them), so its size and fields never change; a richer
 * result would be a new struct with new functions. */
typedef struct dqj_sample {
    int32_t n; /* escape iteration; 0 = did not escape within N */
    double r;  /* norm used for the escape test, at exit */
    double ra; /* |a| at exit */
    double rb; /* |b| at exit */
    double de; /* distance estimate (8-D units); 0 inside, +inf for a zero derivative */
} dqj_sample;

/* Evaluates `count` 8-D points (8 doubles each, a then b) into `out` (count samples). */
DQJ_API dqj_status dqj_evaluate_points(dqj_context context, const double* points, size_t count, dqj_sample* out);
/* Evaluates `count` 3-D points (3 doubles each) mapped through the context's slice. The DE is
 * in 8-D units; divide by the slice's largest stretch for a 3-D distance. */
DQJ_API dqj_status dqj_evaluate_slice_points(dqj_context context, const double* points, size_t count, dqj_sample* out);

/* Progress: called with the fraction done (0..1) on the calling thread: with 0 before the work
 * starts, a few times a second, and with 1 at the end. Return non-zero to go on, 0 to cancel
 * (the call then returns DQJ_ERROR_CANCELLED): the convention of dqj::ProgressCallback, which
 * returns true to go on and false to cancel. */
typedef int (*dqj_progress_fn)(double fraction, void* user_data);

/* Renders into a caller-owned RGBA8 (sRGB) buffer of `height` rows of `stride` bytes
 * (stride >= 4 * width); width and height override the parameters' render size. */
DQJ_API dqj_status dqj_render_rgba8(dqj_context context, uint8_t* pixels, uint32_t width, uint32_t height,
                                    size_t stride, dqj_progress_fn progress, void* user_data);
/* Renders and writes an image file (.png 8-bit, or as the parameters' output.format says;
 * .exr with depth and normals). The file appears only when complete. */
DQJ_API dqj_status dqj_render_to_file(dqj_context context, const char* path, dqj_progress_fn progress, void* user_data);

/* What the constant and slice give: JSON with the equivalent complex constants, Mandelbrot
 * membership, bounds, inside fraction and, when the slice is empty, the reason. Same
 * buffer convention as dqj_context_get_params_json. */
DQJ_API dqj_status dqj_inspect_json(dqj_context context, char* buffer, size_t capacity, size_t* out_size);

/* ---- Baking: OpenVDB volumes and meshes (docs/baking.md) ----------------------------------
 * Bakes and meshes use the context's parameters at its current frame (dqj_context_set_frame)
 * and their "bake" section: resolution, bounds, band width, which grids, mesh adaptivity and
 * vertex colours. Set that section with dqj_context_set_params_json, or the resolution alone
 * with dqj_context_set_bake_resolution. Coordinates are the slice's x, y, z. */

/* Voxels across the largest side of the bake bounds, 8..16384 (sets bake.resolution). */
DQJ_API dqj_status dqj_context_set_bake_resolution(dqj_context context, int resolution);
/* The frame at which keyframed parameters (the parameter file's "animation") are taken by
 * renders, bakes and meshes on this context. Default 1. Without keyframes it changes nothing. */
DQJ_API dqj_status dqj_context_set_frame(dqj_context context, double frame);
/* Bakes and meshes whose estimated memory exceeds `bytes` are refused before any heavy work
 * (DQJ_ERROR_OUT_OF_MEMORY, the message gives the estimate). 0 (the default) means half of the
 * memory available when the work starts. */
DQJ_API dqj_status dqj_context_set_memory_limit(dqj_context context, uint64_t bytes);

/* Bakes an OpenVDB file at `path`: the level set "surface", the fog volume "density" and the
 * attribute grids bake.grids asks for. The file appears only when complete: after a failure or
 * a cancel an existing file at `path` is untouched and no temporary file remains. */
DQJ_API dqj_status dqj_bake_vdb(dqj_context context, const char* path, dqj_progress_fn progress, void* user_data);

/* Meshes the surface (OpenVDB volumeToMesh at the bake resolution and bake.adaptivity, or at
 * most bake.max_faces triangles: docs/baking.md gives the error bound), slab by slab where the
 * memory limit asks for it, and keeps the mesh in the context, replacing the previous one
 * (which is kept if this call fails). */
DQJ_API dqj_status dqj_mesh_compute(dqj_context context, dqj_progress_fn progress, void* user_data);
/* What dqj_mesh_compute would take with the context's parameters and memory limit, known before
 * it starts (from the classification of the surface's blocks alone: a few percent of the mesh's
 * time; `progress` as dqj_mesh_compute's, and it may cancel): `out_bytes` the memory estimate
 * checked against the limit (the one piece's, or the largest slab's), `out_slabs` the slabs it
 * will be made in (1: one piece), `out_faces` about how many triangles (quads count as two;
 * within a third; at most bake.max_faces). Any pointer may be NULL. A mesh that cannot fit the
 * limit even slab by slab (adaptive and bake.max_faces meshes: in one piece) gives
 * DQJ_ERROR_OUT_OF_MEMORY with the reason, as dqj_mesh_compute would. */
DQJ_API dqj_status dqj_mesh_estimate(dqj_context context, uint64_t* out_bytes, uint64_t* out_slabs, uint64_t* out_faces,
                                     dqj_progress_fn progress, void* user_data);
/* The sizes of the context's mesh: vertices, and triangles (quads count as two). 0 and 0 before
 * the first dqj_mesh_compute. Either pointer may be NULL. */
DQJ_API dqj_status dqj_mesh_get_sizes(dqj_context context, size_t* out_vertex_count, size_t* out_triangle_count);
/* Copies the context's mesh into caller-owned buffers sized by dqj_mesh_get_sizes:
 *   positions  3 floats a vertex (x, y, z);
 *   normals    3 floats a vertex, unit, pointing out of the solid; NULL to skip;
 *   colors     3 floats a vertex, linear RGB from the material's colouring; NULL to skip (and
 *              NULL is required when bake.mesh_colors was false: the mesh then has none);
 *   triangles  3 vertex indices a triangle, counter-clockwise seen from outside (every face as
 *              triangles); NULL with triangle_capacity 0 to copy the vertices only (for
 *              dqj_mesh_copy_faces).
 * vertex_capacity and triangle_capacity are the buffers' sizes in vertices and triangles;
 * too small gives DQJ_ERROR_INVALID_ARGUMENT and copies nothing. */
DQJ_API dqj_status dqj_mesh_copy(dqj_context context, float* positions, float* normals, float* colors,
                                 size_t vertex_capacity, uint32_t* triangles, size_t triangle_capacity);
/* The faces of the context's mesh as the core made them: quads, and triangles (with adaptivity
 * or where a quad would repeat a vertex). 0 and 0 before the first dqj_mesh_compute. Either
 * pointer may be NULL. */
DQJ_API dqj_status dqj_mesh_get_face_counts(dqj_context context, size_t* out_quad_count, size_t* out_triangle_count);
/* Copies the faces into caller-owned buffers sized by dqj_mesh_get_face_counts: quads 4 vertex
 * indices each, triangles 3 each, counter-clockwise seen from outside (vertices from dqj_mesh_copy).
 * A buffer may be NULL when its count is 0; too small gives DQJ_ERROR_INVALID_ARGUMENT and
 * copies nothing. */
DQJ_API dqj_status dqj_mesh_copy_faces(dqj_context context, uint32_t* quads, size_t quad_capacity, uint32_t* triangles,
                                       size_t triangle_capacity);
/* Writes the context's mesh to `path`, by its extension: .ply (binary, with normals and colours),
 * .obj, .stl (binary, triangles, no colours) or .3mf (vertex colours; unit millimetre), slice
 * coordinates. Same all-or-nothing file behaviour as dqj_bake_vdb. */
DQJ_API dqj_status dqj_mesh_write(dqj_context context, const char* path);

/* What the context's last successful bake or mesh cost (zeros before the first). It may gain
 * fields at the end: set struct_size before the call (DQJ_BAKE_STATS_INIT does), e.g.
 *   dqj_bake_stats stats = DQJ_BAKE_STATS_INIT;
 * The library fills the fields that fit in struct_size, sets struct_size to the bytes it filled
 * (less than the caller's size when the library is older than the caller's header) and leaves
 * the rest untouched; a struct_size smaller than this first version's gives
 * DQJ_ERROR_INVALID_ARGUMENT and fills nothing. */
typedef struct dqj_bake_stats {
    size_t struct_size;        /* in: sizeof(dqj_bake_stats) of the caller; out: the bytes filled */
    uint64_t voxels_evaluated; /* fractal evaluations, including the block tests */
    uint64_t voxels_dense;     /* voxels of the whole grid: what a dense bake evaluates */
    uint64_t active_voxels;    /* active voxels of the "surface" level set (bakes; 0 for meshes) */
    uint64_t estimated_bytes;  /* the memory estimate checked against the limit */
    double seconds;            /* wall-clock time */
} dqj_bake_stats;
/* An initialiser that sets struct_size (designated: C99, C++20). */
#define DQJ_BAKE_STATS_INIT \
    { .struct_size = sizeof(dqj_bake_stats) }
DQJ_API dqj_status dqj_bake_get_stats(dqj_context context, dqj_bake_stats* out_stats);

/* ---- Variations: the fractal next to the one in front of you (docs/examples.md, "Exploring") ---------------
 * Variations of the context's parameters (at its frame, as a still: without "animation"): each
 * proven non-empty and not dust by the library's own analysis, neither a featureless ball nor
 * too small in the frame, no two nearly the same picture, all of them further from the original
 * as the strength grows. The same seed, strength, locks and count give the same documents on
 * every platform. Feature DQJ_FEATURE_VARIATIONS. */

/* Groups of values a variation may change; the locked ones stay as they are, bit for bit. */
#define DQJ_GROUP_A 0x01u                 /* fractal.c's real part a */
#define DQJ_GROUP_B 0x02u                 /* fractal.c's dual part b */
#define DQJ_GROUP_SLICE_ORIENTATION 0x04u /* slice.rotations */
#define DQJ_GROUP_SLICE_ORIGIN 0x08u      /* slice.origin */
#define DQJ_GROUP_ITERATIONS 0x10u        /* fractal.iterations and fractal.bailout */
#define DQJ_GROUP_VARIANT 0x20u           /* fractal.variant (switched only at large strengths) */
#define DQJ_GROUP_ALL 0x3fu

/* Strengths from 0.01 to 1, named as an artist would (Mandelbulber's Randomizer): */
#define DQJ_STRENGTH_TINY 0.05  /* the same fractal with its details moved a little */
#define DQJ_STRENGTH_SMALL 0.15 /* a close relative: the same overall form, different details */
#define DQJ_STRENGTH_MEDIUM 0.3 /* a sibling: recognisably related, noticeably different */
#define DQJ_STRENGTH_LARGE 0.6  /* a cousin: a different form from the same neighbourhood */
#define DQJ_STRENGTH_HUGE 1.0   /* a stranger: anything the unlocked groups can reach */

/* Computes `count` (1..100) variations and keeps them in the context, replacing the previous
 * ones (which are kept if this call fails). `locked_groups`: DQJ_GROUP_* bits that stay; at
 * least one group must be open. Progress as for renders (0 cancels). Fails with
 * DQJ_ERROR_INVALID_ARGUMENT for a strength, count or lock out of range, and with
 * DQJ_ERROR_PARAMETERS when the context's document is itself empty (or dust in a locked part),
 * or when fewer than `count` variations pass within 60 * count candidates: the message says
 * which measures rejected how many and how to loosen the settings (raise the strength, unlock
 * groups). Never fewer variations than asked for on success. */
DQJ_API dqj_status dqj_variations_compute(dqj_context context, uint64_t seed, double strength, uint32_t locked_groups,
                                          uint32_t count, dqj_progress_fn progress, void* user_data);
/* The context's variations as JSON: {"count", "candidates", "rejected": {"invalid", "empty",
 * "dust", "tiny", "ball", "similar"}, "minimum_distance", "variations": [{"candidate",
 * "coverage", "roughness", "distance", "connected", "description"}, ...]} (count 0 before the first
 * dqj_variations_compute). Same buffer convention as dqj_context_get_params_json. */
DQJ_API dqj_status dqj_variations_get_json(dqj_context context, char* buffer, size_t capacity, size_t* out_size);
/* Variation `index` (0-based) as a complete parameter document, exactly as
 * dqj_context_get_params_json would give it after dqj_context_set_params_json with it. Same
 * buffer convention; an index out of range gives DQJ_ERROR_INVALID_ARGUMENT. */
DQJ_API dqj_status dqj_variation_get_params_json(dqj_context context, size_t index, char* buffer, size_t capacity,
                                                 size_t* out_size);

#ifdef __cplusplus
}
#endif

#endif /* DQJULIA_H */

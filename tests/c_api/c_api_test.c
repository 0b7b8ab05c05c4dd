/* The C ABI used from a program written in C (not C++): versions, features, parameters,
 * evaluation against reference values, errors per handle, rendering with progress and cancel,
 * a growing result struct, and UTF-8 file names (on Windows too, where the test of the Windows
 * build runs it under Wine with SCRATCH_DIR as a drive letter and backslashes).
 *
 *   c_api_test [SCRATCH_DIR]   the checks
 *   c_api_test --layout        prints the size of each struct and the offset and size of each
 *                              field, for tests/python/native_abi_test.py to hold the ctypes bindings to */
#include <errno.h>
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifdef _WIN32
#include <direct.h>
#include <windows.h>
#else
#include <sys/stat.h>
#endif

#include "dqjulia/dqjulia.h"

static int failures = 0;
static int checks = 0;

#define CHECK(condition, ...)                                       \
    do {                                                            \
        ++checks;                                                   \
        if (!(condition)) {                                         \
            ++failures;                                             \
            fprintf(stderr, "%s:%d: FAILED: ", __FILE__, __LINE__); \
            fprintf(stderr, __VA_ARGS__);                           \
            fprintf(stderr, "\n");                                  \
        }                                                           \
    } while (0)

static int close_to(double actual, double expected) {
    if (isinf(expected)) return isinf(actual) && actual > 0;
    return fabs(actual - expected) <= 1e-10 * fabs(expected);
}

static const char* c1_paper =
    "{\"fractal\": {\"c\": [-0.10, 0.8, -0.26, 0.15, -0.23, -0.38, -0.86, 0.64],"
    " \"variant\": \"paper\", \"iterations\": 15, \"bailout\": 4.0}}";

static int count_calls(double fraction, void* user_data) {
    int* calls = (int*)user_data;
    (void)fraction;
    ++*calls;
    return 1; /* go on */
}

static int cancel_at_once(double fraction, void* user_data) {
    (void)fraction;
    (void)user_data;
    return 0; /* cancel */
}

static void test_versions(void) {
    CHECK(dqj_version_number() == DQJ_VERSION_NUMBER, "run-time version %u differs from header %d",
          dqj_version_number(), DQJ_VERSION_NUMBER);
    CHECK(strlen(dqj_version_string()) >= 5, "version string too short");
    CHECK(strcmp(dqj_status_string(DQJ_ERROR_INVALID_HANDLE), "invalid handle") == 0, "status text");
}

static void test_features(void) {
    CHECK(dqj_has_feature(DQJ_FEATURE_VDB) == 1, "no feature vdb");
    CHECK(dqj_has_feature(DQJ_FEATURE_MESH) == 1, "no feature mesh");
    CHECK(dqj_has_feature(DQJ_FEATURE_ANIMATION) == 1, "no feature animation");
    CHECK(dqj_has_feature("teleportation") == 0, "an unknown feature is reported");
    CHECK(dqj_has_feature(NULL) == 0, "NULL is a feature");
}

static void test_bake_stats(dqj_context context) {
    /* The struct as a newer header might have it: the fields of this one, then more. */
    struct newer {
        dqj_bake_stats known;
        uint64_t added;
    } newer;
    dqj_bake_stats stats = DQJ_BAKE_STATS_INIT;
    dqj_bake_stats unset;
    int calls = 0;
    CHECK(dqj_context_set_params_json(context, "{\"bake\": {\"resolution\": 16}}") == DQJ_OK, "params: %s",
          dqj_context_error(context));
    CHECK(dqj_mesh_compute(context, count_calls, &calls) == DQJ_OK && calls >= 2, "mesh: %s",
          dqj_context_error(context));
    CHECK(dqj_bake_get_stats(context, &stats) == DQJ_OK, "stats: %s", dqj_context_error(context));
    CHECK(stats.struct_size == sizeof stats, "struct_size became %zu", stats.struct_size);
    CHECK(stats.voxels_dense == 16 * 16 * 16 && stats.voxels_evaluated > 0, "stats: dense %llu, evaluated %llu",
          (unsigned long long)stats.voxels_dense, (unsigned long long)stats.voxels_evaluated);

    /* A caller with a larger struct gets what this library knows, and is told how much that is. */
    memset(&newer, 0xab, sizeof newer);
    newer.known.struct_size = sizeof newer;
    CHECK(dqj_bake_get_stats(context, &newer.known) == DQJ_OK, "stats into a larger struct");
    CHECK(newer.known.struct_size == sizeof(dqj_bake_stats), "filled %zu bytes", newer.known.struct_size);
    CHECK(newer.known.voxels_dense == stats.voxels_dense, "known field not filled");
    CHECK(newer.added == 0xababababababababull, "a field the library does not know was written");

    /* One that forgot struct_size is refused. */
    memset(&unset, 0, sizeof unset);
    CHECK(dqj_bake_get_stats(context, &unset) == DQJ_ERROR_INVALID_ARGUMENT, "struct_size 0 accepted");
    CHECK(strstr(dqj_context_error(context), "struct_size") != NULL, "message: %s", dqj_context_error(context));
}

#define FIELD(type, field) printf("%s.%s %zu %zu\n", #type, #field, offsetof(type, field), sizeof(((type*)0)->field))

static int print_layout(void) {
    printf("dqj_sample %zu\n", sizeof(dqj_sample));
    FIELD(dqj_sample, n);
    FIELD(dqj_sample, r);
    FIELD(dqj_sample, ra);
    FIELD(dqj_sample, rb);
    FIELD(dqj_sample, de);
    printf("dqj_bake_stats %zu\n", sizeof(dqj_bake_stats));
    FIELD(dqj_bake_stats, struct_size);
    FIELD(dqj_bake_stats, voxels_evaluated);
    FIELD(dqj_bake_stats, voxels_dense);
    FIELD(dqj_bake_stats, active_voxels);
    FIELD(dqj_bake_stats, estimated_bytes);
    FIELD(dqj_bake_stats, seconds);
    return 0;
}

static void test_reference_values(dqj_context context) {
    /* Rows of reference_vectors.csv: c1 point 1 (0.3 0.2 0.1 0 | 0) and point 0. */
    const double points[16] = {0.3, 0.2, 0.1, 0.0, 0.0, 0.0, 0.0, 0.0, 0, 0, 0, 0, 0, 0, 0, 0};
    dqj_sample out[2];
    CHECK(dqj_context_set_params_json(context, c1_paper) == DQJ_OK, "set params: %s", dqj_context_error(context));
    CHECK(dqj_evaluate_points(context, points, 2, out) == DQJ_OK, "evaluate: %s", dqj_context_error(context));
    CHECK(out[0].n == 6 && close_to(out[0].r, 7.214903863267726) && close_to(out[0].ra, 0.8260141247850684) &&
              isinf(out[0].de),
          "c1 point 1 paper: n=%d r=%.17g de=%g", out[0].n, out[0].r, out[0].de);
    CHECK(out[1].n == 6 && isinf(out[1].de), "c1 point 0 paper: n=%d", out[1].n);

    CHECK(dqj_context_set_variant(context, DQJ_VARIANT_DUAL) == DQJ_OK, "set variant");
    CHECK(dqj_evaluate_points(context, points, 1, out) == DQJ_OK, "evaluate dual");
    CHECK(out[0].n == 14 && close_to(out[0].de, 0.004513454803138481) && close_to(out[0].rb, 250.4132804916606),
          "c1 point 1 dual: n=%d de=%.17g", out[0].n, out[0].de);

    CHECK(dqj_context_set_variant(context, DQJ_VARIANT_PAPER_COUPLED) == DQJ_OK, "set variant");
    CHECK(dqj_evaluate_points(context, points, 1, out) == DQJ_OK, "evaluate coupled");
    CHECK(out[0].n == 6 && close_to(out[0].de, 0.00886741806074376) && close_to(out[0].r, 7.262033949971592),
          "c1 point 1 paper-coupled: n=%d de=%.17g", out[0].n, out[0].de);

    /* Slice coordinates: the default slice maps (x, y, z) to a.s, a.i, a.j. */
    {
        const double xyz[3] = {0.3, 0.2, 0.1};
        CHECK(dqj_evaluate_slice_points(context, xyz, 1, out) == DQJ_OK, "evaluate slice");
        CHECK(out[0].n == 6 && close_to(out[0].de, 0.00886741806074376), "slice point: n=%d", out[0].n);
    }
}

static void test_errors(dqj_context context) {
    dqj_sample out[1];
    const double point[8] = {0};
    char small[4];
    size_t needed = 0;
    dqj_context other = NULL;

    CHECK(dqj_context_set_iterations(context, 0) == DQJ_ERROR_PARAMETERS, "iterations 0 accepted");
    CHECK(strstr(dqj_context_error(context), "fractal.iterations") != NULL, "message names the key: %s",
          dqj_context_error(context));
    CHECK(dqj_context_set_bailout(context, 1.2) == DQJ_ERROR_PARAMETERS, "bailout below r_K accepted");
    CHECK(strstr(dqj_context_error(context), "containment radius") != NULL, "bailout message: %s",
          dqj_context_error(context));
    CHECK(dqj_context_set_slice_axes(context, "a.s,a.s,a.j") == DQJ_ERROR_INVALID_ARGUMENT, "repeated axis accepted");
    CHECK(dqj_context_set_params_json(context, "{\"fractal\": {\"iteratons\": 5}}") == DQJ_ERROR_PARAMETERS,
          "typo accepted");
    CHECK(strstr(dqj_context_error(context), "did you mean \"iterations\"") != NULL, "no suggestion: %s",
          dqj_context_error(context));
    CHECK(dqj_context_set_params_json(context, "{\"fractal\": ") == DQJ_ERROR_PARAMETERS, "bad JSON accepted");
    CHECK(strstr(dqj_context_error(context), "line 1") != NULL, "no line number: %s", dqj_context_error(context));
    CHECK(dqj_evaluate_points(context, NULL, 1, out) == DQJ_ERROR_INVALID_ARGUMENT, "NULL points accepted");
    CHECK(dqj_context_get_params_json(context, small, sizeof small, &needed) == DQJ_ERROR_INVALID_ARGUMENT,
          "small buffer");
    CHECK(needed > 100, "size query gave %zu", needed);

    /* Handles: null, destroyed and garbage handles are rejected, not dereferenced. */
    CHECK(dqj_evaluate_points(NULL, point, 1, out) == DQJ_ERROR_INVALID_HANDLE, "NULL handle accepted");
    CHECK(dqj_context_create(&other) == DQJ_OK && other != NULL, "create");
    dqj_context_destroy(other);
    CHECK(dqj_evaluate_points(other, point, 1, out) == DQJ_ERROR_INVALID_HANDLE, "destroyed handle accepted");
    CHECK(dqj_context_error(other)[0] != '\0', "no message for a destroyed handle");
    dqj_context_destroy(other); /* twice: ignored */
    CHECK(dqj_evaluate_points((dqj_context)(void*)&needed, point, 1, out) == DQJ_ERROR_INVALID_HANDLE,
          "garbage handle");
    CHECK(dqj_context_create(NULL) == DQJ_ERROR_INVALID_ARGUMENT, "create(NULL)");

    /* A failed call leaves the previous parameters in place. */
    {
        char* json;
        CHECK(dqj_context_get_params_json(context, NULL, 0, &needed) == DQJ_OK, "size query");
        json = (char*)malloc(needed);
        CHECK(dqj_context_get_params_json(context, json, needed, NULL) == DQJ_OK, "get params");
        CHECK(strstr(json, "\"paper-coupled\"") != NULL, "parameters changed by a failed call: %s", json);
        free(json);
    }
}

static void test_render(dqj_context context, const char* scratch_dir) {
    /* c = 0 under the true algebra is the unit ball, centred in the picture. */
    const double zero[8] = {0};
    enum { W = 64, H = 48 };
    static unsigned char pixels[W * H * 4];
    int calls = 0;
    char path[1024];
    FILE* file;

    CHECK(dqj_context_set_params_json(context, "{\"fractal\": {\"variant\": \"dual\"}}") == DQJ_OK, "params: %s",
          dqj_context_error(context));
    CHECK(dqj_context_set_constant(context, zero) == DQJ_OK, "constant: %s", dqj_context_error(context));
    CHECK(dqj_render_rgba8(context, pixels, W, H, W * 4, count_calls, &calls) == DQJ_OK, "render: %s",
          dqj_context_error(context));
    CHECK(pixels[((H / 2) * W + W / 2) * 4 + 3] == 255, "centre pixel not covered");
    CHECK(pixels[3] == 0, "corner pixel covered");
    CHECK(calls >= 1, "progress never called");
    CHECK(dqj_context_warning(context)[0] == '\0', "warning for a non-empty render: %s", dqj_context_warning(context));
    CHECK(dqj_render_rgba8(context, pixels, W, H, W * 4, cancel_at_once, NULL) == DQJ_ERROR_CANCELLED,
          "cancel ignored");
    CHECK(dqj_render_rgba8(context, pixels, W, H, W * 2, NULL, NULL) == DQJ_ERROR_INVALID_ARGUMENT,
          "short stride accepted");

    /* Writing into a folder that does not exist fails cleanly and leaves nothing behind. */
    snprintf(path, sizeof path, "%s/no-such-folder/x.png", scratch_dir);
    CHECK(dqj_render_to_file(context, path, NULL, NULL) == DQJ_ERROR_IO, "missing folder: %s",
          dqj_context_error(context));
    file = fopen(path, "rb");
    CHECK(file == NULL, "a file appeared");
    if (file) fclose(file);
}

static void test_empty_slice(dqj_context context) {
    /* The paper's first constant: its dual part is outside the Mandelbrot set, so with b fixed
     * at 0 the slice is empty for N >= 6; the library must say so. */
    char* json;
    size_t needed = 0;
    enum { W = 16, H = 12 };
    static unsigned char pixels[W * H * 4];
    CHECK(dqj_context_set_params_json(context, c1_paper) == DQJ_OK, "params: %s", dqj_context_error(context));
    CHECK(dqj_inspect_json(context, NULL, 0, &needed) == DQJ_OK, "inspect size");
    json = (char*)malloc(needed);
    CHECK(dqj_inspect_json(context, json, needed, NULL) == DQJ_OK, "inspect");
    CHECK(strstr(json, "\"empty\": true") != NULL, "not reported empty: %s", json);
    CHECK(strstr(json, "outside the Mandelbrot set") != NULL, "no reason: %s", json);
    free(json);
    CHECK(dqj_render_rgba8(context, pixels, W, H, W * 4, NULL, NULL) == DQJ_OK, "render empty");
    CHECK(strstr(dqj_context_warning(context), "N >= 6") != NULL, "empty render without reason: '%s'",
          dqj_context_warning(context));
}

/* Variations: the same seed gives the same documents, each a complete document the context
 * takes back; bad settings and an empty start get a status and a message. */
static void test_variations(dqj_context context) {
    char first[16384], again[16384], report[8192];
    size_t needed = 0;
    int calls = 0;
    CHECK(dqj_has_feature(DQJ_FEATURE_VARIATIONS) == 1, "no feature variations");
    CHECK(dqj_context_set_params_json(context, "{}") == DQJ_OK, "defaults: %s", dqj_context_error(context));
    CHECK(dqj_variations_get_json(context, report, sizeof report, NULL) == DQJ_OK &&
              strstr(report, "\"count\": 0") != NULL,
          "before any: %s", report);
    CHECK(dqj_variations_compute(context, 7, DQJ_STRENGTH_MEDIUM, DQJ_GROUP_VARIANT, 3, count_calls, &calls) == DQJ_OK,
          "compute: %s", dqj_context_error(context));
    CHECK(calls >= 2, "progress called %d times", calls);
    CHECK(dqj_variation_get_params_json(context, 2, NULL, 0, &needed) == DQJ_OK && needed > 100, "size %zu", needed);
    CHECK(dqj_variation_get_params_json(context, 0, first, sizeof first, NULL) == DQJ_OK, "get: %s",
          dqj_context_error(context));
    CHECK(strstr(first, "Variation 1 (seed 7") != NULL, "description: %.200s", first);
    CHECK(dqj_variation_get_params_json(context, 3, first, sizeof first, NULL) == DQJ_ERROR_INVALID_ARGUMENT &&
              strstr(dqj_context_error(context), "out of range") != NULL,
          "index 3 of 3: %s", dqj_context_error(context));
    CHECK(dqj_variations_get_json(context, report, sizeof report, NULL) == DQJ_OK &&
              strstr(report, "\"count\": 3") != NULL && strstr(report, "\"similar\"") != NULL,
          "report: %s", report);
    CHECK(dqj_variation_get_params_json(context, 0, first, sizeof first, NULL) == DQJ_OK, "get again");
    CHECK(dqj_variations_compute(context, 7, DQJ_STRENGTH_MEDIUM, DQJ_GROUP_VARIANT, 3, NULL, NULL) == DQJ_OK,
          "compute again: %s", dqj_context_error(context));
    CHECK(dqj_variation_get_params_json(context, 0, again, sizeof again, NULL) == DQJ_OK && strcmp(first, again) == 0,
          "the same seed gave another document");
    /* A variation is a complete document the context takes as it is. */
    CHECK(dqj_context_set_params_json(context, first) == DQJ_OK, "set variation: %s", dqj_context_error(context));
    CHECK(dqj_context_get_params_json(context, again, sizeof again, NULL) == DQJ_OK && strcmp(first, again) == 0,
          "the variation changed on the way back");
    /* Bad settings: a status and a message; the variations of the last success are kept. */
    CHECK(dqj_variations_compute(context, 1, 1.5, 0, 3, NULL, NULL) == DQJ_ERROR_INVALID_ARGUMENT &&
              strstr(dqj_context_error(context), "strength") != NULL,
          "strength 1.5: %s", dqj_context_error(context));
    CHECK(dqj_variations_compute(context, 1, 0.3, DQJ_GROUP_ALL, 3, NULL, NULL) == DQJ_ERROR_INVALID_ARGUMENT &&
              strstr(dqj_context_error(context), "every group is locked") != NULL,
          "all locked: %s", dqj_context_error(context));
    CHECK(dqj_variations_compute(context, 1, 0.3, 0, 0, NULL, NULL) == DQJ_ERROR_INVALID_ARGUMENT, "count 0");
    CHECK(dqj_variations_compute(context, 1, 0.3, 0, 3, cancel_at_once, NULL) == DQJ_ERROR_CANCELLED, "cancel");
    CHECK(dqj_variation_get_params_json(context, 2, NULL, 0, &needed) == DQJ_OK, "kept after failures");
    CHECK(dqj_context_set_params_json(context, c1_paper) == DQJ_OK, "params: %s", dqj_context_error(context));
    CHECK(dqj_variations_compute(context, 1, 0.3, 0, 3, NULL, NULL) == DQJ_ERROR_PARAMETERS &&
              strstr(dqj_context_error(context), "itself empty") != NULL,
          "empty start: %s", dqj_context_error(context));
}

#ifdef _WIN32
#define SEPARATOR '\\'
/* Windows opens a UTF-8 name by its UTF-16 form. */
static wchar_t* widen(const char* text) {
    static wchar_t buffers[2][1024];
    static int next = 0;
    wchar_t* wide = buffers[next++ % 2];
    if (!MultiByteToWideChar(CP_UTF8, MB_ERR_INVALID_CHARS, text, -1, wide, 1024)) wide[0] = 0;
    return wide;
}
static FILE* open_utf8(const char* path, const char* mode) { return _wfopen(widen(path), widen(mode)); }
static int make_folder(const char* path) { return _wmkdir(widen(path)) == 0 || errno == EEXIST ? 0 : -1; }
#else
#define SEPARATOR '/'
static FILE* open_utf8(const char* path, const char* mode) { return fopen(path, mode); }
static int make_folder(const char* path) { return mkdir(path, 0777) == 0 || errno == EEXIST ? 0 : -1; }
#endif

/* Whether the file at `path` (UTF-8) starts with `magic`. */
static int starts_with(const char* path, const char* magic) {
    char head[16] = {0};
    size_t length = strlen(magic);
    FILE* file = open_utf8(path, "rb");
    if (!file) return 0;
    length = fread(head, 1, length, file) == length && memcmp(head, magic, length) == 0;
    fclose(file);
    return (int)length;
}

static void test_paths(dqj_context context, const char* scratch_dir) {
    /* A folder with spaces and letters beyond ASCII ("dqj paths été 日本 🌀"): a parameter file read
     * from it, a picture, a bake and a mesh written into it twice (the second time over the first). */
    const char* name = "dqj paths \xc3\xa9t\xc3\xa9 \xe6\x97\xa5\xe6\x9c\xac \xf0\x9f\x8c\x80";
    char folder[1024], path[1200];
    const char* outputs[3] = {"picture \xc3\xbc.png", "volume \xc3\xbc.vdb", "mesh \xc3\xbc.ply"};
    const char* magics[3] = {"\x89PNG", " BDV", "ply\n"};
    size_t needed = 0;
    char* json;
    FILE* file;
    int pass, index;
    snprintf(folder, sizeof folder, "%s%c%s", scratch_dir, SEPARATOR, name);
    CHECK(make_folder(folder) == 0, "cannot make the folder %s", folder);
    /* The parameter file's name with '/' even on Windows, which takes both separators. */
    snprintf(path, sizeof path, "%s/params \xc3\xb1.json", folder);
    file = open_utf8(path, "wb");
    CHECK(file != NULL, "cannot write %s", path);
    if (!file) return;
    fputs(
        "{\"fractal\": {\"iterations\": 7}, \"render\": {\"width\": 32, \"height\": 24}, "
        "\"bake\": {\"resolution\": 16}}",
        file);
    fclose(file);
    CHECK(dqj_context_load_params_file(context, path) == DQJ_OK, "load %s: %s", path, dqj_context_error(context));
    CHECK(dqj_context_get_params_json(context, NULL, 0, &needed) == DQJ_OK, "size query");
    json = (char*)malloc(needed);
    CHECK(dqj_context_get_params_json(context, json, needed, NULL) == DQJ_OK, "get params");
    CHECK(strstr(json, "\"iterations\": 7") != NULL, "the file's parameters were not taken: %s", json);
    free(json);
    for (pass = 0; pass < 2; ++pass) {
        snprintf(path, sizeof path, "%s%c%s", folder, SEPARATOR, outputs[0]);
        CHECK(dqj_render_to_file(context, path, NULL, NULL) == DQJ_OK, "render %s: %s", path,
              dqj_context_error(context));
        snprintf(path, sizeof path, "%s%c%s", folder, SEPARATOR, outputs[1]);
        CHECK(dqj_bake_vdb(context, path, NULL, NULL) == DQJ_OK, "bake %s: %s", path, dqj_context_error(context));
        snprintf(path, sizeof path, "%s%c%s", folder, SEPARATOR, outputs[2]);
        CHECK(dqj_mesh_compute(context, NULL, NULL) == DQJ_OK, "mesh: %s", dqj_context_error(context));
        CHECK(dqj_mesh_write(context, path) == DQJ_OK, "mesh %s: %s", path, dqj_context_error(context));
    }
    for (index = 0; index < 3; ++index) {
        snprintf(path, sizeof path, "%s%c%s", folder, SEPARATOR, outputs[index]);
        CHECK(starts_with(path, magics[index]), "%s is missing or not what was written", path);
    }
    /* A name that is not UTF-8, which no Windows file has, fails with a message (Linux takes any bytes). */
#ifdef _WIN32
    snprintf(path, sizeof path, "%s%cbad \xff.png", folder, SEPARATOR);
    CHECK(dqj_render_to_file(context, path, NULL, NULL) != DQJ_OK && dqj_context_error(context)[0] != '\0',
          "a name that is not UTF-8 was accepted");
#endif
}

int main(int argc, char** argv) {
    dqj_context context = NULL;
    const char* scratch = argc > 1 ? argv[1] : ".";
    if (argc > 1 && strcmp(argv[1], "--layout") == 0) return print_layout();
    test_versions();
    test_features();
    CHECK(dqj_context_create(&context) == DQJ_OK, "create");
    test_reference_values(context);
    test_errors(context);
    test_render(context, scratch);
    test_empty_slice(context);
    test_bake_stats(context);
    test_variations(context);
    test_paths(context, scratch);
    dqj_context_destroy(context);
    printf("%d passed, %d failed\n", checks - failures, failures);
    return failures == 0 ? 0 : 1;
}

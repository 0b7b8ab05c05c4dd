// dqjulia_shading.glsl - the core's colouring and shading (core/include/dqjulia/coloring.hpp
// and core/src/kernel/coloring.cpp), in single precision GLSL: the smooth escape count, the trap's
// scale, the palette, the orbit colour of each colouring and the Phong terms. Same names as
// the core's functions, dqj_ and snake case (orbitColour is dqj_orbit_colour).
//
// Follows dqjulia_de.glsl (it uses DqjEscape) and keeps to the same common subset of GLSL 3.30
// and C++, so tests/shaders compiles it as C++ against GLM and compares it with the core.
// It reads no uniform: the preview (preview_frag.glsl) passes everything in.

// The core's kTrapScaleFactor: the trap colouring divides the orbit trap by this times r_K(c_a)
// (coloring.hpp says why 0.65).
const float DQJ_TRAP_SCALE_FACTOR = 0.65f;

// The colouring of the material (the core's Coloring).
const int DQJ_COLORING_SOLID = 0;
const int DQJ_COLORING_ITERATIONS = 1;
const int DQJ_COLORING_TRAP = 2;

// The part of the core's Material the shading reads.
struct DqjMaterial {
    int coloring;      // DQJ_COLORING_*
    vec3 color;        // the solid colour (linear RGB)
    mat4 palette;      // up to 4 colours (columns; rgb)
    int palette_size;  // 1 to 4
    vec4 phong;        // ambient k_a, diffuse k_d, specular k_s, shininess s
};

// kTrapScaleFactor * r_K(c_a), from r_K (the core's trapScale()).
float dqj_trap_scale(float containment_radius) {
    return DQJ_TRAP_SCALE_FACTOR * containment_radius;
}

// n + 1 - log2(ln r / ln R); N for a point that did not escape or whose exit norm is not above 1.
float dqj_smooth_iterations(DqjEscape e, int iterations, float bailout) {
    if (e.n == 0 || !(e.r > 1.0f)) return float(iterations);
    return float(e.n) + 1.0f - log2(log(e.r) / log(bailout));
}

// Where the point falls on the palette (0 first colour, 1 last): the smooth count / N, or the
// trap / trap scale; 0 for solid.
float dqj_coloring_value(int coloring, DqjEscape e, int iterations, float bailout, float trap_scale) {
    if (coloring == DQJ_COLORING_ITERATIONS) return dqj_smooth_iterations(e, iterations, bailout) / float(iterations);
    if (coloring == DQJ_COLORING_TRAP) return e.trap / trap_scale;
    return 0.0f;
}

// The palette at value: colours evenly spaced over [0, 1], linear between neighbours; the first
// colour at value <= 0 (and NaN), the last at value >= 1.
vec3 dqj_palette_colour(DqjMaterial m, float value) {
    if (m.palette_size <= 1 || !(value > 0.0f)) return vec3(m.palette[0]);
    if (value >= 1.0f) return vec3(m.palette[m.palette_size - 1]);
    float position = value * float(m.palette_size - 1);
    int index = int(position);
    float fraction = position - float(index);
    return vec3(m.palette[index]) * (1.0f - fraction) + vec3(m.palette[index + 1]) * fraction;
}

// The material's colour for a point with this escape result.
vec3 dqj_orbit_colour(DqjMaterial m, DqjEscape e, int iterations, float bailout, float trap_scale) {
    if (m.coloring == DQJ_COLORING_SOLID) return m.color;
    return dqj_palette_colour(m, dqj_coloring_value(m.coloring, e, iterations, bailout, trap_scale));
}

// Phong's ambient term k_a * open * C (open: ambient occlusion, 1 = open).
vec3 dqj_phong_ambient(DqjMaterial m, vec3 base, float open) {
    return m.phong.x * open * base;
}

// One directional light's diffuse and specular terms,
// (k_d (N.L) (0.7 + 0.3 open) C + k_s max(0, R.V)^s) * radiance with R = 2 (N.L) N - L;
// 0 when the light is behind the surface.
vec3 dqj_phong_light(DqjMaterial m, vec3 base, vec3 normal, vec3 to_light, vec3 to_eye, vec3 radiance, float open) {
    float facing = dot(normal, to_light);
    if (facing <= 0.0f) return vec3(0.0f);
    float diffuse_occlusion = 0.7f + 0.3f * open;
    vec3 reflected = 2.0f * facing * normal - to_light;
    float highlight = pow(max(0.0f, dot(reflected, to_eye)), m.phong.w);
    return (m.phong.y * facing * diffuse_occlusion * base + m.phong.z * highlight) * radiance;
}

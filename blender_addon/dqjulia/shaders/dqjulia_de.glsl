// dqjulia_de.glsl - the escape iteration, distance estimate and sphere tracer of the core
// (math.md; core/src/kernel/estimate.cpp and core/src/render/render.cpp), in single precision GLSL.
//
// The one place besides the core where the maths is written again, so it is written to be
// compiled three ways and kept equal to the core by tests:
//   - by Blender's GPU module, as part of the viewport preview (preview.py);
//   - by glslangValidator (tests/shaders/CMakeLists.txt);
//   - as C++ against GLM, whose types and functions mirror GLSL's (tests/shaders/).
// So it keeps to the common subset of GLSL 3.30 and C++: no swizzles, no in/out/inout
// parameters (structs are returned instead), no constructors of structs, float literals with
// an `f` suffix (C++ would otherwise compute in double), no arrays, no overloading on
// qualifiers. Quaternions are vec4 (s, i, j, k) = (x, y, z, w): scalar first, as in math.md.
//
// Cost: at most `iterations` steps of two quaternion squares per evaluation; a ray takes up
// to `max_steps` evaluations plus 8 for the bisection.

// Stands for +inf (the DE of an orbit that started on the critical point): "take the largest step".
const float DQJ_HUGE = 1.0e30f;

// The result for one point, as math.md specifies.
struct DqjEscape {
    int n;       // escape iteration; 0 = did not escape within N
    float r;     // the norm used for the escape test, at exit
    float ra;    // |a| at exit
    float rb;    // |b| at exit
    float de;    // distance estimate in 8-D units; 0 inside, DQJ_HUGE for a zero derivative
    float trap;  // orbit trap: the smallest |a| along the orbit
};

// Hamilton square (s^2 - |v|^2, 2 s v).
vec4 dqj_square(vec4 q) {
    return vec4(q.x * q.x - q.y * q.y - q.z * q.z - q.w * q.w, 2.0f * q.x * q.y, 2.0f * q.x * q.z, 2.0f * q.x * q.w);
}

// sym(a, b) = ab + ba = (2(a0 b0 - a_v.b_v), 2(a0 b_v + b0 a_v)): the dual part of (a + b eps)^2.
vec4 dqj_sym(vec4 a, vec4 b) {
    return vec4(2.0f * (a.x * b.x - a.y * b.y - a.z * b.z - a.w * b.w), 2.0f * (a.x * b.y + b.x * a.y),
                2.0f * (a.x * b.z + b.x * a.z), 2.0f * (a.x * b.w + b.x * a.w));
}

// 0.5 |x| ln|x| / d for an escaped part; DQJ_HUGE when the derivative is zero.
float dqj_part_estimate(float norm, float derivative) {
    if (derivative == 0.0f) return DQJ_HUGE;
    return 0.5f * norm * log(norm) / derivative;
}

// variant: 0 = paper, 1 = paper-coupled, 2 = dual (the order of dqj_variant in dqjulia.h).
DqjEscape dqj_evaluate(vec4 a, vec4 b, vec4 ca, vec4 cb, int variant, int iterations, float bailout) {
    float ra = length(a);
    float rb = length(b);
    float da = 1.0f;  // paper, dual: |da|; paper-coupled: the 8-D dr
    float db = 1.0f;
    float trap = ra;
    DqjEscape result;
    result.n = 0;
    for (int k = 1; k <= iterations; ++k) {
        if (variant == 0) {
            da *= 2.0f * ra;
            db *= 2.0f * rb;
            a = dqj_square(a) + ca;
            b = dqj_square(b) + cb;
        } else if (variant == 1) {
            da *= 2.0f * sqrt(ra * ra + rb * rb);
            a = dqj_square(a) + ca;
            b = dqj_square(b) + cb;
        } else {
            da *= 2.0f * ra;
            vec4 previous = a;  // b must use the old a
            a = dqj_square(a) + ca;
            b = dqj_sym(previous, b) + cb;
        }
        ra = length(a);
        rb = length(b);
        trap = min(trap, ra);
        bool escaped;
        if (variant == 0) {
            escaped = ra > bailout || rb > bailout;
        } else if (variant == 1) {
            escaped = sqrt(ra * ra + rb * rb) > bailout;
        } else {
            escaped = ra > bailout;
        }
        if (escaped) {
            result.n = k;
            break;
        }
    }
    result.ra = ra;
    result.rb = rb;
    result.trap = trap;
    result.de = 0.0f;
    if (variant == 0) {
        result.r = max(ra, rb);
        if (result.n != 0) {
            // max, not min: min is 0 wherever one part never escapes and the marcher stalls.
            float de_a = ra > bailout ? dqj_part_estimate(ra, da) : 0.0f;
            float de_b = rb > bailout ? dqj_part_estimate(rb, db) : 0.0f;
            result.de = max(de_a, de_b);
        }
    } else if (variant == 1) {
        result.r = sqrt(ra * ra + rb * rb);
        if (result.n != 0) result.de = dqj_part_estimate(result.r, da);
    } else {
        result.r = ra;
        if (result.n != 0) result.de = dqj_part_estimate(ra, da);
    }
    return result;
}

// What defines the set in the 3-D slice.
struct DqjFractal {
    mat4 slice_a;    // columns: the slice's origin, x, y and z axes; real part a (s, i, j, k)
    mat4 slice_b;    // the same for the dual part b
    vec4 ca;         // the constant's real part
    vec4 cb;         // the constant's dual part
    int variant;
    int iterations;
    float bailout;
    float stretch;   // the slice's largest stretch: DE / stretch is a safe 3-D step
};

// How rays are marched (the render section of the parameter file).
struct DqjTrace {
    vec4 bounds;        // centre (x, y, z) and radius (w) of the sphere rays start on
    bool clipped;       // the sphere clips an unbounded set: its face is the surface
    float step_factor;
    float max_step;
    int max_steps;
    float detail;       // hit threshold in pixel footprints
    vec2 footprint;     // a pixel's size at distance t along the ray: footprint.x * t + footprint.y
};

struct DqjHit {
    bool hit;
    float t;
    int steps;
    bool cut;           // started inside the set on a clipping sphere
    DqjEscape escape;   // at the hit point (outside the finite-N set when refined)
};

DqjEscape dqj_evaluate_at(DqjFractal f, vec3 p) {
    vec4 x = vec4(1.0f, p);
    return dqj_evaluate(f.slice_a * x, f.slice_b * x, f.ca, f.cb, f.variant, f.iterations, f.bailout);
}

// The DE as a 3-D distance; 0 inside.
float dqj_distance3(DqjFractal f, DqjEscape e) {
    return e.n == 0 ? 0.0f : e.de / f.stretch;
}

// Hit threshold at distance t: `detail` pixel footprints, never below 1e-7 (the core's floor).
float dqj_epsilon(DqjTrace m, float t) {
    return max(m.detail * (m.footprint.x * t + m.footprint.y), 1.0e-7f);
}

// Where a ray (unit direction) meets the bounds: (near, far), or (-1, -1) for a miss.
vec2 dqj_sphere(vec3 origin, vec3 direction, vec4 bounds) {
    vec3 offset = origin - vec3(bounds.x, bounds.y, bounds.z);
    float b = dot(offset, direction);
    float c = dot(offset, offset) - bounds.w * bounds.w;
    float discriminant = b * b - c;
    if (discriminant < 0.0f) return vec2(-1.0f, -1.0f);
    float root = sqrt(discriminant);
    if (-b + root < 0.0f) return vec2(-1.0f, -1.0f);
    return vec2(max(0.0f, -b - root), -b + root);
}

// Sphere tracing exactly as the core's renderer: start where the ray enters the bounds, step
// by step_factor * min(DE / stretch, max_step), hit when the DE falls below the footprint, and
// bisect back to the surface of the finite-N set when a step lands inside it.
DqjHit dqj_march(DqjFractal f, DqjTrace m, vec3 origin, vec3 direction) {
    DqjHit trace;
    trace.hit = false;
    trace.t = DQJ_HUGE;
    trace.steps = 0;
    trace.cut = false;
    vec2 span = dqj_sphere(origin, direction, m.bounds);
    if (span.y < 0.0f) return trace;
    float t = span.x;
    float previous_t = t;
    DqjEscape previous;
    previous.n = 0;
    bool have_previous = false;
    float step3 = DQJ_HUGE;
    float eps = dqj_epsilon(m, t);
    for (int step = 0; step < m.max_steps; ++step) {
        DqjEscape e = dqj_evaluate_at(f, origin + t * direction);
        trace.steps += 1;
        eps = dqj_epsilon(m, t);
        if (e.n == 0) {
            trace.hit = true;
            if (!have_previous) {
                trace.t = t;
                trace.escape = e;
                trace.cut = step == 0 && m.clipped && span.x > 0.0f;
                return trace;
            }
            // The step jumped over the surface of the finite-N set: bisect back to it.
            float outside = previous_t;
            float inside = t;
            for (int k = 0; k < 8; ++k) {
                float middle = 0.5f * (outside + inside);
                DqjEscape probe = dqj_evaluate_at(f, origin + middle * direction);
                if (probe.n == 0) {
                    inside = middle;
                } else {
                    outside = middle;
                    previous = probe;
                }
            }
            trace.t = outside;
            trace.escape = previous;
            return trace;
        }
        step3 = e.de / f.stretch;
        if (e.de >= DQJ_HUGE) step3 = m.max_step;  // zero derivative: the largest step
        if (step3 < eps) {
            trace.hit = true;
            trace.t = t;
            trace.escape = e;
            return trace;
        }
        previous_t = t;
        previous = e;
        have_previous = true;
        t += m.step_factor * min(step3, m.max_step);
        if (t > span.y) return trace;
    }
    // Out of steps: close enough to count, or give up.
    if (have_previous && step3 < 10.0f * eps) {
        trace.hit = true;
        trace.t = previous_t;
        trace.escape = previous;
    }
    return trace;
}

// Surface normal by central differences of the 3-D distance, one-sided where one probe is
// inside (the DE is clamped to 0 there); the bounds' normal on a clipped face. Faces the ray:
// one tipped past perpendicular (a surface seen edge on) is bent onto the silhouette, not
// mirrored, as the core's facingRay (mirroring made one-pixel dark speckles).
vec3 dqj_normal(DqjFractal f, DqjTrace m, DqjHit trace, vec3 p, vec3 direction, float eps) {
    vec3 gradient = vec3(0.0f);
    if (trace.cut) {
        gradient = p - vec3(m.bounds.x, m.bounds.y, m.bounds.z);
    } else {
        float h = max(eps, 1.0e-6f);
        float here = dqj_distance3(f, trace.escape);
        for (int axis = 0; axis < 3; ++axis) {
            vec3 offset = vec3(axis == 0 ? h : 0.0f, axis == 1 ? h : 0.0f, axis == 2 ? h : 0.0f);
            DqjEscape plus = dqj_evaluate_at(f, p + offset);
            DqjEscape minus = dqj_evaluate_at(f, p - offset);
            float d_plus = dqj_distance3(f, plus);
            float d_minus = dqj_distance3(f, minus);
            float g = 0.0f;
            if (plus.n != 0 && minus.n != 0) {
                g = (d_plus - d_minus) / (2.0f * h);
            } else if (plus.n != 0) {
                g = (d_plus - here) / h;
            } else if (minus.n != 0) {
                g = (here - d_minus) / h;
            }
            if (axis == 0) gradient.x = g;
            if (axis == 1) gradient.y = g;
            if (axis == 2) gradient.z = g;
        }
    }
    float len = length(gradient);
    vec3 normal = len > 0.0f && len < DQJ_HUGE ? gradient / len : -direction;
    float along = dot(normal, direction);
    if (along > 0.0f) {
        vec3 bent = normal - along * direction;
        float bent_length = length(bent);
        normal = bent_length > 1.0e-6f ? bent / bent_length : -direction;
    }
    return normal;
}

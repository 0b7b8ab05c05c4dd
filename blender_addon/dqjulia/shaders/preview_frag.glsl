// preview_frag.glsl - the viewport preview: one ray a pixel through the back faces of the
// cube around the bounds, marched by dqj_march (dqjulia_de.glsl, which precedes this file),
// shaded like the core's renderer without its shadows and occlusion, and written with its
// true depth so the preview sits among the scene's other objects.
//
// dqj_eye: w = 1, the eye in object coordinates (perspective); w = 0, the viewing direction
// (orthographic). dqj_footprint: a pixel's size at distance t, footprint.x * t + footprint.y.
// Everything else is in the uniform buffer `dqj` (preview_params.glsl).

vec3 dqj_palette_colour(float value) {
    int count = dqj.ints.w;
    if (count <= 1 || !(value > 0.0)) return vec3(dqj.palette[0]);
    if (value >= 1.0) return vec3(dqj.palette[count - 1]);
    float position = value * float(count - 1);
    int index = int(position);
    float fraction = position - float(index);
    return mix(vec3(dqj.palette[index]), vec3(dqj.palette[index + 1]), fraction);
}

vec3 dqj_base_colour(DqjEscape e) {
    if (dqj.ints.z == 0) return dqj.color.rgb;
    if (dqj.ints.z == 1) {
        if (e.n == 0 || !(e.r > 1.0)) return dqj_palette_colour(1.0);
        float smooth_count = float(e.n) + 1.0 - log2(log(e.r) / log(dqj.floats.x));
        return dqj_palette_colour(smooth_count / float(dqj.ints.y));
    }
    return dqj_palette_colour(e.trap / dqj.floats.z);
}

void main() {
    DqjFractal f;
    f.slice_a = dqj.slice_a;
    f.slice_b = dqj.slice_b;
    f.ca = dqj.ca;
    f.cb = dqj.cb;
    f.variant = dqj.ints.x;
    f.iterations = dqj.ints.y;
    f.bailout = dqj.floats.x;
    f.stretch = dqj.floats.y;

    DqjTrace m;
    m.bounds = dqj.bounds;
    m.clipped = dqj.floats.w > 0.5;
    m.step_factor = dqj.marching.x;
    m.max_step = dqj.marching.y;
    m.max_steps = int(dqj.marching.z);
    m.detail = dqj.marching.w;
    m.footprint = dqj_footprint;

    vec3 origin;
    vec3 direction;
    if (dqj_eye.w > 0.5) {
        origin = dqj_eye.xyz;
        direction = normalize(v_pos - origin);
    } else {
        direction = normalize(dqj_eye.xyz);
        // Start behind the cube: far enough back that the whole sphere is ahead.
        origin = v_pos - direction * (4.0 * dqj.bounds.w + 1.0);
    }

    DqjHit trace = dqj_march(f, m, origin, direction);
    if (!trace.hit) discard;

    vec3 p = origin + trace.t * direction;
    float eps = dqj_epsilon(m, trace.t);
    vec3 normal = dqj_normal(f, m, trace, p, direction, eps);
    vec3 base = dqj_base_colour(trace.escape);
    vec3 colour = dqj.phong.x * base;
    vec3 to_eye = -direction;
    for (int i = 0; i < 2; ++i) {
        vec3 light = dqj.lights[2 * i].xyz;
        vec3 radiance = dqj.lights[2 * i + 1].xyz;
        float facing = dot(normal, light);
        if (facing <= 0.0) continue;
        vec3 reflected = 2.0 * facing * normal - light;
        float highlight = pow(max(0.0, dot(reflected, to_eye)), dqj.phong.w);
        colour += (dqj.phong.y * facing * base + dqj.phong.z * highlight) * radiance;
    }

    vec4 clip = dqj_mvp * vec4(p, 1.0);
    gl_FragDepth = clamp(0.5 * clip.z / clip.w + 0.5, 0.0, 1.0);
    // Scene-linear, like the rest of the viewport: Blender's view transform makes it display
    // colour (with "Standard" it looks as the CLI's PNG does).
    fragColor = vec4(colour, 1.0);
}

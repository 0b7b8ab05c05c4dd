// preview_frag.glsl - the viewport preview: one ray a pixel through the back faces of the
// cube around the bounds, marched by dqj_march (dqjulia_de.glsl, which precedes this file),
// coloured and shaded by the core's colouring and Phong terms (dqjulia_shading.glsl, the port of
// coloring.hpp, which also precedes it) without the renderer's shadows and occlusion, and
// written with its true depth so the preview sits among the scene's other objects.
//
// dqj_eye: w = 1, the eye in object coordinates (perspective); w = 0, the viewing direction
// (orthographic). dqj_footprint: a pixel's size at distance t, footprint.x * t + footprint.y.
// Everything else is in the uniform buffer `dqj` (preview_params.glsl).

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
    DqjMaterial material;
    material.coloring = dqj.ints.z;
    material.color = vec3(dqj.color);
    material.palette = dqj.palette;
    material.palette_size = dqj.ints.w;
    material.phong = dqj.phong;
    float trap_scale = dqj_trap_scale(dqj.floats.z);
    vec3 base = dqj_orbit_colour(material, trace.escape, f.iterations, f.bailout, trap_scale);
    // No ambient occlusion (open = 1) and no shadows: the renderer's terms otherwise.
    vec3 colour = dqj_phong_ambient(material, base, 1.0);
    for (int i = 0; i < 2; ++i)
        colour += dqj_phong_light(material, base, normal, dqj.lights[2 * i].xyz, -direction, dqj.lights[2 * i + 1].xyz,
                                  1.0);

    vec4 clip = dqj_mvp * vec4(p, 1.0);
    gl_FragDepth = clamp(0.5 * clip.z / clip.w + 0.5, 0.0, 1.0);
    // Scene-linear, like the rest of the viewport: Blender's view transform makes it display
    // colour (with "Standard" it looks as the CLI's PNG does).
    fragColor = vec4(colour, 1.0);
}

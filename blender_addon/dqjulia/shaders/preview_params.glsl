// preview_params.glsl - the preview's parameters, one uniform buffer (std140) named `dqj`.
// preview.py fills it from a ctypes structure with the same layout: every member is a
// multiple of 16 bytes, matrices column by column.
struct DqjPreviewParams {
    mat4 slice_a;   // columns: the slice's origin, x, y, z axes; real part a (s, i, j, k)
    mat4 slice_b;   // the same for the dual part b
    mat4 palette;   // up to 4 colours (columns, linear RGB)
    mat4 lights;    // columns: direction 0, radiance 0, direction 1, radiance 1 (object space)
    vec4 ca;        // the constant's real part
    vec4 cb;        // the constant's dual part
    vec4 bounds;    // centre (xyz) and radius (w) of the bounding sphere
    vec4 marching;  // step_factor, max_step, max_steps, detail
    vec4 color;     // the material colour (solid colouring)
    vec4 phong;     // ambient, diffuse, specular, shininess
    ivec4 ints;     // variant (0 paper, 1 paper-coupled, 2 dual), iterations, colouring (0 solid,
                    // 1 iterations, 2 trap), palette size
    vec4 floats;    // bailout, stretch, r_K(c_a) (for the trap's scale), clipped (1 = the sphere clips an
                    // extrusion)
};

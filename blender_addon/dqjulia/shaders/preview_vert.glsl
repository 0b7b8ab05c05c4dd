// preview_vert.glsl - the corners of the cube around the bounds, in object (= slice)
// coordinates; the fragment shader marches the ray through each pixel the cube covers.
void main() {
    v_pos = pos;
    gl_Position = dqj_mvp * vec4(pos, 1.0);
}

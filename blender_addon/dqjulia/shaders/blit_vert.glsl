// blit_vert.glsl - a quad over the whole viewport, in normalized device coordinates.
void main() {
    v_uv = pos * 0.5 + 0.5;
    gl_Position = vec4(pos, 0.0, 1.0);
}

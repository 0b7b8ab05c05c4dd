// blit_frag.glsl - the cached preview: its colour where the preview hit, at its depth, so the
// viewport's later redraws (Workbench's anti-aliasing samples, overlays) cost a texture read
// instead of a ray march. When the cache is smaller than the viewport (a preview resolution
// below 100%), colour is filtered and the silhouette is where coverage is at least a half.
void main() {
    vec4 colour = texture(dqj_image, v_uv);
    if (colour.a < 0.5) discard;
    gl_FragDepth = texture(dqj_depth, v_uv).r;
    fragColor = vec4(colour.rgb / colour.a, 1.0);
}

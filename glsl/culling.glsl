// Task-shader culling tests shared by the descriptor layouts (descriptors.glsl) and the
// compressed formats (compressed.task): every test errs on the side of keeping a meshlet.

// Rounding slack of a plane test: 1e-5 of the magnitudes summed, far above f32's error (~1e-7
// relative per operation), so rounding can only keep a meshlet, never drop a visible one.
float slack(vec4 p, vec3 c) { return 1e-5 * (dot(abs(p.xyz), abs(c)) + abs(p.w)); }

// Gribb-Hartmann planes from the rows of view_proj (Vulkan depth 0..1).
vec4 frustum_plane(int i) {
    mat4 m = transpose(pc.view_proj);
    vec4 planes[6] = vec4[6](m[3] + m[0], m[3] - m[0], m[3] + m[1], m[3] - m[1], m[2], m[3] - m[2]);
    return planes[i];
}

// Sphere entirely outside one of the six clip planes. An instance's sphere moves to world space
// with its radius scaled by the instance's largest stretch (rounded up on the host).
bool sphere_outside(vec4 s) {
    if (instanced()) { s = vec4(to_world(s.xyz), s.w * instances[pc.instance].extra.x * 1.00001); }
    for (int i = 0; i < 6; i++) {
        vec4 p = frustum_plane(i);
        if (dot(p.xyz, s.xyz) + p.w < -s.w * length(p.xyz) * 1.00001 - slack(p, s.xyz)) { return true; }
    }
    return false;
}

// Box (centre, half extent) entirely outside one of the six clip planes.
bool box_outside(vec3 c, vec3 h) {
    if (instanced()) { return sphere_outside(vec4(c, length(h) * 1.00001)); }
    for (int i = 0; i < 6; i++) {
        vec4 p = frustum_plane(i);
        if (dot(p.xyz, c) + p.w < -dot(abs(p.xyz), h) * 1.00001 - slack(p, c)) { return true; }
    }
    return false;
}

// meshletlab::meshlet::Cone::culls, the same f32 expression. An instance's cone is tested in its
// object space (eye()): whether a triangle faces the camera survives any invertible affine map
// once mirrored instances flip their front face.
bool apex_backfacing(vec4 apex_cutoff, vec3 axis) {
    if (apex_cutoff.w >= 1.0) { return false; }
    vec3 d = apex_cutoff.xyz - eye();
    float len = length(d);
    return len > 0.0 && dot(d, axis) >= apex_cutoff.w * len;
}

// meshlet::descriptor::sphere_cone_backfacing: no apex, so meshoptimizer's sphere-centre test.
bool sphere_backfacing(vec3 c, float r, vec3 axis, float cutoff) {
    if (cutoff >= 1.0) { return false; }
    vec3 d = c - eye();
    float len = length(d);
    return dot(d, axis) > cutoff * len + r + 1e-5 * len;
}

// QuantisedBounds::backfacing: the sphere-centre test on the box's sphere.
bool box_backfacing(vec3 c, vec3 h, vec3 axis, float cutoff) { return sphere_backfacing(c, length(h), axis, cutoff); }

// Octahedral unit vector from two signed 8-bit codes (meshlet::descriptor::decode_octahedral).
vec3 decode_octahedral(int x, int y) {
    vec2 p = vec2(x, y) / 127.0;
    float z = 1.0 - abs(p.x) - abs(p.y);
    if (z < 0.0) {
        p = (1.0 - abs(p.yx)) * vec2(p.x >= 0.0 ? 1.0 : -1.0, p.y >= 0.0 ? 1.0 : -1.0);
    }
    return normalize(vec3(p, z));
}

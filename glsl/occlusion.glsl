// Two-phase occlusion culling in the task shader (meshlet.task): the visibility words of the last
// frame and the depth pyramid built from this frame's early phase (pyramid.comp).

layout(std430, set = 0, binding = BINDING_VISIBILITY) buffer Visibility { uint visibility[]; };
layout(std430, set = 0, binding = BINDING_PYRAMID) readonly buffer Pyramid { float pyramid[]; };

uvec2 pyramid_size(uint k) {
    uvec2 s = uvec2(IMAGE_WIDTH, IMAGE_HEIGHT);
    for (uint j = 0u; j < k; j++) { s = (s + 1u) / 2u; }
    return s;
}

uint pyramid_offset(uint k) {
    uint o = 0u;
    uvec2 s = uvec2(IMAGE_WIDTH, IMAGE_HEIGHT);
    for (uint j = 0u; j < k; j++) { o += s.x * s.y; s = (s + 1u) / 2u; }
    return o;
}

// Whether bounding sphere s (the meshlet's, in the space of its positions) is wholly behind the
// early phase's depth. The sphere's world box is projected corner by corner: its screen rectangle
// holds the sphere's, and its nearest corner is at most as deep as the sphere's nearest point.
// The pyramid level is the finest at which the rectangle spans at most 2 x 2 texels, which then
// cover it whole. Divisions and rounding are paid for with a pixel of margin on each side and a
// relative 1e-5 of depth, always towards keeping the meshlet.
bool occluded(vec4 s) {
    if (instanced()) { s = vec4(to_world(s.xyz), s.w * instances[pc.instance].extra.x * 1.00001); }
    vec2 lo = vec2(1e30), hi = vec2(-1e30);
    float nearest = 1.0;
    for (int k = 0; k < 8; k++) {
        vec3 corner = s.xyz + s.w * vec3((k & 1) != 0 ? 1.0 : -1.0, (k & 2) != 0 ? 1.0 : -1.0, (k & 4) != 0 ? 1.0 : -1.0);
        vec4 c = pc.view_proj * vec4(corner, 1.0);
        // A corner at or behind the camera plane: the rectangle is unbounded, keep the meshlet.
        if (c.w <= 1e-6) { return false; }
        vec3 n = c.xyz / c.w;
        lo = min(lo, n.xy);
        hi = max(hi, n.xy);
        nearest = min(nearest, n.z);
    }
    vec2 image = vec2(IMAGE_WIDTH, IMAGE_HEIGHT);
    vec2 plo = (lo * 0.5 + 0.5) * image - 1.0;
    vec2 phi = (hi * 0.5 + 0.5) * image + 1.0;
    // Nothing of it on screen (the frustum test culls that before this one is asked).
    if (phi.x < 0.0 || phi.y < 0.0 || plo.x >= image.x || plo.y >= image.y) { return false; }
    ivec2 a = ivec2(max(floor(plo), vec2(0.0)));
    ivec2 b = ivec2(min(floor(phi), image - 1.0));
    uint span = uint(max(b.x - a.x, b.y - a.y)) + 1u;
    uint level = span <= 1u ? 0u : uint(findMSB(span - 1u)) + 1u;
    level = min(level, PYRAMID_LEVELS - 1u);
    uvec2 size = pyramid_size(level);
    uint base = pyramid_offset(level);
    uvec2 t0 = min(uvec2(a) >> level, size - 1u);
    uvec2 t1 = min(uvec2(b) >> level, size - 1u);
    // Tests only: the one pixel at the rectangle's centre (level 0), which no longer covers it.
    if ((pc.flags & FLAG_PYRAMID_ONE_TEXEL) != 0u) {
        size = pyramid_size(0u);
        base = 0u;
        t0 = (uvec2(a) + uvec2(b)) / 2u;
        t1 = t0;
    }
    float deepest = 0.0;
    for (uint y = t0.y; y <= t1.y; y++) {
        for (uint x = t0.x; x <= t1.x; x++) {
            deepest = max(deepest, pyramid[base + y * size.x + x]);
        }
    }
    return nearest * (1.0 - 1e-5) > deepest;
}

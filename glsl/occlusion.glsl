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
// early phase's depth. The sphere is projected exactly (Mara and McGuire, JCGT 2(2), 2013, per
// axis as niagara does): the rows of view_proj are the view's rows scaled by the projection
// (x, y) or negated (w, the distance along the view axis), so the sphere's view-space centre and
// its tangent lines give the screen rectangle, and its nearest depth is at w = w_c - r. The
// pyramid level is the finest at which the rectangle is at most 8 texels across; the texels it
// touches there cover it whole. Square roots, divisions and rounding are paid for with a pixel of
// margin on each side and a relative 1e-5 of depth, always towards keeping the meshlet.
bool occluded_in(vec4 s, mat4 view_proj) {
    if (instanced()) { s = vec4(to_world(s.xyz), s.w * instances[pc.instance].extra.x * 1.00001); }
    mat4 m = transpose(view_proj);
    vec4 c = vec4(s.xyz, 1.0);
    float p00 = length(m[0].xyz), p11 = length(m[1].xyz), pw = length(m[3].xyz);
    float cx = dot(m[0], c) / p00, cy = dot(m[1], c) / p11, cz = dot(m[3], c) / pw;
    float r = s.w;
    // Not wholly in front of the camera plane (with room for rounding): keep it.
    if (cz - r <= 1e-4 * cz + 1e-6) { return false; }
    float czr2 = cz * cz - r * r;
    float vx = sqrt(cx * cx + czr2), vy = sqrt(cy * cy + czr2);
    vec2 lo = vec2((vx * cx - r * cz) / (vx * cz + r * cx), (vy * cy - r * cz) / (vy * cz + r * cy));
    vec2 hi = vec2((vx * cx + r * cz) / (vx * cz - r * cx), (vy * cy + r * cz) / (vy * cz - r * cy));
    // The projection's scales are positive (x) and may flip y: order each axis again.
    vec2 scale = vec2(p00, p11) / pw;
    vec2 a0 = lo * scale, a1 = hi * scale;
    lo = min(a0, a1);
    hi = max(a0, a1);
    float w = dot(m[3], c) - r * pw;
    float nearest = (dot(m[2], c) - r * dot(m[2].xyz, m[3].xyz) / pw) / w;
    vec2 image = vec2(IMAGE_WIDTH, IMAGE_HEIGHT);
    vec2 plo = (lo * 0.5 + 0.5) * image - 1.0;
    vec2 phi = (hi * 0.5 + 0.5) * image + 1.0;
    // Nothing of it on screen (the frustum test culls that before this one is asked).
    if (phi.x < 0.0 || phi.y < 0.0 || plo.x >= image.x || plo.y >= image.y) { return false; }
    ivec2 a = ivec2(max(floor(plo), vec2(0.0)));
    ivec2 b = ivec2(min(floor(phi), image - 1.0));
    // The finest level at which the rectangle is at most 8 texels wide and high: it then touches
    // at most 9 x 9 texels, all read. Coarser levels (at most 2 or 4 texels across) read depth
    // further beyond the rectangle and hid measurably fewer triangles on the dense scenes.
    uint span = uint(max(b.x - a.x, b.y - a.y)) + 1u;
    uint level = span <= 8u ? 0u : uint(findMSB((span - 1u) / 8u)) + 1u;
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

bool occluded(vec4 s) { return occluded_in(s, pc.view_proj); }

// The view-projection the pyramid was built with, after its levels (LOD passes, whose early phase
// tests against the previous frame's pyramid; the host writes it).
mat4 previous_view_proj() {
    uint o = pyramid_offset(PYRAMID_LEVELS);
    mat4 m;
    for (int c = 0; c < 4; c++) {
        m[c] = vec4(pyramid[o + 4u * uint(c)], pyramid[o + 4u * uint(c) + 1u],
                    pyramid[o + 4u * uint(c) + 2u], pyramid[o + 4u * uint(c) + 3u]);
    }
    return m;
}

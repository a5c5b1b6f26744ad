#version 460
#extension GL_GOOGLE_include_directive : require
// The depth pyramid of two-phase occlusion culling, and the depth copy of the exactness check.
// Mode 0: level 0, each pixel's largest depth over its samples. Mode 1: level `level`, each texel
// the largest of the 2 x 2 texels of the level below it (at an odd edge, of those that exist), so
// texel (x, y) of level k covers pixels [x 2^k, (x + 1) 2^k) x [y 2^k, (y + 1) 2^k) of the image.
// Mode 2: every sample's depth, for the check.
#include "interface.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0) uniform sampler2DMS depth;
layout(std430, set = 0, binding = 1) buffer Pyramid { float pyramid[]; };
layout(std430, set = 0, binding = 2) buffer Samples { float samples[]; };
layout(push_constant) uniform Push { uint mode; uint level; uint sample_count; } pc;

uvec2 level_size(uint k) {
    uvec2 s = uvec2(IMAGE_WIDTH, IMAGE_HEIGHT);
    for (uint j = 0u; j < k; j++) { s = (s + 1u) / 2u; }
    return s;
}

uint level_offset(uint k) {
    uint o = 0u;
    uvec2 s = uvec2(IMAGE_WIDTH, IMAGE_HEIGHT);
    for (uint j = 0u; j < k; j++) { o += s.x * s.y; s = (s + 1u) / 2u; }
    return o;
}

void main() {
    uvec2 p = gl_GlobalInvocationID.xy;
    uvec2 size = level_size(pc.mode == 1u ? pc.level : 0u);
    if (p.x >= size.x || p.y >= size.y) { return; }
    if (pc.mode == 0u || pc.mode == 2u) {
        float most = 0.0;
        for (int s = 0; s < int(pc.sample_count); s++) {
            float d = texelFetch(depth, ivec2(p), s).r;
            most = max(most, d);
            if (pc.mode == 2u) { samples[(p.y * IMAGE_WIDTH + p.x) * pc.sample_count + uint(s)] = d; }
        }
        if (pc.mode == 0u) { pyramid[p.y * IMAGE_WIDTH + p.x] = most; }
        return;
    }
    uvec2 below = level_size(pc.level - 1u);
    uint src = level_offset(pc.level - 1u);
    float most = 0.0;
    for (uint dy = 0u; dy < 2u; dy++) {
        for (uint dx = 0u; dx < 2u; dx++) {
            uvec2 q = min(2u * p + uvec2(dx, dy), below - 1u);
            most = max(most, pyramid[src + q.y * below.x + q.x]);
        }
    }
    pyramid[level_offset(pc.level) + p.y * size.x + p.x] = most;
}

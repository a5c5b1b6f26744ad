#version 460
#extension GL_GOOGLE_include_directive : require
// The depth pyramid of two-phase occlusion culling (src/render/pass/occlusion.rs), and the depth
// copy of its exactness check. Level 0 holds each pixel's largest depth over its samples; texel i
// of level k the largest of texels 2i and 2i + 1 (per axis) of level k - 1 where they exist, so
// it covers pixels [i 2^k, (i + 1) 2^k) of the image. Depths are never negative, so a texel past
// an odd edge can count as 0.
//
// Mode 0 (one invocation per 8 x 8 pixels): levels 0 to 3 of the block; mode 1 (one workgroup):
//   levels 4 and up from level 3; mode 2: every depth sample, for the check. Two dispatches build
//   the pyramid, where one per level (or one workgroup barrier per level) cost a barrier each.
#include "interface.glsl"

layout(local_size_x = 16, local_size_y = 16) in;
layout(set = 0, binding = 0) uniform sampler2DMS depth;
layout(std430, set = 0, binding = 1) buffer Pyramid { float pyramid[]; };
layout(std430, set = 0, binding = 2) buffer Samples { float samples[]; };
layout(push_constant) uniform Push { uint mode; uint level; uint sample_count; } pc;

const uint TILE_LEVELS = 4u;

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

void put(uint k, uvec2 p, float d) {
    uvec2 size = level_size(k);
    if (p.x < size.x && p.y < size.y) { pyramid[level_offset(k) + p.y * size.x + p.x] = d; }
}

float get(uint k, uvec2 p) {
    uvec2 size = level_size(k);
    return p.x < size.x && p.y < size.y ? pyramid[level_offset(k) + p.y * size.x + p.x] : 0.0;
}

// Largest depth over a pixel's samples (0 outside the image); mode 2 also copies them.
float pixel(uvec2 p) {
    if (p.x >= IMAGE_WIDTH || p.y >= IMAGE_HEIGHT) { return 0.0; }
    float most = 0.0;
    for (int s = 0; s < int(pc.sample_count); s++) {
        float d = texelFetch(depth, ivec2(p), s).r;
        most = max(most, d);
        if (pc.mode == 2u) { samples[(p.y * IMAGE_WIDTH + p.x) * pc.sample_count + uint(s)] = d; }
    }
    return most;
}

void main() {
    uvec2 lid = gl_LocalInvocationID.xy;
    if (pc.mode == 2u) {
        uvec2 p = gl_GlobalInvocationID.xy;
        pixel(p);
        return;
    }
    if (pc.mode == 0u) {
        // Levels 0 to 3 of one 8 x 8 pixel block, in registers: no workgroup barriers, which
        // cost more than the arithmetic on a CPU driver.
        uvec2 q = gl_GlobalInvocationID.xy;
        float l1[4][4];
        for (uint y = 0u; y < 4u; y++) {
            for (uint x = 0u; x < 4u; x++) {
                float most = 0.0;
                for (uint dy = 0u; dy < 2u; dy++) {
                    for (uint dx = 0u; dx < 2u; dx++) {
                        uvec2 p = 8u * q + 2u * uvec2(x, y) + uvec2(dx, dy);
                        float d = pixel(p);
                        put(0u, p, d);
                        most = max(most, d);
                    }
                }
                l1[y][x] = most;
                put(1u, 4u * q + uvec2(x, y), most);
            }
        }
        float l3 = 0.0;
        for (uint y = 0u; y < 2u; y++) {
            for (uint x = 0u; x < 2u; x++) {
                float d = max(max(l1[2u * y][2u * x], l1[2u * y][2u * x + 1u]),
                              max(l1[2u * y + 1u][2u * x], l1[2u * y + 1u][2u * x + 1u]));
                put(2u, 2u * q + uvec2(x, y), d);
                l3 = max(l3, d);
            }
        }
        put(3u, q, l3);
        return;
    }
    // Mode 1, one workgroup: every level above the tiles', each from the one below in memory.
    uint i = lid.y * 16u + lid.x;
    for (uint k = TILE_LEVELS; k < PYRAMID_LEVELS; k++) {
        memoryBarrierBuffer();
        barrier();
        uvec2 size = level_size(k);
        for (uint t = i; t < size.x * size.y; t += 256u) {
            uvec2 p = uvec2(t % size.x, t / size.x);
            float d = max(max(get(k - 1u, 2u * p), get(k - 1u, 2u * p + uvec2(1u, 0u))),
                          max(get(k - 1u, 2u * p + uvec2(0u, 1u)), get(k - 1u, 2u * p + 1u)));
            put(k, p, d);
        }
    }
}

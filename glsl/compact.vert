#version 460
#extension GL_GOOGLE_include_directive : require
// The compact formats without a mesh shader (Mlakar et al. §5.1; src/compress/baseline.rs),
// through the vertex pipeline: one non-indexed draw of 3 x triangles vertices, each pulling its
// corner from the compressed bytes. Its meshlet is found by binary search over the first-triangle
// table (binding 3), its corner by the offset within the meshlet.
//   -DKIND=3 GI compact: a packed global index, then the quantised global vertex buffer;
//   -DKIND=0 TS compact: the corner's own offsets from the meshlet's anchor.
#include "common.glsl"
#include "compressed.glsl"

layout(location = 0) out vec3 world;

void main() {
    uint v = uint(gl_VertexIndex);
    uint t = v / 3u;
    uint lo = 0u;
    uint hi = pc.meshlet_count;
    while (hi - lo > 1u) {
        uint mid = (lo + hi) >> 1u;
        if (first_triangle[mid] <= t) { lo = mid; } else { hi = mid; }
    }
    uint c = v - 3u * first_triangle[lo];
    uint rec = 8u * offsets[lo];
    uint g = (data[0] >> 16u) & 255u;
#if KIND == 3
    uint vbits = data[0] >> 24u;
    uint at = 8u * data[1] + bits_at(rec + 8u + c * vbits, vbits) * 3u * g;
    uvec3 q = uvec3(bits_at(at, g), bits_at(at + g, g), bits_at(at + 2u * g, g));
#else
    uvec3 anchor = uvec3(bits_at(rec + 8u, g), bits_at(rec + 8u + g, g), bits_at(rec + 8u + 2u * g, g));
    uint b = bits_at(rec + 8u + 3u * g, 15u);
    uvec3 bits = uvec3(b & 31u, (b >> 5u) & 31u, b >> 10u);
    uint at = rec + 23u + 3u * g + c * (bits.x + bits.y + bits.z);
    uvec3 q = anchor + uvec3(bits_at(at, bits.x), bits_at(at + bits.x, bits.y), bits_at(at + bits.x + bits.y, bits.z));
#endif
    vec3 p = grid_position(q);
    gl_Position = pc.view_proj * vec4(p, 1.0);
    world = p;
}

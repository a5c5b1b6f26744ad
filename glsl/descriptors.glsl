// The four meshlet descriptor layouts of src/meshlet/descriptor.rs, selected by DESC at compile
// time (build.rs): 0 split, 1 NVIDIA A, 2 NVIDIA B, 3 monolithic. Each provides the same accessors
// to the task shader (culling data) and the mesh shader (counts, vertices, corners), so the two
// shaders are written once.

#ifndef DESC
#define DESC 0
#endif

#if DESC == 3
// Monolithic: one block offset per meshlet; the block holds 12 bound floats, the counts, copied
// positions and the triangles.
layout(std430, set = 0, binding = BINDING_DESCRIPTORS) readonly buffer Offsets { uint offsets[]; };
#else
// Split: vertex offset, triangle byte offset, counts. NVIDIA A and B: see descriptor.rs.
layout(std430, set = 0, binding = BINDING_DESCRIPTORS) readonly buffer Descriptors { uvec4 desc[]; };
#endif
// Split, A: global vertex indices. B: the pack buffer. Monolithic: the blocks.
layout(std430, set = 0, binding = BINDING_DATA) readonly buffer Data { uint data[]; };
#if DESC <= 1
// Local triangle corners, one byte each, four to a word.
layout(std430, set = 0, binding = BINDING_TRIANGLES) readonly buffer Triangles { uint triangles[]; };
#endif
#if DESC == 0
// Split's task descriptor: (sphere centre, radius), (cone apex, cutoff), (axis, triangle count).
layout(std430, set = 0, binding = BINDING_TASK) readonly buffer Task { vec4 task[]; };
#endif

const uint BLOCK_HEADER = 13;

// ---- mesh side ----

struct Meshlet {
    uint vertex_count;
    uint triangle_count;
    // Split, A: first vertex index in data[]; B: first pack word; monolithic: first position word.
    uint vertex_base;
    // Byte index of the first corner (in triangles[] for split and A, in data[] otherwise).
    uint corner_base;
    // B: 2 when the vertex indices are 16-bit.
    uint pack;
};

Meshlet load_meshlet(uint i) {
    Meshlet m;
    m.pack = 1u;
#if DESC == 0
    uvec4 d = desc[i];
    m.vertex_base = d.x;
    m.corner_base = d.y;
    m.vertex_count = d.z;
    m.triangle_count = d.w;
#elif DESC <= 2
    uvec4 d = desc[i];
    m.vertex_count = (d.x >> 24) + 1u;
    m.triangle_count = (d.y >> 24) + 1u;
#if DESC == 1
    m.vertex_base = d.z & 0xfffffu;
    m.corner_base = 4u * (d.w & 0xfffffu);
#else
    m.pack = d.z >> 24;
    m.vertex_base = d.w;
    uint vertex_words = m.pack == 2u ? (m.vertex_count + 1u) / 2u : m.vertex_count;
    m.corner_base = 4u * (d.w + vertex_words);
#endif
#else
    uint off = offsets[i];
    uint counts = data[off + 12u];
    m.vertex_count = counts & 0xffffu;
    m.triangle_count = counts >> 16;
    m.vertex_base = off + BLOCK_HEADER;
    m.corner_base = 4u * (m.vertex_base + 3u * m.vertex_count);
#endif
    return m;
}

vec3 meshlet_position(Meshlet m, uint k) {
#if DESC <= 1
    return position(data[m.vertex_base + k]);
#elif DESC == 2
    uint v = m.pack == 2u ? (data[m.vertex_base + k / 2u] >> (16u * (k & 1u))) & 0xffffu
                          : data[m.vertex_base + k];
    return position(v);
#else
    uint w = m.vertex_base + 3u * k;
    return uintBitsToFloat(uvec3(data[w], data[w + 1u], data[w + 2u]));
#endif
}

uint meshlet_corner(Meshlet m, uint c) {
    uint k = m.corner_base + c;
#if DESC <= 1
    uint w = triangles[k >> 2];
#else
    uint w = data[k >> 2];
#endif
    return (w >> ((k & 3u) * 8u)) & 0xffu;
}

// ---- task side ----

#include "culling.glsl"

#if DESC == 1 || DESC == 2
void decode_box(uvec4 d, out vec3 c, out vec3 h) {
    vec3 lo = pc.box_min.xyz + vec3(d.x & 0xffu, (d.x >> 8) & 0xffu, (d.x >> 16) & 0xffu) * pc.box_step.xyz;
    vec3 hi = pc.box_min.xyz + vec3(d.y & 0xffu, (d.y >> 8) & 0xffu, (d.y >> 16) & 0xffu) * pc.box_step.xyz;
    c = (lo + hi) * 0.5;
    h = (hi - lo) * 0.5;
}
#endif

uint task_triangles(uint i) {
#if DESC == 0
    return floatBitsToUint(task[3 * i + 2].w);
#elif DESC <= 2
    return (desc[i].y >> 24) + 1u;
#else
    return data[offsets[i] + 12u] >> 16;
#endif
}

#if DESC == 3
vec4 block_vec4(uint i, uint k) {
    uint w = offsets[i] + 4u * k;
    return uintBitsToFloat(uvec4(data[w], data[w + 1u], data[w + 2u], data[w + 3u]));
}
#endif

// The meshlet's bounding sphere (a quantised box's circumscribed sphere for NVIDIA A and B).
vec4 task_sphere(uint i) {
#if DESC == 0
    return task[3 * i];
#elif DESC <= 2
    vec3 c, h;
    decode_box(desc[i], c, h);
    return vec4(c, length(h) * 1.00001);
#else
    return block_vec4(i, 0u);
#endif
}

bool task_outside_frustum(uint i) {
#if DESC == 0
    return sphere_outside(task[3 * i]);
#elif DESC <= 2
    vec3 c, h;
    decode_box(desc[i], c, h);
    return box_outside(c, h);
#else
    return sphere_outside(block_vec4(i, 0u));
#endif
}

bool task_backfacing(uint i) {
#if DESC == 0
    return apex_backfacing(task[3 * i + 1], task[3 * i + 2].xyz);
#elif DESC <= 2
    uvec4 d = desc[i];
    vec3 c, h;
    decode_box(d, c, h);
#if DESC == 1
    int ox = bitfieldExtract(int(d.z), 20, 8);
    int oy = bitfieldExtract(int(d.w), 20, 8);
    uint cut = (d.z >> 28) | ((d.w >> 28) << 4);
#else
    int ox = bitfieldExtract(int(d.z), 0, 8);
    int oy = bitfieldExtract(int(d.z), 8, 8);
    uint cut = (d.z >> 16) & 0xffu;
#endif
    return box_backfacing(c, h, decode_octahedral(ox, oy), float(cut) / 255.0);
#else
    return apex_backfacing(block_vec4(i, 1u), block_vec4(i, 2u).xyz);
#endif
}

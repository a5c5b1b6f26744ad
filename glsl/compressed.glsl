// Compressed meshlets (src/compress) read straight from their encoded bytes: the format's data as
// 32-bit words (binding 2), each meshlet's record byte offset (binding 1, the file's offset table)
// and, for the formats drawn through the vertex pipeline, each meshlet's first triangle (binding
// 3, one more entry than meshlets). The grid: position = box_min + q * box_step (push constants:
// the origin and 2^e), which is exactly the CPU's dequantise when q < 2^24 (q * 2^e is exact in
// f32, so the sum is rounded once, as the CPU rounds its f64 sum once).

layout(std430, set = 0, binding = BINDING_DESCRIPTORS) readonly buffer Offsets { uint offsets[]; };
layout(std430, set = 0, binding = BINDING_DATA) readonly buffer Data { uint data[]; };
layout(std430, set = 0, binding = BINDING_TRIANGLES) readonly buffer FirstTriangle { uint first_triangle[]; };

// `n` (<= 32) bits at bit offset `at`, least significant bit first (src/compress read_bits).
uint bits_at(uint at, uint n) {
    if (n == 0u) { return 0u; }
    uint w = at >> 5u;
    uint s = at & 31u;
    uint v = data[w] >> s;
    if (s + n > 32u) { v |= data[w + 1u] << (32u - s); }
    return n == 32u ? v : v & ((1u << n) - 1u);
}

// Bits that hold the values 0..n (src/compress bits_for).
uint bits_for(uint n) { return n <= 1u ? 0u : uint(findMSB(n - 1u)) + 1u; }

vec3 grid_position(uvec3 q) { return pc.box_min.xyz + vec3(q) * pc.box_step.xyz; }

// Shared by the mesh-shader pass and the vertex-pipeline baseline (src/render).

layout(push_constant) uniform Push {
    mat4 view_proj;
    // xyz: camera position (world).
    vec4 camera;
    uint meshlet_count;
    // Bit 0: frustum culling, bit 1: normal-cone culling, bit 2: unlit (shade.frag).
    uint flags;
} pc;

layout(std430, set = 0, binding = 0) readonly buffer Positions { float positions[]; };
// Per meshlet: vertex offset, triangle offset (bytes of the local index array), vertex and triangle counts.
layout(std430, set = 0, binding = 1) readonly buffer Meshlets { uvec4 meshlets[]; };
layout(std430, set = 0, binding = 2) readonly buffer Vertices { uint vertices[]; };
// Local triangle corners, one byte each, packed four to a word.
layout(std430, set = 0, binding = 3) readonly buffer Triangles { uint triangles[]; };
// Per meshlet: (sphere centre, radius), (cone apex, cutoff), (cone axis, 0).
layout(std430, set = 0, binding = 4) readonly buffer Bounds { vec4 bounds[]; };
// 0: meshlets culled by the frustum, 1: by the normal cone, 2: meshlets drawn; 3, 4: triangles
// culled by the frustum and by the cone.
layout(std430, set = 0, binding = 5) buffer Counters { uint counters[]; };

vec3 position(uint v) { return vec3(positions[3 * v], positions[3 * v + 1], positions[3 * v + 2]); }

uint corner(uint k) { return (triangles[k >> 2] >> ((k & 3u) * 8u)) & 0xffu; }

const uint TASK_GROUP = 32;

// Shared by the mesh-shader pass and the vertex-pipeline baseline (src/render).

layout(push_constant) uniform Push {
    mat4 view_proj;
    // xyz: camera position (world).
    vec4 camera;
    // The object box quantised meshlet boxes are relative to (NVIDIA A and B): min, step per code.
    vec4 box_min;
    vec4 box_step;
    uint meshlet_count;
    // Bit 0: frustum culling, bit 1: normal-cone culling, bit 2: unlit (shade.frag), bit 3: the LOD
    // task shader records drawn meshlets (meshlet.task).
    uint flags;
} pc;

layout(std430, set = 0, binding = 0) readonly buffer Positions { float positions[]; };
// 0: meshlets culled by the frustum, 1: by the normal cone, 2: meshlets drawn; 3, 4: triangles
// culled by the frustum and by the cone; 5: LOD meshlets not on the cut; from 8: drawn-meshlet
// bits when flag bit 3 is set.
layout(std430, set = 0, binding = 5) buffer Counters { uint counters[]; };

vec3 position(uint v) { return vec3(positions[3 * v], positions[3 * v + 1], positions[3 * v + 2]); }

const uint TASK_GROUP = 32;

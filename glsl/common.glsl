// Shared by the mesh-shader pass and the vertex-pipeline baseline (src/render).

// BINDING_*, FLAG_*, COUNTER_* and TASK_GROUP, written by build.rs from src/render/interface.rs.
#include "interface.glsl"

layout(push_constant) uniform Push {
    mat4 view_proj;
    // xyz: camera position (world).
    vec4 camera;
    // The object box quantised meshlet boxes are relative to (NVIDIA A and B): min, step per code.
    vec4 box_min;
    vec4 box_step;
    uint meshlet_count;
    // FLAG_FRUSTUM, FLAG_CONE, FLAG_UNLIT (shade.frag), FLAG_RECORD_IDS (the LOD task shader).
    uint flags;
} pc;

layout(std430, set = 0, binding = BINDING_POSITIONS) readonly buffer Positions { float positions[]; };
// COUNTER_* slots; from COUNTER_WORDS, drawn-meshlet bits when FLAG_RECORD_IDS is set.
layout(std430, set = 0, binding = BINDING_COUNTERS) buffer Counters { uint counters[]; };

vec3 position(uint v) { return vec3(positions[3 * v], positions[3 * v + 1], positions[3 * v + 2]); }


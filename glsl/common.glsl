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
    // FLAG_FRUSTUM, FLAG_CONE, FLAG_UNLIT (shade.frag), FLAG_RECORD_IDS (the LOD task shader),
    // FLAG_INSTANCED.
    uint flags;
    // Instanced passes: the instance drawn, and its mesh's first meshlet.
    uint instance;
    uint meshlet_first;
} pc;

layout(std430, set = 0, binding = BINDING_POSITIONS) readonly buffer Positions { float positions[]; };
// COUNTER_* slots; from COUNTER_WORDS, drawn-meshlet bits when FLAG_RECORD_IDS is set.
layout(std430, set = 0, binding = BINDING_COUNTERS) buffer Counters { uint counters[]; };

vec3 position(uint v) { return vec3(positions[3 * v], positions[3 * v + 1], positions[3 * v + 2]); }

// Per instance: object-to-world rows, world-to-object rows, (largest stretch, first slot as
// bits, 0, 0), the mesh's bounding sphere in object space.
struct Instance { vec4 to_world[3]; vec4 to_object[3]; vec4 extra; vec4 sphere; };
layout(std430, set = 0, binding = BINDING_INSTANCES) readonly buffer Instances { Instance instances[]; };

bool instanced() { return (pc.flags & FLAG_INSTANCED) != 0u; }

// An object-space point in world space: the same expression in every pipeline, so the mesh and
// vertex pipelines place a vertex identically.
vec3 to_world(vec3 p) {
    if (!instanced()) { return p; }
    Instance s = instances[pc.instance];
    vec4 q = vec4(p, 1.0);
    return vec3(dot(s.to_world[0], q), dot(s.to_world[1], q), dot(s.to_world[2], q));
}

// The (instance, meshlet) slot of meshlet i: what occlusion culling keeps a visibility word for
// and the exactness check's id image names. Without instances, the meshlet.
uint slot_of(uint i) {
    if (!instanced()) { return i; }
    return floatBitsToUint(instances[pc.instance].extra.y) + (i - pc.meshlet_first);
}

// The camera in the space the bounds are in (the instance's object space when instanced).
vec3 eye() {
    if (!instanced()) { return pc.camera.xyz; }
    Instance s = instances[pc.instance];
    vec4 q = vec4(pc.camera.xyz, 1.0);
    return vec3(dot(s.to_object[0], q), dot(s.to_object[1], q), dot(s.to_object[2], q));
}


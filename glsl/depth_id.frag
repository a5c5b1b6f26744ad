#version 460
#extension GL_EXT_mesh_shader : require
#extension GL_GOOGLE_include_directive : require
#extension GL_ARB_gpu_shader_int64 : require
#extension GL_EXT_shader_atomic_int64 : require
// The exactness check: per sample, the least (depth bits << 32 | slot) over every fragment drawn.
// Reading gl_SampleID shades each covered sample on its own, at the sample's position, so a
// hidden triangle never wins a sample (at the pixel centre its depth would be extrapolated and
// could). A fragment shader with side effects and no early fragment tests runs for every fragment
// before the depth test, so the result does not depend on draw order; ties between coplanar
// surfaces go to the lower slot. An image with occlusion culling equals one without exactly when
// no meshlet that owns a sample was culled.
#include "common.glsl"

layout(location = 0) in vec3 world;
layout(location = 1) perprimitiveEXT flat in uint meshlet_id;
layout(location = 0) out vec4 colour;
layout(std430, set = 0, binding = BINDING_IDS) buffer Ids { uint64_t ids[]; };

void main() {
    uint p = (uint(gl_FragCoord.y) * IMAGE_WIDTH + uint(gl_FragCoord.x)) * IMAGE_SAMPLES
        + uint(gl_SampleID);
    // Depths are non-negative floats: their bits order as they do.
    atomicMin(ids[p], (uint64_t(floatBitsToUint(gl_FragCoord.z)) << 32) | uint64_t(meshlet_id));
    colour = vec4(1.0);
}

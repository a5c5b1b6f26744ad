#version 460
#extension GL_GOOGLE_include_directive : require
// Flat shading from the derivatives of the world position: the same in both pipelines, no normals
// needed. Flag bit 2 draws unlit white instead (coverage only, for exact image comparisons).
#include "common.glsl"

layout(location = 0) in vec3 world;
layout(location = 0) out vec4 colour;

void main() {
    if ((pc.flags & FLAG_UNLIT) != 0u) {
        colour = vec4(1.0);
        return;
    }
    vec3 n = normalize(cross(dFdx(world), dFdy(world)));
    float light = 0.25 + 0.75 * abs(dot(n, normalize(vec3(0.3, 0.8, 0.5))));
    colour = vec4(vec3(light), 1.0);
}

#version 460
#extension GL_GOOGLE_include_directive : require
// The classic vertex pipeline: one indexed draw of the whole mesh, same transform as the mesh shader.
#include "common.glsl"

layout(location = 0) in vec3 in_position;
layout(location = 0) out vec3 world;

void main() {
    vec3 p = to_world(in_position);
    gl_Position = pc.view_proj * vec4(p, 1.0);
    world = p;
}

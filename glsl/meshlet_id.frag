#version 460
#extension GL_EXT_mesh_shader : require
// Colour by meshlet id (the paper's Figure 1), lit like shade.frag.
layout(location = 0) in vec3 world;
layout(location = 1) perprimitiveEXT flat in uint meshlet_id;
layout(location = 0) out vec4 colour;

vec3 hue(uint id) {
    uint h = id * 2654435761u;
    return vec3(float(h & 255u), float((h >> 8) & 255u), float((h >> 16) & 255u)) / 255.0 * 0.7 + 0.3;
}

void main() {
    vec3 n = normalize(cross(dFdx(world), dFdy(world)));
    float light = 0.35 + 0.65 * abs(dot(n, normalize(vec3(0.3, 0.8, 0.5))));
    colour = vec4(hue(meshlet_id) * light, 1.0);
}

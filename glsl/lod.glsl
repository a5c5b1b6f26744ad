// Cluster-LOD selection in the task shader: the same decision, in the same exact arithmetic, as
// wgsl/select.wgsl and its CPU reference lod::flat::decide (see src/lod/select.rs: every factor
// of every product is cut to 12 significant bits, so products are exact and a fused multiply-add
// changes nothing; sums run x, y, z in the CPU's order). Included by meshlet.task with -DLOD.

// lod::flat::Record.
struct Record {
    vec4 bounds;
    vec4 parent;
    vec4 sphere;
    vec4 apex_cutoff;
    vec4 axis_error;
    float parent_error;
    uint level;
    uint triangles;
    uint pad;
};

// gpu::select::ViewData, written by the host before each frame.
struct LodView {
    vec4 eye_k;
    vec4 planes[6];
    uint finest;
    uint loaded;
    uint flags;
    uint pad;
};

layout(std430, set = 0, binding = BINDING_LOD_RECORDS) readonly buffer Records { Record records[]; };
layout(std430, set = 0, binding = BINDING_LOD_VIEW) readonly buffer Views { LodView lod_view; };

float trunc12(float x) {
    uint b = floatBitsToUint(x);
    if (((b >> 23) & 0xffu) < 87u) { return 0.0; }
    return uintBitsToFloat(b & 0xfffff000u);
}

float dot_exact(vec3 a, vec3 b) {
    return trunc12(a.x) * trunc12(b.x) + trunc12(a.y) * trunc12(b.y) + trunc12(a.z) * trunc12(b.z);
}

vec3 cut3(vec3 d) { return vec3(trunc12(d.x), trunc12(d.y), trunc12(d.z)); }

bool lod_visible(float e, vec4 s, vec3 eye, float k) {
    if (!(e > 0.0)) { return false; }
    if (floatBitsToUint(e) == 0x7f800000u) { return true; }
    vec3 d = cut3(s.xyz - eye);
    float d2 = d.x * d.x + d.y * d.y + d.z * d.z;
    float reach = trunc12(trunc12(e) * trunc12(k) + s.w);
    return reach * reach >= d2;
}

bool lod_outside_frustum(vec4 s) {
    for (int i = 0; i < 6; i++) {
        vec4 pl = lod_view.planes[i];
        float mag = abs(trunc12(pl.x) * trunc12(s.x)) + abs(trunc12(pl.y) * trunc12(s.y))
            + abs(trunc12(pl.z) * trunc12(s.z)) + abs(pl.w);
        if (dot_exact(pl.xyz, s.xyz) + pl.w + s.w + mag * (1.0 / 512.0) < 0.0) { return true; }
    }
    return false;
}

bool lod_backfacing(vec3 apex, vec3 axis, float cutoff, vec3 eye) {
    if (!(cutoff < 1.0)) { return false; }
    vec3 d = cut3(apex - eye);
    float l2 = d.x * d.x + d.y * d.y + d.z * d.z;
    if (l2 <= 0.0) { return false; }
    float a = trunc12(dot_exact(d, axis));
    float c = trunc12(cutoff);
    float rhs = trunc12(c * c) * trunc12(l2);
    float margin = rhs * (1.0 / 64.0);
    if (c >= 0.0) { return a > 0.0 && a * a >= rhs + margin; }
    return a >= 0.0 || a * a <= rhs - margin;
}

const uint LOD_DRAWN = 0u;
const uint LOD_NOT_SELECTED = 1u;
const uint LOD_FRUSTUM = 2u;
const uint LOD_CONE = 3u;

// lod::flat::decide for loaded meshlet i.
uint lod_decide(uint i) {
    Record r = records[i];
    vec3 eye = lod_view.eye_k.xyz;
    float k = lod_view.eye_k.w;
    bool own_hidden = r.level == lod_view.finest || !lod_visible(r.axis_error.w, r.bounds, eye, k);
    if (r.level < lod_view.finest || !own_hidden || !lod_visible(r.parent_error, r.parent, eye, k)) {
        return LOD_NOT_SELECTED;
    }
    if ((lod_view.flags & 1u) != 0u && lod_outside_frustum(r.sphere)) { return LOD_FRUSTUM; }
    if ((lod_view.flags & 2u) != 0u && lod_backfacing(r.apex_cutoff.xyz, r.axis_error.xyz, r.apex_cutoff.w, eye)) {
        return LOD_CONE;
    }
    return LOD_DRAWN;
}

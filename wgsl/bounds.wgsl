// Meshlet bounding spheres, one thread per meshlet; the CPU mirror is gpu::bounds::sphere_f32.
//
// Precision: positions far from the origin (a scan placed at 1e6) leave f32 few bits for the
// meshlet's extent, so every difference is taken relative to the meshlet's first vertex p0, where
// subtraction of nearby floats is exact (Sterbenz). The centre is p0 plus the local box centre,
// rounded once to f32; the radius is then measured from that rounded centre, again through p0, and
// padded by a relative 2^-16: WGSL lets sqrt be as loose as 1/inverseSqrt (lavapipe was seen ~18 ulps
// from the CPU), and the padding must cover that so every vertex is inside.

struct Params { n: u32 }
struct Meshlet { vertex_offset: u32, triangle_offset: u32, vertex_count: u32, triangle_count: u32 }

@group(0) @binding(0) var<uniform> p: Params;
@group(0) @binding(1) var<storage, read> positions: array<f32>;
@group(0) @binding(2) var<storage, read> meshlets: array<Meshlet>;
@group(0) @binding(3) var<storage, read> vertices: array<u32>;
@group(0) @binding(4) var<storage, read_write> spheres: array<vec4<f32>>;

fn pos(v: u32) -> vec3<f32> { return vec3<f32>(positions[3u * v], positions[3u * v + 1u], positions[3u * v + 2u]); }

@compute @workgroup_size(64)
fn sphere(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = flat(gid);
    if (i >= p.n) { return; }
    let m = meshlets[i];
    let p0 = pos(vertices[m.vertex_offset]);
    var lo = vec3<f32>(0.0);
    var hi = vec3<f32>(0.0);
    for (var k = 0u; k < m.vertex_count; k++) {
        let d = pos(vertices[m.vertex_offset + k]) - p0;
        lo = min(lo, d);
        hi = max(hi, d);
    }
    let c = p0 + (lo + hi) * 0.5;
    let cl = c - p0;
    var r2 = 0.0;
    for (var k = 0u; k < m.vertex_count; k++) {
        let d = (pos(vertices[m.vertex_offset + k]) - p0) - cl;
        r2 = max(r2, dot(d, d));
    }
    // Shader compilers may fold (p0 + h) - p0 back into h (NIR does inexact algebra unless told
    // otherwise, and WGSL cannot tell it), which measures from the unrounded centre: one ulp of
    // the centre's largest coordinate covers its rounding.
    let ac = abs(c);
    spheres[i] = vec4<f32>(c, sqrt(r2) * (1.0 + 1.0 / 65536.0) + max(ac.x, max(ac.y, ac.z)) / 4194304.0);
}

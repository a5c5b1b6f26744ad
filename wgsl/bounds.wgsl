// Meshlet bounds, one thread per meshlet:
//   sphere        bounding spheres; the CPU mirror is gpu::bounds::sphere_f32
//   task_bounds   sphere, normal cone and triangle count in the mesh-shader pass's split task layout
//                 (meshlet::descriptor, three vec4 per meshlet), for meshlets built on the device
//
// Precision: positions far from the origin (a scan placed at 1e6) leave f32 few bits for the
// meshlet's extent, so every difference is taken relative to the meshlet's first vertex p0, where
// subtraction of nearby floats is exact (Sterbenz). The centre is p0 plus the local box centre,
// rounded once to f32; the radius is then measured from that rounded centre, again through p0, and
// padded by a relative 2^-16: WGSL lets sqrt be as loose as 1/inverseSqrt (lavapipe was seen ~18 ulps
// from the CPU), and the padding must cover that so every vertex is inside.
//
// The cone is the mean of the unit normals, widened by a margin that covers f32 normals and the
// loose inverseSqrt, its apex pushed behind every triangle plane with room for the same errors; a
// meshlet with a sliver (edges meeting at a sine under 1e-3, whose f32 normal is unreliable) or
// normals over a half-space gets the cone that never culls. No CPU twin computes it bit for bit:
// gpu::bounds checks it conservative in f64 (no culled meshlet has a front-facing triangle).

struct Params { n: u32 }
struct Meshlet { vertex_offset: u32, triangle_offset: u32, vertex_count: u32, triangle_count: u32 }

@group(0) @binding(0) var<uniform> p: Params;
@group(0) @binding(1) var<storage, read> positions: array<f32>;
@group(0) @binding(2) var<storage, read> meshlets: array<Meshlet>;
@group(0) @binding(3) var<storage, read> vertices: array<u32>;
@group(0) @binding(4) var<storage, read_write> spheres: array<vec4<f32>>;
// Local corners, bytes four to a word (the meshlets' triangles).
@group(0) @binding(5) var<storage, read> triangles: array<u32>;
// Out: (centre, radius), (apex, cutoff), (axis, triangle count as bits) per meshlet.
@group(0) @binding(6) var<storage, read_write> task: array<vec4<f32>>;

fn pos(v: u32) -> vec3<f32> { return vec3<f32>(positions[3u * v], positions[3u * v + 1u], positions[3u * v + 2u]); }

// Global vertex of corner k of meshlet m.
fn corner(m: Meshlet, k: u32) -> u32 {
    let b = m.triangle_offset + k;
    return vertices[m.vertex_offset + ((triangles[b / 4u] >> (8u * (b % 4u))) & 0xffu)];
}

// Angular margin of the cone (on the cosine and on the cutoff): f32 normals of non-slivers are
// within about 1e-4 of the true direction, inverseSqrt within a few ulps.
const MARGIN: f32 = 1e-3;
// sin^2 of the angle between a triangle's edges below which its f32 normal is not trusted.
const SLIVER: f32 = 1e-6;

// Unit normal of triangle j of m in xyz; w: 1 usable, 0 degenerate (coincident corners: no
// fragments, ignored), 2 unreliable (a sliver, or out of f32 range).
fn unit_normal(m: Meshlet, j: u32) -> vec4<f32> {
    let a = pos(corner(m, 3u * j));
    let b = pos(corner(m, 3u * j + 1u));
    let c = pos(corner(m, 3u * j + 2u));
    if (all(a == b) || all(b == c) || all(a == c)) { return vec4<f32>(0.0); }
    let e1 = b - a;
    let e2 = c - a;
    let n = cross(e1, e2);
    let l2 = dot(n, n);
    let e = dot(e1, e1) * dot(e2, e2);
    if (!(l2 > SLIVER * e) || !(e < 1e38)) { return vec4<f32>(0.0, 0.0, 0.0, 2.0); }
    return vec4<f32>(n * inverseSqrt(l2), 1.0);
}

fn sphere_of(m: Meshlet) -> vec4<f32> {
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
    return vec4<f32>(c, sqrt(r2) * (1.0 + 1.0 / 65536.0) + max(ac.x, max(ac.y, ac.z)) / 4194304.0);
}

@compute @workgroup_size(64)
fn sphere(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = flat(gid);
    if (i >= p.n) { return; }
    spheres[i] = sphere_of(meshlets[i]);
}

@compute @workgroup_size(64)
fn task_bounds(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = flat(gid);
    if (i >= p.n) { return; }
    let m = meshlets[i];
    let s = sphere_of(m);
    var sum = vec3<f32>(0.0);
    var usable = true;
    for (var j = 0u; j < m.triangle_count; j++) {
        let u = unit_normal(m, j);
        if (u.w == 2.0) { usable = false; }
        if (u.w == 1.0) { sum += u.xyz; }
    }
    var apex = vec3<f32>(0.0);
    var axis = vec3<f32>(0.0, 0.0, 1.0);
    var cutoff = 1.0;
    let s2 = dot(sum, sum);
    if (usable && s2 > 1e-6) {
        let ax = sum * inverseSqrt(s2);
        var low = 1.0;
        for (var j = 0u; j < m.triangle_count; j++) {
            let u = unit_normal(m, j);
            if (u.w == 1.0) { low = min(low, dot(u.xyz, ax)); }
        }
        low -= MARGIN;
        let cut = sqrt(max(1.0 - low * low, 0.0)) + MARGIN;
        if (low > 0.01 && cut < 1.0) {
            // Behind plane j: t >= dot(c - a_j, n_j) / dot(axis, n_j), measured from p0.
            let p0 = pos(vertices[m.vertex_offset]);
            let cl = s.xyz - p0;
            var t = 0.0;
            for (var j = 0u; j < m.triangle_count; j++) {
                let u = unit_normal(m, j);
                if (u.w == 1.0) {
                    let a = pos(corner(m, 3u * j)) - p0;
                    t = max(t, dot(cl - a, u.xyz) / dot(ax, u.xyz));
                }
            }
            // Room for the normals' errors (up to the margin times the meshlet's size, over a
            // dot product of at least 0.01) and for rounding the apex itself.
            let ac = abs(s.xyz);
            t += 0.2 * s.w + 1e-5 * (t + max(ac.x, max(ac.y, ac.z)));
            apex = s.xyz - ax * t;
            axis = ax;
            cutoff = cut;
        }
    }
    task[3u * i] = s;
    task[3u * i + 1u] = vec4<f32>(apex, cutoff);
    task[3u * i + 2u] = vec4<f32>(axis, bitcast<f32>(m.triangle_count));
}

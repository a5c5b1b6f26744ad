// LOD selection of a meshlet DAG for a batch of views, with frustum and normal-cone culling, and a
// deterministic compaction of the drawn meshlets. One thread per (view, meshlet).
//
// Kernel map (CPU mirror in src/lod/flat.rs and src/lod/select.rs):
//   decide   -> flat::decide: select::should_render_streamed (visible), outside_frustum, backfacing;
//               writes 1/0 to flags[] and offsets[]
//   (scan)   -> exclusive prefix sum of offsets[] (scan.wgsl), one scan over all views
//   compact  -> flat::select_meshlets: ids[offsets[i]] = i for every drawn (view, meshlet), so each view's
//               drawn meshlets come out in ascending order after the previous view's
//
// Exactness: every factor of every product is cut to 12 significant bits (trunc12), so products
// are exact and an FMA the compiler may form changes nothing; sums run x, y, z in the order the
// CPU writes them; infinity is tested through its bits. See src/lod/select.rs.

struct Params { n: u32, per_view: u32 }

// Mirrors lod::flat::Record.
struct Record {
    bounds: vec4<f32>,
    parent: vec4<f32>,
    sphere: vec4<f32>,
    apex_cutoff: vec4<f32>,
    axis_error: vec4<f32>,
    parent_error: f32,
    level: u32,
    triangles: u32,
    pad: u32,
}

// Mirrors gpu::select::ViewData.
struct View {
    // Camera position, and k = pixels per unit error at unit distance over the threshold.
    eye_k: vec4<f32>,
    planes: array<vec4<f32>, 6>,
    // Finest loaded level; meshlets loaded (a prefix); bit 0 frustum culling, bit 1 cone culling.
    finest: u32,
    loaded: u32,
    flags: u32,
    pad: u32,
}

@group(0) @binding(0) var<uniform> p: Params;
@group(0) @binding(1) var<storage, read> records: array<Record>;
@group(0) @binding(2) var<storage, read> views: array<View>;
@group(0) @binding(3) var<storage, read_write> flags: array<u32>;
@group(0) @binding(4) var<storage, read_write> offsets: array<u32>;
@group(0) @binding(5) var<storage, read_write> ids: array<u32>;

fn trunc12(x: f32) -> f32 {
    let b = bitcast<u32>(x);
    if (((b >> 23u) & 0xffu) < 87u) { return 0.0; }
    return bitcast<f32>(b & 0xfffff000u);
}

fn dot_exact(a: vec3<f32>, b: vec3<f32>) -> f32 {
    return trunc12(a.x) * trunc12(b.x) + trunc12(a.y) * trunc12(b.y) + trunc12(a.z) * trunc12(b.z);
}

fn cut3(d: vec3<f32>) -> vec3<f32> { return vec3<f32>(trunc12(d.x), trunc12(d.y), trunc12(d.z)); }

fn visible(e: f32, s: vec4<f32>, eye: vec3<f32>, k: f32) -> bool {
    if (!(e > 0.0)) { return false; }
    if (bitcast<u32>(e) == 0x7f800000u) { return true; }
    let d = cut3(s.xyz - eye);
    let d2 = d.x * d.x + d.y * d.y + d.z * d.z;
    let reach = trunc12(trunc12(e) * trunc12(k) + s.w);
    return reach * reach >= d2;
}

fn outside_frustum(s: vec4<f32>, v: View) -> bool {
    for (var i = 0u; i < 6u; i++) {
        let pl = v.planes[i];
        let mag = abs(trunc12(pl.x) * trunc12(s.x)) + abs(trunc12(pl.y) * trunc12(s.y))
            + abs(trunc12(pl.z) * trunc12(s.z)) + abs(pl.w);
        if (dot_exact(pl.xyz, s.xyz) + pl.w + s.w + mag * (1.0 / 512.0) < 0.0) { return true; }
    }
    return false;
}

fn backfacing(apex: vec3<f32>, axis: vec3<f32>, cutoff: f32, eye: vec3<f32>) -> bool {
    if (!(cutoff < 1.0)) { return false; }
    let d = cut3(apex - eye);
    let l2 = d.x * d.x + d.y * d.y + d.z * d.z;
    if (l2 <= 0.0) { return false; }
    let a = trunc12(dot_exact(d, axis));
    let c = trunc12(cutoff);
    let rhs = trunc12(c * c) * trunc12(l2);
    let margin = rhs * (1.0 / 64.0);
    if (c >= 0.0) { return a > 0.0 && a * a >= rhs + margin; }
    return a >= 0.0 || a * a <= rhs - margin;
}

@compute @workgroup_size(64)
fn decide(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = flat(gid);
    if (i >= p.n) { return; }
    let v = views[i / p.per_view];
    let m = i % p.per_view;
    var draw = m < v.loaded;
    if (draw) {
        let r = records[m];
        let eye = v.eye_k.xyz;
        let own_hidden = r.level == v.finest || !visible(r.axis_error.w, r.bounds, eye, v.eye_k.w);
        draw = r.level >= v.finest && own_hidden && visible(r.parent_error, r.parent, eye, v.eye_k.w);
        if (draw && (v.flags & 1u) != 0u) { draw = !outside_frustum(r.sphere, v); }
        if (draw && (v.flags & 2u) != 0u) {
            draw = !backfacing(r.apex_cutoff.xyz, r.axis_error.xyz, r.apex_cutoff.w, eye);
        }
    }
    flags[i] = select(0u, 1u, draw);
    offsets[i] = select(0u, 1u, draw);
}

@compute @workgroup_size(64)
fn compact(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = flat(gid);
    if (i >= p.n) { return; }
    if (flags[i] != 0u) { ids[offsets[i]] = i; }
}

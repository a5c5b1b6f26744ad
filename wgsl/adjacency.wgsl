// Adjacency on the GPU, mirroring src/adjacency (CPU reference):
//   vt_count -> scan -> vt_scatter -> vt_sort   vertex -> triangles CSR, rows ascending
//   dual_count -> scan -> dual_fill             triangle dual graph CSR, rows ascending, no
//                                               duplicates; per-side edge flags (dual_fill copies
//                                               the rows dual_count gathered)
// Large arrays are split in two bindings of at most 2^25 u32 (lavapipe's 128 MiB binding limit).

struct Params { n: u32, t: u32 }

@group(0) @binding(0) var<uniform> p: Params;
@group(0) @binding(1) var<storage, read> idx_a: array<u32>;
@group(0) @binding(2) var<storage, read> idx_b: array<u32>;
@group(0) @binding(3) var<storage, read_write> vt_off: array<atomic<u32>>;
@group(0) @binding(4) var<storage, read_write> vt_a: array<u32>;
@group(0) @binding(5) var<storage, read_write> vt_b: array<u32>;
@group(0) @binding(6) var<storage, read_write> cursor: array<atomic<u32>>;
@group(0) @binding(7) var<storage, read_write> dual_off: array<u32>;
@group(0) @binding(8) var<storage, read_write> dual_a: array<u32>;
@group(0) @binding(9) var<storage, read_write> dual_b: array<u32>;
@group(0) @binding(10) var<storage, read_write> side_flags: array<u32>;
@group(0) @binding(11) var<storage, read_write> degenerate: array<u32>;
// Three words per triangle: dual_count's sorted neighbours (NONE-padded) for dual_fill to copy, or
// COMPLEX first when the triangle has a non-manifold side.
@group(0) @binding(12) var<storage, read_write> near_a: array<u32>;
@group(0) @binding(13) var<storage, read_write> near_b: array<u32>;

fn idx(i: u32) -> u32 { if (i < PART) { return idx_a[i]; } return idx_b[i - PART]; }
fn vt(i: u32) -> u32 { if (i < PART) { return vt_a[i]; } return vt_b[i - PART]; }
fn set_vt(i: u32, v: u32) { if (i < PART) { vt_a[i] = v; } else { vt_b[i - PART] = v; } }
fn set_dual(i: u32, v: u32) { if (i < PART) { dual_a[i] = v; } else { dual_b[i - PART] = v; } }
fn near(i: u32) -> u32 { if (i < PART) { return near_a[i]; } return near_b[i - PART]; }
fn set_near(i: u32, v: u32) { if (i < PART) { near_a[i] = v; } else { near_b[i - PART] = v; } }
const COMPLEX: u32 = 0xfffffffeu;

fn tri(t: u32) -> vec3<u32> { return vec3<u32>(idx(3u * t), idx(3u * t + 1u), idx(3u * t + 2u)); }

// The triangle's distinct vertices in corner order (a repeated vertex counts once), as the CPU's
// vertex_triangles lists them.
fn distinct(v: vec3<u32>) -> vec3<bool> { return vec3<bool>(true, v.y != v.x, v.z != v.x && v.z != v.y); }

@compute @workgroup_size(64)
fn vt_count(@builtin(global_invocation_id) gid: vec3<u32>) {
    let t = flat(gid);
    if (t >= p.t) { return; }
    let v = tri(t);
    let d = distinct(v);
    for (var i = 0u; i < 3u; i++) {
        if (d[i]) { atomicAdd(&vt_off[v[i]], 1u); }
    }
    degenerate[t] = u32(!all(d));
}

// Any slot order (atomics); vt_sort makes rows ascending.
@compute @workgroup_size(64)
fn vt_scatter(@builtin(global_invocation_id) gid: vec3<u32>) {
    let t = flat(gid);
    if (t >= p.t) { return; }
    let v = tri(t);
    let d = distinct(v);
    for (var i = 0u; i < 3u; i++) {
        if (d[i]) {
            let at = atomicLoad(&vt_off[v[i]]) + atomicAdd(&cursor[v[i]], 1u);
            set_vt(at, t);
        }
    }
}

// Insertion sort per row: rows are a few triangles (valence), so this is linear in practice.
@compute @workgroup_size(64)
fn vt_sort(@builtin(global_invocation_id) gid: vec3<u32>) {
    let v = flat(gid);
    if (v >= p.n) { return; }
    let lo = atomicLoad(&vt_off[v]);
    let hi = atomicLoad(&vt_off[v + 1u]);
    for (var i = lo + 1u; i < hi; i++) {
        let x = vt(i);
        var j = i;
        while (j > lo && vt(j - 1u) > x) {
            set_vt(j, vt(j - 1u));
            j--;
        }
        set_vt(j, x);
    }
}

fn contains(u: u32, b: u32) -> bool {
    let w = tri(u);
    return w.x == b || w.y == b || w.z == b;
}

// The smallest edge neighbour of t (a triangle u != t with both vertices of a non-collapsed side
// of t: any two distinct vertices of u form one of its sides) that is >= lo; NONE if none. Rows
// come out sorted and without duplicates by calling this with lo = previous + 1.
fn next_neighbour(t: u32, v: vec3<u32>, lo: u32) -> u32 {
    var best = NONE;
    for (var i = 0u; i < 3u; i++) {
        let a = v[i];
        let b = v[(i + 1u) % 3u];
        if (a == b) { continue; }
        let hi = atomicLoad(&vt_off[a + 1u]);
        for (var k = atomicLoad(&vt_off[a]); k < hi; k++) {
            let u = vt(k);
            if (u != t && u >= lo && u < best && contains(u, b)) { best = u; }
        }
    }
    return best;
}

// Neighbours of t gathered in one pass without private arrays (llvmpipe runs invocations in SIMD
// lanes, where dynamically indexed private arrays are slow): for each non-collapsed side {a, b},
// the triangles on both vertex rows (a sorted merge of two short rows). A manifold side has at most
// one other triangle; a side with more is `complex` and t falls back to next_neighbour. Also the
// side flags: bit i boundary (valence 1), bit 3 + i non-manifold (valence > 2), bit 6 + i
// collapsed.
struct Gathered { nb: vec3<u32>, complex: bool, flags: u32 }

fn gather(t: u32, v: vec3<u32>) -> Gathered {
    var g: Gathered;
    g.nb = vec3<u32>(NONE);
    g.complex = false;
    g.flags = 0u;
    for (var s = 0u; s < 3u; s++) {
        let a = v[s];
        let b = v[(s + 1u) % 3u];
        if (a == b) { g.flags |= 1u << (6u + s); continue; }
        var i = atomicLoad(&vt_off[a]);
        let ie = atomicLoad(&vt_off[a + 1u]);
        var j = atomicLoad(&vt_off[b]);
        let je = atomicLoad(&vt_off[b + 1u]);
        var valence = 0u;
        var other = NONE;
        while (i < ie && j < je) {
            let x = vt(i);
            let y = vt(j);
            if (x <= y) { i++; }
            if (y <= x) { j++; }
            if (x != y) { continue; }
            // A triangle on both rows has one side on {a, b}, or two if it repeats a vertex.
            valence += 1u + degenerate[x];
            if (x != t) {
                if (other != NONE) { g.complex = true; }
                other = x;
            }
        }
        g.nb[s] = other;
        if (valence == 1u) { g.flags |= 1u << s; }
        if (valence > 2u) { g.flags |= 1u << (3u + s); }
    }
    // Sort the three (NONE last) and drop repeats (two triangles can share two sides).
    var n = g.nb;
    if (n.x > n.y) { n = n.yxz; }
    if (n.y > n.z) { n = n.xzy; }
    if (n.x > n.y) { n = n.yxz; }
    if (n.z == n.y) { n.z = NONE; }
    if (n.y == n.x) { n.y = n.z; n.z = NONE; }
    g.nb = n;
    return g;
}

fn gathered_count(g: Gathered) -> u32 {
    return u32(g.nb.x != NONE) + u32(g.nb.y != NONE) + u32(g.nb.z != NONE);
}

@compute @workgroup_size(64)
fn dual_count(@builtin(global_invocation_id) gid: vec3<u32>) {
    let t = flat(gid);
    if (t >= p.t) { return; }
    let v = tri(t);
    let g = gather(t, v);
    var count = gathered_count(g);
    // Kept for dual_fill, which then copies instead of gathering again.
    set_near(3u * t, select(g.nb.x, COMPLEX, g.complex));
    set_near(3u * t + 1u, g.nb.y);
    set_near(3u * t + 2u, g.nb.z);
    if (g.complex) {
        count = 0u;
        var u = next_neighbour(t, v, 0u);
        while (u != NONE) {
            count++;
            u = next_neighbour(t, v, u + 1u);
        }
    }
    dual_off[t] = count;
    side_flags[t] = g.flags;
}

@compute @workgroup_size(64)
fn dual_fill(@builtin(global_invocation_id) gid: vec3<u32>) {
    let t = flat(gid);
    if (t >= p.t) { return; }
    var at = dual_off[t];
    if (near(3u * t) != COMPLEX) {
        let c = dual_off[t + 1u] - at;
        for (var k = 0u; k < c; k++) { set_dual(at + k, near(3u * t + k)); }
        return;
    }
    let v = tri(t);
    var u = next_neighbour(t, v, 0u);
    while (u != NONE) {
        set_dual(at, u);
        at++;
        u = next_neighbour(t, v, u + 1u);
    }
}

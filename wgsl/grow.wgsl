// The parallel bounding-sphere grower, mirroring src/strategy/parallel.rs step by step:
//   init                                          every triangle unclaimed
//   label_init, label_round x n                   unclaimed components (min id), waves after the first
//   clear_cells, cell_dist, cell_pick             the unclaimed triangle nearest each grid cell's centre
//   seed_flags, scan, place                       seeds in ascending triangle order become meshlets
//   (propose, claim) x rounds                     growth: score the border, claim by atomicMin
//
// propose runs one workgroup per meshlet: thread 0 accepts last round's proposal if its claim won,
// then its PW threads score the border candidates in parallel (vertices inside + island bonus, ties
// to the smaller exact squared radius, then the lower triangle id) and reduce to the best. claim
// lets every proposal atomicMin its meshlet id into the triangle's owner, so the lowest id wins
// whatever the order of the threads. All arithmetic is on u32: the result is the same on every GPU.

struct Params { t: u32, n: u32, base: u32, slot: u32, max_v: u32, max_t: u32, cell: u32, grid: u32 }

@group(0) @binding(0) var<uniform> p: Params;
@group(0) @binding(1) var<storage, read> dual_off: array<u32>;
@group(0) @binding(2) var<storage, read> dual_a: array<u32>;
@group(0) @binding(3) var<storage, read> dual_b: array<u32>;
@group(0) @binding(4) var<storage, read> idx_a: array<u32>;
@group(0) @binding(5) var<storage, read> idx_b: array<u32>;
// Quantised positions, three per vertex (15 bits each).
@group(0) @binding(6) var<storage, read> q: array<u32>;
// Owner (meshlet id) per triangle, NONE while unclaimed.
@group(0) @binding(7) var<storage, read_write> claim: array<atomic<u32>>;
// Position of each triangle in its meshlet.
@group(0) @binding(8) var<storage, read_write> order: array<u32>;
@group(0) @binding(9) var<storage, read_write> label: array<atomic<u32>>;
// [0, G) best squared distance per cell, [G, 2G) the triangle that has it (lowest id on ties).
@group(0) @binding(10) var<storage, read_write> cells: array<atomic<u32>>;
@group(0) @binding(11) var<storage, read_write> flags: array<u32>;
// Per meshlet of the wave: 0 triangles, 1 vertices, 2 squared radius, 3 centre vertex,
// 4 proposal, 5 open.
@group(0) @binding(12) var<storage, read_write> state: array<u32>;
@group(0) @binding(13) var<storage, read_write> mt: array<u32>;
@group(0) @binding(14) var<storage, read_write> mv: array<u32>;
// 0..8 proposals per growth round, 8..16 label changes per component round.
@group(0) @binding(15) var<storage, read_write> counters: array<atomic<u32>>;

// Marks a meshlet triangle (in mt) whose neighbours are all claimed. Triangle ids stay below 2^25.
const INTERIOR: u32 = 0x80000000u;

fn nb(i: u32) -> u32 { if (i < PART) { return dual_a[i]; } return dual_b[i - PART]; }
fn idx(i: u32) -> u32 { if (i < PART) { return idx_a[i]; } return idx_b[i - PART]; }
fn tri(t: u32) -> vec3<u32> { return vec3<u32>(idx(3u * t), idx(3u * t + 1u), idx(3u * t + 2u)); }
fn unclaimed(t: u32) -> bool { return atomicLoad(&claim[t]) == NONE; }
// Corner k of v repeats an earlier corner (a degenerate triangle): the CPU's `distinct` skips it.
fn repeats(v: vec3<u32>, k: u32) -> bool { return (k >= 1u && v[k] == v.x) || (k == 2u && v[k] == v.y); }

// Exact squared distance of two quantised vertices (at most 3 * 32767^2 < 2^32).
fn d2(a: u32, b: u32) -> u32 {
    var s = 0u;
    for (var k = 0u; k < 3u; k++) {
        let x = q[3u * a + k];
        let y = q[3u * b + k];
        let d = select(y - x, x - y, x >= y);
        s += d * d;
    }
    return s;
}

// Grid cell of triangle t and the squared distance (in thirds) from its centroid to the cell centre.
fn cell_of(t: u32) -> vec2<u32> {
    let v = tri(t);
    let s3 = 3u * p.cell;
    var cell = 0u;
    var dist = 0u;
    for (var k = 0u; k < 3u; k++) {
        let c3 = q[3u * v.x + k] + q[3u * v.y + k] + q[3u * v.z + k];
        let i = c3 / s3;
        let centre = i * s3 + s3 / 2u;
        let d = select(centre - c3, c3 - centre, c3 >= centre);
        dist += d * d;
        cell = cell * p.grid + i;
    }
    return vec2<u32>(cell, dist);
}

fn cell_count() -> u32 { return p.grid * p.grid * p.grid; }

@compute @workgroup_size(64)
fn init(@builtin(global_invocation_id) gid: vec3<u32>) {
    let t = flat(gid);
    if (t < p.t) { atomicStore(&claim[t], NONE); }
}

@compute @workgroup_size(64)
fn clear_counters(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = flat(gid);
    if (i < arrayLength(&counters)) { atomicStore(&counters[i], 0u); }
}

@compute @workgroup_size(64)
fn label_init(@builtin(global_invocation_id) gid: vec3<u32>) {
    let t = flat(gid);
    if (t < p.t) { atomicStore(&label[t], select(NONE, t, unclaimed(t))); }
}

// Connected components by min-label hooking and pointer jumping (Shiloach-Vishkin style): a
// triangle takes the smallest label among its unclaimed neighbours and hooks a neighbour's larger
// label onto its own (atomicMin on that label's entry), then follows the chain of labels to its
// end. Labels only fall and always name a triangle of the same component, so the fixed point (a
// round with no change) is the component minimum whatever the order of the threads.
@compute @workgroup_size(64)
fn label_round(@builtin(global_invocation_id) gid: vec3<u32>) {
    let t = flat(gid);
    if (t >= p.t || !unclaimed(t)) { return; }
    var m = atomicLoad(&label[t]);
    var changed = 0u;
    for (var i = dual_off[t]; i < dual_off[t + 1u]; i++) {
        let n = nb(i);
        if (!unclaimed(n)) { continue; }
        let l = atomicLoad(&label[n]);
        if (l < m) {
            m = l;
        } else if (m < l && m < atomicMin(&label[l], m)) {
            changed = 1u;
        }
    }
    loop {
        let l = atomicLoad(&label[m]);
        if (l >= m) { break; }
        m = l;
    }
    if (m < atomicMin(&label[t], m)) { changed = 1u; }
    if (changed != 0u) { atomicAdd(&counters[p.slot], 1u); }
}

@compute @workgroup_size(64)
fn clear_cells(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = flat(gid);
    if (i < 2u * cell_count()) { atomicStore(&cells[i], NONE); }
}

@compute @workgroup_size(64)
fn cell_dist(@builtin(global_invocation_id) gid: vec3<u32>) {
    let t = flat(gid);
    if (t >= p.t || !unclaimed(t)) { return; }
    let c = cell_of(t);
    atomicMin(&cells[c.x], c.y);
}

@compute @workgroup_size(64)
fn cell_pick(@builtin(global_invocation_id) gid: vec3<u32>) {
    let t = flat(gid);
    if (t >= p.t || !unclaimed(t)) { return; }
    let c = cell_of(t);
    if (atomicLoad(&cells[c.x]) == c.y) { atomicMin(&cells[cell_count() + c.x], t); }
}

// flags[t] = 1 for a seed (p.slot = 1: component minima too), flags[T] = 0; then scanned.
@compute @workgroup_size(64)
fn seed_flags(@builtin(global_invocation_id) gid: vec3<u32>) {
    let t = flat(gid);
    if (t > p.t) { return; }
    var seed = false;
    if (t < p.t && unclaimed(t)) {
        seed = atomicLoad(&cells[cell_count() + cell_of(t).x]) == t
            || (p.slot == 1u && atomicLoad(&label[t]) == t);
    }
    flags[t] = select(0u, 1u, seed);
}

@compute @workgroup_size(64)
fn place(@builtin(global_invocation_id) gid: vec3<u32>) {
    let t = flat(gid);
    if (t >= p.t || flags[t + 1u] == flags[t]) { return; }
    let j = flags[t];
    atomicStore(&claim[t], p.base + j);
    order[t] = 0u;
    let v = tri(t);
    mt[j * p.max_t] = t;
    var nv = 0u;
    var r2 = 0u;
    for (var k = 0u; k < 3u; k++) {
        let x = v[k];
        if (repeats(v, k)) { continue; }
        mv[j * p.max_v + nv] = x;
        nv++;
        r2 = max(r2, d2(v.x, x));
    }
    let s = 8u * j;
    state[s] = 1u;
    state[s + 1u] = nv;
    state[s + 2u] = r2;
    state[s + 3u] = v.x;
    state[s + 4u] = NONE;
    state[s + 5u] = 1u;
}

var<workgroup> s_open: u32;
var<workgroup> s_nt: u32;
var<workgroup> s_nv: u32;
var<workgroup> s_r2: u32;
var<workgroup> s_centre: u32;
var<workgroup> s_prop: u32;
var<workgroup> s_verts: array<u32, 256>;
var<workgroup> s_bloom: array<atomic<u32>, 64>;
// Threads per meshlet in propose. A meshlet's border is a few dozen candidates, and lavapipe pays
// for every barrier per 8-lane group: on the dragon 64 threads took 6.0 s of propose, 16 took 4.3 s
// and 8 (lavapipe's SIMD width) 3.6 s. A 32-wide GPU would want one warp per meshlet instead.
const PW: u32 = 8u;
var<workgroup> r_score: array<u32, PW>;
var<workgroup> r_r2: array<u32, PW>;
var<workgroup> r_t: array<u32, PW>;

fn better(s: u32, r: u32, t: u32, bs: u32, br: u32, bt: u32) -> bool {
    return s > bs || (s == bs && (r < br || (r == br && t < bt)));
}

// A 2048-bit filter of the meshlet's vertices: most border candidates' third vertex is outside,
// and the filter says so without the linear search.
fn bloom_bit(v: u32) -> u32 { return (v * 2654435761u) >> 21u; }

fn inside(v: u32, nv: u32) -> bool {
    let h = bloom_bit(v);
    if ((atomicLoad(&s_bloom[h >> 5u]) & (1u << (h & 31u))) == 0u) { return false; }
    for (var i = 0u; i < nv; i++) {
        if (s_verts[i] == v) { return true; }
    }
    return false;
}

@compute @workgroup_size(PW)
fn propose(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let j = group(wid);
    if (j >= p.n) { return; }
    let s = 8u * j;
    let m = p.base + j;
    if (lid == 0u) {
        s_nt = state[s];
        s_nv = state[s + 1u];
        s_r2 = state[s + 2u];
        s_centre = state[s + 3u];
        s_prop = state[s + 4u];
        s_open = state[s + 5u];
        state[s + 4u] = NONE;
    }
    if (workgroupUniformLoad(&s_open) == 0u) { return; }
    let nv0 = workgroupUniformLoad(&s_nv);
    for (var i = lid; i < 64u; i += PW) { atomicStore(&s_bloom[i], 0u); }
    workgroupBarrier();
    for (var i = lid; i < nv0; i += PW) {
        let v = mv[j * p.max_v + i];
        s_verts[i] = v;
        let h = bloom_bit(v);
        atomicOr(&s_bloom[h >> 5u], 1u << (h & 31u));
    }
    workgroupBarrier();
    // Accept last round's proposal if its claim won (thread 0, against the shared vertex list).
    if (lid == 0u) {
        let prop = s_prop;
        if (prop != NONE && atomicLoad(&claim[prop]) == m) {
            var nt = s_nt;
            var nv = s_nv;
            var r2 = s_r2;
            order[prop] = nt;
            mt[j * p.max_t + nt] = prop;
            nt++;
            let v = tri(prop);
            for (var k = 0u; k < 3u; k++) {
                let x = v[k];
                if (repeats(v, k) || inside(x, nv)) { continue; }
                s_verts[nv] = x;
                let h = bloom_bit(x);
                atomicOr(&s_bloom[h >> 5u], 1u << (h & 31u));
                mv[j * p.max_v + nv] = x;
                nv++;
                r2 = max(r2, d2(s_centre, x));
            }
            state[s] = nt;
            state[s + 1u] = nv;
            state[s + 2u] = r2;
            s_nt = nt;
            s_nv = nv;
            s_r2 = r2;
        }
    }
    let nt = workgroupUniformLoad(&s_nt);
    let nv = workgroupUniformLoad(&s_nv);
    let r2 = s_r2;
    let c = s_centre;

    var bs = 0u;
    var br = NONE;
    var bt = NONE;
    // A full meshlet has nothing to score.
    let scan_to = select(0u, nt, nt < p.max_t);
    for (var i = lid; i < scan_to; i += PW) {
        let entry = mt[j * p.max_t + i];
        if (entry >= INTERIOR) { continue; }
        let t = entry;
        let vt = tri(t);
        var border = false;
        for (var e = dual_off[t]; e < dual_off[t + 1u]; e++) {
            let n = nb(e);
            if (!unclaimed(n)) { continue; }
            border = true;
            let v = tri(n);
            var ins = 0u;
            var count = 0u;
            var nr2 = r2;
            for (var k = 0u; k < 3u; k++) {
                let x = v[k];
                if (repeats(v, k)) { continue; }
                count++;
                // The vertices of t (the shared edge) are inside without a search.
                if (any(vt == vec3<u32>(x)) || inside(x, nv)) { ins++; } else { nr2 = max(nr2, d2(c, x)); }
            }
            if (nt >= p.max_t || nv + count - ins > p.max_v) { continue; }
            var island = 1u;
            for (var f = dual_off[n]; f < dual_off[n + 1u]; f++) {
                if (atomicLoad(&claim[nb(f)]) != m) { island = 0u; break; }
            }
            let score = ins + island;
            if (better(score, nr2, n, bs, br, bt)) {
                bs = score;
                br = nr2;
                bt = n;
            }
        }
        // Claims are final: a triangle with no unclaimed neighbour is skipped from now on.
        if (!border) { mt[j * p.max_t + i] = entry | INTERIOR; }
    }
    r_score[lid] = bs;
    r_r2[lid] = br;
    r_t[lid] = bt;
    workgroupBarrier();
    for (var w = PW / 2u; w > 0u; w >>= 1u) {
        if (lid < w && better(r_score[lid + w], r_r2[lid + w], r_t[lid + w], r_score[lid], r_r2[lid], r_t[lid])) {
            r_score[lid] = r_score[lid + w];
            r_r2[lid] = r_r2[lid + w];
            r_t[lid] = r_t[lid + w];
        }
        workgroupBarrier();
    }
    if (lid == 0u) {
        let best = r_t[0];
        state[s + 4u] = best;
        if (best == NONE) {
            state[s + 5u] = 0u;
        } else {
            atomicAdd(&counters[p.slot], 1u);
        }
    }
}

@compute @workgroup_size(64)
fn claim_best(@builtin(global_invocation_id) gid: vec3<u32>) {
    let j = flat(gid);
    if (j >= p.n) { return; }
    let prop = state[8u * j + 4u];
    if (prop != NONE) { atomicMin(&claim[prop], p.base + j); }
}

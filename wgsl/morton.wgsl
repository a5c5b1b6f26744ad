// The Morton order on the device, step for step strategy::kmedoids::morton::{morton_order,
// initial_medoids} (the seeds of kmedoids-flat and of the coarse regions):
//   bbox                        the positions' box, as order-preserving integers (atomic min/max)
//   keys                        each triangle's Morton key (MortonFrame::key) and its id
//   centre_cells                each triangle's packed fine centroid cell (morton::packed_centres)
//   (hist, scan, scatter) x 8   a stable radix sort by key, 4 bits a pass: ids in Morton order,
//                               ties by id (they start in id order and every pass is stable)
//   pick                        the triangle at each requested rank (the middle of each of k runs)
//
// The frame (three times the low corner, and the factor) is computed on the host from bbox, as
// the CPU computes it; a key then takes only f32 +, - and x in a fixed order, exact on every
// device. scatter ranks a block's elements per digit in workgroup memory, in element order, so
// the sort does not depend on scheduling. hist_count and scatter alone also sort other (key, id)
// pairs bound as key_a and id_a (gpu::morton::PairSort).

struct Params { t: u32, n: u32, shift: u32, blocks: u32, lo_x: u32, lo_y: u32, lo_z: u32, factor: u32, k: u32, base: u32, fine: u32 }

@group(0) @binding(0) var<uniform> p: Params;
// Three f32 per vertex.
@group(0) @binding(1) var<storage, read> positions: array<f32>;
@group(0) @binding(2) var<storage, read> idx_a: array<u32>;
@group(0) @binding(3) var<storage, read> idx_b: array<u32>;
// Min x, y, z then max x, y, z, as ordered(): the host starts them at NONE and 0.
@group(0) @binding(4) var<storage, read_write> bbox: array<atomic<u32>>;
// Keys and ids, sorted back and forth between a and b (pass 0 reads a).
@group(0) @binding(5) var<storage, read_write> key_a: array<u32>;
@group(0) @binding(6) var<storage, read_write> id_a: array<u32>;
@group(0) @binding(7) var<storage, read_write> key_b: array<u32>;
@group(0) @binding(8) var<storage, read_write> id_b: array<u32>;
// 16 counts per block, digit-major (digit * blocks + block), scanned into first slots.
@group(0) @binding(9) var<storage, read_write> hist: array<u32>;
@group(0) @binding(10) var<storage, read> ranks: array<u32>;
@group(0) @binding(11) var<storage, read_write> medoids: array<u32>;
// Packed fine centroid cells, two words a triangle (x | y << 16, z), from word base.
@group(0) @binding(12) var<storage, read_write> centres: array<u32>;

fn idx(i: u32) -> u32 { if (i < PART) { return idx_a[i]; } return idx_b[i - PART]; }
fn pos(v: u32) -> vec3<f32> { return vec3<f32>(positions[3u * v], positions[3u * v + 1u], positions[3u * v + 2u]); }

// Elements per block of the sort: 64 threads, PER consecutive elements each (large blocks: on a
// CPU adapter every workgroup start costs more than its elements).
const BLOCK: u32 = 4096u;
// Consecutive elements per thread.
const PER: u32 = BLOCK / 64u;

// An f32 as a u32 in the same order (negative values flipped, positive ones above them).
fn ordered(x: f32) -> u32 {
    let u = bitcast<u32>(x);
    return select(u | 0x80000000u, ~u, (u & 0x80000000u) != 0u);
}

var<workgroup> wbox: array<atomic<u32>, 6>;

// A grid-stride loop: each thread keeps its own box, a workgroup merges them in workgroup memory,
// and only that reaches the six global words (every vertex's six atomics on the same words were
// the kernel's cost).
@compute @workgroup_size(64)
fn bbox_reduce(
    @builtin(global_invocation_id) gid: vec3<u32>,
    @builtin(local_invocation_index) lid: u32,
    @builtin(num_workgroups) nwg: vec3<u32>,
) {
    if (lid < 6u) { atomicStore(&wbox[lid], select(0u, NONE, lid < 3u)); }
    workgroupBarrier();
    var lo = vec3<u32>(NONE);
    var hi = vec3<u32>(0u);
    for (var v = flat(gid); v < p.n; v += stride(nwg)) {
        let q = pos(v);
        for (var a = 0u; a < 3u; a++) {
            lo[a] = min(lo[a], ordered(q[a]));
            hi[a] = max(hi[a], ordered(q[a]));
        }
    }
    for (var a = 0u; a < 3u; a++) {
        atomicMin(&wbox[a], lo[a]);
        atomicMax(&wbox[3u + a], hi[a]);
    }
    workgroupBarrier();
    if (lid < 3u) {
        atomicMin(&bbox[lid], atomicLoad(&wbox[lid]));
    } else if (lid < 6u) {
        atomicMax(&bbox[lid], atomicLoad(&wbox[lid]));
    }
}

// Bits 0..9 of v spread to every third bit (common::morton3 for values below 1024).
fn spread(v: u32) -> u32 {
    var x = v & 0x3ffu;
    x = (x | (x << 16u)) & 0x030000ffu;
    x = (x | (x << 8u)) & 0x0300f00fu;
    x = (x | (x << 4u)) & 0x030c30c3u;
    x = (x | (x << 2u)) & 0x09249249u;
    return x;
}

// The triangle's corner sum minus three times the low corner (MortonFrame::cell's first step).
fn offset_sum(t: u32) -> vec3<f32> {
    let lo3 = vec3<f32>(bitcast<f32>(p.lo_x), bitcast<f32>(p.lo_y), bitcast<f32>(p.lo_z));
    return (pos(idx(3u * t)) + pos(idx(3u * t + 1u))) + pos(idx(3u * t + 2u)) - lo3;
}

// The triangle's centroid cell, 0..=1023 per axis (MortonFrame::cell).
fn cell(t: u32) -> vec3<u32> {
    return vec3<u32>(clamp(offset_sum(t) * bitcast<f32>(p.factor), vec3<f32>(0.0), vec3<f32>(1023.0)));
}

// The triangle's fine centroid cell, 0..=FINE_MAX per axis (MortonFrame::fine_cell).
fn fine_cell(t: u32) -> vec3<u32> {
    let top = vec3<f32>(f32(FINE_MAX));
    return vec3<u32>(clamp(offset_sum(t) * bitcast<f32>(p.fine), vec3<f32>(0.0), top));
}

@compute @workgroup_size(64)
fn keys(@builtin(global_invocation_id) gid: vec3<u32>) {
    let t = flat(gid);
    if (t >= p.t) { return; }
    let q = cell(t);
    key_a[t] = spread(q.x) | (spread(q.y) << 1u) | (spread(q.z) << 2u);
    id_a[t] = t;
}

@compute @workgroup_size(64)
fn centre_cells(@builtin(global_invocation_id) gid: vec3<u32>) {
    let t = flat(gid);
    if (t >= p.t) { return; }
    let q = fine_cell(t);
    centres[p.base + 2u * t] = q.x | (q.y << 16u);
    centres[p.base + 2u * t + 1u] = q.z;
}

// Pass parity: even passes read a and write b.
fn from_a() -> bool { return ((p.shift / 4u) & 1u) == 0u; }
fn src_key(i: u32) -> u32 { if (from_a()) { return key_a[i]; } return key_b[i]; }
fn src_id(i: u32) -> u32 { if (from_a()) { return id_a[i]; } return id_b[i]; }
fn digit(key: u32) -> u32 { return (key >> p.shift) & 15u; }

var<workgroup> counts: array<atomic<u32>, 16>;
// Per digit, per thread: elements of that digit (then: before that thread) in the block.
var<workgroup> slots: array<u32, 1024>;

@compute @workgroup_size(64)
fn hist_count(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let b = group(wid);
    if (lid < 16u) { atomicStore(&counts[lid], 0u); }
    workgroupBarrier();
    for (var e = 0u; e < PER; e++) {
        let i = b * BLOCK + PER * lid + e;
        if (i < p.t) { atomicAdd(&counts[digit(src_key(i))], 1u); }
    }
    workgroupBarrier();
    if (lid < 16u) { hist[lid * p.blocks + b] = atomicLoad(&counts[lid]); }
}

@compute @workgroup_size(64)
fn scatter(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let b = group(wid);
    for (var d = 0u; d < 16u; d++) { slots[d * 64u + lid] = 0u; }
    for (var e = 0u; e < PER; e++) {
        let i = b * BLOCK + PER * lid + e;
        if (i < p.t) { slots[digit(src_key(i)) * 64u + lid] += 1u; }
    }
    workgroupBarrier();
    if (lid < 16u) {
        var sum = 0u;
        for (var j = 0u; j < 64u; j++) {
            let c = slots[lid * 64u + j];
            slots[lid * 64u + j] = sum;
            sum += c;
        }
    }
    workgroupBarrier();
    for (var e = 0u; e < PER; e++) {
        let i = b * BLOCK + PER * lid + e;
        if (i < p.t) {
            let key = src_key(i);
            let d = digit(key);
            let to = hist[d * p.blocks + b] + slots[d * 64u + lid];
            slots[d * 64u + lid] += 1u;
            if (from_a()) {
                key_b[to] = key;
                id_b[to] = id_a[i];
            } else {
                key_a[to] = key;
                id_a[to] = id_b[i];
            }
        }
    }
}

@compute @workgroup_size(64)
fn pick(@builtin(global_invocation_id) gid: vec3<u32>) {
    let j = flat(gid);
    if (j < p.k) { medoids[j] = id_a[ranks[j]]; }
}

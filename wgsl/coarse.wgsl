// The coarse regions of the region-parallel k-medoids on the device, mirroring
// src/strategy/kmedoids/coarse.rs step by step (driver: src/gpu/coarse.rs):
//   (morton.wgsl)              step 1: the Morton order and the seeds at the middle of each run
//   (assign.wgsl)              step 2: the multi-source BFS from the seeds in ascending order
//   piece_init, piece_round xn step 3: in every piece no seed reached, the least Morton rank, by
//                              min-label hooking and pointer jumping over ranks
//   finish                     each triangle's region: its BFS label, or for an unreached piece the
//                              label of the seed of the run its least rank falls in; the pairs
//                              (region, triangle) to sort
//   (morton.wgsl: sort)        members of each region, ascending (a stable radix sort by region)
//   offsets_of                 each region's first member (regions are never empty: each holds
//                              its seed)

struct Params { t: u32, k: u32, slot: u32, pad: u32 }

@group(0) @binding(0) var<uniform> p: Params;
@group(0) @binding(1) var<storage, read> dual_off: array<u32>;
@group(0) @binding(2) var<storage, read> dual_a: array<u32>;
@group(0) @binding(3) var<storage, read> dual_b: array<u32>;
// Triangles in Morton order.
@group(0) @binding(4) var<storage, read> order: array<u32>;
// [0, k) the first Morton rank of each run, [k, 2k) the rank of its seed.
@group(0) @binding(5) var<storage, read> runs: array<u32>;
// The BFS label of each triangle (its nearest seed's position in ascending order), NONE where
// no seed reached.
@group(0) @binding(6) var<storage, read> bfs: array<u32>;
// Per unreached triangle, the least Morton rank met so far in its piece.
@group(0) @binding(7) var<storage, read_write> least: array<atomic<u32>>;
// Label changes per piece_round, one slot each.
@group(0) @binding(8) var<storage, read_write> counters: array<atomic<u32>>;
// Out: the region of each triangle.
@group(0) @binding(9) var<storage, read_write> region: array<u32>;
// Out: the pairs to sort, (region, triangle).
@group(0) @binding(10) var<storage, read_write> key: array<u32>;
@group(0) @binding(11) var<storage, read_write> id: array<u32>;
// The sorted keys when the sort ended in its own buffers (p.slot = 1), else unused.
@group(0) @binding(12) var<storage, read> sorted: array<u32>;
// Out: [0, k] each region's first member in the sorted order, then T.
@group(0) @binding(13) var<storage, read_write> offsets: array<u32>;

fn nb(i: u32) -> u32 { if (i < PART) { return dual_a[i]; } return dual_b[i - PART]; }

@compute @workgroup_size(64)
fn piece_init(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = flat(gid);
    if (i >= p.t) { return; }
    let x = order[i];
    atomicStore(&least[x], select(NONE, i, bfs[x] == NONE));
}

// A label is a Morton rank; the triangle that holds it is order[rank]. An unreached triangle
// takes the least label among its neighbours (all unreached: a piece is reached whole or not at
// all) and hooks a neighbour's larger label's triangle onto its own, then follows the chain of
// labels to its end. Labels only fall and always name a triangle of the same piece, so the fixed
// point (a round with no change) is the piece's least rank whatever the order of the threads.
@compute @workgroup_size(64)
fn piece_round(@builtin(global_invocation_id) gid: vec3<u32>) {
    let x = flat(gid);
    if (x >= p.t || bfs[x] != NONE) { return; }
    var m = atomicLoad(&least[x]);
    var changed = 0u;
    for (var e = dual_off[x]; e < dual_off[x + 1u]; e++) {
        let l = atomicLoad(&least[nb(e)]);
        if (l < m) {
            m = l;
        } else if (m < l && m < atomicMin(&least[order[l]], m)) {
            changed = 1u;
        }
    }
    loop {
        let l = atomicLoad(&least[order[m]]);
        if (l >= m) { break; }
        m = l;
    }
    if (m < atomicMin(&least[x], m)) { changed = 1u; }
    if (changed != 0u) { atomicAdd(&counters[p.slot], 1u); }
}

// coarse::run_of: the last run whose first rank is at most i.
fn run_of(i: u32) -> u32 {
    var lo = 0u;
    var hi = p.k;
    while (hi - lo > 1u) {
        let mid = (lo + hi) / 2u;
        if (runs[mid] <= i) { lo = mid; } else { hi = mid; }
    }
    return lo;
}

@compute @workgroup_size(64)
fn finish(@builtin(global_invocation_id) gid: vec3<u32>) {
    let x = flat(gid);
    if (x >= p.t) { return; }
    var r = 0u;
    if (p.k > 1u) {
        r = bfs[x];
        if (r == NONE) { r = bfs[order[runs[p.k + run_of(atomicLoad(&least[x]))]]]; }
    }
    region[x] = r;
    key[x] = r;
    id[x] = x;
}

fn sorted_key(i: u32) -> u32 { if (p.slot == 1u) { return sorted[i]; } return key[i]; }

@compute @workgroup_size(64)
fn offsets_of(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = flat(gid);
    if (i >= p.t) { return; }
    let r = sorted_key(i);
    if (i == 0u || sorted_key(i - 1u) != r) { offsets[r] = i; }
    if (i + 1u == p.t) { offsets[p.k] = p.t; }
}

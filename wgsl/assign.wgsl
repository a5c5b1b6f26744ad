// k-medoids assignment on the triangle dual graph: the multi-source BFS of
// src/strategy/kmedoids.rs `assign`, level by level over the frontier only:
//   clear       labels and distances to NONE
//   seed        each medoid labels itself at distance 0 and forms the level-0 frontier
//   push x L    level d: every frontier triangle offers its label to its neighbours; the first to
//               reach an unreached neighbour (atomicMin on its distance) appends it to frontier d + 1
//
// Determinism: a neighbour reached at level d + 1 takes the smallest label among its level-d
// neighbours (atomicMin), which is the CPU's fetch_min on (distance << 32 | cluster) because every
// competitor is at the same distance. Only the order of the frontier lists depends on thread
// timing, and nothing reads that order.
//
// Work is proportional to the frontier (each triangle pushes once per assign), not to T per level.
// Frontier sizes live in a ring of counters so a submission can record many levels and the host
// reads them once: level d appends to slot (d + 1) % RING and clears slot (d + 2) % RING for the
// level after next.

struct Params { t: u32, k: u32, d: u32, slot: u32, max_v: u32, max_t: u32 }

@group(0) @binding(0) var<uniform> p: Params;
@group(0) @binding(1) var<storage, read> dual_off: array<u32>;
@group(0) @binding(2) var<storage, read> dual_a: array<u32>;
@group(0) @binding(3) var<storage, read> dual_b: array<u32>;
@group(0) @binding(4) var<storage, read_write> labels: array<atomic<u32>>;
@group(0) @binding(5) var<storage, read_write> dist: array<atomic<u32>>;
@group(0) @binding(6) var<storage, read> medoids: array<u32>;
// Shared with update.wgsl: [0, 8) its counters, [8, 8 + RING) frontier sizes by level.
@group(0) @binding(7) var<storage, read_write> counters: array<atomic<u32>>;
// Two frontier lists of T entries each: level d's at (d % 2) * T.
@group(0) @binding(8) var<storage, read_write> frontier: array<u32>;

const RING: u32 = 64u;
const SIZES: u32 = 8u;

fn nb(i: u32) -> u32 { if (i < PART) { return dual_a[i]; } return dual_b[i - PART]; }
// Grid-stride loops: the host sizes dispatches to the device (few workgroups on a CPU adapter).

@compute @workgroup_size(64)
fn clear(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    for (var t = flat(gid); t < p.t; t += stride(nwg)) {
        atomicStore(&labels[t], NONE);
        atomicStore(&dist[t], NONE);
    }
}

@compute @workgroup_size(64)
fn seed(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let first = flat(gid);
    if (first == 0u) {
        atomicStore(&counters[SIZES], p.k);
        atomicStore(&counters[SIZES + 1u], 0u);
    }
    for (var c = first; c < p.k; c += stride(nwg)) {
        let m = medoids[c];
        atomicStore(&labels[m], c);
        atomicStore(&dist[m], 0u);
        frontier[c] = m;
    }
}

@compute @workgroup_size(64)
fn push(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let first = flat(gid);
    let d = p.d;
    if (first == 0u) { atomicStore(&counters[SIZES + (d + 2u) % RING], 0u); }
    let n = atomicLoad(&counters[SIZES + d % RING]);
    let here = (d % 2u) * p.t;
    let to = ((d + 1u) % 2u) * p.t;
    let next = SIZES + (d + 1u) % RING;
    for (var i = first; i < n; i += stride(nwg)) {
        let u = frontier[here + i];
        let label = atomicLoad(&labels[u]);
        for (var e = dual_off[u]; e < dual_off[u + 1u]; e++) {
            let x = nb(e);
            // Settled at an earlier level: the common case, without a read-modify-write.
            if (atomicLoad(&dist[x]) <= d) { continue; }
            let old = atomicMin(&dist[x], d + 1u);
            if (old == NONE) { frontier[to + atomicAdd(&counters[next], 1u)] = x; }
            atomicMin(&labels[x], label);
        }
    }
}

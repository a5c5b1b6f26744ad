// Capacity-aware assignment, src/strategy/kmedoids_capacity.rs `assign_capacity`, as kernels:
//   clear_labels   every triangle free, no claims                        labels = FREE
//   seed           cluster c takes its medoid: level 0, its corners      the first loop
//   walk           one thread per cluster: the free neighbours of its    one cluster's pass over
//                  last level, ascending, each taken if it fits          its sorted candidates
//   check          which clusters the next walk must redo                (the fixed-point test)
//   commit         the level's takes become labels; the next level       frontier = this level's takes
//                  starts from them
//   restamp        renumbers the claim stamps when they run out          (bookkeeping)
//
// The CPU takes a level's clusters in ascending id, and a cluster skips a triangle a lower cluster
// took earlier in the same level: a chain of dependencies no thread order can follow. So the walk
// is iterated (Jacobi on that order): each walk skips what a lower cluster claimed in the previous
// walk (atomicMin, so the lowest claimant is read whatever the thread order). Cluster 0's walk is
// exact at once; cluster c's once every lower cluster it meets is. The fixed point, where no
// cluster's takes change, is the sequential result, so the labels equal the CPU's.
// A level's first walk reads no claims. `check` marks for the next walk only the clusters whose
// inputs changed: one that lost a triangle it took, or one that skipped a triangle no lower
// cluster holds any more (one that skipped more than SKIP is always redone); the others only
// claim their takes again, since their walk would repeat itself. The level is done when no
// cluster is marked, or when a walk changed no cluster's takes (the host reads the counters). A
// walk at the fixed point reproduces it, so the host may record spare walks.
//
// Claims carry a stamp so that nothing is cleared between walks: a claim is (code << 25) | cluster,
// the code falling by one per walk, so atomicMin lets a newer walk's claim replace an older one,
// and a reader tells the previous walk's claims by their code. Cluster ids stay below 2^24
// (gpu::kmedoids refuses larger meshes). All arithmetic is on u32: the same on every device.

struct Params { t: u32, k: u32, max_v: u32, max_t: u32, first: u32, par: u32, slot: u32, code: u32 }

@group(0) @binding(0) var<uniform> p: Params;
@group(0) @binding(1) var<storage, read> dual_off: array<u32>;
@group(0) @binding(2) var<storage, read> dual_a: array<u32>;
@group(0) @binding(3) var<storage, read> dual_b: array<u32>;
@group(0) @binding(4) var<storage, read> idx_a: array<u32>;
@group(0) @binding(5) var<storage, read> idx_b: array<u32>;
@group(0) @binding(6) var<storage, read> medoids: array<u32>;
// Cluster per triangle, NONE while free (the CPU's FREE).
@group(0) @binding(7) var<storage, read_write> labels: array<u32>;
// Lowest cluster that took each triangle in a walk, stamped: walk w writes claim_a if w is even,
// else claim_b.
@group(0) @binding(8) var<storage, read_write> claim_a: array<atomic<u32>>;
@group(0) @binding(9) var<storage, read_write> claim_b: array<atomic<u32>>;
// Each cluster's triangles in the order taken, max_t slots per cluster: committed ones, then the
// current walk's takes.
@group(0) @binding(10) var<storage, read_write> ct: array<u32>;
// Each cluster's vertices, max_v slots per cluster: committed ones (ascending), then the current
// walk's.
@group(0) @binding(11) var<storage, read_write> cv: array<u32>;
// Per cluster, STATE words: see the S_ constants.
@group(0) @binding(12) var<storage, read_write> state: array<u32>;
// The triangles each cluster's last walk skipped as a lower cluster's, SKIP slots per cluster.
@group(0) @binding(13) var<storage, read_write> skipped: array<u32>;
@group(0) @binding(14) var<storage, read_write> counters: array<atomic<u32>>;

const STATE: u32 = 8u;
// Committed triangles; where the last level starts in ct; committed vertex slots (the medoid's
// three corners count three, as the CPU's list holds them); the walk's takes and added vertices;
// 1 while the cluster still grows (it took triangles last level and has room).
const S_COUNT: u32 = 0u;
const S_LEVEL: u32 = 1u;
const S_VERTS: u32 = 2u;
const S_TAKEN: u32 = 3u;
const S_ADDED: u32 = 4u;
const S_OPEN: u32 = 5u;
// 1 when the next walk must redo the cluster; triangles its last walk skipped.
const S_DIRTY: u32 = 6u;
const S_SKIPPED: u32 = 7u;
const SKIP: u32 = 16u;
// The cluster-id bits of a claim.
const ID: u32 = 0x1ffffffu;
// Candidates a walk sorts in registers; a cluster with more (non-manifold fans) finds them in
// ascending order by repeated minimum search instead: the same sequence, slower.
const CAND: u32 = 192u;

fn nb(i: u32) -> u32 { if (i < PART) { return dual_a[i]; } return dual_b[i - PART]; }
fn idx(i: u32) -> u32 { if (i < PART) { return idx_a[i]; } return idx_b[i - PART]; }

fn stamp(key: u32) -> u32 { return key >> 25u; }

// Whether a cluster below c took t in the previous walk (whose claims carry code + 1).
fn lower_before(t: u32, c: u32) -> bool {
    var key: u32;
    if (p.par == 0u) { key = atomicLoad(&claim_b[t]); } else { key = atomicLoad(&claim_a[t]); }
    return stamp(key) == p.code + 1u && (key & ID) < c;
}

// Same, in the walk that just ran (`check` runs after it with its parameters).
fn lower_now(t: u32, c: u32) -> bool {
    var key: u32;
    if (p.par == 0u) { key = atomicLoad(&claim_a[t]); } else { key = atomicLoad(&claim_b[t]); }
    return stamp(key) == p.code && (key & ID) < c;
}

fn claim(t: u32, c: u32) {
    let key = (p.code << 25u) | c;
    if (p.par == 0u) { atomicMin(&claim_a[t], key); } else { atomicMin(&claim_b[t], key); }
}

@compute @workgroup_size(64)
fn clear_labels(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    for (var t = flat(gid); t < p.t; t += stride(nwg)) {
        labels[t] = NONE;
        atomicStore(&claim_a[t], NONE);
        atomicStore(&claim_b[t], NONE);
    }
}

// Before the walk of parity `par`, when the codes run out: the previous walk's claims (`code`)
// get the code `first` (here not a flag: the host's top code + 1, what the next walk reads as
// its previous walk's), and every other claim goes.
@compute @workgroup_size(64)
fn restamp(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    for (var t = flat(gid); t < p.t; t += stride(nwg)) {
        var a = atomicLoad(&claim_a[t]);
        var b = atomicLoad(&claim_b[t]);
        if (p.par == 0u) {
            b = select(NONE, (p.first << 25u) | (b & ID), stamp(b) == p.code);
            a = NONE;
        } else {
            a = select(NONE, (p.first << 25u) | (a & ID), stamp(a) == p.code);
            b = NONE;
        }
        atomicStore(&claim_a[t], a);
        atomicStore(&claim_b[t], b);
    }
}

@compute @workgroup_size(64)
fn clear_counters(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = flat(gid);
    if (i < 8u) { atomicStore(&counters[i], 0u); }
}

// Counts open clusters into `slot`.
@compute @workgroup_size(64)
fn seed(@builtin(global_invocation_id) gid: vec3<u32>) {
    let c = flat(gid);
    if (c >= p.k) { return; }
    let m = medoids[c];
    labels[m] = c;
    ct[c * p.max_t] = m;
    // Sorted (a committed list is searched by bisection); a degenerate medoid's repeated corner
    // stays, as in the CPU's list.
    var v = vec3<u32>(idx(3u * m), idx(3u * m + 1u), idx(3u * m + 2u));
    if (v.x > v.y) { v = v.yxz; }
    if (v.y > v.z) { v = v.xzy; }
    if (v.x > v.y) { v = v.yxz; }
    for (var j = 0u; j < 3u; j++) { cv[c * p.max_v + j] = v[j]; }
    let s = c * STATE;
    state[s + S_COUNT] = 1u;
    state[s + S_LEVEL] = 0u;
    state[s + S_VERTS] = 3u;
    state[s + S_TAKEN] = 0u;
    state[s + S_ADDED] = 0u;
    let open = 1u < p.max_t;
    state[s + S_OPEN] = select(0u, 1u, open);
    state[s + S_DIRTY] = 1u;
    if (open) { atomicAdd(&counters[p.slot], 1u); }
}

// The smallest free neighbour of cluster c's last level above `after` (any if !started), or NONE.
fn next_min(lo: u32, hi: u32, after: u32, started: bool) -> u32 {
    var best = NONE;
    for (var i = lo; i < hi; i++) {
        let t = ct[i];
        for (var j = dual_off[t]; j < dual_off[t + 1u]; j++) {
            let u = nb(j);
            if (labels[u] == NONE && (!started || u > after) && u < best) { best = u; }
        }
    }
    return best;
}

// Whether v is among cluster vertices [bv, bv + sorted) (ascending: binary search) or
// [bv + sorted, end) (this walk's additions, few: linear).
fn has_vertex(bv: u32, sorted: u32, end: u32, v: u32) -> bool {
    var lo = bv;
    var hi = bv + sorted;
    while (lo < hi) {
        let mid = (lo + hi) / 2u;
        if (cv[mid] < v) { lo = mid + 1u; } else { hi = mid; }
    }
    if (lo < bv + sorted && cv[lo] == v) { return true; }
    for (var i = bv + sorted; i < end; i++) { if (cv[i] == v) { return true; } }
    return false;
}

// Counts clusters whose takes differ from the previous walk's into `slot`.
@compute @workgroup_size(64)
fn walk(@builtin(global_invocation_id) gid: vec3<u32>) {
    let c = flat(gid);
    if (c >= p.k) { return; }
    let s = c * STATE;
    if (state[s + S_OPEN] == 0u) { return; }
    let count = state[s + S_COUNT];
    if (state[s + S_DIRTY] == 0u) {
        // Its inputs did not change: the same takes, claimed again for this walk.
        let at = c * p.max_t + count;
        for (var i = 0u; i < state[s + S_TAKEN]; i++) { claim(ct[at + i], c); }
        return;
    }
    let verts = state[s + S_VERTS];
    let bt = c * p.max_t;
    let bv = c * p.max_v;
    let lo = bt + state[s + S_LEVEL];
    let hi = bt + count;
    // Gather the free neighbours of the last level; sort them unless there are too many.
    var cand: array<u32, CAND>;
    var n = 0u;
    var many = false;
    for (var i = lo; i < hi && !many; i++) {
        let t = ct[i];
        for (var j = dual_off[t]; j < dual_off[t + 1u]; j++) {
            let u = nb(j);
            if (labels[u] == NONE) {
                if (n == CAND) { many = true; break; }
                cand[n] = u;
                n++;
            }
        }
    }
    if (!many) {
        for (var i = 1u; i < n; i++) {
            let x = cand[i];
            var j = i;
            while (j > 0u && cand[j - 1u] > x) { cand[j] = cand[j - 1u]; j--; }
            cand[j] = x;
        }
    }
    var taken = 0u;
    var added = 0u;
    var skips = 0u;
    var changed = false;
    var i = 0u;
    var last = 0u;
    var started = false;
    loop {
        var t: u32;
        if (many) {
            t = next_min(lo, hi, last, started);
            if (t == NONE) { break; }
        } else {
            while (i < n && started && cand[i] == last) { i++; }
            if (i == n) { break; }
            t = cand[i];
            i++;
        }
        last = t;
        started = true;
        if (count + taken >= p.max_t) { break; }
        // Taken by a lower cluster earlier in this level (as the previous walk has it).
        if (p.first == 0u && lower_before(t, c)) {
            if (skips < SKIP) { skipped[c * SKIP + skips] = t; }
            skips++;
            continue;
        }
        let end = bv + verts + added;
        var fresh = 0u;
        for (var j = 0u; j < 3u; j++) {
            if (!has_vertex(bv, verts, end, idx(3u * t + j))) { fresh++; }
        }
        if (verts + added + fresh > p.max_v) { continue; }
        for (var j = 0u; j < 3u; j++) {
            let v = idx(3u * t + j);
            if (!has_vertex(bv, verts, bv + verts + added, v)) {
                cv[bv + verts + added] = v;
                added++;
            }
        }
        let at = hi + taken;
        if (ct[at] != t) { changed = true; }
        ct[at] = t;
        taken++;
        claim(t, c);
    }
    if (taken != state[s + S_TAKEN]) { changed = true; }
    state[s + S_TAKEN] = taken;
    state[s + S_ADDED] = added;
    state[s + S_SKIPPED] = skips;
    if (changed) { atomicAdd(&counters[p.slot], 1u); }
}

// After a walk (same parameters): marks the clusters the next walk must redo, counted into `slot`.
@compute @workgroup_size(64)
fn check(@builtin(global_invocation_id) gid: vec3<u32>) {
    let c = flat(gid);
    if (c >= p.k) { return; }
    let s = c * STATE;
    if (state[s + S_OPEN] == 0u) { return; }
    var dirty = state[s + S_SKIPPED] > SKIP;
    let at = c * p.max_t + state[s + S_COUNT];
    for (var i = 0u; i < state[s + S_TAKEN] && !dirty; i++) {
        dirty = lower_now(ct[at + i], c);
    }
    for (var i = 0u; i < state[s + S_SKIPPED] && !dirty; i++) {
        dirty = !lower_now(skipped[c * SKIP + i], c);
    }
    state[s + S_DIRTY] = select(0u, 1u, dirty);
    if (dirty) { atomicAdd(&counters[p.slot], 1u); }
}

// The fixed point's takes become labels; counts the clusters still open into `slot`.
@compute @workgroup_size(64)
fn commit(@builtin(global_invocation_id) gid: vec3<u32>) {
    let c = flat(gid);
    if (c >= p.k) { return; }
    let s = c * STATE;
    if (state[s + S_OPEN] == 0u) { return; }
    let count = state[s + S_COUNT];
    let taken = state[s + S_TAKEN];
    let at = c * p.max_t + count;
    for (var i = 0u; i < taken; i++) { labels[ct[at + i]] = c; }
    state[s + S_LEVEL] = count;
    state[s + S_COUNT] = count + taken;
    // Insert the level's new vertices into the sorted list.
    let bv = c * p.max_v;
    let verts = state[s + S_VERTS] + state[s + S_ADDED];
    for (var i = state[s + S_VERTS]; i < verts; i++) {
        let x = cv[bv + i];
        var j = i;
        while (j > 0u && cv[bv + j - 1u] > x) { cv[bv + j] = cv[bv + j - 1u]; j--; }
        cv[bv + j] = x;
    }
    state[s + S_VERTS] = verts;
    state[s + S_TAKEN] = 0u;
    state[s + S_ADDED] = 0u;
    let open = taken > 0u && count + taken < p.max_t;
    state[s + S_OPEN] = select(0u, 1u, open);
    state[s + S_DIRTY] = 1u;
    if (open) { atomicAdd(&counters[p.slot], 1u); }
}

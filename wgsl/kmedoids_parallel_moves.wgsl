// Boundary moves, the medoid iteration of kmedoids-parallel on the device, mirroring
// src/strategy/kmedoids/parallel/moves.rs (driver: src/gpu/kmedoids_parallel_moves.rs). Each round runs
//   tally          the per-cluster sums set to zero, "changed" moved to "changed last round"
//                  (per cluster)
//   count_members  members and distinct vertices per cluster (move_boundaries' vertex counts)
//                  and each triangle's slot in its cluster's list; in round 0 also the clusters
//                  that are not edge-connected (`movable`) and the objective before (per triangle)
//   (scan.wgsl)    the member offsets, the counts scanned in place
//   place          the member lists: cluster c's members from offset[c] (per triangle)
//   settle         step 4 for the clusters that took a triangle last round (one that only gave
//                  keeps its distances): BFS from the fixed medoid over the new list (one
//                  invocation per cluster)
//   candidates     step 1 (per triangle)
//   propose        step 2 (the distance rule over `centres`), and step 3's per-target sums and
//                  greatest gain by atomics (per triangle)
//   pick_best      step 3: the lowest triangle id among the proposals of greatest gain
//   accept         step 3: labels and distances of the accepted moves (per triangle)
// After the last round tally, count_members (members only: `round` is NONE), scan and place run
// once more, then `new_medoids` (step 5: the paper's medoid of every changed cluster,
// medoid.wgsl). A round that moves nothing leaves
// the state as it found it, so the rounds after it do nothing, as the CPU's early stop does.
// The CPU keeps members in sorted lists; here a list is in slot order, which nothing depends on:
// the BFS distances and the medoid (ties by triangle id) are functions of the member set.

struct Params {
    t: u32, k: u32, max_v: u32, max_t: u32, round: u32, medoid_at: u32, centres_at: u32, pad: u32
}

@group(0) @binding(0) var<uniform> p: Params;
@group(0) @binding(1) var<storage, read> idx_a: array<u32>;
@group(0) @binding(2) var<storage, read> idx_b: array<u32>;
@group(0) @binding(3) var<storage, read> vt_off: array<u32>;
@group(0) @binding(4) var<storage, read> vt_a: array<u32>;
@group(0) @binding(5) var<storage, read> vt_b: array<u32>;
@group(0) @binding(6) var<storage, read> dual_off: array<u32>;
@group(0) @binding(7) var<storage, read> dual_a: array<u32>;
@group(0) @binding(8) var<storage, read> dual_b: array<u32>;
@group(0) @binding(9) var<storage, read_write> labels: array<u32>;
@group(0) @binding(10) var<storage, read_write> dist: array<u32>;
// Per triangle, sections of T: member lists (cluster order), BFS queue, candidate flag, proposed
// target, distance there, new vertices there, slot in the cluster's list.
@group(0) @binding(11) var<storage, read_write> arena: array<u32>;
// The shared medoid's scratch, 9 words per member at 9x its list offset.
@group(0) @binding(12) var<storage, read_write> cstate: array<u32>;
// Per cluster, sections of K + 1: members (then their offsets, scanned in place), vertices,
// triangles asked for, new vertices asked for, greatest gain, its lowest triangle, flags; then
// the counters: objective before (low, high word), changed clusters, triangles moved per round.
@group(0) @binding(13) var<storage, read_write> state: array<atomic<u32>>;
// The medoids, at `medoid_at`.
@group(0) @binding(14) var<storage, read_write> info: array<u32>;
// The triangles' packed centroid cells (x | y << 16, z) at `centres_at` (morton::packed_centres).
@group(0) @binding(15) var<storage, read> centres: array<u32>;

fn idx(i: u32) -> u32 { if (i < PART) { return idx_a[i]; } return idx_b[i - PART]; }
fn vtn(i: u32) -> u32 { if (i < PART) { return vt_a[i]; } return vt_b[i - PART]; }
fn nb(i: u32) -> u32 { if (i < PART) { return dual_a[i]; } return dual_b[i - PART]; }

// arena sections.
fn s_list() -> u32 { return 0u; }
fn s_queue() -> u32 { return p.t; }
fn s_cand() -> u32 { return 2u * p.t; }
fn s_target() -> u32 { return 3u * p.t; }
fn s_pdist() -> u32 { return 4u * p.t; }
fn s_pnew() -> u32 { return 5u * p.t; }
fn s_slot() -> u32 { return 6u * p.t; }

// state sections.
fn c_count(c: u32) -> u32 { return c; }
fn c_verts(c: u32) -> u32 { return (p.k + 1u) + c; }
fn c_ask_t(c: u32) -> u32 { return 2u * (p.k + 1u) + c; }
fn c_ask_v(c: u32) -> u32 { return 3u * (p.k + 1u) + c; }
fn c_gain(c: u32) -> u32 { return 4u * (p.k + 1u) + c; }
fn c_best(c: u32) -> u32 { return 5u * (p.k + 1u) + c; }
fn c_flags(c: u32) -> u32 { return 6u * (p.k + 1u) + c; }
fn h_sum() -> u32 { return 7u * (p.k + 1u); }
fn h_changed() -> u32 { return 7u * (p.k + 1u) + 2u; }
fn h_moved(r: u32) -> u32 { return 7u * (p.k + 1u) + 3u + r; }

// Cluster flags: took a triangle in this round, in the last one; gave or took in any; not
// edge-connected.
const NOW: u32 = 1u;
const LAST: u32 = 2u;
const CHANGED: u32 = 4u;
const FIXED: u32 = 8u;

fn ld(i: u32) -> u32 { return atomicLoad(&state[i]); }
// Member offsets once the scan has run.
fn offset(c: u32) -> u32 { return ld(c_count(c)); }
fn size(c: u32) -> u32 { return ld(c_count(c + 1u)) - ld(c_count(c)); }
fn open(u: u32) -> bool { return (ld(c_flags(labels[u])) & FIXED) == 0u; }

@compute @workgroup_size(64)
fn tally(@builtin(global_invocation_id) gid: vec3<u32>) {
    let c = flat(gid);
    if (c > p.k) { return; }
    for (var s = 0u; s < 4u; s++) { atomicStore(&state[s * (p.k + 1u) + c], 0u); }
    atomicStore(&state[c_gain(c)], 0u);
    atomicStore(&state[c_best(c)], NONE);
    let f = ld(c_flags(c));
    atomicStore(&state[c_flags(c)], (f & (CHANGED | FIXED)) | select(0u, LAST, (f & NOW) != 0u));
}

@compute @workgroup_size(64)
fn count_members(@builtin(global_invocation_id) gid: vec3<u32>) {
    let x = flat(gid);
    if (x >= p.t) { return; }
    let a = labels[x];
    arena[s_slot() + x] = atomicAdd(&state[c_count(a)], 1u);
    // After the rounds only the lists are needed.
    if (p.round == NONE) { return; }
    // A vertex counts once per cluster: at the cluster's lowest triangle using it (rows ascend).
    var v = vec3<u32>(idx(3u * x), idx(3u * x + 1u), idx(3u * x + 2u));
    for (var j = 0u; j < 3u; j++) {
        if ((j > 0u && v[j] == v[0]) || (j > 1u && v[j] == v[1])) { continue; }
        var first = true;
        for (var e = vt_off[v[j]]; e < vt_off[v[j] + 1u]; e++) {
            let y = vtn(e);
            if (y >= x) { break; }
            if (labels[y] == a) { first = false; break; }
        }
        if (first) { atomicAdd(&state[c_verts(a)], 1u); }
    }
    if (p.round != 0u) { return; }
    // Not edge-connected: a member, not the medoid, with no parent one hop nearer.
    let d = dist[x];
    if (d > 0u) {
        var parent = false;
        for (var e = dual_off[x]; e < dual_off[x + 1u]; e++) {
            let u = nb(e);
            if (labels[u] == a && dist[u] + 1u == d) { parent = true; }
        }
        if (!parent) { atomicOr(&state[c_flags(a)], FIXED); }
        // The objective's sum in two words.
        let lo = atomicAdd(&state[h_sum()], d);
        if (lo + d < lo) { atomicAdd(&state[h_sum() + 1u], 1u); }
    }
}

@compute @workgroup_size(64)
fn place(@builtin(global_invocation_id) gid: vec3<u32>) {
    let x = flat(gid);
    if (x >= p.t) { return; }
    arena[s_list() + offset(labels[x]) + arena[s_slot() + x]] = x;
}

@compute @workgroup_size(64)
fn settle(@builtin(global_invocation_id) gid: vec3<u32>) {
    let c = flat(gid);
    if (c >= p.k || (ld(c_flags(c)) & LAST) == 0u) { return; }
    let o = offset(c);
    let m = size(c);
    for (var j = 0u; j < m; j++) { dist[arena[s_list() + o + j]] = NONE; }
    bfs(c, s_queue() + o, info[p.medoid_at + c], 0u);
}

@compute @workgroup_size(64)
fn candidates(@builtin(global_invocation_id) gid: vec3<u32>) {
    let x = flat(gid);
    if (x >= p.t) { return; }
    let a = labels[x];
    let d = dist[x];
    var moving = false;
    if (d > 0u && open(x)) {
        for (var e = dual_off[x]; e < dual_off[x + 1u]; e++) {
            let u = nb(e);
            if (labels[u] != a && open(u) && dist[u] + 1u < d) { moving = true; }
        }
    }
    arena[s_cand() + x] = select(0u, 1u, moving);
}

// Triangle x's centroid cell.
fn cell_of(x: u32) -> vec3<u32> {
    return unpack_cell(centres[p.centres_at + 2u * x], centres[p.centres_at + 2u * x + 1u]);
}
// Squared distance from x's centroid cell to the cell of cluster c's medoid.
fn medoid_distance2(x: u32, c: u32) -> u32 {
    return cell_distance2(cell_of(x), cell_of(info[p.medoid_at + c]));
}

@compute @workgroup_size(64)
fn propose(@builtin(global_invocation_id) gid: vec3<u32>) {
    let x = flat(gid);
    if (x >= p.t) { return; }
    arena[s_target() + x] = NONE;
    if (arena[s_cand() + x] == 0u) { return; }
    let a = labels[x];
    let d = dist[x];
    // The nearest neighbour in another cluster that stays, then the lowest cluster, among the
    // clusters whose medoid's cell is no farther from x's than its own medoid's.
    var best_d = NONE;
    var goal = NONE;
    let own = medoid_distance2(x, a);
    for (var e = dual_off[x]; e < dual_off[x + 1u]; e++) {
        let u = nb(e);
        let b = labels[u];
        if (b != a && open(u) && arena[s_cand() + u] == 0u && medoid_distance2(x, b) <= own) {
            let du = dist[u] + 1u;
            if (du < best_d || (du == best_d && b < goal)) {
                best_d = du;
                goal = b;
            }
        }
    }
    if (goal == NONE || best_d >= d) { return; }
    // Every member one level further out keeps a parent that stays.
    for (var e = dual_off[x]; e < dual_off[x + 1u]; e++) {
        let u = nb(e);
        if (labels[u] != a || dist[u] != d + 1u) { continue; }
        var kept = false;
        for (var f = dual_off[u]; f < dual_off[u + 1u]; f++) {
            let w = nb(f);
            if (w != x && labels[w] == a && dist[w] == d && arena[s_cand() + w] == 0u) {
                kept = true;
            }
        }
        if (!kept) { return; }
    }
    var v = vec3<u32>(idx(3u * x), idx(3u * x + 1u), idx(3u * x + 2u));
    var fresh = 0u;
    for (var j = 0u; j < 3u; j++) {
        if ((j > 0u && v[j] == v[0]) || (j > 1u && v[j] == v[1])) { continue; }
        var used = false;
        for (var e = vt_off[v[j]]; e < vt_off[v[j] + 1u]; e++) {
            if (labels[vtn(e)] == goal) { used = true; break; }
        }
        if (!used) { fresh += 1u; }
    }
    // One that cannot fit alone is no demand on its goal.
    if (size(goal) >= p.max_t || ld(c_verts(goal)) + fresh > p.max_v) { return; }
    arena[s_target() + x] = goal;
    arena[s_pdist() + x] = best_d;
    arena[s_pnew() + x] = fresh;
    atomicAdd(&state[c_ask_t(goal)], 1u);
    atomicAdd(&state[c_ask_v(goal)], fresh);
    atomicMax(&state[c_gain(goal)], d - best_d);
}

@compute @workgroup_size(64)
fn pick_best(@builtin(global_invocation_id) gid: vec3<u32>) {
    let x = flat(gid);
    if (x >= p.t) { return; }
    let b = arena[s_target() + x];
    if (b == NONE) { return; }
    if (dist[x] - arena[s_pdist() + x] == ld(c_gain(b))) { atomicMin(&state[c_best(b)], x); }
}

@compute @workgroup_size(64)
fn accept(@builtin(global_invocation_id) gid: vec3<u32>) {
    let x = flat(gid);
    if (x >= p.t) { return; }
    let b = arena[s_target() + x];
    if (b == NONE) { return; }
    let all_fit = size(b) + ld(c_ask_t(b)) <= p.max_t && ld(c_verts(b)) + ld(c_ask_v(b)) <= p.max_v;
    if (!all_fit && ld(c_best(b)) != x) { return; }
    let a = labels[x];
    labels[x] = b;
    dist[x] = arena[s_pdist() + x];
    atomicOr(&state[c_flags(a)], CHANGED);
    atomicOr(&state[c_flags(b)], NOW | CHANGED);
    atomicAdd(&state[h_moved(p.round)], 1u);
}

// Where the shared medoid stores its result.
fn set_medoid(g: u32, m: u32) { info[p.medoid_at + g] = m; }

// Step 5, one invocation per cluster: the paper's medoid of each changed cluster.
@compute @workgroup_size(64)
fn new_medoids(@builtin(global_invocation_id) gid: vec3<u32>) {
    let c = flat(gid);
    if (c >= p.k || (ld(c_flags(c)) & CHANGED) == 0u) { return; }
    atomicAdd(&state[h_changed()], 1u);
    let o = offset(c);
    let span = vec3<u32>(s_list() + o, s_queue() + o, size(c));
    if (!medoid_bits(c, span, o)) { medoid_serial(c, span); }
}

// The paper's medoid of one cluster and its members' hop distances, shared by kmedoids_parallel.wgsl and
// kmedoids_parallel_moves.wgsl (src/gpu/mod.rs puts it after each, `wgsl!`). The CPU reference is
// `local_graph::medoid_of` (`LocalGraph::least_sum_128` for the reach sets). The including
// module declares `labels`, `dist`, `arena` (the member list at `M`, a BFS queue at `Q`), `cstate`
// (9 scratch words per member), `dual_off` with `nb`, and `set_medoid(g, m)`.

// BFS inside cluster `g` (queue at `Q`) from `s` over the members
// whose distance is NONE, starting at `d0`; returns (sum of the distances set, members reached).
fn bfs(g: u32, Q: u32, s: u32, d0: u32) -> vec2<u32> {
    dist[s] = d0;
    arena[Q] = s;
    var ql = 1u;
    var head = 0u;
    var sum = d0;
    while (head < ql) {
        let u = arena[Q + head];
        head += 1u;
        let next = dist[u] + 1u;
        for (var e = dual_off[u]; e < dual_off[u + 1u]; e++) {
            let y = nb(e);
            if (labels[y] == g && dist[y] == NONE) {
                dist[y] = next;
                sum += next;
                arena[Q + ql] = y;
                ql += 1u;
            }
        }
    }
    return vec2<u32>(sum, ql);
}


// Every member's distances from `best`, the medoid (other pieces continue the count from their
// lowest triangle), and the medoid stored. Expects the members' distances at NONE.
fn finish_cluster(g: u32, Q: u32, M: u32, m: u32, best: u32) {
    bfs(g, Q, best, 0u);
    loop {
        var u = NONE;
        var top = 0u;
        for (var j = 0u; j < m; j++) {
            let x = arena[M + j];
            if (dist[x] == NONE) { u = min(u, x); } else { top = max(top, dist[x]); }
        }
        if (u == NONE) { break; }
        bfs(g, Q, u, top + 1u);
    }
    set_medoid(g, best);
}

// medoid_index by one BFS per member, O(m^2 * degree): the clusters medoid_bits does not take.
fn medoid_serial(g: u32, span: vec3<u32>) {
    let M = span.x;
    let Q = span.y;
    let m = span.z;
    var best = NONE;
    var best_sum = NONE;
    for (var i = 0u; i < m; i++) {
        for (var j = 0u; j < m; j++) { dist[arena[M + j]] = NONE; }
        let s = arena[M + i];
        let got = bfs(g, Q, s, 0u);
        // Unreached members count as the member count.
        let sum = got.x + (m - got.y) * m;
        if (sum < best_sum || (sum == best_sum && s < best)) {
            best_sum = sum;
            best = s;
        }
    }
    for (var j = 0u; j < m; j++) { dist[arena[M + j]] = NONE; }
    finish_cluster(g, Q, M, m, best);
}

// medoid_index with 128-bit reach sets (least_sum_128): the medoid of medoid_serial for
// clusters of at most 128 members, each with at most 4 in-cluster neighbours (every manifold
// cluster); `reach_k(i)` is i's set OR its neighbours' `reach_{k-1}`, and i's sum adds
// m - |reach_k(i)| per level until the least sum is decided or no set grows. Its scratch is the
// cluster's corner-state words (free once `grow` is done: 9 per member hold two generations of
// sets and the sums) and its queue words (each member's neighbours, 4 local numbers of 8 bits).
// Returns false, touching nothing the BFS path reads, when the cluster does not fit.
fn medoid_bits(g: u32, span: vec3<u32>, o: u32) -> bool {
    let M = span.x;
    let Q = span.y;
    let m = span.z;
    if (m > 128u) { return false; }
    // Local numbers through the distance words, reset before the final BFS.
    for (var i = 0u; i < m; i++) { dist[arena[M + i]] = i; }
    let S = 9u * o;
    var fits = true;
    for (var i = 0u; i < m; i++) {
        let u = arena[M + i];
        var packed = 0xffffffffu;
        var deg = 0u;
        for (var e = dual_off[u]; e < dual_off[u + 1u]; e++) {
            let y = nb(e);
            if (labels[y] == g) {
                if (deg < 4u) {
                    packed = (packed & ~(0xffu << (8u * deg))) | (dist[y] << (8u * deg));
                }
                deg += 1u;
            }
        }
        if (deg > 4u) { fits = false; }
        arena[Q + i] = packed;
        for (var w = 0u; w < 4u; w++) { cstate[S + 4u * i + w] = select(0u, 1u << (i % 32u), w == i / 32u); }
        cstate[S + 8u * m + i] = 0u;
    }
    if (!fits) {
        for (var i = 0u; i < m; i++) { dist[arena[M + i]] = NONE; }
        return false;
    }
    var cur = S;
    var nxt = S + 4u * m;
    var levels = 0u;
    // least_sum_128's early stop: the least (sum, triangle) among full sets against the least
    // (bound, triangle) among the others; `best` stays NONE if the levels run to the end.
    var best = NONE;
    loop {
        levels += 1u;
        var grew = false;
        var full_sum = NONE;
        var full_s = NONE;
        var bound = NONE;
        var bound_s = NONE;
        for (var i = 0u; i < m; i++) {
            let c = cur + 4u * i;
            var d = vec4<u32>(cstate[c], cstate[c + 1u], cstate[c + 2u], cstate[c + 3u]);
            let before = dot(countOneBits(d), vec4<u32>(1u));
            let acc = cstate[S + 8u * m + i] + m - before;
            cstate[S + 8u * m + i] = acc;
            var after = before;
            if (before != m) {
                let packed = arena[Q + i];
                for (var b = 0u; b < 4u; b++) {
                    let j = (packed >> (8u * b)) & 0xffu;
                    if (j == 0xffu) { break; }
                    let y = cur + 4u * j;
                    d |= vec4<u32>(cstate[y], cstate[y + 1u], cstate[y + 2u], cstate[y + 3u]);
                }
                after = dot(countOneBits(d), vec4<u32>(1u));
                if (after != before) { grew = true; }
            }
            let n = nxt + 4u * i;
            cstate[n] = d.x;
            cstate[n + 1u] = d.y;
            cstate[n + 2u] = d.z;
            cstate[n + 3u] = d.w;
            let s = arena[M + i];
            if (after == m) {
                if (acc < full_sum || (acc == full_sum && s < full_s)) {
                    full_sum = acc;
                    full_s = s;
                }
            } else {
                let lb = acc + m - after;
                if (lb < bound || (lb == bound && s < bound_s)) {
                    bound = lb;
                    bound_s = s;
                }
            }
        }
        let t = cur;
        cur = nxt;
        nxt = t;
        if (full_sum < bound || (full_sum == bound && full_s < bound_s)) {
            best = full_s;
            break;
        }
        if (!grew) { break; }
    }
    let decided = best != NONE;
    var best_sum = NONE;
    for (var i = 0u; i < m; i++) {
        let s = arena[M + i];
        if (!decided) {
            let c = cur + 4u * i;
            let reach = vec4<u32>(cstate[c], cstate[c + 1u], cstate[c + 2u], cstate[c + 3u]);
            let count = dot(countOneBits(reach), vec4<u32>(1u));
            // In pieces: an unreachable member was counted once per level; it counts m instead.
            let missing = m - count;
            let sum = cstate[S + 8u * m + i] - missing * levels + missing * m;
            if (sum < best_sum || (sum == best_sum && s < best)) {
                best_sum = sum;
                best = s;
            }
        }
        dist[s] = NONE;
    }
    finish_cluster(g, Q, M, m, best);
    return true;
}

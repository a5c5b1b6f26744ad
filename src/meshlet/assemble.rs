//! Meshlets from a clustering: one meshlet per non-empty group, its triangles in the order of a
//! key (ties to the lower triangle id), vertices numbered in first-use order. The CPU reference of
//! `wgsl/assemble.wgsl` (`gpu::assemble`), which builds the same arrays on the device.

use super::{Limits, MeshletBuilder, Meshlets};
use crate::mesh::Mesh;
use rayon::prelude::*;

/// Triangles per block of whole groups packed by one task: enough that a task's scratch (one slot
/// per mesh vertex) is set up rarely, few enough that a large mesh spreads over every core.
const BLOCK_TRIANGLES: usize = 32 * 1024;

/// Assembles `groups` groups: `owner[t]` is triangle `t`'s group, `key[t]` its place in it. A
/// group over the limits becomes several meshlets here (the builder flushes when the next
/// triangle does not fit); the device refuses such a group instead, and no strategy that feeds
/// either one makes one. Blocks of groups are packed in parallel and joined in group order, so
/// the output does not depend on the thread count.
pub fn assemble(
    mesh: &Mesh,
    owner: &[u32],
    key: &[u32],
    groups: usize,
    limits: Limits,
) -> Meshlets {
    // Counting sort by group, then each group by (key, id): what the kernels' place and sort do.
    let mut start = vec![0usize; groups + 1];
    for &g in owner {
        start[g as usize + 1] += 1;
    }
    for g in 0..groups {
        start[g + 1] += start[g];
    }
    let mut slot = start.clone();
    let mut members = vec![0u32; owner.len()];
    for (t, &g) in owner.iter().enumerate() {
        members[slot[g as usize]] = t as u32;
        slot[g as usize] += 1;
    }
    // Blocks of whole groups, each with its rows of `members`.
    let mut blocks = Vec::new();
    let (mut rest, mut first) = (members.as_mut_slice(), 0);
    for g in 0..groups {
        if start[g + 1] - start[first] >= BLOCK_TRIANGLES || g + 1 == groups {
            let (rows, tail) = std::mem::take(&mut rest).split_at_mut(start[g + 1] - start[first]);
            blocks.push((first..g + 1, rows));
            (rest, first) = (tail, g + 1);
        }
    }
    let parts: Vec<Meshlets> = blocks
        .into_par_iter()
        .map_init(
            || MeshletBuilder::new(mesh.vertex_count(), limits),
            |b, (range, rows)| {
                let base = start[range.start];
                for g in range {
                    let row = &mut rows[start[g] - base..start[g + 1] - base];
                    row.sort_unstable_by_key(|&t| (key[t as usize], t));
                    for &t in row.iter() {
                        b.push(mesh.triangle(t as usize));
                    }
                    b.flush();
                }
                b.take()
            },
        )
        .collect();
    Meshlets::concat(parts)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate;
    use crate::meshlet::validate;

    #[test]
    fn groups_become_meshlets_in_key_order_with_first_use_vertices() {
        let m = generate::terrain(4, 1);
        let t = m.triangle_count();
        // Even and odd triangles in two groups and a third group left empty; keys descend by id.
        let owner: Vec<u32> = (0..t as u32).map(|i| i % 2).collect();
        let key: Vec<u32> = (0..t as u32).map(|i| t as u32 - i).collect();
        let limits = Limits::new(64, 126).unwrap();
        let ml = assemble(&m, &owner, &key, 3, limits);
        validate(&m, &ml, limits).unwrap();
        // The empty third group makes no meshlet.
        assert_eq!(ml.len(), 2);
        let first = ml.meshlets[0];
        assert_eq!(first.triangle_count as usize, t.div_ceil(2));
        // The first triangle of meshlet 0 is the even one with the largest id; its vertices are
        // local 0, 1, 2 (unless it repeats one).
        let last_even = (t as u32 - 1) & !1;
        let tri = m.triangle(last_even as usize);
        assert_eq!(&ml.vertices[..3], &tri);
        assert_eq!(&ml.triangles[..3], &[0, 1, 2]);
    }

    #[test]
    fn the_parallel_blocks_pack_as_one_builder_does_on_any_thread_count() {
        // Several blocks of groups, with empty groups between, groups over the limits (split by
        // the builder) and keys that reorder every group.
        let m = generate::terrain(200, 3);
        let t = m.triangle_count() as u32;
        assert!(t as usize > 2 * BLOCK_TRIANGLES);
        let groups = 3 * (t as usize).div_ceil(100);
        let owner: Vec<u32> = (0..t)
            .map(|i| 3 * (i / 100) + (i % 7 == 0) as u32)
            .collect();
        let key: Vec<u32> = (0..t).map(|i| i.wrapping_mul(2_654_435_761) >> 8).collect();
        let limits = Limits::new(64, 84).unwrap();
        // One builder over the groups in order: the packing before blocks.
        let mut b = MeshletBuilder::new(m.vertex_count(), limits);
        let mut rows = vec![Vec::new(); groups];
        for i in 0..t {
            rows[owner[i as usize] as usize].push(i);
        }
        for mut row in rows {
            row.sort_unstable_by_key(|&i| (key[i as usize], i));
            for i in row {
                b.push(m.triangle(i as usize));
            }
            b.flush();
        }
        let expected = b.finish();
        validate(&m, &expected, limits).unwrap();
        for threads in [1, 3] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let ml = pool.install(|| assemble(&m, &owner, &key, groups, limits));
            assert_eq!(ml, expected, "{threads} threads");
        }
    }
}

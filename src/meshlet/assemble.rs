//! Meshlets from a clustering: one meshlet per non-empty group, its triangles in the order of a
//! key (ties to the lower triangle id), vertices numbered in first-use order. The CPU reference of
//! `wgsl/assemble.wgsl` (`gpu::assemble`), which builds the same arrays on the device.

use super::{Limits, MeshletBuilder, Meshlets};
use crate::mesh::Mesh;

/// Assembles `groups` groups: `owner[t]` is triangle `t`'s group, `key[t]` its place in it. A
/// group over the limits becomes several meshlets here (the builder flushes when the next
/// triangle does not fit); the device refuses such a group instead, and no strategy that feeds
/// either one makes one.
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
    let mut b = MeshletBuilder::new(mesh.vertex_count(), limits);
    for g in 0..groups {
        let row = &mut members[start[g]..start[g + 1]];
        row.sort_unstable_by_key(|&t| (key[t as usize], t));
        for &t in row.iter() {
            b.push(mesh.triangle(t as usize));
        }
        b.flush();
    }
    b.finish()
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
}

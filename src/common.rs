//! Small helpers that every room of the crate reads: the flat sparse-row array, the "no value"
//! sentinel, a triangle's distinct corners, sorted sets, Morton codes and the one-thread pool.
//! The lowest room: it imports nothing from the crate, so any module may use it without breaking
//! the one-way flow.

/// The sentinel for "no value" in a u32 array (no cluster, no edge, no group, not yet placed):
/// every index the crate stores is below it, since meshes are limited to u32 indices.
pub const NONE: u32 = u32::MAX;

/// Compressed sparse rows: row `r` is `items[offsets[r]..offsets[r + 1]]`.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Csr {
    /// Row starts; `offsets.len() == rows + 1`.
    pub offsets: Vec<u32>,
    /// Concatenated rows.
    pub items: Vec<u32>,
}

impl Csr {
    /// Number of rows.
    pub fn rows(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }

    /// Row `r`.
    #[inline]
    pub fn row(&self, r: usize) -> &[u32] {
        &self.items[self.offsets[r] as usize..self.offsets[r + 1] as usize]
    }

    /// Builds a CSR from (row, item) pairs by count, prefix sum and scatter; pairs keep their input
    /// order within a row, so sorted input gives sorted rows.
    pub fn from_pairs(rows: usize, pairs: impl Iterator<Item = (u32, u32)> + Clone) -> Self {
        let mut offsets = vec![0u32; rows + 1];
        for (r, _) in pairs.clone() {
            offsets[r as usize + 1] += 1;
        }
        for i in 0..rows {
            offsets[i + 1] += offsets[i];
        }
        let mut cursor = offsets.clone();
        let mut items = vec![0u32; offsets[rows] as usize];
        for (r, it) in pairs {
            let c = &mut cursor[r as usize];
            items[*c as usize] = it;
            *c += 1;
        }
        Self { offsets, items }
    }
}

/// Distinct vertices of `tri` in order (a degenerate triangle repeats one).
#[inline]
pub fn distinct(tri: [u32; 3]) -> impl Iterator<Item = u32> {
    let [a, b, c] = tri;
    [
        Some(a),
        (b != a).then_some(b),
        (c != a && c != b).then_some(c),
    ]
    .into_iter()
    .flatten()
}

/// `v` sorted ascending without repeats: a set as the crate keeps one.
pub fn sorted(mut v: Vec<u32>) -> Vec<u32> {
    v.sort_unstable();
    v.dedup();
    v
}

/// Makes `v[start..]` a set as [`sorted`] does, in place: a CSR row appended to its items.
pub fn sort_dedup_tail(v: &mut Vec<u32>, start: usize) {
    v[start..].sort_unstable();
    let mut w = start;
    for r in start..v.len() {
        if r == start || v[r] != v[w - 1] {
            v[w] = v[r];
            w += 1;
        }
    }
    v.truncate(w);
}

/// Size of the union of two sorted sets (as [`sorted`] makes them).
pub fn union_len(a: &[u32], b: &[u32]) -> usize {
    let (mut i, mut j, mut n) = (0, 0, 0);
    while i < a.len() && j < b.len() {
        match a[i].cmp(&b[j]) {
            std::cmp::Ordering::Less => i += 1,
            std::cmp::Ordering::Greater => j += 1,
            std::cmp::Ordering::Equal => {
                i += 1;
                j += 1;
            }
        }
        n += 1;
    }
    n + (a.len() - i) + (b.len() - j)
}

/// A rayon pool of exactly one thread. The benches time one-thread runs in it (the global pool
/// may be wider) and check determinism by comparing its output with a many-thread run's.
pub fn one_thread_pool() -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("a one-thread rayon pool")
}

/// The Morton (Z-order) code of a point quantised to 21 bits per axis: nearby codes are nearby
/// points, so sorting by it gives a locality-preserving order. Inputs above 21 bits are masked.
pub fn morton3(x: u32, y: u32, z: u32) -> u64 {
    fn spread(v: u32) -> u64 {
        let mut v = v as u64 & 0x1f_ffff;
        v = (v | v << 32) & 0x1f_0000_0000_ffff;
        v = (v | v << 16) & 0x1f_0000_ff00_00ff;
        v = (v | v << 8) & 0x100f_00f0_0f00_f00f;
        v = (v | v << 4) & 0x10c3_0c30_c30c_30c3;
        (v | v << 2) & 0x1249_2492_4924_9249
    }
    spread(x) | spread(y) << 1 | spread(z) << 2
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn morton_interleaves_the_low_bits_first() {
        assert_eq!(morton3(1, 0, 0), 1);
        assert_eq!(morton3(0, 1, 0), 2);
        assert_eq!(morton3(0, 0, 1), 4);
        assert_eq!(morton3(3, 0, 0), 0b1001);
        // The top bit of each 21-bit axis, and masking above it.
        assert_eq!(morton3(1 << 20, 0, 0), 1 << 60);
        assert_eq!(morton3(1 << 21, 0, 0), 0);
    }

    #[test]
    fn sets_and_corners() {
        assert_eq!(sorted(vec![3, 1, 3, 2]), vec![1, 2, 3]);
        assert_eq!(union_len(&[1, 2, 5], &[2, 3, 5, 9]), 5);
        assert_eq!(distinct([4, 4, 7]).collect::<Vec<_>>(), vec![4, 7]);
        assert_eq!(distinct([1, 2, 3]).count(), 3);
    }
}

//! The Morton frame and the centroid cells that several k-medoids methods read: the flat
//! method's seed order ([`morton_order`]), the coarse regions' seeds, and the fine cells of
//! `kmedoids-parallel`'s growth key and boundary moves ([`packed_centres`]). CPU reference of
//! `wgsl/morton.wgsl` (driven by `gpu::morton`). Only `+`, `-` and `x` touch a triangle, so every
//! device computes the same keys and cells.

use crate::common::morton3;
use crate::mesh::Mesh;
use rayon::prelude::*;

/// Triangles in the Morton order of their centroids (10 bits per axis over the bounding box's
/// longest side), ties to the lower id.
pub fn morton_order(mesh: &Mesh) -> Vec<u32> {
    let (lo, hi) = mesh.bounding_box();
    let frame = MortonFrame::new(lo, hi);
    // (key, id) pairs are distinct, so the parallel unstable sort has one result.
    let mut keyed: Vec<(u32, u32)> = (0..mesh.triangle_count())
        .into_par_iter()
        .map(|i| {
            let [a, b, c] = mesh.triangle(i).map(|v| mesh.position(v));
            (frame.key(a, b, c), i as u32)
        })
        .collect();
    keyed.par_sort_unstable();
    keyed.into_par_iter().map(|(_, i)| i).collect()
}

/// The frame of the Morton keys, from the mesh's bounding box: a triangle's corner sum minus
/// `lo3`, times `factor`, is its centroid in 0..=1023 along the box's longest side. Only `+`, `-`
/// and `x` touch a triangle, in a fixed order, so `wgsl/morton.wgsl` computes the same keys on
/// any device (the divisions happen once, here, and reach the GPU as these two values).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MortonFrame {
    /// Three times the box's low corner.
    pub lo3: glam::Vec3,
    /// 1023 over three times the box's longest side.
    pub factor: f32,
    /// [`FINE_MAX`] over three times the box's longest side.
    pub fine: f32,
}

/// The largest coordinate of a fine centroid cell ([`MortonFrame::fine_cell`], 15 bits per axis):
/// `kmedoids-parallel`'s growth key. The Morton cells (10 bits) are as large as a triangle of a
/// mesh of some million triangles, and ties in the key then leave clusters less round, so more of
/// them (the bit counts measured are in `docs/gpu-clustering.md`); 15 bits is the most whose
/// squared distances still fit a `u32` (three squares of `2^15 - 1` stay under `2^32`).
/// `wgsl/prelude.wgsl` holds the same value.
pub const FINE_MAX: u32 = (1 << 15) - 1;

impl MortonFrame {
    /// The frame of the box `lo`..`hi`.
    pub fn new(lo: glam::Vec3, hi: glam::Vec3) -> Self {
        let scale = (hi - lo).max_element().max(f32::MIN_POSITIVE);
        Self {
            lo3: lo * 3.0,
            factor: 1023.0 / (3.0 * scale),
            fine: FINE_MAX as f32 / (3.0 * scale),
        }
    }

    /// The fine grid cell (0..=[`FINE_MAX`] per axis) of the centroid of `a`, `b`, `c`: as
    /// [`Self::cell`], with `fine` for the factor.
    pub fn fine_cell(&self, a: glam::Vec3, b: glam::Vec3, c: glam::Vec3) -> [u32; 3] {
        self.quantise(a, b, c, self.fine, FINE_MAX)
    }

    /// The corner sum minus `lo3`, times `factor`, truncated to `0..=top` per axis.
    fn quantise(
        &self,
        a: glam::Vec3,
        b: glam::Vec3,
        c: glam::Vec3,
        factor: f32,
        top: u32,
    ) -> [u32; 3] {
        let q = (((a + b) + c - self.lo3) * factor)
            .clamp(glam::Vec3::ZERO, glam::Vec3::splat(top as f32));
        [q.x as u32, q.y as u32, q.z as u32]
    }

    /// The grid cell (0..=1023 per axis) of the centroid of the triangle `a`, `b`, `c`.
    pub fn cell(&self, a: glam::Vec3, b: glam::Vec3, c: glam::Vec3) -> [u32; 3] {
        self.quantise(a, b, c, self.factor, 1023)
    }

    /// Morton key (30 bits) of the triangle with corners `a`, `b`, `c`.
    pub fn key(&self, a: glam::Vec3, b: glam::Vec3, c: glam::Vec3) -> u32 {
        let [x, y, z] = self.cell(a, b, c);
        morton3(x, y, z) as u32
    }
}

/// A packed centre: `[x | y << 16, z]`, 15 bits per axis.
pub type Centre = [u32; 2];

/// The three coordinates of a packed centre.
pub(crate) fn unpack(c: Centre) -> [u32; 3] {
    [c[0] & 0xffff, c[0] >> 16, c[1]]
}

/// Squared distance between two cells.
pub(crate) fn distance2(a: [u32; 3], b: [u32; 3]) -> u32 {
    (0..3).map(|j| a[j].abs_diff(b[j]).pow(2)).sum()
}

/// Each triangle's fine centroid cell in the Morton frame ([`MortonFrame::fine_cell`], 15 bits
/// per axis along the box's longest side), packed as a [`Centre`]: the geometric term of
/// `kmedoids-parallel`'s growth key and of the boundary moves' rule.
/// Only `+`, `-` and `x` touch a triangle, so `wgsl/morton.wgsl` computes the same words.
pub fn packed_centres(mesh: &Mesh) -> Vec<Centre> {
    let (lo, hi) = mesh.bounding_box();
    let frame = MortonFrame::new(lo, hi);
    (0..mesh.triangle_count())
        .into_par_iter()
        .map(|t| {
            let [a, b, c] = mesh.triangle(t).map(|v| mesh.position(v));
            let [x, y, z] = frame.fine_cell(a, b, c);
            [x | y << 16, z]
        })
        .collect()
}

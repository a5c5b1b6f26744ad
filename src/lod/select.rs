//! Per-meshlet LOD selection (the CMO's `ShouldRenderMeshlet` and `ShouldRenderMeshletStreamed`),
//! the culling tests the selection kernel and the task shader apply with it, and the checks a cut
//! must pass.
//!
//! **The test.** An error `e` with bounds (c, r) is *visible* from a camera at `p` when
//! `e > 0` and `(e * k + r)^2 >= |c - p|^2`, with `k = projection scale / threshold in pixels`:
//! the error, projected from the sphere's nearest possible point, is at least the threshold. A
//! meshlet is drawn when its own error is invisible and its parent's is visible. Because a
//! parent's error is at least its child's and its sphere encloses the child's, "visible" can only
//! switch on going up a DAG path, so exactly one meshlet per path is drawn.
//!
//! **Bit-exact on CPU and GPU.** Vulkan rounds +, - and * exactly, but a shader compiler may fuse
//! `a * b + c` into one FMA (one rounding instead of two), and WGSL cannot forbid it. So every
//! factor of every product is first cut to 12 significant bits ([`trunc12`], a bit mask): the
//! product of two such numbers has at most 24 significant bits and is exact in f32, so fused or
//! not, the result is the same. Sums are evaluated in one fixed order on both sides, comparisons
//! are exact, and values below 2^-40 become 0 so no subnormal (which a GPU may flush) appears. The
//! kernel (`wgsl/select.wgsl`) and the task shader (`glsl/lod.glsl`) spell out the same operations.
//!
//! **Monotonic despite the cut bits.** Truncation moves each factor toward zero by less than
//! 2^-11: a computed "visible" implies `e k + r >= d (1 - 2^-11)` (distance cut once), and
//! `e k + r >= d (1 + 3 * 2^-11)` (error, k and the reach cut) implies a computed "visible", up to
//! f32 rounding (2^-24 per operation). The build pads every group's radius and error by [`PAD`] =
//! 2^-8 (`reach_parent >= (reach_child + centre distance) * (1 + PAD)`), twice the 2^-9 gap
//! between the two, so a visible child still implies a visible parent as computed, and the cut
//! stays crack-free. (2^-8 compounds to about 4 % over a dozen levels where nothing else grows.)
//!
//! **Streaming.** With levels `finest..` loaded, a meshlet of the finest loaded level counts as
//! exact (its children are not there), which again gives one meshlet per path.

use super::{Lod, LodInfo, NO_GROUP};
use crate::meshlet::bounds::Sphere;
use glam::Vec3;

/// A camera for selection: position and `k` = projection scale over the pixel threshold.
#[derive(Clone, Copy, Debug)]
pub struct View {
    /// Camera position.
    pub eye: [f32; 3],
    /// Pixels per unit error at unit distance, over the threshold in pixels
    /// (`height / (2 tan(fov_y / 2)) / threshold`).
    pub k: f32,
}

impl View {
    /// A view for an image `height` pixels high with vertical field of view `fov_y` (radians) and a
    /// threshold of `pixels`.
    pub fn new(eye: Vec3, height: f32, fov_y: f32, pixels: f32) -> Self {
        Self {
            eye: eye.to_array(),
            k: height / (2.0 * (fov_y * 0.5).tan()) / pixels,
        }
    }
}

/// Relative padding of every group's radius and error over what encloses its children (see the
/// module docs): twice the truncation noise of [`visible`].
pub const PAD: f64 = 1.0 / 256.0;

/// `x` cut to 12 significant bits toward zero (sign, exponent and the top 11 stored mantissa
/// bits); magnitudes below 2^-40 (and subnormals) become 0. Products of two cut values are exact
/// in f32. Infinity stays infinity.
#[inline]
pub fn trunc12(x: f32) -> f32 {
    let b = x.to_bits();
    if (b >> 23) & 0xff < 127 - 40 {
        return 0.0;
    }
    f32::from_bits(b & 0xffff_f000)
}

/// `a . b` with cut factors, summed x, y, z in that order: the same bits on every device.
#[inline]
fn dot_exact(a: [f32; 3], b: [f32; 3]) -> f32 {
    let t = trunc12;
    t(a[0]) * t(b[0]) + t(a[1]) * t(b[1]) + t(a[2]) * t(b[2])
}

/// `|a - b|^2` with each difference cut, and the cut differences.
#[inline]
fn dist2_exact(a: [f32; 3], b: [f32; 3]) -> (f32, [f32; 3]) {
    let d = [
        trunc12(a[0] - b[0]),
        trunc12(a[1] - b[1]),
        trunc12(a[2] - b[2]),
    ];
    (d[0] * d[0] + d[1] * d[1] + d[2] * d[2], d)
}

/// Whether error `e` with bounds `s` is visible (see the module docs), in the exact operation order
/// the GPU kernel and the task shader mirror.
pub fn visible(e: f32, s: &Sphere, v: &View) -> bool {
    if e.is_nan() || e <= 0.0 {
        return false;
    }
    if e == f32::INFINITY {
        return true;
    }
    let (d2, _) = dist2_exact(s.center, v.eye);
    let reach = trunc12(trunc12(e) * trunc12(v.k) + s.radius);
    reach * reach >= d2
}

/// Whether a sphere lies entirely outside one of `planes` (`n . x + w >= 0` inside, `n` unit), with
/// a slack of 2^-9 of the magnitudes summed so truncation can only keep a meshlet. Exact as
/// [`visible`] is.
pub fn outside_frustum(s: &Sphere, planes: &[[f32; 4]; 6]) -> bool {
    planes.iter().any(|p| {
        let n = [p[0], p[1], p[2]];
        let t = trunc12;
        let mag = (t(n[0]) * t(s.center[0])).abs()
            + (t(n[1]) * t(s.center[1])).abs()
            + (t(n[2]) * t(s.center[2])).abs()
            + p[3].abs();
        dot_exact(n, s.center) + p[3] + s.radius + mag * (1.0 / 512.0) < 0.0
    })
}

/// The normal-cone backface test (`dot(apex - eye, axis) >= cutoff * |apex - eye|`, as
/// [`crate::meshlet::bounds::Cone::culls`]) in squared form with cut factors, exact as
/// [`visible`] is, with a margin of 2^-6 on the squares so truncation can only keep a meshlet.
pub fn backfacing(apex: [f32; 3], axis: [f32; 3], cutoff: f32, eye: [f32; 3]) -> bool {
    if cutoff.is_nan() || cutoff >= 1.0 {
        return false;
    }
    let (l2, d) = dist2_exact(apex, eye);
    if l2 <= 0.0 {
        return false; // at the apex the direction is undefined
    }
    let a = trunc12(dot_exact(d, axis));
    let c = trunc12(cutoff);
    // cutoff^2 * |d|^2, both factors cut so the product is exact.
    let rhs = trunc12(c * c) * trunc12(l2);
    let margin = rhs * (1.0 / 64.0);
    if c >= 0.0 {
        a > 0.0 && a * a >= rhs + margin
    } else {
        a >= 0.0 || a * a <= rhs - margin
    }
}

/// `ShouldRenderMeshlet`: own error invisible, parent's visible.
pub fn should_render(i: &LodInfo, v: &View) -> bool {
    !visible(i.error, &i.bounds, v) && visible(i.parent_error, &i.parent_bounds, v)
}

/// `ShouldRenderMeshletStreamed`: as [`should_render`], with a meshlet of the finest loaded level
/// (`at_finest`) treated as exact.
pub fn should_render_streamed(i: &LodInfo, at_finest: bool, v: &View) -> bool {
    (at_finest || !visible(i.error, &i.bounds, v)) && visible(i.parent_error, &i.parent_bounds, v)
}

/// The selected meshlets per level (`selected[level][meshlet]`) with levels `finest..` loaded.
pub fn select_cut(lod: &Lod, v: &View, finest: usize) -> Vec<Vec<bool>> {
    lod.levels
        .iter()
        .enumerate()
        .map(|(l, level)| {
            level
                .info
                .iter()
                .map(|i| l >= finest && should_render_streamed(i, l == finest, v))
                .collect()
        })
        .collect()
}

/// Checks that exactly one meshlet is selected on every DAG path from a meshlet of level `finest`
/// to a root. Returns the first offending meshlet (level, index) and its path counts.
pub fn check_cut(lod: &Lod, sel: &[Vec<bool>], finest: usize) -> Result<(), String> {
    // counts[l][m]: bit c set when some path from (l, m) to a root selects c meshlets (c < 64).
    let mut counts: Vec<Vec<u64>> = lod.levels.iter().map(|l| vec![0; l.info.len()]).collect();
    for l in (finest..lod.levels.len()).rev() {
        for m in 0..lod.levels[l].info.len() {
            let i = &lod.levels[l].info[m];
            let above = if i.group == NO_GROUP {
                1u64 // the empty path above a root selects nothing
            } else {
                let g = &lod.groups[i.group as usize];
                let next = &counts[l + 1];
                (g.first..g.first + g.count).fold(0, |acc, p| acc | next[p as usize])
            };
            counts[l][m] = if sel[l][m] { above << 1 } else { above };
        }
    }
    for (m, &c) in counts[finest].iter().enumerate() {
        if c != 0b10 {
            return Err(format!(
                "meshlet {m} of level {finest}: paths to the roots select {:?} meshlets, not exactly 1",
                (0..64).filter(|b| c >> b & 1 == 1).collect::<Vec<_>>()
            ));
        }
    }
    // A selected meshlet above `finest` must lie on some path (it always does: every meshlet of
    // level l > finest is an output of a group of level l - 1).
    Ok(())
}

/// Checks the monotonicity the selection relies on: for every meshlet, parent error >= error and
/// the parent sphere encloses its own (in f64), both with the margin [`PAD`]. Returns the first
/// violation.
pub fn check_monotonic(lod: &Lod) -> Result<(), String> {
    for (l, level) in lod.levels.iter().enumerate() {
        for (m, i) in level.info.iter().enumerate() {
            if i.group == NO_GROUP {
                continue;
            }
            if i.parent_error.is_nan() || (i.parent_error as f64) < i.error as f64 * (1.0 + PAD) {
                return Err(format!(
                    "level {l} meshlet {m}: parent error {} < error {} padded by {PAD}",
                    i.parent_error, i.error
                ));
            }
            let d = (Vec3::from_array(i.parent_bounds.center).as_dvec3()
                - Vec3::from_array(i.bounds.center).as_dvec3())
            .length();
            if (d + i.bounds.radius as f64) * (1.0 + PAD) > i.parent_bounds.radius as f64 {
                return Err(format!(
                    "level {l} meshlet {m}: parent sphere (r {}) does not enclose its own (r {}, {d} apart)",
                    i.parent_bounds.radius, i.bounds.radius
                ));
            }
            // The parents' own data is the group's: the same values, so the same decisions.
            let g = &lod.groups[i.group as usize];
            for p in g.first..g.first + g.count {
                let pi = &lod.levels[l + 1].info[p as usize];
                if pi.bounds != i.parent_bounds || pi.error != i.parent_error {
                    return Err(format!(
                        "level {l} meshlet {m}: parent {p} carries other bounds or error than its group"
                    ));
                }
            }
        }
    }
    Ok(())
}

/// Edges of the selected triangles over welded vertices, for the crack test: for each undirected
/// edge, (uses, uses in the a->b direction).
pub fn cut_edges(
    lod: &Lod,
    sel: &[Vec<bool>],
    remap: &[u32],
) -> std::collections::HashMap<(u32, u32), (u32, u32)> {
    let mut edges = std::collections::HashMap::new();
    for (l, level) in lod.levels.iter().enumerate() {
        for m in (0..level.meshlets.len()).filter(|&m| sel[l][m]) {
            for t in level.meshlets.global_triangles(m) {
                let t = t.map(|v| remap[v as usize]);
                if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
                    continue; // degenerate after welding: no area, no edges
                }
                for k in 0..3 {
                    let (a, b) = (t[k], t[(k + 1) % 3]);
                    let e = edges.entry((a.min(b), a.max(b))).or_insert((0, 0));
                    e.0 += 1;
                    e.1 += (a < b) as u32;
                }
            }
        }
    }
    edges
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Products of cut values are exact (so an FMA cannot change them), and a cut moves a value
    /// by less than 2^-11 of itself.
    #[test]
    fn cut_products_are_exact() {
        let mut s = 0x1234_5678_9abc_def0u64;
        let mut next = || {
            s = crate::mesh::generate::splitmix64(s);
            // Magnitudes 2^-30..2^30, both signs.
            let m = (s >> 40) as f32 / (1u64 << 24) as f32 + 1.0;
            let e = ((s >> 8) & 63) as i32 - 30;
            let sign = if s & 1 == 0 { 1.0 } else { -1.0 };
            sign * m * 2f32.powi(e)
        };
        for _ in 0..100_000 {
            let (a, b) = (next(), next());
            let (ta, tb) = (trunc12(a), trunc12(b));
            assert_eq!((ta * tb) as f64, ta as f64 * tb as f64, "{a} * {b}");
            assert_eq!(ta.mul_add(tb, a), ta * tb + a, "fused and unfused differ");
            assert!(((a - ta) / a).abs() < 1.0 / 2048.0);
            assert!(ta.abs() <= a.abs());
        }
        assert_eq!(trunc12(1e-13), 0.0);
        assert_eq!(trunc12(f32::INFINITY), f32::INFINITY);
    }
}

//! Per-meshlet LOD selection (the CMO's `ShouldRenderMeshlet` and `ShouldRenderMeshletStreamed`) and
//! the checks a cut must pass.
//!
//! **The test.** An error `e` with bounds (c, r) is *visible* from a camera at `p` when
//! `e > 0` and `(e * k + r)^2 >= |c - p|^2`, with `k = projection scale / threshold in pixels`:
//! the error, projected from the sphere's nearest possible point, is at least the threshold. Only
//! +, - and * appear, so a GPU kernel can compute the identical bit pattern (Vulkan rounds only
//! those exactly). A meshlet is drawn when its own error is invisible and its parent's is visible.
//! Because a parent's error is at least its child's and its sphere encloses the child's, "visible"
//! can only switch on going up a DAG path, so exactly one meshlet per path is drawn.
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

/// Whether error `e` with bounds `s` is visible (see the module docs); the exact operation order the
/// GPU kernel will mirror.
pub fn visible(e: f32, s: &Sphere, v: &View) -> bool {
    if e <= 0.0 {
        return false;
    }
    if e == f32::INFINITY {
        return true;
    }
    let dx = s.center[0] - v.eye[0];
    let dy = s.center[1] - v.eye[1];
    let dz = s.center[2] - v.eye[2];
    let d2 = dx * dx + dy * dy + dz * dz;
    let reach = e * v.k + s.radius;
    reach * reach >= d2
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
pub fn select(lod: &Lod, v: &View, finest: usize) -> Vec<Vec<bool>> {
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

/// Checks the monotonicity the selection relies on: for every meshlet, parent error >= error, and
/// the parent sphere encloses its own (in f64). Returns the first violation.
pub fn check_monotonic(lod: &Lod) -> Result<(), String> {
    for (l, level) in lod.levels.iter().enumerate() {
        for (m, i) in level.info.iter().enumerate() {
            if i.group == NO_GROUP {
                continue;
            }
            if i.parent_error.is_nan() || i.parent_error < i.error {
                return Err(format!(
                    "level {l} meshlet {m}: parent error {} < error {}",
                    i.parent_error, i.error
                ));
            }
            let d = (Vec3::from_array(i.parent_bounds.center).as_dvec3()
                - Vec3::from_array(i.bounds.center).as_dvec3())
            .length();
            if d + i.bounds.radius as f64 > i.parent_bounds.radius as f64 {
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

//! Step 7 of `partition`: cone repair. A cell whose normals spread over (almost) a half-space has
//! no backface cone, so it is never culled by one; it hands its most opposed boundary triangles to
//! neighbours (never taking a neighbour's cone away) until its cone can cull, or is rolled back.

use crate::mesh::Mesh;
use crate::meshlet::bounds::{cone_axis, triangle_normal};
use crate::strategy::refine::state::Search;
use glam::DVec3;

/// Step 7's view of the cones: triangle normals and the cone test as `meshlet::bounds` computes
/// them, so a cell found cullable here gets a cone there (up to rounding right at the test's
/// thresholds: the bounds see the normals in another order).
struct Cones<'a> {
    mesh: &'a Mesh,
}

/// Smallest dot product of every normal with the mean normal at which a cell passes without the
/// exact test: the bounds' axis maximises the smallest dot product, and their test asks for more
/// than about 0.0045 (cutoff sqrt(1 - d^2) plus its margin under 1), so this is sure. It spares
/// the smallest-sphere search on most cells (step 7 checks every cell, and that search was a
/// visible share of the partition's time without it).
const SURELY_CULLABLE_DOT: f64 = 0.01;

impl Cones<'_> {
    /// Unit normal of triangle `t`, `None` at zero area.
    fn normal(&self, t: u32) -> Option<DVec3> {
        let p = self
            .mesh
            .triangle(t as usize)
            .map(|v| DVec3::from(self.mesh.positions[v as usize].map(f64::from)));
        triangle_normal(&p)
    }

    /// The mean unit normal of cell `m` (zero where it has none).
    fn mean(&self, s: &Search, m: u32) -> DVec3 {
        s.cells.members[m as usize]
            .iter()
            .filter_map(|&t| self.normal(t))
            .sum::<DVec3>()
            .normalize_or_zero()
    }

    /// Whether cell `m`'s cone can cull. The exact test reads its normals in triangle order, so
    /// the answer does not depend on the order moves left the members in.
    fn culls(&self, s: &Search, m: u32) -> bool {
        let members = &s.cells.members[m as usize];
        let mean = self.mean(s, m);
        let sure = mean != DVec3::ZERO
            && members
                .iter()
                .filter_map(|&t| self.normal(t))
                .all(|n| n.dot(mean) > SURELY_CULLABLE_DOT);
        if sure {
            return true;
        }
        let mut tris = members.clone();
        tris.sort_unstable();
        let normals: Vec<DVec3> = tris.iter().filter_map(|&t| self.normal(t)).collect();
        cone_axis(&normals).is_some()
    }

    /// Whether cell `m` has a triangle of non-zero area (one without has nothing to fix).
    fn has_normals(&self, s: &Search, m: u32) -> bool {
        s.cells.members[m as usize]
            .iter()
            .any(|&t| self.normal(t).is_some())
    }
}

/// Step 7: every cell whose cone cannot cull hands boundary triangles to neighbours, those most
/// opposed to the cell's mean normal first, each to the neighbour whose mean normal is nearest
/// its own; within the limits, the cell staying one piece, never taking a neighbour's cone away.
/// At most a quarter of the cell moves, and a cell that does not become cullable is rolled back.
/// Returns the cells fixed.
pub(super) fn cone_repair(s: &mut Search) -> usize {
    // Candidates tried per step: the most opposed triangles are usually inside the cell or on a
    // full neighbour's border, so a few more than one.
    const TRIES: usize = 8;
    let cones = Cones { mesh: s.cells.mesh };
    let mut fixed = 0;
    for m in 0..s.cells.tcount.len() as u32 {
        // Under 4 triangles the budget below is 0.
        if s.cells.tcount[m as usize] < 4 || !cones.has_normals(s, m) || cones.culls(s, m) {
            continue;
        }
        s.cells.journal = Some(Vec::new());
        let mut budget = s.cells.tcount[m as usize] / 4;
        while budget > 0 && !cones.culls(s, m) {
            budget -= 1;
            let axis = cones.mean(s, m);
            let mut worst: Vec<(f64, u32)> = s.cells.members[m as usize]
                .iter()
                .filter_map(|&t| cones.normal(t).map(|n| (n.dot(axis), t)))
                .collect();
            worst.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            let mut moved = false;
            for &(_, t) in worst.iter().take(TRIES) {
                let (nb, n) = s.cells.neighbour_labels(t);
                let nt = cones.normal(t).expect("a normal");
                let mut to: Vec<(f64, u32)> = nb[..n]
                    .iter()
                    .map(|&b| (-nt.dot(cones.mean(s, b)), b))
                    .collect();
                to.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
                for (_, b) in to {
                    let add = s.cells.added(t, b);
                    if !s.cells.fits(b, add) || !s.stays_connected(t) {
                        continue;
                    }
                    let had = cones.culls(s, b);
                    s.cells.apply(t, b);
                    if had && !cones.culls(s, b) {
                        // Out of the journal first: a rollback journals its own moves.
                        let mut j = s.cells.journal.take().expect("open journal");
                        let last = j.pop().expect("the move just made");
                        s.cells.rollback(&[last]);
                        s.cells.journal = Some(j);
                        continue;
                    }
                    moved = true;
                    break;
                }
                if moved {
                    break;
                }
            }
            if !moved {
                break;
            }
        }
        let journal = s.cells.journal.take().expect("open journal");
        if cones.culls(s, m) {
            fixed += 1;
        } else {
            s.cells.rollback(&journal);
        }
    }
    fixed
}

//! The JCGT paper's bounding-sphere grower (Jensen et al. 2023, §3, Listing 2), and its spatially
//! coherent variant (§6, Figure 11).
//!
//! A meshlet grows one triangle at a time from its border (unused triangles touching it). Each
//! candidate scores +1 per vertex already in the meshlet and +1 if it closes a triangle island (all
//! its edge neighbours are in the meshlet); candidates with only one vertex inside are skipped. Ties
//! go to the candidate that gives the smallest bounding sphere under the incremental (Ritter-style)
//! update, then to the lowest triangle id. When the border is empty, `bsphere` jumps to the next
//! unused vertex of the sorted list and keeps filling the same meshlet; `bsphere-coherent` closes
//! the meshlet instead (more meshlets, tighter and more cullable).
//!
//! The paper's published code has two bugs: a shadowed radius variable (so the sphere never grows)
//! and an assignment used as a comparison. This implements the algorithm as the paper *describes*
//! it: the sphere is updated after every accepted triangle.

use super::{live_counts, mark_used, sorted_vertices, Strategy};
use crate::adjacency::{dual_graph, vertex_triangles, Csr};
use crate::mesh::Mesh;
use crate::meshlet::{Limits, MeshletBuilder, Meshlets};
use glam::DVec3;

/// The bounding-sphere grower.
pub struct BoundingSphere {
    /// Close the meshlet when its border is empty instead of jumping to the next seed.
    pub coherent: bool,
}

impl Strategy for BoundingSphere {
    fn name(&self) -> &'static str {
        if self.coherent {
            "bsphere-coherent"
        } else {
            "bsphere"
        }
    }

    fn summary(&self) -> &'static str {
        if self.coherent {
            "bsphere that closes a meshlet when its border empties: connected, tighter, more cullable meshlets"
        } else {
            "the paper's bounding sphere: grow by shared vertices and island closing, ties to the smallest sphere"
        }
    }

    fn build(&self, mesh: &Mesh, limits: Limits) -> Meshlets {
        let vt = vertex_triangles(mesh);
        let dual = dual_graph(mesh, &vt);
        Grower::new(mesh, &vt, &dual, limits).run(self.coherent)
    }
}

/// Ritter's incremental sphere: the smallest sphere containing the old one and `p`.
#[inline]
pub(crate) fn grow_sphere(c: DVec3, r: f64, p: DVec3) -> (DVec3, f64) {
    let d2 = (p - c).length_squared();
    if d2 <= r * r {
        return (c, r); // inside: no square root needed
    }
    let d = d2.sqrt();
    let nr = (r + d) * 0.5;
    (c + (p - c) * ((nr - r) / d), nr)
}

struct Grower<'a> {
    mesh: &'a Mesh,
    vt: &'a Csr,
    dual: &'a Csr,
    b: MeshletBuilder,
    used: Vec<bool>,
    live: Vec<u32>,
    /// Vertices of t inside the current meshlet, valid when `inside_gen[t] == gen`. Kept
    /// incrementally so that only candidates with two or more vertices inside are ever scanned.
    inside: Vec<u8>,
    inside_gen: Vec<u32>,
    /// `in_meshlet[t] == gen`: t belongs to the current meshlet.
    in_meshlet: Vec<u32>,
    border: Vec<u32>,
    /// Scratch: candidates tied at the best score.
    tied: Vec<u32>,
    gen: u32,
    center: DVec3,
    radius: f64,
}

impl<'a> Grower<'a> {
    fn new(mesh: &'a Mesh, vt: &'a Csr, dual: &'a Csr, limits: Limits) -> Self {
        let t = mesh.triangle_count();
        Self {
            mesh,
            vt,
            dual,
            b: MeshletBuilder::new(mesh.vertex_count(), limits),
            used: vec![false; t],
            live: live_counts(vt),
            inside: vec![0; t],
            inside_gen: vec![u32::MAX; t],
            in_meshlet: vec![u32::MAX; t],
            border: Vec::new(),
            tied: Vec::new(),
            gen: 0,
            center: DVec3::ZERO,
            radius: -1.0,
        }
    }

    fn pos(&self, v: u32) -> DVec3 {
        DVec3::from_array(self.mesh.positions[v as usize].map(f64::from))
    }

    fn add(&mut self, t: u32) {
        let tri = self.mesh.triangle(t as usize);
        for (k, &v) in tri.iter().enumerate() {
            // Distinct vertices only: a degenerate triangle repeats one, and the builder records
            // vertices only at the push below.
            if !tri[..k].contains(&v) && !self.b.contains_vertex(v) {
                let p = self.pos(v);
                (self.center, self.radius) = if self.radius < 0.0 {
                    (p, 0.0)
                } else {
                    grow_sphere(self.center, self.radius, p)
                };
                for &n in self.vt.row(v as usize) {
                    let n = n as usize;
                    if self.used[n] {
                        continue;
                    }
                    if self.inside_gen[n] != self.gen {
                        self.inside_gen[n] = self.gen;
                        self.inside[n] = 0;
                    }
                    self.inside[n] += 1;
                    // Two vertices inside: it becomes a candidate (once).
                    if self.inside[n] == 2 {
                        self.border.push(n as u32);
                    }
                }
            }
        }
        self.b.push(tri);
        self.in_meshlet[t as usize] = self.gen;
        mark_used(self.mesh, t, &mut self.used, &mut self.live);
    }

    /// Radius after adding `tri`'s vertices that are not yet inside.
    fn radius_with(&self, tri: [u32; 3]) -> f64 {
        let (mut c, mut r) = (self.center, self.radius);
        for v in tri {
            if !self.b.contains_vertex(v) {
                (c, r) = if r < 0.0 {
                    (self.pos(v), 0.0)
                } else {
                    grow_sphere(c, r, self.pos(v))
                };
            }
        }
        r
    }

    /// The best border candidate (two or more vertices inside), or `Err(true)` if candidates exist
    /// but none fits (meshlet full), `Err(false)` if there is none.
    fn best(&mut self) -> Result<u32, bool> {
        // Pass 1: scores (cheap). The radius only breaks ties, so it is computed in pass 2 for the
        // top-scoring candidates alone.
        let mut top_score = 0u32;
        let mut blocked = false;
        self.tied.clear();
        let mut i = 0;
        while i < self.border.len() {
            let t = self.border[i];
            if self.used[t as usize] {
                self.border.swap_remove(i);
                continue;
            }
            i += 1;
            let [a, b, c] = self.mesh.triangle(t as usize);
            let distinct = 1 + (b != a) as usize + (c != a && c != b) as usize;
            let inside = self.inside[t as usize] as usize;
            let (tris, verts) = self.b.open_size();
            let limits = self.b.limits();
            if tris >= limits.max_triangles as usize
                || verts + distinct - inside > limits.max_vertices as usize
            {
                blocked = true;
                continue;
            }
            // Island bonus (+1): every edge neighbour is already in this meshlet. Skipped when even
            // the bonus could not reach the current top score.
            let mut score = inside as u32;
            if score + 1 >= top_score
                && self
                    .dual
                    .row(t as usize)
                    .iter()
                    .all(|&n| self.in_meshlet[n as usize] == self.gen)
            {
                score += 1;
            }
            if score > top_score {
                top_score = score;
                self.tied.clear();
            }
            if score == top_score {
                self.tied.push(t);
            }
        }
        // Pass 2: smallest resulting sphere, then lowest triangle id.
        let mut best: Option<(f64, u32)> = None;
        for &t in &self.tied {
            let r = self.radius_with(self.mesh.triangle(t as usize));
            if best.is_none_or(|(br, bt)| r < br || (r == br && t < bt)) {
                best = Some((r, t));
            }
        }
        best.map(|(_, t)| t).ok_or(blocked)
    }

    /// The unused triangle of `v` that fits and gives the smallest sphere (lowest id on ties).
    fn seed_triangle(&self, v: u32) -> Option<u32> {
        let mut best: Option<(f64, u32)> = None;
        for &t in self.vt.row(v as usize) {
            let tri = self.mesh.triangle(t as usize);
            if self.used[t as usize] || !self.b.fits(tri) {
                continue;
            }
            let r = self.radius_with(tri);
            if best.is_none_or(|(br, bt)| r < br || (r == br && t < bt)) {
                best = Some((r, t));
            }
        }
        best.map(|(_, t)| t)
    }

    fn close(&mut self) {
        self.b.flush();
        self.border.clear();
        self.gen += 1;
        self.radius = -1.0;
    }

    fn run(mut self, coherent: bool) -> Meshlets {
        let order = sorted_vertices(self.mesh);
        let mut cursor = 0usize;
        loop {
            match self.best() {
                Ok(t) => self.add(t),
                Err(true) => self.close(),
                Err(false) => {
                    let open = self.b.open_size().0 > 0;
                    if coherent && open {
                        self.close();
                        continue;
                    }
                    while cursor < order.len() && self.live[order[cursor] as usize] == 0 {
                        cursor += 1;
                    }
                    let Some(&seed) = order.get(cursor) else {
                        break;
                    };
                    match self.seed_triangle(seed) {
                        Some(t) => self.add(t),
                        None => self.close(), // the jump does not fit: start the next meshlet there
                    }
                }
            }
        }
        self.b.finish()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ritter_update_contains_both() {
        let (c, r) = grow_sphere(DVec3::ZERO, 1.0, DVec3::new(3.0, 0.0, 0.0));
        assert!((r - 2.0).abs() < 1e-12 && (c.x - 1.0).abs() < 1e-12);
        assert_eq!(
            grow_sphere(DVec3::ZERO, 1.0, DVec3::X * 0.5),
            (DVec3::ZERO, 1.0)
        );
    }
}

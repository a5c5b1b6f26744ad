//! Incremental meshlet assembly shared by the growing strategies: add triangles one at a time,
//! flush when the next one would break a limit.

use super::{Limits, Meshlet, Meshlets};

const UNSET: u32 = crate::common::NONE;

/// Builds a [`Meshlets`] collection triangle by triangle. Local vertex numbers are assigned in
/// first-use order.
pub struct MeshletBuilder {
    limits: Limits,
    out: Meshlets,
    /// Global vertex -> local index in the open meshlet, or UNSET. Reset only for touched vertices.
    local: Vec<u32>,
    open_vertices: usize,
    open_triangles: usize,
}

impl MeshletBuilder {
    /// A builder for a mesh with `vertex_count` vertices.
    pub fn new(vertex_count: usize, limits: Limits) -> Self {
        Self {
            limits,
            out: Meshlets::default(),
            local: vec![UNSET; vertex_count],
            open_vertices: 0,
            open_triangles: 0,
        }
    }

    /// Vertices of `tri` not yet in the open meshlet.
    #[inline]
    pub fn new_vertices(&self, tri: [u32; 3]) -> usize {
        let [a, b, c] = tri;
        (self.local[a as usize] == UNSET) as usize
            + (self.local[b as usize] == UNSET && b != a) as usize
            + (self.local[c as usize] == UNSET && c != a && c != b) as usize
    }

    /// Whether `tri` fits into the open meshlet.
    #[inline]
    pub fn fits(&self, tri: [u32; 3]) -> bool {
        self.open_triangles < self.limits.max_triangles as usize
            && self.open_vertices + self.new_vertices(tri) <= self.limits.max_vertices as usize
    }

    /// Whether vertex `v` is in the open meshlet.
    #[inline]
    pub fn contains_vertex(&self, v: u32) -> bool {
        self.local[v as usize] != UNSET
    }

    /// Global vertices of the open meshlet, in local order.
    pub fn open_vertices(&self) -> &[u32] {
        &self.out.vertices[self.out.vertices.len() - self.open_vertices..]
    }

    /// Whether the open meshlet has reached the triangle limit.
    pub fn triangles_full(&self) -> bool {
        self.open_triangles >= self.limits.max_triangles as usize
    }

    /// Whether the open meshlet has reached the vertex limit.
    pub fn vertices_full(&self) -> bool {
        self.open_vertices >= self.limits.max_vertices as usize
    }

    /// The limits this builder enforces.
    pub fn limits(&self) -> Limits {
        self.limits
    }

    /// Triangles and vertices in the open meshlet.
    pub fn open_size(&self) -> (usize, usize) {
        (self.open_triangles, self.open_vertices)
    }

    /// Adds `tri` to the open meshlet, first flushing it if `tri` does not fit.
    pub fn push(&mut self, tri: [u32; 3]) {
        if !self.fits(tri) {
            self.flush();
        }
        let mut corners = [0u8; 3];
        for (k, &v) in tri.iter().enumerate() {
            if self.local[v as usize] == UNSET {
                self.local[v as usize] = self.open_vertices as u32;
                self.out.vertices.push(v);
                self.open_vertices += 1;
            }
            corners[k] = self.local[v as usize] as u8;
        }
        self.out.triangles.extend_from_slice(&corners);
        self.open_triangles += 1;
    }

    /// Closes the open meshlet (no-op when it is empty).
    pub fn flush(&mut self) {
        if self.open_triangles == 0 {
            return;
        }
        let vertex_offset = (self.out.vertices.len() - self.open_vertices) as u32;
        let triangle_offset = (self.out.triangles.len() - 3 * self.open_triangles) as u32;
        for &v in &self.out.vertices[vertex_offset as usize..] {
            self.local[v as usize] = UNSET;
        }
        self.out.meshlets.push(Meshlet {
            vertex_offset,
            triangle_offset,
            vertex_count: self.open_vertices as u32,
            triangle_count: self.open_triangles as u32,
        });
        self.open_vertices = 0;
        self.open_triangles = 0;
    }

    /// Flushes and returns the collection built so far, leaving the builder empty and reusable
    /// (its vertex-indexed scratch is kept, so a task can pack many blocks with one builder).
    pub fn take(&mut self) -> Meshlets {
        self.flush();
        std::mem::take(&mut self.out)
    }

    /// Flushes and returns the collection.
    pub fn finish(mut self) -> Meshlets {
        self.flush();
        self.out
    }
}

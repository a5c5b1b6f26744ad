//! Topology and quality counts of a mesh: what `meshletlab stats` shows before any meshlet is built.

use super::edges::EdgeTable;
use super::Mesh;

/// Counts that describe a mesh's size, defects and topology. None of these defects are errors: every
/// strategy must still place every triangle.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct MeshStats {
    /// Vertices in the vertex array.
    pub vertices: usize,
    /// Triangles.
    pub triangles: usize,
    /// Vertices that no triangle references.
    pub unreferenced_vertices: usize,
    /// Triangles that repeat a vertex index.
    pub degenerate_triangles: usize,
    /// Triangles with three distinct indices but zero area (collinear or coincident positions).
    pub zero_area_triangles: usize,
    /// Triangles whose vertex set equals an earlier triangle's (either winding).
    pub duplicate_triangles: usize,
    /// Unique undirected edges.
    pub edges: usize,
    /// Edges with exactly one triangle.
    pub boundary_edges: usize,
    /// Edges with more than two triangles.
    pub non_manifold_edges: usize,
    /// Connected components, counted through shared vertices (unreferenced vertices excluded).
    pub components: usize,
}

impl MeshStats {
    /// Computes all counts.
    pub fn of(mesh: &Mesh) -> Self {
        let n = mesh.vertex_count();
        let t = mesh.triangle_count();
        let mut referenced = vec![false; n];
        let mut degenerate = 0;
        let mut zero_area = 0;
        let mut uf = UnionFind::new(n);
        for i in 0..t {
            let [a, b, c] = mesh.triangle(i);
            for v in [a, b, c] {
                referenced[v as usize] = true;
            }
            uf.union(a, b);
            uf.union(b, c);
            if a == b || b == c || a == c {
                degenerate += 1;
            } else if triangle_area2(mesh, [a, b, c]) == 0.0 {
                zero_area += 1;
            }
        }
        let mut sorted: Vec<[u32; 3]> = (0..t)
            .map(|i| {
                let mut k = mesh.triangle(i);
                k.sort_unstable();
                k
            })
            .collect();
        sorted.sort_unstable();
        let duplicates = sorted.windows(2).filter(|w| w[0] == w[1]).count();

        let et = EdgeTable::new(mesh);
        let valences = (0..et.edges.len()).map(|e| et.valence(e));
        let (mut boundary, mut non_manifold) = (0, 0);
        for k in valences {
            boundary += (k == 1) as usize;
            non_manifold += (k > 2) as usize;
        }
        let components = (0..n as u32)
            .filter(|&v| referenced[v as usize] && uf.find(v) == v)
            .count();
        Self {
            vertices: n,
            triangles: t,
            unreferenced_vertices: referenced.iter().filter(|&&r| !r).count(),
            degenerate_triangles: degenerate,
            zero_area_triangles: zero_area,
            duplicate_triangles: duplicates,
            edges: et.edges.len(),
            boundary_edges: boundary,
            non_manifold_edges: non_manifold,
            components,
        }
    }
}

/// Twice the triangle's area, in f64 so that tiny-but-real triangles do not round to zero.
pub(crate) fn triangle_area2(mesh: &Mesh, [a, b, c]: [u32; 3]) -> f64 {
    let p = |v: u32| glam::DVec3::from_array(mesh.positions[v as usize].map(f64::from));
    (p(b) - p(a)).cross(p(c) - p(a)).length()
}

/// Union-find with path halving; the root of a set is its smallest-index member after `union`, which
/// keeps component ids deterministic.
struct UnionFind {
    parent: Vec<u32>,
}

impl UnionFind {
    fn new(n: usize) -> Self {
        Self {
            parent: (0..n as u32).collect(),
        }
    }
    fn find(&mut self, mut v: u32) -> u32 {
        while self.parent[v as usize] != v {
            let p = self.parent[v as usize];
            self.parent[v as usize] = self.parent[p as usize];
            v = p;
        }
        v
    }
    fn union(&mut self, a: u32, b: u32) {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra != rb {
            let (lo, hi) = (ra.min(rb), ra.max(rb));
            self.parent[hi as usize] = lo;
        }
    }
}

//! One region's context for the growth steps of `kmedoids-parallel`: what the steps read
//! (`Region`: the region's dual graph, canonical corners and centroid cells in local numbers,
//! and the limits), the words they change (`State`), and the clusters between the growth and
//! the renumbering (`Clusters`). Each step file takes these three instead of a bundle of
//! arguments; the kernel (`wgsl/kmedoids_parallel.wgsl`) keeps the same words in global arrays.

use super::super::morton::Centre;
use super::NONE;
use crate::common::Csr;
use crate::meshlet::Limits;

/// What a region's steps read, in local numbers: triangle `i` is the region's `i`-th member
/// (ascending), corner `3i + j` its `j`-th corner.
pub(super) struct Region {
    /// Neighbours inside the region.
    dual: Csr,
    /// The canonical corner of each corner's vertex ([`super::canonical_corners`]), local.
    corners: Vec<[usize; 3]>,
    /// Each triangle's packed centroid cell ([`super::super::morton::packed_centres`]).
    pub cells: Vec<Centre>,
    /// Whether no edge of the triangle leaves the region.
    pub inner: Vec<bool>,
    /// The triangles using each canonical corner's vertex (rows of other corners are empty).
    users: Csr,
    /// The vertex limit.
    pub mv: usize,
    /// The triangle limit.
    pub mt: usize,
}

impl Region {
    /// A region from its local arrays; `inner` as [`Region::inner`].
    pub fn new(
        dual: Csr,
        corners: Vec<[usize; 3]>,
        cells: Vec<Centre>,
        inner: Vec<bool>,
        limits: Limits,
    ) -> Self {
        let n = corners.len();
        // Each triangle listed once per distinct vertex, in ascending order.
        let pairs = corners.iter().enumerate().flat_map(|(i, k)| {
            (0..3)
                .filter(|&j| !k[..j].contains(&k[j]))
                .map(move |j| (k[j] as u32, i as u32))
        });
        let users = Csr::from_pairs(3 * n, pairs);
        Self {
            dual,
            corners,
            cells,
            inner,
            users,
            mv: limits.max_vertices as usize,
            mt: limits.max_triangles as usize,
        }
    }

    /// Triangles in the region.
    pub fn len(&self) -> usize {
        self.corners.len()
    }

    /// Neighbours of triangle `i` inside the region, ascending.
    pub fn nbrs(&self, i: usize) -> impl Iterator<Item = usize> + '_ {
        self.dual.row(i).iter().map(|&x| x as usize)
    }

    /// Canonical corners of triangle `i`.
    pub fn corners(&self, i: usize) -> [usize; 3] {
        self.corners[i]
    }

    /// Triangles of the region using the vertex of canonical corner `kk`, ascending.
    pub fn users(&self, kk: usize) -> impl Iterator<Item = usize> + '_ {
        self.users.row(kk).iter().map(|&x| x as usize)
    }
}

/// One region's mutable state, indexed by local triangle (`i`) or local canonical corner
/// (`3i + j`). The kernel keeps the same words in global arrays.
pub(super) struct State {
    /// Cluster of each triangle (`NONE` while free).
    pub label: Vec<u32>,
    /// Cluster that last put the triangle on its frontier.
    pub inq: Vec<u32>,
    /// Hops from the seed, set when put on the frontier.
    pub hop: Vec<u32>,
    /// Free neighbours while on the frontier (the growth key's second term): counted when put on
    /// the frontier and decremented as neighbours are grown, so that choosing the next triangle
    /// does not walk every frontier triangle's neighbours again.
    pub free: Vec<u32>,
    /// Position in the growing cluster (while grown) or the pocket stamp `c + 1` (while free).
    pub aux: Vec<u32>,
    /// Piece of the region's dual graph (the seed order's pieces).
    pub piece: Vec<u32>,
    /// Position in the seed order.
    pub opos: Vec<u32>,
    /// Per corner: the cluster that last used the vertex, and the position in that cluster of
    /// the first triangle using it.
    pub mark: Vec<u32>,
    /// See `mark`.
    pub first: Vec<u32>,
    /// Per corner: the pocket evaluation that last counted the vertex.
    pub wmark: Vec<u32>,
    /// The last stamp handed out for `wmark` (and the front rule's `hop` stamps).
    pub serial: u32,
}

impl State {
    /// A region of `n` triangles before its growth: everything free, no piece found yet.
    pub fn new(n: usize) -> Self {
        Self {
            label: vec![NONE; n],
            inq: vec![NONE; n],
            hop: vec![0; n],
            free: vec![0; n],
            aux: vec![0; n],
            piece: vec![NONE; n],
            opos: vec![0; n],
            mark: vec![NONE; 3 * n],
            first: vec![0; 3 * n],
            wmark: vec![0; 3 * n],
            serial: 0,
        }
    }
}

/// A region's clusters between the growth and the renumbering: members (local indices), distinct
/// vertices, and whether a merge has emptied them.
pub(super) struct Clusters {
    /// Members of each cluster, local indices.
    pub mem: Vec<Vec<usize>>,
    /// Distinct vertices of each cluster.
    pub nverts: Vec<usize>,
    /// Whether the cluster is still there (a merge or a dissolution empties it).
    pub alive: Vec<bool>,
}

impl Clusters {
    /// The survivors renumbered in order; returns their count.
    pub fn renumber(&self, label: &mut [u32]) -> u32 {
        let mut new_id = vec![NONE; self.alive.len()];
        let mut next = 0;
        for (c, &alive) in self.alive.iter().enumerate() {
            if alive {
                new_id[c] = next;
                next += 1;
            }
        }
        for l in label.iter_mut() {
            *l = new_id[*l as usize];
        }
        next
    }

    /// Distinct vertices of the clusters `cs` and the triangles `extra` together (a stamp per
    /// evaluation).
    pub fn vertices(&self, g: &Region, s: &mut State, cs: &[usize], extra: &[usize]) -> usize {
        s.serial += 1;
        let serial = s.serial;
        let mut nv = 0;
        let lists = cs.iter().map(|&c| &self.mem[c][..]).chain([extra]);
        for &i in lists.flatten() {
            for kk in g.corners(i) {
                if s.wmark[kk] != serial {
                    s.wmark[kk] = serial;
                    nv += 1;
                }
            }
        }
        nv
    }
}

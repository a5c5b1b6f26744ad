//! Meshlet strategies: each splits a mesh into meshlets under [`Limits`]. One file per strategy;
//! all are selected by name through [`by_name`], and every output goes through the validator in tests.
//!
//! Determinism: every strategy gives the same meshlets for the same input on every run and thread
//! count.

mod bsphere;
mod compact;
mod greedy;
pub mod kmedoids;
mod meshopt;
mod nvidia;
pub mod parallel;
pub mod qem;
pub mod refine;
pub mod tipsify;

pub use self::meshopt::{Meshopt, MeshoptScan, MeshoptSpatial};
pub use bsphere::{BoundingSphere, BoundingSpherePaper};
pub use compact::Compact;
pub use greedy::{Greedy, GreedyPaper};
pub use kmedoids::KMedoids;
pub use nvidia::Nvidia;
pub use parallel::ParallelGrower;

use crate::mesh::Mesh;
use crate::meshlet::order::{optimize_triangle_order, order_meshlets, MeshletOrder};
use crate::meshlet::{Limits, Meshlets};
use thiserror::Error;

/// A way of splitting a mesh into meshlets.
pub trait Strategy: Send + Sync {
    /// Name as selected on the command line.
    fn name(&self) -> &'static str;
    /// One line on what it optimises, for `--help` and the README.
    fn summary(&self) -> &'static str;
    /// Builds meshlets covering every triangle of `mesh` exactly once within `limits`.
    fn build(&self, mesh: &Mesh, limits: Limits) -> Meshlets;
}

/// Tunables that some strategies read; every field has a sensible default.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Options {
    /// meshoptimizer's cone weight (0..=1): trades meshlet size for tighter normal cones.
    pub cone_weight: f32,
    /// Post-transform cache size that tipsify optimises for (Sander et al. use 12-24).
    pub cache_size: u32,
    /// meshoptimizer's spatial builder fill weight (>= 0): fuller clusters vs. SAH quality.
    pub fill_weight: f32,
    /// k-medoids settings (the mode is set by the strategy name).
    pub kmedoids: kmedoids::Config,
    /// Reorder triangles inside each meshlet for vertex reuse (any strategy).
    pub local_order: bool,
    /// Order of the meshlets in the collection (any strategy).
    pub meshlet_order: MeshletOrder,
}

impl Default for Options {
    fn default() -> Self {
        // Cone weight 0 is the setting the JCGT comparison and our 720-meshlet bunny reference use.
        Self {
            cone_weight: 0.0,
            cache_size: 16,
            fill_weight: 0.5,
            kmedoids: kmedoids::Config::default(),
            local_order: false,
            meshlet_order: MeshletOrder::AsBuilt,
        }
    }
}

/// Appended to any strategy name, these send its output through [`refine`] at an effort level:
/// `meshopt+refine` (full), `meshopt+refine-fast`, `meshopt+refine-max`.
pub const REFINE_SUFFIXES: [(&str, refine::Effort); 3] = [
    ("+refine-fast", refine::Effort::Fast),
    ("+refine-max", refine::Effort::Max),
    ("+refine", refine::Effort::Full),
];

/// Splits a refined name into its base strategy, the effort and the name as a `'static` string
/// (strategy names are `'static`; the refined ones are made once).
fn refined(name: &str) -> Option<(&str, refine::Effort, &'static str)> {
    static REFINED: std::sync::OnceLock<Vec<String>> = std::sync::OnceLock::new();
    let (base, effort) = REFINE_SUFFIXES
        .iter()
        .find_map(|&(suffix, e)| name.strip_suffix(suffix).map(|b| (b, e)))?;
    let all = REFINED.get_or_init(|| {
        NAMES
            .iter()
            .flat_map(|n| REFINE_SUFFIXES.iter().map(move |(s, _)| format!("{n}{s}")))
            .collect()
    });
    let full = all.iter().find(|n| n.as_str() == name)?;
    Some((base, effort, full.as_str()))
}

/// Names accepted by [`by_name`], in table order (each also with one of [`REFINE_SUFFIXES`]).
pub const NAMES: &[&str] = &[
    "nvidia",
    "nvidia+tipsify",
    "greedy",
    "greedy-paper",
    "bsphere",
    "bsphere-paper",
    "bsphere-coherent",
    "bsphere-parallel",
    "kmedoids",
    "kmedoids-paper",
    "compact",
    "meshopt",
    "meshopt-scan",
    "meshopt-spatial",
    "qem",
];

/// Referenced vertices sorted along the mesh's longest bounding-box axis, low to high (ties by
/// index): the paper's seed order for the greedy and bounding-sphere growers.
pub(crate) fn sorted_vertices(mesh: &Mesh) -> Vec<u32> {
    let (lo, hi) = mesh.bounding_box();
    let ext = hi - lo;
    let axis = if ext.x >= ext.y && ext.x >= ext.z {
        0
    } else if ext.y >= ext.z {
        1
    } else {
        2
    };
    let mut referenced = vec![false; mesh.vertex_count()];
    for &i in &mesh.indices {
        referenced[i as usize] = true;
    }
    let mut v: Vec<u32> = (0..mesh.vertex_count() as u32)
        .filter(|&i| referenced[i as usize])
        .collect();
    v.sort_by(|&a, &b| {
        mesh.positions[a as usize][axis]
            .total_cmp(&mesh.positions[b as usize][axis])
            .then(a.cmp(&b))
    });
    v
}

/// Unused-triangle counts per vertex (a degenerate triangle counts once per distinct vertex), kept in
/// step with a `used` flag array by [`mark_used`].
pub(crate) fn live_counts(adj: &crate::adjacency::Csr) -> Vec<u32> {
    (0..adj.rows()).map(|v| adj.row(v).len() as u32).collect()
}

/// Marks triangle `t` used and decrements its distinct vertices' live counts.
pub(crate) fn mark_used(mesh: &Mesh, t: u32, used: &mut [bool], live: &mut [u32]) {
    used[t as usize] = true;
    let tri = mesh.triangle(t as usize);
    for (i, &v) in tri.iter().enumerate() {
        if !tri[..i].contains(&v) {
            live[v as usize] -= 1;
        }
    }
}

/// A name that no strategy answers to.
#[derive(Debug, Error)]
#[error("unknown strategy '{0}' (known: {known}; any of them followed by +refine, +refine-fast or +refine-max)", known = NAMES.join(", "))]
pub struct UnknownStrategy(pub String);

/// Looks a strategy up by name; the ordering options wrap it in a post-pass.
pub fn by_name(name: &str, opts: &Options) -> Result<Box<dyn Strategy>, UnknownStrategy> {
    let inner = match refined(name) {
        Some((base, effort, full_name)) => Box::new(refine::Refined {
            inner: base_by_name(base, opts).map_err(|_| UnknownStrategy(name.to_string()))?,
            config: refine::Config::new(effort),
            name: full_name,
        }),
        None => base_by_name(name, opts)?,
    };
    if !opts.local_order && opts.meshlet_order == MeshletOrder::AsBuilt {
        return Ok(inner);
    }
    Ok(Box::new(Ordered {
        inner,
        local_order: opts.local_order,
        meshlet_order: opts.meshlet_order,
    }))
}

/// A strategy followed by the ordering post-passes (which keep every meshlet's triangle set).
struct Ordered {
    inner: Box<dyn Strategy>,
    local_order: bool,
    meshlet_order: MeshletOrder,
}

impl Strategy for Ordered {
    fn name(&self) -> &'static str {
        self.inner.name()
    }
    fn summary(&self) -> &'static str {
        self.inner.summary()
    }
    fn build(&self, mesh: &Mesh, limits: Limits) -> Meshlets {
        let mut ml = self.inner.build(mesh, limits);
        if self.local_order {
            optimize_triangle_order(&mut ml);
        }
        order_meshlets(&mut ml, self.meshlet_order);
        ml
    }
}

fn base_by_name(name: &str, opts: &Options) -> Result<Box<dyn Strategy>, UnknownStrategy> {
    Ok(match name {
        "nvidia" => Box::new(Nvidia {
            tipsify_cache: None,
        }),
        "nvidia+tipsify" => Box::new(Nvidia {
            tipsify_cache: Some(opts.cache_size),
        }),
        "greedy" => Box::new(Greedy),
        "greedy-paper" => Box::new(GreedyPaper {
            close_on_empty_queue: false,
        }),
        "bsphere-paper" => Box::new(BoundingSpherePaper),
        "bsphere" => Box::new(BoundingSphere { coherent: false }),
        "bsphere-coherent" => Box::new(BoundingSphere { coherent: true }),
        "bsphere-parallel" => Box::new(ParallelGrower {
            spacing: parallel::DEFAULT_SPACING,
        }),
        "compact" => Box::new(Compact),
        "kmedoids" => Box::new(KMedoids {
            config: kmedoids::Config {
                mode: kmedoids::Mode::Fast,
                ..opts.kmedoids
            },
        }),
        "kmedoids-paper" => Box::new(KMedoids {
            config: kmedoids::Config {
                mode: kmedoids::Mode::Paper,
                ..opts.kmedoids
            },
        }),
        "meshopt" => Box::new(Meshopt {
            cone_weight: opts.cone_weight,
        }),
        "meshopt-scan" => Box::new(MeshoptScan),
        "meshopt-spatial" => Box::new(MeshoptSpatial {
            fill_weight: opts.fill_weight,
        }),
        "qem" => Box::new(qem::Qem),
        _ => return Err(UnknownStrategy(name.to_string())),
    })
}

/// Strategies that are slow by design and only run when named (or by `bench kmedoids`).
pub const SLOW: &[&str] = &["kmedoids-paper"];

/// All strategies except the [`SLOW`] ones, in table order.
pub fn all(opts: &Options) -> Vec<Box<dyn Strategy>> {
    NAMES
        .iter()
        .filter(|n| !SLOW.contains(n))
        .map(|n| by_name(n, opts).expect("NAMES are known"))
        .collect()
}

//! Meshlet strategies: each splits a mesh into meshlets under [`Limits`]. One file or folder per
//! strategy family; all are selected by type ([`Kind`]) or by name ([`by_name`]), and every output
//! goes through the validator in tests. Every strategy is one line of the `strategies!` table
//! below (variant, name, summary, constructor): [`NAMES`], [`Kind::ALL`], `--help` and the
//! README's strategy table (checked by a test) follow from it.
//!
//! | family | names | file | GPU kernel (driver, shader) |
//! |---|---|---|---|
//! | the JCGT paper's greedy | `greedy`, `greedy-paper` | `greedy.rs` | |
//! | the paper's bounding sphere | `bsphere`, `bsphere-paper`, `bsphere-coherent` | `bsphere.rs` | |
//! | many bsphere meshlets grown at once | `bsphere-parallel` | [`grow`] | `gpu/grow.rs`, `wgsl/grow.wgsl` |
//! | k-medoids | `kmedoids`, `kmedoids-parallel`, `kmedoids-flat`, `kmedoids-paper` | [`kmedoids`] (a folder: a file per method or shared step; `parallel/` a file per step) | `kmedoids-parallel`: `gpu/kmedoids_parallel.rs`, `wgsl/kmedoids_parallel.wgsl`; `kmedoids-flat`: `gpu/kmedoids_flat.rs`, `wgsl/{assign,update,split}.wgsl` |
//! | NVIDIA's scan | `nvidia`, `nvidia+tipsify` | `nvidia.rs` (tipsify: `mesh::tipsify`) | |
//! | ours: compact, QEM merging | `compact`, `qem` | `compact.rs`, [`qem`] | |
//! | meshoptimizer 1.3 (the peer) | `meshopt`, `meshopt-scan`, `meshopt-spatial` | `meshopt.rs` | |
//! | refinement of any strategy's output | `S+refine`, `S+refine-fast`, `S+refine-max` | [`refine`] | |
//! | re-partition of any strategy's output | `partition`, `S+partition` | [`refine::partition`] (inside `refine/`, whose state it edits) | |
//! | a clustering made elsewhere (per-triangle ids, `--labels`) | none (not a named strategy) | [`labels`] (`labels/mod.rs`; `labels/file.rs`: the label files) | |
//!
//! Determinism: every strategy gives the same meshlets for the same input on every run and thread
//! count.

mod bsphere;
mod compact;
mod greedy;
pub mod grow;
pub mod kmedoids;
pub mod labels;
mod meshopt;
mod nvidia;
pub mod qem;
pub mod refine;

pub use self::meshopt::{Meshopt, MeshoptScan, MeshoptSpatial};
pub use bsphere::{BoundingSphere, BoundingSpherePaper};
pub use compact::Compact;
pub use greedy::{Greedy, GreedyPaper};
pub use grow::ParallelGrower;
pub use kmedoids::KMedoids;
pub use nvidia::Nvidia;

use crate::mesh::Mesh;
use crate::meshlet::order::{optimize_triangle_order, order_meshlets, MeshletOrder};
use crate::meshlet::{Limits, Meshlets};
use thiserror::Error;

/// A way of splitting a mesh into meshlets.
pub trait Strategy: Send + Sync {
    /// Name as selected on the command line.
    fn name(&self) -> &'static str;
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
    /// k-medoids tunables (the method itself, [`kmedoids::Mode`], comes from the strategy name).
    pub kmedoids: kmedoids::Config,
    /// Reorder triangles inside each meshlet for vertex reuse
    /// ([`optimize_triangle_order`]); every strategy made from these options applies it
    /// ([`Kind::strategy`], [`Kind::refined`], [`Kind::partitioned`], [`by_name`]). `meshopt`'s
    /// meshlets come optimised by meshoptimizer already.
    pub local_order: bool,
    /// Order of the meshlets in the collection ([`order_meshlets`]); applied as `local_order` is.
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

/// Appended to a strategy name, this sends its output through [`partition`](refine::partition):
/// `greedy+partition`.
pub const PARTITION_SUFFIX: &str = "+partition";

/// Splits a `+partition` name into its base strategy and the name as a `'static` string; `None`
/// for an unknown base and for `partition` itself (`meshopt+partition` builds what `partition`
/// does).
fn partitioned(name: &str) -> Option<(&str, &'static str)> {
    static NAMED: std::sync::OnceLock<Vec<String>> = std::sync::OnceLock::new();
    let base = name.strip_suffix(PARTITION_SUFFIX)?;
    let all = NAMED.get_or_init(|| {
        NAMES
            .iter()
            .filter(|&&n| n != "partition")
            .map(|n| format!("{n}{PARTITION_SUFFIX}"))
            .collect()
    });
    let full = all.iter().find(|n| n.as_str() == name)?;
    Some((base, full.as_str()))
}

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
#[error("unknown strategy '{0}'{hint} (known: {known}; any of them followed by +refine, +refine-fast or +refine-max, or by +partition)", hint = retired_hint(&self.0), known = NAMES.join(", "))]
pub struct UnknownStrategy(pub String);

/// ` (<the way on>)` for a retired name (also with a suffix), else nothing.
fn retired_hint(name: &str) -> String {
    let base = name.split('+').next().unwrap_or(name);
    RETIRED
        .iter()
        .find(|(n, _)| *n == base)
        .map_or(String::new(), |(_, hint)| format!(" ({hint})"))
}

/// Looks a strategy up by name, with every option in `opts` applied. The typed way to the same
/// strategies is [`Kind::strategy`], [`Kind::refined`] and [`Kind::partitioned`].
pub fn by_name(name: &str, opts: &Options) -> Result<Box<dyn Strategy>, UnknownStrategy> {
    let unknown = || UnknownStrategy(name.to_string());
    Ok(match refined(name) {
        Some((base, effort, _)) => Kind::from_name(base)
            .ok_or_else(unknown)?
            .refined(effort, opts),
        None => match partitioned(name) {
            Some((base, _)) => Kind::from_name(base)
                .and_then(|k| k.partitioned(opts))
                .ok_or_else(unknown)?,
            None => Kind::from_name(name).ok_or_else(unknown)?.strategy(opts),
        },
    })
}

/// Wraps `inner` in the ordering post-passes that `opts` asks for ([`Options::local_order`],
/// [`Options::meshlet_order`]); returns it unchanged when they ask for none. The strategies this
/// module makes have them already: this is for a [`Strategy`] of one's own.
pub fn with_order(inner: Box<dyn Strategy>, opts: &Options) -> Box<dyn Strategy> {
    if !opts.local_order && opts.meshlet_order == MeshletOrder::AsBuilt {
        return inner;
    }
    Box::new(Ordered {
        inner,
        local_order: opts.local_order,
        meshlet_order: opts.meshlet_order,
    })
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
    fn build(&self, mesh: &Mesh, limits: Limits) -> Meshlets {
        let mut ml = self.inner.build(mesh, limits);
        if self.local_order {
            optimize_triangle_order(&mut ml);
        }
        order_meshlets(&mut ml, self.meshlet_order);
        ml
    }
}

/// The strategy table: one line per strategy, `Variant => "name", "summary", |opts| constructor;`
/// (with the variant's doc above it). Writes [`Kind`], [`Kind::ALL`], [`NAMES`],
/// [`Kind::name`], [`Kind::summary`] and [`Kind::strategy`].
macro_rules! strategies {
    ($($(#[$doc:meta])* $kind:ident => $name:literal, $summary:literal, |$o:ident| $make:expr;)*) => {
        /// Every strategy, by type: what an engine names instead of a string. `Kind::ALL[i].name()`
        /// is `NAMES[i]`, and [`by_name`] goes through this enum.
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
        pub enum Kind {
            $($(#[$doc])* $kind,)*
        }

        impl Kind {
            /// Every kind, in table order.
            pub const ALL: [Kind; [$($name),*].len()] = [$(Kind::$kind),*];

            /// The name the command line and the files use.
            pub fn name(self) -> &'static str {
                match self {
                    $(Kind::$kind => $name,)*
                }
            }

            /// One line on what it optimises, for `--help` and the README.
            pub fn summary(self) -> &'static str {
                match self {
                    $(Kind::$kind => $summary,)*
                }
            }

            /// The strategy with the tunables in `opts` it reads, before the ordering options.
            fn bare(self, opts: &Options) -> Box<dyn Strategy> {
                match self {
                    $(Kind::$kind => {
                        let $o = opts;
                        Box::new($make)
                    })*
                }
            }
        }

        /// Names accepted by [`by_name`], in table order (each also with one of
        /// [`REFINE_SUFFIXES`] or [`PARTITION_SUFFIX`]).
        pub const NAMES: &[&str] = &[$($name),*];
    };
}

/// A k-medoids strategy: `mode` with the settings in `opts`.
fn kmedoids_with(mode: kmedoids::Mode, opts: &Options) -> KMedoids {
    KMedoids {
        mode,
        config: opts.kmedoids,
    }
}

strategies! {
    /// [`Nvidia`] without tipsify.
    Nvidia => "nvidia",
        "NVIDIA's scan of the index buffer as given: fastest, quality follows the input order",
        |_o| Nvidia { tipsify_cache: None };
    /// [`Nvidia`] over a tipsify-ordered index buffer.
    NvidiaTipsify => "nvidia+tipsify",
        "tipsify vertex-cache order, then the NVIDIA scan: cheap, and better locality than raw order",
        |o| Nvidia { tipsify_cache: Some(o.cache_size) };
    /// [`Greedy`].
    Greedy => "greedy",
        "the paper's greedy: BFS over vertices from a spatially sorted seed, free triangles added when vertex-bound",
        |_o| Greedy;
    /// [`GreedyPaper`].
    GreedyPaper => "greedy-paper",
        "greedy as the paper's published code runs it: meshlets close only when full (may be disconnected)",
        |_o| GreedyPaper { close_on_empty_queue: false };
    /// [`BoundingSphere`].
    Bsphere => "bsphere",
        "the paper's bounding sphere: grow by shared vertices and island closing, ties to the smallest sphere",
        |_o| BoundingSphere { coherent: false };
    /// [`BoundingSpherePaper`].
    BspherePaper => "bsphere-paper",
        "bsphere as the paper's published code runs it: ties to scan order, island bonus for any meshlet",
        |_o| BoundingSpherePaper;
    /// [`BoundingSphere`], connected growth only.
    BsphereCoherent => "bsphere-coherent",
        "bsphere that closes a meshlet when its border empties: connected, tighter, more cullable meshlets",
        |_o| BoundingSphere { coherent: true };
    /// [`ParallelGrower`].
    BsphereParallel => "bsphere-parallel",
        "many bsphere meshlets grown at once from grid seeds, conflicts by atomic claims (CPU reference of the GPU grower)",
        |_o| ParallelGrower { spacing: grow::DEFAULT_SPACING };
    /// [`KMedoids`], sequential (clusters grown to the limits, nothing split).
    Kmedoids => "kmedoids",
        "k-medoids whose clusters grow to the limits and take triangles only while they have room",
        |o| kmedoids_with(kmedoids::Mode::Sequential, o);
    /// [`KMedoids`] on regions at once, every step a kernel (the same on the GPU).
    KmedoidsParallel => "kmedoids-parallel",
        "k-medoids on regions of the mesh at once, each grown by integer keys (the same on the GPU)",
        |o| kmedoids_with(kmedoids::Mode::Parallel, o);
    /// [`KMedoids`], flat: nearest-medoid assignment, overflowing clusters split and the mesh
    /// re-clustered (what the GPU's flat kernels run).
    KmedoidsFlat => "kmedoids-flat",
        "k-medoids on the triangle dual graph (hop distance), overflowing clusters split a fraction at a time",
        |o| kmedoids_with(kmedoids::Mode::Flat, o);
    /// [`KMedoids`] as the paper runs it (slow by design).
    KmedoidsPaper => "kmedoids-paper",
        "k-medoids as the paper runs it: one cluster added and everything re-run per overflow",
        |o| kmedoids_with(kmedoids::Mode::Paper, o);
    /// [`Compact`].
    Compact => "compact",
        "ours: fewest new vertices (dangling triangles free), island closing, nearest to centroid, corner-first seeds",
        |_o| Compact;
    /// [`Meshopt`] (meshoptimizer's `build_meshlets`). Its output has already been through
    /// meshoptimizer's per-meshlet triangle optimisation (`meshopt_optimizeMeshlet`), so
    /// [`Options::local_order`] on top gains little vertex reuse for its time.
    Meshopt => "meshopt",
        "meshoptimizer 1.3 build_meshlets: the peer; adjacency- and distance-driven greedy growth",
        |o| Meshopt { cone_weight: o.cone_weight };
    /// [`MeshoptScan`].
    MeshoptScan => "meshopt-scan",
        "meshoptimizer vertex-cache order, then its index-buffer scan (its analogue of nvidia+tipsify)",
        |_o| MeshoptScan;
    /// [`MeshoptSpatial`].
    MeshoptSpatial => "meshopt-spatial",
        "meshoptimizer spatial builder: SAH-optimal clusters (for ray tracing), min = max triangles",
        |o| MeshoptSpatial { fill_weight: o.fill_weight };
    /// [`qem::Qem`].
    Qem => "qem",
        "hierarchical face clustering (Garland et al. 2001): cheapest merge of plane fit plus irregularity first (Mlakar et al. 2024, §3.1)",
        |_o| qem::Qem;
    /// [`refine::partition::Partitioned`] over [`Meshopt`].
    Partition => "partition",
        "meshoptimizer's meshlets (or any strategy's), re-partitioned globally by balanced Lloyd and packed along ejection chains (fewer meshlets)",
        |o| refine::partition::Partitioned {
            inner: Kind::Meshopt.strategy(o),
            config: refine::partition::Config::default(),
            name: "partition",
        };
}

/// Names that no longer build anything, each with the way on (the unknown-strategy error says
/// it).
pub const RETIRED: &[(&str, &str)] = &[("kmedoids-tiled", "retired: use kmedoids-parallel")];

impl Kind {
    /// The kind named `name` (without a refine suffix).
    pub fn from_name(name: &str) -> Option<Kind> {
        NAMES.iter().position(|&n| n == name).map(|i| Kind::ALL[i])
    }

    /// The strategy followed by [`partition`](refine::partition), named e.g. `greedy+partition`
    /// (`partition` is `meshopt+partition`); `None` for [`Kind::Partition`].
    /// Every option in `opts` applies: the ordering ones to the partitioned output.
    pub fn partitioned(self, opts: &Options) -> Option<Box<dyn Strategy>> {
        let (_, name) = partitioned(&format!("{}{PARTITION_SUFFIX}", self.name()))?;
        let partitioned = Box::new(refine::partition::Partitioned {
            inner: self.bare(opts),
            config: refine::partition::Config::default(),
            name,
        });
        Some(with_order(partitioned, opts))
    }

    /// The strategy, with every option in `opts` applied: the tunables it reads, then the
    /// ordering post-passes ([`Options::local_order`], [`Options::meshlet_order`]).
    pub fn strategy(self, opts: &Options) -> Box<dyn Strategy> {
        with_order(self.bare(opts), opts)
    }

    /// The strategy followed by [`refine`] at `effort`, named e.g. `meshopt+refine`; every option
    /// in `opts` applies, the ordering ones to the refined output.
    pub fn refined(self, effort: refine::Effort, opts: &Options) -> Box<dyn Strategy> {
        let suffix = REFINE_SUFFIXES
            .iter()
            .find(|&&(_, e)| e == effort)
            .map_or("", |&(s, _)| s);
        let (_, _, name) =
            refined(&format!("{}{suffix}", self.name())).expect("every kind has every suffix");
        let refined = Box::new(refine::Refined {
            inner: self.bare(opts),
            config: refine::Config::new(effort),
            name,
        });
        with_order(refined, opts)
    }
}

impl std::str::FromStr for Kind {
    type Err = UnknownStrategy;
    fn from_str(s: &str) -> Result<Self, UnknownStrategy> {
        Kind::from_name(s).ok_or_else(|| UnknownStrategy(s.to_string()))
    }
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kinds_and_names_agree() {
        assert_eq!(Kind::ALL.len(), NAMES.len());
        let opts = Options::default();
        for (i, k) in Kind::ALL.into_iter().enumerate() {
            assert_eq!(k.name(), NAMES[i]);
            assert_eq!(Kind::from_name(NAMES[i]), Some(k));
            assert_eq!(k.strategy(&opts).name(), NAMES[i]);
            for (suffix, effort) in REFINE_SUFFIXES {
                let by_type = k.refined(effort, &opts);
                let by_string = by_name(&format!("{}{suffix}", NAMES[i]), &opts).unwrap();
                assert_eq!(by_type.name(), by_string.name());
                assert_eq!(by_type.name(), format!("{}{suffix}", NAMES[i]));
            }
        }
        assert!("meshopt2".parse::<Kind>().is_err());
        assert!(by_name("meshopt+refine+refine", &opts).is_err());
    }

    #[test]
    fn retired_names_are_unknown_with_the_way_on() {
        let opts = Options::default();
        for (name, hint) in RETIRED {
            assert!(Kind::from_name(name).is_none());
            for full in [name.to_string(), format!("{name}+refine")] {
                let e = by_name(&full, &opts).err().expect("retired").to_string();
                assert!(
                    e.starts_with(&format!("unknown strategy '{full}' ({hint})")),
                    "{e}"
                );
            }
        }
        let e = by_name("kmedoids-x", &opts)
            .err()
            .expect("unknown")
            .to_string();
        assert!(
            e.starts_with("unknown strategy 'kmedoids-x' (known: "),
            "{e}"
        );
    }

    #[test]
    fn typed_and_named_strategies_build_the_same_meshlets() {
        let mesh = crate::mesh::generate::terrain(14, 3);
        let limits = Limits::new(64, 84).unwrap();
        let opts = Options {
            local_order: true,
            meshlet_order: MeshletOrder::Triangles,
            ..Options::default()
        };
        for k in [
            Kind::Greedy,
            Kind::Meshopt,
            Kind::Kmedoids,
            Kind::KmedoidsFlat,
        ] {
            let typed = k.strategy(&opts).build(&mesh, limits);
            let named = by_name(k.name(), &opts).unwrap().build(&mesh, limits);
            assert_eq!(typed, named, "{}", k.name());
            crate::meshlet::validate(&mesh, &typed, limits).unwrap();
            // The options act: the typed strategy is the bare one followed by both passes.
            let mut by_hand = k.strategy(&Options::default()).build(&mesh, limits);
            assert_ne!(
                typed,
                by_hand,
                "{}: the ordering options did nothing",
                k.name()
            );
            optimize_triangle_order(&mut by_hand);
            order_meshlets(&mut by_hand, opts.meshlet_order);
            assert_eq!(typed, by_hand, "{}", k.name());
        }
        let partitioned = Kind::Greedy.partitioned(&opts).unwrap();
        let named = by_name("greedy+partition", &opts).unwrap();
        assert_eq!(partitioned.build(&mesh, limits), named.build(&mesh, limits));
        let refined = Kind::Greedy.refined(refine::Effort::Fast, &opts);
        let named = by_name("greedy+refine-fast", &opts).unwrap();
        assert_eq!(refined.build(&mesh, limits), named.build(&mesh, limits));
    }
}

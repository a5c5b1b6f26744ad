//! `--labels`, `--meshlets` and `--split`: a clustering made elsewhere (numpy, a partitioner,
//! another engine's builder) in place of a strategy, in every command that builds meshlets.

use crate::mesh::Mesh;
use crate::meshlet::{Limits, Meshlets};
use crate::strategy::labels::{self, file::read_labels};
use anyhow::Result;
use clap::Args;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// A clustering made elsewhere, in place of `--strategy`.
#[derive(Args, Debug, Clone, Default)]
pub struct ClusterArgs {
    /// Clusters made elsewhere, in place of --strategy: one id per triangle in the order the mesh
    /// loads, as text (one non-negative integer a line) or a numpy .npy of any integer type; each
    /// distinct id is one meshlet (gaps allowed).
    #[arg(long, value_name = "FILE", conflicts_with = "meshlets")]
    pub labels: Option<PathBuf>,
    /// Meshlets made elsewhere, in place of --strategy: an .npz in meshoptimizer's layout
    /// (`meshlets`: M x 4 vertex offset, triangle offset, vertex count, triangle count;
    /// `vertices`; `triangles`: three u8 corners each) or a meshlet file from `build`.
    #[arg(long, value_name = "FILE")]
    pub meshlets: Option<PathBuf>,
    /// With --labels or --meshlets: divide each cluster over --limits with meshopt (on its own
    /// triangles) instead of refusing it.
    #[arg(long)]
    pub split: bool,
}

/// Meshlets from [`ClusterArgs`].
pub struct Imported {
    /// `labels:FILE` or `meshlets:FILE` (the file's name), the row name in tables.
    pub name: String,
    /// The meshlets, within the limits.
    pub meshlets: Meshlets,
    /// Clusters or meshlets in the file.
    pub clusters: usize,
    /// How many of them `--split` divided.
    pub split: usize,
    /// Milliseconds to read the file and pack it (or to build, for a strategy).
    pub ms: f64,
}

impl ClusterArgs {
    /// The file given, if any.
    pub fn file(&self) -> Option<&Path> {
        self.labels.as_deref().or(self.meshlets.as_deref())
    }

    /// The row name: `labels:NAME` or `meshlets:NAME`.
    pub fn name(&self) -> Option<String> {
        let kind = if self.labels.is_some() {
            "labels"
        } else {
            "meshlets"
        };
        self.file().map(|f| {
            let n = f
                .file_name()
                .map(|n| n.to_string_lossy())
                .unwrap_or_default();
            format!("{kind}:{n}")
        })
    }

    /// `--split` alone is a usage error; so is a strategy chosen beside a file, where the
    /// command takes one or the other (`strategy_given`), and a file where the command builds on
    /// the GPU (`on_gpu`).
    pub fn check(&self, strategy_given: bool, on_gpu: bool) -> Result<()> {
        if self.split && self.file().is_none() {
            return Err(super::usage(
                "--split divides clusters of --labels or --meshlets; give one",
            ));
        }
        if on_gpu && self.file().is_some() {
            return Err(super::usage(
                "--device gpu builds with a strategy, not with --labels or --meshlets",
            ));
        }
        if strategy_given && self.file().is_some() {
            return Err(super::usage(
                "--strategy builds the meshlets; --labels and --meshlets bring them: give one",
            ));
        }
        Ok(())
    }

    /// The meshlets of the file, for `mesh` under `limits` (`None` without a file). Errors name
    /// the file.
    pub fn import(&self, mesh: &Mesh, limits: Limits) -> Result<Option<Imported>> {
        let (Some(path), Some(name)) = (self.file(), self.name()) else {
            return Ok(None);
        };
        let at = |e: labels::LabelsError| anyhow::anyhow!("{}: {e}", path.display());
        let t0 = Instant::now();
        let (meshlets, clusters, split) = if self.labels.is_some() {
            let ids = read_labels(path, mesh.triangle_count())?;
            let c = labels::from_labels(mesh, &ids, limits, self.split).map_err(at)?;
            (c.meshlets, c.clusters, c.split)
        } else {
            let ml = crate::meshlet::npz::load_meshlets(path, mesh)?;
            let n = ml.len();
            let (ml, split) = labels::split_meshlets(mesh, ml, limits, self.split).map_err(at)?;
            (ml, n, split)
        };
        crate::meshlet::validate(mesh, &meshlets, limits)
            .map_err(|e| anyhow::anyhow!("{}: invalid meshlets: {e}", path.display()))?;
        Ok(Some(Imported {
            name,
            meshlets,
            clusters,
            split,
            ms: t0.elapsed().as_secs_f64() * 1e3,
        }))
    }
}

impl Imported {
    /// What `--split` did, for a command's summary line ("" when nothing was divided).
    pub fn split_note(&self) -> String {
        match self.split {
            0 => String::new(),
            n => format!(
                " ({n} of {} clusters split by meshopt to fit)",
                self.clusters
            ),
        }
    }
}

/// An instanced scene has no one triangle order a file could follow.
pub fn refuse_instanced(path: &Path, what: &str) -> anyhow::Error {
    anyhow::anyhow!(
        "{}: an instanced scene has one triangle list per mesh; {what} take one mesh (bake the scene or give its meshes one at a time)",
        path.display()
    )
}

/// The meshlets a command works on, validated: the file's when one is given, else `strategy`'s
/// build (named by the strategy, nothing split).
pub fn meshlets_or_build(
    m: &Mesh,
    path: &Path,
    strategy: &str,
    args: &super::StrategyArgs,
    c: &ClusterArgs,
) -> Result<Imported> {
    if let Some(i) = c.import(m, args.limits)? {
        return Ok(i);
    }
    let t0 = Instant::now();
    let meshlets = super::build_validated(m, path, strategy, args)?;
    Ok(Imported {
        name: strategy.to_string(),
        clusters: meshlets.len(),
        split: 0,
        meshlets,
        ms: t0.elapsed().as_secs_f64() * 1e3,
    })
}

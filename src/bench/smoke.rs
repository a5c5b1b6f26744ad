//! Smoke runs of the benchmarks (`meshletlab bench ... --smoke`): tiny generated meshes and one
//! run, so every table and plot writer runs in seconds (`make test` runs each bench this way and
//! checks its results file). Nothing a smoke run writes is a measurement; it goes to a folder
//! other than results/.

use crate::mesh::{generate, save_ply, Mesh};
use anyhow::{bail, Context, Result};
use std::path::{Path, PathBuf};

/// The first smoke mesh's file stem: the mesh of a bench that takes a single one.
pub const FIRST: &str = "sphere";

/// The smoke meshes, by file stem: a closed noisy sphere, a torus-knot tube and an open terrain,
/// each under 1,300 triangles. The first is the one a bench that takes a single mesh uses.
pub fn meshes() -> Vec<(&'static str, Mesh)> {
    vec![
        (FIRST, generate::noisy_sphere(3, 0.2, 1)),
        ("knot", generate::knot_tube(48, 10, 2)),
        ("terrain", generate::terrain(20, 3)),
    ]
}

/// The folder of the smoke meshes inside a smoke run's output folder `out`: `out/smoke-meshes`.
pub fn dir(out: &Path) -> PathBuf {
    out.join("smoke-meshes")
}

/// The folder the smoke meshes are written to inside `out` ([`dir`]), written. Refuses `results`
/// itself, so a smoke run never overwrites reported tables.
pub fn prepare(out: &Path) -> Result<PathBuf> {
    if out.file_name().is_some_and(|n| n == "results") {
        bail!(
            "{}: --smoke writes throwaway tables, never into results: give --out another folder",
            out.display()
        );
    }
    let dir = dir(out);
    std::fs::create_dir_all(&dir).with_context(|| format!("{}: cannot create", dir.display()))?;
    for (name, m) in meshes() {
        save_ply(&m, &dir.join(format!("{name}.ply")))?;
    }
    Ok(dir)
}

/// The single mesh of a smoke run (the first of [`meshes`]) in a folder made by [`prepare`].
pub fn first(dir: &Path) -> (String, PathBuf) {
    (FIRST.to_string(), dir.join(format!("{FIRST}.ply")))
}

//! `meshletlab lod-check`: validate a LOD file against its mesh, and its cuts over random views.

use super::load;
use crate::lod::{io::LodFile, select};
use anyhow::{bail, Result};
use clap::Args;
use std::path::PathBuf;

/// Arguments of `lod-check`.
#[derive(Args, Debug)]
pub struct LodCheckArgs {
    /// Mesh file the LOD was built from.
    mesh: PathBuf,
    /// LOD file written by `meshletlab lod`.
    file: PathBuf,
    /// Random views (distances 0.5-64 radii, thresholds 0.25-8 pixels) whose cuts are checked, each
    /// also for every streaming prefix of levels.
    #[arg(long, default_value_t = 200, value_parser = clap::value_parser!(u32).range(1..=100_000))]
    views: u32,
}

pub(super) fn run(a: LodCheckArgs, quiet: bool) -> Result<()> {
    let f = LodFile::load(&a.file)?;
    let m = load(&a.mesh, quiet)?;
    f.check(&m, &a.file)?;
    let (lo, hi) = m.bounding_box();
    let (c, r) = ((lo + hi) * 0.5, ((hi - lo).length() * 0.5).max(1e-6));
    let mut cuts = 0;
    let views = a.views as usize;
    for (i, dir) in crate::mesh::generate::random_directions(views, 1)
        .into_iter()
        .enumerate()
    {
        // Deterministic spread of distances and thresholds over the views.
        let u = (i as f32 + 0.5) / views as f32;
        let w = ((i * 7919) % views) as f32 / views as f32;
        let v = select::View::new(
            c + dir * r * 0.5 * 128f32.powf(u),
            crate::render::HEIGHT as f32,
            60f32.to_radians(),
            0.25 * 32f32.powf(w),
        );
        for finest in 0..f.lod.levels.len() {
            let sel = select::select_cut(&f.lod, &v, finest);
            if let Err(e) = select::check_cut(&f.lod, &sel, finest) {
                bail!("{}: view {i}, levels {finest}..: {e}", a.file.display());
            }
            cuts += 1;
        }
    }
    say!(
        "{}: valid — {} levels, {} meshlets, {} groups ({} stuck), {} root(s); level 0 validated against {}; errors and bounds monotonic; {cuts} cuts ({} views x every streaming prefix) select exactly one meshlet per DAG path",
        a.file.display(),
        f.lod.levels.len(),
        f.lod.meshlet_count(),
        f.lod.groups.len(),
        f.lod.stuck_groups(),
        f.lod.roots(),
        a.mesh.display(),
        a.views
    );
    Ok(())
}

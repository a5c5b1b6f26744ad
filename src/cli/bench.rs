//! `meshletlab bench ...`: the benchmarks that write results/. Each bench's arguments are its
//! configuration (`bench::<x>::Config`, or `Args` where a library caller builds the `Config`), so
//! this file only adds what the command owns: the global `--quiet`, the default mesh folder, the
//! strategy options of `bench build`, and the line saying what was written.

use super::{default_meshes_dir, load, spinner, StrategyArgs};
use crate::bench::{self, Common};
use anyhow::{bail, Context as _, Result};
use clap::Subcommand;

/// Benchmarks.
#[derive(Subcommand, Debug)]
pub enum BenchCommand {
    /// Every mesh x strategy: time (median), meshlet count, fills, culling, radius -> build.md, build.csv.
    Build {
        /// The bench's own arguments.
        #[command(flatten)]
        bench: bench::build::Args,
        /// Limits and strategy options.
        #[command(flatten)]
        args: StrategyArgs,
    },
    /// GPU kernels against their CPU references (bunny, igea, dragon, dragon x4 and x16) -> gpu.md.
    Gpu(bench::gpu::Config),
    /// Mesh shaders against the vertex pipeline on every shared mesh: ms per frame with and without
    /// task-shader culling, culled shares, ns per triangle, bunny images -> render.md.
    Render(bench::render::Config),
    /// GPU/CPU agreement and conservative bounds on a mesh translated, scaled, flattened, with
    /// duplicate vertices and a huge coordinate range -> stability.md.
    Stability(bench::stability::Config),
    /// Paper fidelity: greedy and bounding sphere on the bunny as the paper's text describes them,
    /// as its published code runs them, and with one of the code's traits reverted, at 64/126 and
    /// the code's 64/125, beside the paper's Tables 4, 7, 8 -> fidelity.md, fidelity.csv.
    Fidelity(bench::fidelity::Args),
    /// k-medoids at scale (fast and paper modes, every mesh) and a run-time-vs-error sweep -> kmedoids.md.
    Kmedoids(bench::kmedoids::Config),
    /// Cluster LOD: our DAG beside meshoptimizer's clod_build(clod_default_config(128)) on every
    /// shared mesh: build time on 1 and 2 threads, levels, roots, stuck groups, per-level ratios,
    /// triangles selected and frame time against camera distance at a 1-pixel threshold, the best
    /// level-0 strategy, the dragon at 14 M triangles -> lod.md, lod.csv, lod_levels.csv,
    /// lod_curve.csv, plots.
    Lod(bench::lod::Config),
    /// Compressed meshlets: laced wires and meshoptimizer's codec on every shared mesh and a
    /// multi-mesh scene, at the paper's 14-bit tolerance and at 1e-4 of the diagonal: bytes per
    /// triangle split by kind, errors, duplication, encode/decode speed on 1 and 2 threads, the
    /// paper's Figure 8 (bits per vertex against error) -> compress.md, compress.csv,
    /// compress_fig8.csv, plots.
    Compress(bench::compress::Config),
    /// Compressed meshlets drawn from their encoded bytes (laced wires, SC/IX/GI/TS compact)
    /// against the uncompressed split layout and the vertex pipeline, per shared mesh and on a
    /// multi-mesh scene: bytes resident, ms per frame, the targets' ratios, size against speed
    /// -> compress-render.md, compress-render.csv, compress_render_tradeoff.svg.
    CompressRender(bench::compress_render::Config),
    /// Mutation fuzzer over every file reader (PLY ASCII/LE/BE, OBJ, glTF, GLB, .zst, meshlet
    /// files): >= 1 M seeded cases in child processes; panics, hangs and allocations over the bound
    /// are counted -> robustness.md, robustness.csv. Exit 1 if any case is a defect.
    Robustness(bench::robustness::Config),
}

/// What the command adds to a bench's common arguments: the global `--quiet` and the default
/// mesh folder.
fn complete(c: &mut Common, quiet: bool) -> Result<()> {
    c.quiet = quiet;
    c.meshes.get_or_insert_with(default_meshes_dir);
    // A long run must not end on a folder it cannot write.
    super::output::check_dir(&c.out)
}

pub(super) fn run(cmd: BenchCommand, q: bool) -> Result<()> {
    match cmd {
        BenchCommand::Stability(mut c) => {
            complete(&mut c.common, q)?;
            let (mesh, path) = c.common.mesh_file(&c.mesh)?;
            let m = load(&path, q)?;
            let pb = spinner(q, format!("stress variants of {mesh}"));
            let reports =
                bench::stability::run(&mesh, &m, c.limits, &c.common.out, c.common.smoke)?;
            pb.finish_and_clear();
            let bad: Vec<_> = reports.iter().filter(|r| !r.ok()).map(|r| r.name).collect();
            let md = c.common.out.join("stability.md");
            say!("wrote {}", md.display());
            if !bad.is_empty() {
                bail!(
                    "{}: stability checks failed for: {}",
                    md.display(),
                    bad.join(", ")
                );
            }
            Ok(())
        }
        BenchCommand::Gpu(mut c) => {
            complete(&mut c.common, q)?;
            bench::gpu::run(&c)?;
            say!(
                "wrote {}",
                c.common.out.join(c.tag.name("gpu.md")).display()
            );
            Ok(())
        }
        BenchCommand::Render(mut c) => {
            complete(&mut c.common, q)?;
            bench::render::run(&c)?;
            say!(
                "wrote {}",
                c.common.out.join(c.tag.name("render.md")).display()
            );
            Ok(())
        }
        BenchCommand::Fidelity(mut a) => {
            complete(&mut a.common, q)?;
            let cfg = a.config()?;
            bench::fidelity::run(&cfg)?;
            say!("wrote {}", cfg.out.join("fidelity.md").display());
            Ok(())
        }
        BenchCommand::Kmedoids(mut c) => {
            complete(&mut c.common, q)?;
            bench::kmedoids::run(&c)?;
            say!(
                "wrote {}",
                c.common.out.join(c.tag.name("kmedoids.md")).display()
            );
            Ok(())
        }
        BenchCommand::Build { mut bench, args } => {
            complete(&mut bench.common, q)?;
            let cfg = bench.config(args.limits, args.options())?;
            let rows = bench::build::run(&cfg)?;
            say!(
                "wrote {} and {} ({} rows)",
                cfg.out.join("build.md").display(),
                cfg.out.join("build.csv").display(),
                rows.len()
            );
            Ok(())
        }
        BenchCommand::Lod(mut c) => {
            complete(&mut c.common, q)?;
            bench::lod::run(&c)?;
            say!(
                "wrote {}",
                c.common.out.join(c.tag.name("lod.md")).display()
            );
            Ok(())
        }
        BenchCommand::Compress(mut c) => {
            complete(&mut c.common, q)?;
            let rows = bench::compress::run(&c)?;
            say!(
                "wrote {} ({} encodings)",
                c.common.out.join("compress.md").display(),
                rows.len()
            );
            Ok(())
        }
        BenchCommand::CompressRender(mut c) => {
            complete(&mut c.common, q)?;
            let rows = bench::compress_render::run(&c)?;
            say!(
                "wrote {} ({} rows)",
                c.common
                    .out
                    .join(c.tag.name("compress-render.md"))
                    .display(),
                rows.len()
            );
            Ok(())
        }
        BenchCommand::Robustness(mut c) => {
            if let Some(k) = c.dump {
                // Created if missing; errors name the folder first (an I/O error alone does not).
                super::output::check_dir(&c.output)?;
                let p = crate::fuzz::harness::dump(c.seed, k, &c.output)
                    .with_context(|| format!("{}: cannot write", c.output.display()))?;
                say!("case {k} of seed {} -> {}", c.seed, p.display());
                return Ok(());
            }
            c.quiet = q;
            super::output::check_dir(&c.out)?;
            let report = bench::robustness::run(&c)?;
            let t = report.totals();
            say!(
                "{} cases in {:.0} s: {} valid, {} typed errors, {} defects; wrote {}",
                report.cases,
                report.seconds,
                t.get(crate::fuzz::harness::Verdict::Valid),
                t.get(crate::fuzz::harness::Verdict::Error),
                t.defects(),
                c.out.join("robustness.md").display()
            );
            if t.defects() > 0 {
                bail!(
                    "{}: {} fuzz cases were defects (listed there)",
                    c.out.join("robustness.md").display(),
                    t.defects()
                );
            }
            Ok(())
        }
    }
}

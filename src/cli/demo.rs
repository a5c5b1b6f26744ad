//! `meshletlab demo`: the whole pipeline on generated meshes (or --mesh files) in about a minute:
//! every strategy compared; adjacency, k-medoids and the other GPU kernels beside their CPU
//! references with the parity verdict; a mesh-shader render with culling statistics and a
//! meshlet-coloured PNG; the same meshlets as laced wires drawn from their compressed bytes; a
//! glTF of the meshlets.

use super::{describe, evaluate_all, fail_on_invalid, load, StrategyArgs};
use crate::bench::metrics_table;
use crate::mesh::{generate, Mesh, MeshStats};
use crate::render::{Camera, Context, Pass, Pipeline, Shading, HEIGHT, WIDTH};
use crate::strategy;
use anyhow::{Context as _, Result};
use clap::Args;
use std::path::{Path, PathBuf};

/// Arguments of `demo`.
#[derive(Args, Debug)]
pub struct DemoArgs {
    /// Use these mesh files instead of the generated set (repeatable).
    #[arg(long)]
    mesh: Vec<PathBuf>,
    /// Seed of the generated meshes.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Folder for the PNG and the glTF the demo writes (created; checked writable before the
    /// run). They are named by the rendered mesh: `NAME_meshopt.png` and `.glb`, NAME the file
    /// name without its extensions (`bunny.ply.zst` -> `bunny`), `-2`, `-3`, ... added where
    /// `--mesh` files share a name.
    #[arg(long, default_value = "demo-output")]
    out: PathBuf,
    /// Only the CPU strategy table.
    #[arg(long)]
    no_gpu: bool,
    #[command(flatten)]
    args: StrategyArgs,
}

/// A demo mesh: its label in the text, the stem its files are named by, the mesh.
struct DemoMesh {
    label: String,
    stem: String,
    mesh: Mesh,
}

pub(super) fn run(a: DemoArgs, quiet: bool) -> Result<()> {
    if !a.no_gpu {
        super::output::check_dir(&a.out)?;
    }
    let meshes: Vec<DemoMesh> = if a.mesh.is_empty() {
        generate::demo_set(a.seed)
            .into_iter()
            .map(|g| DemoMesh {
                label: g.name.to_string(),
                stem: g.name.to_string(),
                mesh: g.mesh,
            })
            .collect()
    } else {
        let paths: Vec<&Path> = a.mesh.iter().map(PathBuf::as_path).collect();
        a.mesh
            .iter()
            .zip(super::output::stems(&paths))
            .map(|(p, stem)| {
                Ok(DemoMesh {
                    label: p.display().to_string(),
                    stem,
                    mesh: load(p, quiet)?,
                })
            })
            .collect::<Result<_>>()?
    };
    say!(
        "== 1/3 Strategies: every strategy on {} (limits {}; every output validated) ==\n",
        if a.mesh.is_empty() {
            format!("generated meshes (seed {}); --mesh FILE for yours", a.seed)
        } else {
            "your meshes".to_string()
        },
        a.args.limits
    );
    strategy_tables(&meshes, &a.args, quiet)?;
    if a.no_gpu {
        return Ok(());
    }
    // The GPU parts use the smallest mesh: lavapipe runs on the same two cores.
    let smallest = meshes
        .iter()
        .min_by_key(|d| d.mesh.triangle_count())
        .expect("at least one mesh");
    let (name, m) = (&smallest.label, &smallest.mesh);
    say!(
        "\n== 2/3 GPU compute: each kernel beside its CPU reference on {name} ({} triangles) ==\n",
        m.triangle_count()
    );
    let gpu = match crate::gpu::Gpu::new() {
        Ok(g) => g,
        Err(e) => {
            say!(
                "No Vulkan adapter ({e}); skipping the GPU parts. The CPU part above is complete."
            );
            return Ok(());
        }
    };
    say!("GPU: {}", gpu.describe());
    say!("(Wall-clock times, uploads, readbacks and first-use shader compilation included; `bench gpu` measures steady state.)");
    let checks = crate::gpu::parity::run(&gpu, m, a.args.limits)
        .with_context(|| format!("{name}: GPU run failed"))?
        .checks;
    super::parity::print_checks(&checks);
    super::parity::verdict(Path::new(name), &checks)?;
    say!(
        "Parity: all {} GPU kernels identical to their CPU references.",
        checks.len()
    );
    say!("\n== 3/3 Mesh shaders: task-shader culling and a meshlet-coloured image of {name} ==\n");
    render(smallest, &a)
}

fn strategy_tables(meshes: &[DemoMesh], args: &StrategyArgs, quiet: bool) -> Result<()> {
    let list = strategy::all(&args.options());
    let mut totals: Vec<(String, usize)> = list.iter().map(|s| (s.name().to_string(), 0)).collect();
    for DemoMesh {
        label: name,
        mesh: m,
        ..
    } in meshes
    {
        say!("{}", describe(name, &MeshStats::of(m)));
        let rows = evaluate_all(m, &list, args.limits, 3, name, quiet);
        say!("{}\n", metrics_table(&rows));
        fail_on_invalid(&rows, name)?;
        for (t, r) in totals.iter_mut().zip(&rows) {
            t.1 += r.metrics.meshlets;
        }
    }
    let reference = totals
        .iter()
        .find(|t| t.0 == "meshopt")
        .map(|t| t.1)
        .unwrap_or(1)
        .max(1);
    say!(
        "Total meshlets over {} meshes (fewer is better; relative to meshopt):",
        meshes.len()
    );
    for (n, c) in &totals {
        say!("  {n:<16} {c:>8}  {:>6.3}", *c as f64 / reference as f64);
    }
    say!("\nAll outputs validated: every triangle exactly once, limits respected.");
    Ok(())
}

fn render(d: &DemoMesh, a: &DemoArgs) -> Result<()> {
    const STRATEGY: &str = "meshopt";
    let (name, m) = (d.label.as_str(), &d.mesh);
    let ml = super::build_validated(m, Path::new(name), STRATEGY, &a.args)?;
    let ctx = match Context::new(false) {
        Ok(c) => c,
        Err(e) => {
            say!("No mesh-shader device ({e}); skipping the render.");
            return Ok(());
        }
    };
    let pass = Pass::new(&ctx, m, &ml)?;
    let aspect = WIDTH as f32 / HEIGHT as f32;
    let cam = Camera::framed_views(m, 1, 1, aspect, crate::render::FRAME_FILL)[0];
    let cull = Pipeline::mesh(true);
    // First frame warms up caches and pipelines; the second is measured.
    pass.render(&cam, cull, Shading::Lit)?;
    let f = pass.render(&cam, cull, Shading::Lit)?;
    let all = pass.render(&cam, Pipeline::mesh(false), Shading::Lit)?;
    let v = pass.render(&cam, Pipeline::Vertex, Shading::Lit)?;
    let n = ml.len().max(1) as f64;
    say!(
        "{name}, {} {STRATEGY} meshlets on {}: the task shader culled {:.1} % of meshlets by the frustum and {:.1} % by their normal cones ({} of {} triangles skipped).",
        ml.len(),
        ctx.name,
        100.0 * f.culled_frustum as f64 / n,
        100.0 * f.culled_cone as f64 / n,
        f.culled_triangles[0] + f.culled_triangles[1],
        m.triangle_count()
    );
    say!(
        "GPU time per frame: mesh shaders {:.2} ms with culling, {:.2} ms without; vertex pipeline {:.2} ms.",
        f.gpu_ns * 1e-6,
        all.gpu_ns * 1e-6,
        v.gpu_ns * 1e-6
    );
    compressed(&ctx, m, &ml, &pass, &cam)?;
    let png = a.out.join(format!("{}_{STRATEGY}.png", d.stem));
    crate::render::write_meshlet_png(&pass, &cam, true, &png)?;
    let glb = a.out.join(format!("{}_{STRATEGY}.glb", d.stem));
    crate::atomic::write(&glb, crate::meshlet::export::glb(m, &ml))
        .with_context(|| format!("{}: cannot write", glb.display()))?;
    say!(
        "Wrote {} (meshlet-coloured, culled meshlets absent) and {} (open it in any glTF viewer).",
        png.display(),
        glb.display()
    );
    Ok(())
}

/// The same meshlets as laced wires, drawn from their compressed bytes by the mesh shader and
/// compared with the uncompressed pass over the CPU-decoded meshlets.
fn compressed(
    ctx: &Context,
    m: &Mesh,
    ml: &crate::meshlet::Meshlets,
    split: &Pass,
    cam: &Camera,
) -> Result<()> {
    use crate::compress::Codec;
    use crate::render::compressed::{decoded_reference, prepare};
    let enc = match Codec::LacedWires.encode(m, ml, crate::compress::paper_tolerance(m)) {
        Ok(e) => e,
        Err(e) => {
            say!("Laced wires skipped: {e}.");
            return Ok(());
        }
    };
    let up = prepare(&enc, Codec::LacedWires)?;
    let pass = Pass::compressed(ctx, &up)?;
    let (rm, rml) = decoded_reference(&enc, Codec::LacedWires)?;
    let reference = Pass::new(ctx, &rm, &rml)?;
    let ids = Pipeline::mesh_ids(false);
    let same = pass.render(cam, ids, Shading::Lit)?.pixels
        == reference.render(cam, ids, Shading::Lit)?.pixels;
    // The first frame compiles the pipeline; the second is measured.
    pass.render(cam, Pipeline::mesh(true), Shading::Lit)?;
    let f = pass.render(cam, Pipeline::mesh(true), Shading::Lit)?;
    let tris = m.triangle_count().max(1) as f64;
    say!(
        "Compressed: laced wires hold {:.2} bytes per triangle on the device (uncompressed split: {:.2}); the mesh shader decodes them in {:.2} ms per frame with culling; image {} the CPU-decoded reference.",
        up.device_bytes() as f64 / tris,
        split.device_bytes() as f64 / tris,
        f.gpu_ns * 1e-6,
        if same { "identical to" } else { "DIFFERENT from" }
    );
    if !same {
        anyhow::bail!("the laced-wires image differs from its CPU-decoded reference");
    }
    Ok(())
}

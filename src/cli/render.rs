//! `meshletlab render`: task + mesh shaders beside the vertex pipeline from seeded random views.

use super::{build_validated, load, StrategyArgs};
use crate::meshlet::descriptor::Format;
use crate::render::{Camera, Context, Pass, Pipeline, Shading, HEIGHT, WIDTH};
use anyhow::{bail, Context as _, Result};
use clap::Args;
use std::path::PathBuf;

/// Arguments of `render`.
#[derive(Args, Debug)]
pub struct RenderArgs {
    /// Mesh file.
    mesh: PathBuf,
    /// Strategy name.
    #[arg(short, long, default_value = "meshopt")]
    strategy: String,
    /// Views (random directions around the mesh, the paper's protocol).
    #[arg(long, default_value_t = 5)]
    views: usize,
    /// Seed of the view sequence (the same for every strategy).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Camera distance from the mesh centre in bounding radii (half the box diagonal). Default:
    /// each view framed so the mesh fills most of the image.
    #[arg(long)]
    distance: Option<f32>,
    /// No task-shader culling.
    #[arg(long)]
    no_cull: bool,
    /// Meshlet descriptor layout on the GPU: split (exact bounds), nvidia-a, nvidia-b
    /// (quantised bounds), monolithic (per-meshlet vertex copies).
    #[arg(short, long, default_value = "split", value_parser = clap::value_parser!(Format))]
    descriptor: Format,
    /// Write the first view, coloured by meshlet (the paper's Figure 1), to this PNG.
    #[arg(short, long = "output", visible_alias = "png", value_name = "PNG")]
    output: Option<PathBuf>,
    /// Enable the Khronos validation layer and fail on any error it reports.
    #[arg(long)]
    validate: bool,
    /// Print JSON (mesh, device, bytes, one object per view) instead of text.
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    args: StrategyArgs,
}

/// One view's measurements.
#[derive(serde::Serialize)]
struct ViewRow {
    view: usize,
    distance_radii: f32,
    mesh_ms: f64,
    vertex_ms: f64,
    meshlets_culled_frustum: u32,
    meshlets_culled_backface: u32,
    meshlets_drawn: u32,
    mesh_primitives_generated: Option<u64>,
}

pub(super) fn run(a: RenderArgs, quiet: bool) -> Result<()> {
    let name = &a.strategy;
    crate::strategy::by_name(name, &a.args.options())?;
    let m = load(&a.mesh, quiet)?;
    let ml = build_validated(&m, &a.mesh, name, &a.args)?;
    let ctx = Context::new(a.validate)?;
    let pass = Pass::with_format(&ctx, &m, &ml, a.descriptor)
        .with_context(|| format!("{}: {name}", a.mesh.display()))?;
    let bytes_per_triangle = pass.device_bytes() as f64 / m.triangle_count().max(1) as f64;
    if !a.json {
        println!(
            "{}: {} triangles, {name}: {} meshlets, {} descriptors: {bytes_per_triangle:.1} bytes per triangle; device: {}",
            a.mesh.display(),
            m.triangle_count(),
            ml.len(),
            a.descriptor,
            ctx.name
        );
    }
    let cull = !a.no_cull;
    let how = Pipeline::Mesh {
        frustum: cull,
        cone: cull,
        colour_ids: false,
    };
    let aspect = WIDTH as f32 / HEIGHT as f32;
    let views = match a.distance {
        Some(d) => Camera::random_views(&m, a.views, a.seed, d),
        None => Camera::framed_views(&m, a.views, a.seed, aspect, crate::render::FRAME_FILL),
    };
    let (lo, hi) = m.bounding_box();
    let radius = ((hi - lo).length() * 0.5).max(1e-6);
    let mut rows = Vec::new();
    for (i, cam) in views.iter().enumerate() {
        let f = pass.render(cam, how, Shading::Lit)?;
        let v = pass.render(cam, Pipeline::Vertex, Shading::Lit)?;
        let row = ViewRow {
            view: i,
            distance_radii: (cam.eye - cam.target).length() / radius,
            mesh_ms: f.gpu_ns * 1e-6,
            vertex_ms: v.gpu_ns * 1e-6,
            meshlets_culled_frustum: f.culled_frustum,
            meshlets_culled_backface: f.culled_cone,
            meshlets_drawn: f.drawn,
            mesh_primitives_generated: f.queries.map(|q| q.primitives),
        };
        if !a.json {
            let pct = |x: u32| 100.0 * x as f64 / ml.len().max(1) as f64;
            let prims = row
                .mesh_primitives_generated
                .map(|p| format!("  mesh primitives generated {p}"))
                .unwrap_or_default();
            println!(
                "view {i} ({:.2} radii): mesh shaders {:8.3} ms  vertex pipeline {:8.3} ms  culled: frustum {:5.1} %  backface {:5.1} %{prims}",
                row.distance_radii,
                row.mesh_ms,
                row.vertex_ms,
                pct(f.culled_frustum),
                pct(f.culled_cone)
            );
        }
        rows.push(row);
        if i == 0 {
            if let Some(p) = &a.output {
                crate::render::write_meshlet_png(&pass, cam, cull, p)?;
            }
        }
    }
    let validation_errors = ctx.validation.as_ref().map(|v| v.errors());
    if a.json {
        let out = serde_json::json!({
            "mesh": a.mesh.display().to_string(),
            "triangles": m.triangle_count(),
            "strategy": name,
            "limits": a.args.limits.to_string(),
            "meshlets": ml.len(),
            "descriptor": a.descriptor.to_string(),
            "device_bytes_per_triangle": bytes_per_triangle,
            "device": ctx.name,
            "culling": cull,
            "png": a.output.as_ref().map(|p| p.display().to_string()),
            "validation_errors": validation_errors.as_ref().map(|e| e.0),
            "views": rows,
        });
        println!("{}", serde_json::to_string_pretty(&out)?);
    }
    if let (Some(p), false) = (&a.output, a.json) {
        println!("wrote {}", p.display());
    }
    if let Some((errors, first)) = validation_errors {
        if errors > 0 {
            bail!("the validation layer reported {errors} errors, first: {first:#?}");
        }
        if !a.json {
            println!("validation layer: no errors");
        }
    }
    Ok(())
}

//! `bench render`'s occlusion section: two-phase occlusion culling on instanced scenes, per
//! strategy, against frustum and cone culling alone and against the oracle (the meshlets that own
//! a sample), every frame checked sample for sample (`render::occlusion`).
//!
//! Scenes: a 4 x 4 x 4 grid of interpenetrating copies of a shared mesh (spacing 0.7 of its
//! extent) for every strategy; `gen:scene-grid` (generated, dense); the mesh alone, where little is
//! hidden and the pyramid and second phase are overhead.

use super::Common;
use crate::mesh::{Mesh, Scene};
use crate::meshlet::{validate, Limits, Meshlets};
use crate::render::occlusion::{measure_path, slot_triangles, Policy, Totals};
use crate::render::{Camera, Context, Pass};
use crate::strategy::{self, Options};
use anyhow::{Context as _, Result};
use std::fmt::Write as _;

/// The occlusion section's arguments (flattened into `bench render`'s).
#[derive(clap::Args, Clone, Debug)]
pub struct OcclusionArgs {
    /// Strategies compared under occlusion culling on the grid scene (comma-separated; empty:
    /// no occlusion section).
    #[arg(long, value_delimiter = ',', value_parser = super::strategy_name_or_none, default_values_t = ["meshopt", "kmedoids", "bsphere", "nvidia"].map(String::from))]
    pub occlusion_strategy: Vec<String>,
    /// Camera paths per scene.
    #[arg(long, default_value_t = 3, value_parser = clap::builder::RangedU64ValueParser::<usize>::new().range(1..))]
    pub occlusion_views: usize,
    /// Frames per path, at least 2 (the first warms the visibility and is reported apart).
    #[arg(long, default_value_t = 8, value_parser = clap::builder::RangedU64ValueParser::<usize>::new().range(2..))]
    pub occlusion_frames: usize,
    /// The shared mesh copied on the 4 x 4 x 4 grid.
    #[arg(long, default_value = "stanford_bunny")]
    pub occlusion_mesh: String,
}

/// One scene and strategy.
pub struct SceneRow {
    scene: String,
    strategy: String,
    instances: usize,
    meshlets_built: usize,
    /// Frames after the first, summed over the paths.
    totals: Totals,
    /// The first frames.
    warm_up: Totals,
    /// Device bytes of the scene, and of its per-instance part (records and visibility words).
    bytes: (u64, u64),
}

/// The targets, per scene kind.
const GRID_TRIANGLES: f64 = 0.5;
const DENSE_TRIANGLES: f64 = 0.3;
const ORACLE: f64 = 1.5;
const TIME: f64 = 0.6;
const OVERHEAD: f64 = 0.10;
const MEMORY: f64 = 1.1;

/// Runs every scene (`tick` after each).
pub fn run(
    args: &OcclusionArgs,
    common: &Common,
    ctx: &Context,
    limits: Limits,
    mut tick: impl FnMut(&str),
) -> Result<Vec<SceneRow>> {
    let strategies: Vec<&String> = args
        .occlusion_strategy
        .iter()
        .filter(|s| !s.is_empty())
        .collect();
    let Some(first) = strategies.first() else {
        return Ok(Vec::new());
    };
    let (name, file) = common.mesh_file(&args.occlusion_mesh)?;
    let mesh = crate::mesh::load(&file)?;
    let views = common.or_smoke(args.occlusion_views, 1).max(1);
    let frames = common.or_smoke(args.occlusion_frames, 3).max(2);
    let mut rows = Vec::new();
    let grid = Scene::grid(mesh.clone(), 4, 0.7)?;
    for s in &strategies {
        tick(&format!("occlusion: {name} 4x4x4, {s}"));
        rows.push(scene_row(
            ctx,
            &format!("{name} 4x4x4"),
            &grid,
            s,
            limits,
            views,
            frames,
        )?);
    }
    let dense_name = if common.smoke {
        "scene-small"
    } else {
        "scene-grid"
    };
    let dense = crate::mesh::generate::named_scene(dense_name).expect("a generated scene");
    tick(&format!("occlusion: gen:{dense_name}, {first}"));
    rows.push(scene_row(
        ctx,
        &format!("gen:{dense_name}"),
        &dense,
        first,
        limits,
        views,
        frames,
    )?);
    tick(&format!("occlusion: {name} alone, {first}"));
    rows.push(scene_row(
        ctx,
        &name,
        &Scene::single(mesh),
        first,
        limits,
        views,
        frames,
    )?);
    Ok(rows)
}

fn build(m: &Mesh, s: &str, limits: Limits) -> Result<Meshlets> {
    let ml = strategy::by_name(s, &Options::default())?.build(m, limits);
    validate(m, &ml, limits).with_context(|| format!("{s} built invalid meshlets"))?;
    Ok(ml)
}

fn scene_row(
    ctx: &Context,
    label: &str,
    scene: &Scene,
    s: &str,
    limits: Limits,
    views: usize,
    frames: usize,
) -> Result<SceneRow> {
    let meshlets: Vec<Meshlets> = scene
        .meshes
        .iter()
        .map(|m| build(m, s, limits))
        .collect::<Result<_>>()?;
    let pass = Pass::instanced(ctx, scene, &meshlets)?;
    let slots = slot_triangles(scene, &meshlets);
    let cams = Camera::framed_views(
        &scene.box_corners(),
        views,
        1,
        crate::render::WIDTH as f32 / crate::render::HEIGHT as f32,
        crate::render::FRAME_FILL,
    );
    let (mut totals, mut warm_up) = (Totals::default(), Totals::default());
    totals.images_identical = true;
    warm_up.images_identical = true;
    for (i, cam) in cams.iter().enumerate() {
        let p = measure_path(&pass, cam, i, frames, &slots, Policy::default(), None)?;
        totals.add(&p.frames);
        warm_up.add(&p.warm_up);
    }
    Ok(SceneRow {
        scene: label.to_string(),
        strategy: s.to_string(),
        instances: scene.instances.len(),
        meshlets_built: meshlets.iter().map(Meshlets::len).sum(),
        totals,
        warm_up,
        bytes: (pass.scene_bytes(), pass.per_instance_bytes()),
    })
}

fn mark(ok: bool) -> &'static str {
    if ok {
        "met"
    } else {
        "missed"
    }
}

/// The section of render.md.
pub fn write(md: &mut String, args: &OcclusionArgs, rows: &[SceneRow]) -> Result<()> {
    if rows.is_empty() {
        return Ok(());
    }
    let w0 = &rows[0].warm_up;
    let frames = (rows[0].totals.frames + w0.frames) / w0.frames.max(1);
    writeln!(
        md,
        "\n## Occlusion culling: two phases, checked sample by sample\n"
    )?;
    writeln!(md, "Each view (framed on the scene, seeded directions) becomes a path of {} frames closing in on it, the first from half again as far. The early phase draws what the previous frame found visible; a depth pyramid (each level the largest depth of 2 x 2 texels below it, level 0 the largest of each pixel's 4 samples) is built from its depth; the late phase tests every meshlet's bounding sphere, projected exactly, against the texels covering it at the finest level where it is at most 8 texels across, and draws what is newly visible. Every frame is drawn again with frustum and cone culling alone, and twice more through an id shader that keeps each sample's least (depth, slot): the depth samples and id images must be identical (`images identical`). The oracle is the set of (instance, meshlet) slots that own a sample. Sums over the frames after the first of every path; the first frames (nothing visible before them) are in the last columns. Triangles and meshlets count what was sent to the mesh shaders.\n", frames)?;
    writeln!(md, "| scene | strategy | instances | meshlets built | triangles: frustum+cone | occlusion | ratio | oracle | meshlets / oracle | early / late triangles % | culled: frustum % | backface % | occluded % | ms: frustum+cone | occlusion | ratio | first frame: ms frustum+cone | occlusion | images identical |")?;
    writeln!(md, "|---|---|---:|---:|---:|---:|---:|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---|")?;
    for r in rows {
        let t = &r.totals;
        let tests = (t.meshlets_frustum_cone + t.meshlets_culled_frustum + t.meshlets_culled_cone)
            .max(1) as f64;
        let drawn = t.triangles_occlusion.max(1) as f64;
        let f = t.frames.max(1) as f64;
        let w = &r.warm_up;
        let wf = w.frames.max(1) as f64;
        writeln!(
            md,
            "| {} | {} | {} | {} | {} | {} | {:.3} | {} | {:.2} | {:.0} / {:.0} | {:.1} | {:.1} | {:.1} | {:.2} | {:.2} | {:.3} | {:.2} | {:.2} | {} |",
            r.scene,
            r.strategy,
            r.instances,
            r.meshlets_built,
            t.triangles_frustum_cone,
            t.triangles_occlusion,
            t.triangle_ratio(),
            t.triangles_oracle,
            t.oracle_ratio(),
            100.0 * t.triangles_early as f64 / drawn,
            100.0 * t.triangles_late as f64 / drawn,
            100.0 * t.meshlets_culled_frustum as f64 / tests,
            100.0 * t.meshlets_culled_cone as f64 / tests,
            100.0 * t.meshlets_occluded as f64 / tests,
            t.frame_ms_frustum_cone / f,
            t.frame_ms_occlusion / f,
            t.time_ratio(),
            w.frame_ms_frustum_cone / wf,
            w.frame_ms_occlusion / wf,
            if t.images_identical && w.images_identical { "yes" } else { "**no**" },
        )?;
    }
    writeln!(md, "\nms are per frame (GPU timestamps around the whole frame: both phases and the pyramid with occlusion culling). Culled shares are of the meshlet tests (paper Figure 7's frustum and backface shares beside the share the pyramid adds). On lavapipe the rasteriser defers work to the next barrier, so time per phase is not reported; the first frame's pyramid is built from an empty early phase.\n")?;
    // Targets.
    writeln!(md, "### Targets\n")?;
    writeln!(md, "| scene | strategy | triangles <= {GRID_TRIANGLES}x (grid), <= {DENSE_TRIANGLES}x (generated) | meshlets <= {ORACLE}x the oracle's | frame time <= {TIME}x | alone: occlusion costs <= {:.0} % | device bytes of N instances <= {MEMORY}x one's + per-instance data | images identical |", 100.0 * OVERHEAD)?;
    writeln!(md, "|---|---|---|---|---|---|---|---|")?;
    let single = rows.iter().find(|r| r.instances == 1);
    for r in rows {
        let t = &r.totals;
        let (tri, orc, time, over, mem) = if r.instances == 1 {
            let over = t.time_ratio() - 1.0;
            (
                "-".into(),
                "-".into(),
                "-".into(),
                format!("{:+.1} % {}", 100.0 * over, mark(over <= OVERHEAD)),
                "-".to_string(),
            )
        } else {
            let limit = if r.scene.starts_with("gen:") {
                DENSE_TRIANGLES
            } else {
                GRID_TRIANGLES
            };
            let mem = match single {
                Some(s) if !r.scene.starts_with("gen:") && s.strategy == r.strategy => {
                    let shared =
                        (r.bytes.0 - r.bytes.1) as f64 / (s.bytes.0 - s.bytes.1).max(1) as f64;
                    format!("{shared:.3}x {}", mark(shared <= MEMORY))
                }
                _ => "-".into(),
            };
            (
                format!(
                    "{:.3} {}",
                    t.triangle_ratio(),
                    mark(t.triangle_ratio() <= limit)
                ),
                format!(
                    "{:.2} {}",
                    t.oracle_ratio(),
                    mark(t.oracle_ratio() <= ORACLE)
                ),
                format!("{:.3} {}", t.time_ratio(), mark(t.time_ratio() <= TIME)),
                "-".to_string(),
                mem,
            )
        };
        writeln!(
            md,
            "| {} | {} | {tri} | {orc} | {time} | {over} | {mem} | {} |",
            r.scene,
            r.strategy,
            mark(t.images_identical && r.warm_up.images_identical)
        )?;
    }
    writeln!(md, "\nDevice bytes: positions, meshlets, culling data and index buffer are held once per mesh; the per-instance part is the instance records (128 B each) and one visibility word per (instance, meshlet). Strategies on the grid: {}.\n", args.occlusion_strategy.join(", "))?;
    Ok(())
}

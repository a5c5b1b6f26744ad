//! `meshletlab render`: task + mesh shaders beside the vertex pipeline from seeded random views.

use super::clusters::{meshlets_or_build, refuse_instanced, ClusterArgs};
use super::{build_validated, load, load_scene, StrategyArgs};
use crate::compress::file::CompressedFile;
use crate::compress::Codec;
use crate::lod::flat::Flat;
use crate::mesh::Scene;
use crate::meshlet::descriptor::{pack, DescriptorFormat};
use crate::meshlet::Meshlets;
use crate::render::{Camera, Context, Pass, Pipeline, Shading, HEIGHT, WIDTH};
use anyhow::{bail, Context as _, Result};
use clap::Args;
use std::path::{Path, PathBuf};

/// Arguments of `render`.
#[derive(Args, Debug)]
pub struct RenderArgs {
    /// Mesh file.
    mesh: PathBuf,
    /// Strategy name (`meshletlab --help` lists them, e.g. meshopt, kmedoids, partition).
    #[arg(short, long, default_value = "meshopt")]
    strategy: String,
    /// Views (random directions around the mesh, the paper's protocol).
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..=10_000))]
    views: u32,
    /// Seed of the view sequence (the same for every strategy).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Camera distance from the mesh centre in bounding radii (half the box diagonal). Default:
    /// each view framed so the mesh fills most of the image.
    #[arg(long, value_parser = distance)]
    distance: Option<f32>,
    /// No task-shader culling.
    #[arg(long)]
    no_cull: bool,
    /// Meshlet descriptor layout on the GPU: split (exact bounds), nvidia-a, nvidia-b
    /// (quantised bounds), monolithic (per-meshlet vertex copies).
    #[arg(short, long, default_value = "split", value_parser = clap::value_parser!(DescriptorFormat))]
    descriptor: DescriptorFormat,
    /// Write the first view, coloured by meshlet (the paper's Figure 1), to this PNG; with
    /// `--occlusion`, the first path's last frame; with `--lod`, the first view's cut.
    #[arg(short, long = "output", visible_alias = "png", value_name = "PNG")]
    output: Option<PathBuf>,
    /// Cluster LOD: build the meshlet DAG with the strategy and let the task shader draw, per
    /// view, the crack-free cut whose simplification error stays under `--threshold` pixels
    /// (with frustum and cone culling unless `--no-cull`). Each view's drawn meshlets are checked
    /// against the CPU reference selection.
    #[arg(long)]
    lod: bool,
    /// LOD error threshold in pixels (at 1280x720, 60 degree vertical field of view).
    #[arg(long, default_value_t = 1.0, requires = "lod", value_name = "PX", value_parser = crate::bench::positive::<f32>)]
    threshold: f32,
    /// Streaming: only the N coarsest levels are loaded (default: all); a meshlet of the finest
    /// loaded level is drawn where finer detail would be wanted.
    #[arg(long, requires = "lod", value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    levels: Option<u32>,
    /// Draw the meshlets compressed in this format, decoded by the shaders from the encoded bytes
    /// (Mlakar et al. 2024): laced-wires (task-shader culling from its records), sc-compact and
    /// ix-compact (mesh shaders), gi-compact and ts-compact (vertex shader). Each view is also
    /// drawn uncompressed from the CPU-decoded meshlets, and the two images must be identical.
    #[arg(long, value_name = "FORMAT", conflicts_with_all = ["lod", "compressed"])]
    format: Option<Codec>,
    /// Draw a file written by `meshletlab compress` (of MESH) instead; it is decoded on the CPU
    /// first and refused if damaged, before anything is uploaded.
    #[arg(long, value_name = "FILE", conflicts_with = "lod")]
    compressed: Option<PathBuf>,
    /// With --format: largest position error in mesh units (default: the paper's 14-bit grid).
    #[arg(long, requires = "format", conflicts_with = "relative_tolerance")]
    tolerance: Option<f64>,
    /// With --format: largest position error as a fraction of the bounding-box diagonal.
    #[arg(long, requires = "format")]
    relative_tolerance: Option<f64>,
    /// Two-phase occlusion culling: each view becomes a path of `--frames` frames closing in on
    /// it; the early phase draws what the last frame saw, a depth pyramid is built from it, the
    /// late phase tests the rest against the pyramid. Every frame is also drawn with frustum and
    /// cone culling alone, and the two are checked pixel for pixel through an id image (exit 1 on
    /// any difference); the meshlets that own a pixel are the oracle the result is reported
    /// against. Draws the split layout, for meshes and instanced scenes, and with `--lod` the cut
    /// (the early phase then tests against the previous frame's pyramid).
    #[arg(long, conflicts_with_all = ["format", "compressed"])]
    occlusion: bool,
    /// Draw N x N x N copies of the mesh, spaced at `--spacing` of its largest extent, as an
    /// instanced scene (the mesh's meshlets built once).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=16), conflicts_with_all = ["lod", "format", "compressed"])]
    grid: Option<u32>,
    /// With `--grid`: spacing as a fraction of the mesh's largest extent (below 1 the copies
    /// interpenetrate).
    #[arg(long, default_value_t = 0.7, requires = "grid", value_parser = crate::bench::positive::<f32>)]
    spacing: f32,
    /// With `--occlusion`: build the pyramid in every frame (by default a frame whose pyramid
    /// hid under a fifth of the triangles makes the next frames skip it, trying again every 4th).
    #[arg(long, requires = "occlusion")]
    always_pyramid: bool,
    /// Frames per view with `--occlusion` (the first warms the visibility and is reported apart).
    #[arg(long, default_value_t = 8, requires = "occlusion", value_parser = clap::value_parser!(u32).range(2..=64))]
    frames: u32,
    /// Enable the Khronos validation layer and fail on any error it reports.
    #[arg(long)]
    validate: bool,
    /// Print JSON (mesh, device, bytes, one object per view) instead of text.
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    args: StrategyArgs,
    /// Plain, with --format and with --lod (level 0; --strategy splits the levels above).
    #[command(flatten)]
    clusters: ClusterArgs,
}

/// Refuses the options the chosen mode would ignore, by name, before anything is loaded.
fn refuse_unused_options(a: &RenderArgs, m: &clap::ArgMatches) -> Result<()> {
    a.clusters
        .check(!a.lod && super::given(m, "strategy"), false)?;
    if a.clusters.file().is_some() {
        let other = [
            (a.occlusion, "--occlusion"),
            (a.grid.is_some(), "--grid"),
            (a.compressed.is_some(), "--compressed"),
        ];
        if let Some((_, flag)) = other.iter().find(|(on, _)| *on) {
            return Err(super::usage(format!(
                "--labels and --meshlets draw plain, with --format or with --lod, not with {flag}"
            )));
        }
    }
    if a.format.is_none() {
        super::refuse_unused(
            m,
            &["tolerance", "relative_tolerance"],
            "a mode that encodes nothing (they set --format's error)",
        )?;
    }
    if a.compressed.is_some() {
        // The file holds its meshlets: nothing is built.
        let mut ids = super::StrategyArgs::ids();
        ids.extend(["strategy", "descriptor"].map(String::from));
        let ids: Vec<&str> = ids.iter().map(String::as_str).collect();
        return super::refuse_unused(m, &ids, "--compressed (the file holds its meshlets)");
    }
    if a.format.is_some() {
        return super::refuse_unused(m, &["descriptor"], "--format (it draws the encoded bytes)");
    }
    if a.occlusion {
        return super::refuse_unused(
            m,
            &["descriptor", "no_cull"],
            "--occlusion (it draws the split layout and culls on top of frustum and cones)",
        );
    }
    if a.lod {
        return super::refuse_unused(m, &["descriptor"], "--lod (it draws the split layout)");
    }
    Ok(())
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

/// `--distance`: a finite number of bounding radii in (0, 1000] (farther, the depth range of a
/// 32-bit float buffer no longer separates the mesh's own surfaces).
fn distance(s: &str) -> Result<f32, String> {
    match crate::bench::positive::<f64>(s)? {
        d if d <= 1000.0 => Ok(d as f32),
        d => Err(format!("{d} is farther than 1000 bounding radii")),
    }
}

pub(super) fn run(a: RenderArgs, matches: &clap::ArgMatches, quiet: bool) -> Result<()> {
    refuse_unused_options(&a, matches)?;
    if let Some(p) = &a.output {
        super::output::check_file(p, "a PNG", &["png"])?;
    }
    if a.lod {
        return run_lod(a, quiet);
    }
    if a.format.is_some() || a.compressed.is_some() {
        return run_compressed(a, quiet);
    }
    let name = &a.strategy;
    crate::strategy::by_name(name, &a.args.options())?;
    let mut scene = load_scene(&a.mesh, quiet)?;
    if let Some(n) = a.grid {
        if scene.is_instanced() {
            bail!(
                "--grid copies one mesh; {} is already a scene",
                a.mesh.display()
            );
        }
        let m = scene.meshes.pop().expect("one mesh");
        scene = Scene::grid(m, n as usize, a.spacing)?;
    }
    if scene.is_instanced() && a.clusters.file().is_some() {
        return Err(refuse_instanced(&a.mesh, "--labels and --meshlets"));
    }
    if a.occlusion {
        return run_occlusion(a, scene, quiet);
    }
    if scene.is_instanced() {
        return run_scene(a, scene, quiet);
    }
    let m = scene.meshes.into_iter().next().expect("one mesh");
    let imported = meshlets_or_build(&m, &a.mesh, name, &a.args, &a.clusters)?;
    let name = &(imported.name.clone() + &imported.split_note());
    let ml = imported.meshlets;
    let ctx = Context::new(a.validate)?;
    let pass = Pass::with_format(&ctx, &m, &ml, a.descriptor)
        .with_context(|| format!("{}: {name}", a.mesh.display()))?;
    let bytes_per_triangle = pass.device_bytes() as f64 / m.triangle_count().max(1) as f64;
    if !a.json {
        say!(
            "{}: {} triangles, {name}: {} meshlets, {} descriptors: {bytes_per_triangle:.2} bytes per triangle; device: {}",
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
    let (views, radius) = cameras(&a, &m);
    let measure = |i, cam: &Camera| -> Result<ViewRow> {
        let f = pass.render(cam, how, Shading::Lit)?;
        let v = pass.render(cam, Pipeline::Vertex, Shading::Lit)?;
        Ok(ViewRow {
            view: i,
            distance_radii: (cam.eye - cam.target).length() / radius,
            mesh_ms: f.gpu_ns * 1e-6,
            vertex_ms: v.gpu_ns * 1e-6,
            meshlets_culled_frustum: f.culled_frustum,
            meshlets_culled_backface: f.culled_cone,
            meshlets_drawn: f.drawn,
            mesh_primitives_generated: f.queries.map(|q| q.primitives),
        })
    };
    let line = |row: &ViewRow| {
        let pct = |x: u32| 100.0 * x as f64 / ml.len().max(1) as f64;
        let prims = row
            .mesh_primitives_generated
            .map(|p| format!("  mesh primitives generated {p}"))
            .unwrap_or_default();
        Some(format!(
            "view {} ({:.2} radii): mesh shaders {:8.3} ms  vertex pipeline {:8.3} ms  culled: frustum {:5.1} %  backface {:5.1} %{prims}",
            row.view,
            row.distance_radii,
            row.mesh_ms,
            row.vertex_ms,
            pct(row.meshlets_culled_frustum),
            pct(row.meshlets_culled_backface)
        ))
    };
    let png = |cam: &Camera, p: &Path| crate::render::write_meshlet_png(&pass, cam, cull, p);
    let rows = each_view(&a, &views, measure, line, png)?;
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
        });
        print_json(out, &ctx, cull, &a, &validation_errors, &rows)?;
    }
    if let (Some(p), false) = (&a.output, a.json) {
        say!("wrote {}", p.display());
    }
    report_validation(validation_errors, a.json)
}

/// One view of an instanced scene.
#[derive(serde::Serialize)]
struct SceneRow {
    view: usize,
    mesh_ms: f64,
    vertex_ms: f64,
    instances_culled_frustum: u32,
    meshlets_culled_frustum: u32,
    meshlets_culled_backface: u32,
    meshlets_drawn: u32,
    mesh_primitives_generated: Option<u64>,
}

/// Each of `scene`'s meshes' meshlets, built once and validated.
fn build_per_mesh(a: &RenderArgs, scene: &Scene, quiet: bool) -> Result<Vec<Meshlets>> {
    let name = &a.strategy;
    let pb = super::spinner(
        quiet || a.json,
        format!("building {name} meshlets per mesh"),
    );
    let meshlets = scene
        .meshes
        .iter()
        .enumerate()
        .map(|(i, m)| {
            build_validated(m, &a.mesh, name, &a.args).with_context(|| format!("mesh {i}"))
        })
        .collect::<Result<Vec<_>>>()?;
    pb.finish_and_clear();
    Ok(meshlets)
}

/// `render` of an instanced scene: meshlets built once per mesh, drawn once per instance.
fn run_scene(a: RenderArgs, scene: Scene, quiet: bool) -> Result<()> {
    if a.descriptor != DescriptorFormat::Split {
        return Err(super::usage(format!(
            "--descriptor is not used with an instanced scene ({} is drawn in the split layout)",
            a.mesh.display()
        )));
    }
    let name = &a.strategy;
    let meshlets = build_per_mesh(&a, &scene, quiet)?;
    let built: usize = meshlets.iter().map(|m| m.len()).sum();
    let per_instance: usize = scene
        .instances
        .iter()
        .map(|i| meshlets[i.mesh as usize].len())
        .sum();
    let ctx = Context::new(a.validate)?;
    let pass = Pass::instanced(&ctx, &scene, &meshlets)
        .with_context(|| format!("{}: {name}", a.mesh.display()))?;
    if !a.json {
        say!(
            "{}: {} meshes, {} instances: {} triangles built, {} drawn; {name}: {built} meshlets built, {per_instance} drawn over the instances; device: {}",
            a.mesh.display(),
            scene.meshes.len(),
            scene.instances.len(),
            scene.triangles_built(),
            scene.triangles_drawn(),
            ctx.name
        );
    }
    let cull = !a.no_cull;
    let how = Pipeline::Mesh {
        frustum: cull,
        cone: cull,
        colour_ids: false,
    };
    let (views, _) = cameras(&a, &scene.box_corners());
    let measure = |i, cam: &Camera| -> Result<SceneRow> {
        let f = pass.render(cam, how, Shading::Lit)?;
        let v = pass.render(cam, Pipeline::Vertex, Shading::Lit)?;
        Ok(SceneRow {
            view: i,
            mesh_ms: f.gpu_ns * 1e-6,
            vertex_ms: v.gpu_ns * 1e-6,
            instances_culled_frustum: f.culled_instances,
            meshlets_culled_frustum: f.culled_frustum,
            meshlets_culled_backface: f.culled_cone,
            meshlets_drawn: f.drawn,
            mesh_primitives_generated: f.queries.map(|q| q.primitives),
        })
    };
    let line = |row: &SceneRow| {
        Some(format!(
            "view {}: mesh shaders {:8.3} ms  vertex pipeline {:8.3} ms  instances culled {}  meshlets culled: frustum {}  backface {}  drawn {}",
            row.view,
            row.mesh_ms,
            row.vertex_ms,
            row.instances_culled_frustum,
            row.meshlets_culled_frustum,
            row.meshlets_culled_backface,
            row.meshlets_drawn
        ))
    };
    let png = |cam: &Camera, p: &Path| crate::render::write_meshlet_png(&pass, cam, cull, p);
    let rows = each_view(&a, &views, measure, line, png)?;
    let validation_errors = ctx.validation.as_ref().map(|v| v.errors());
    if a.json {
        let out = serde_json::json!({
            "mesh": a.mesh.display().to_string(),
            "meshes": scene.meshes.len(),
            "instances": scene.instances.len(),
            "triangles_built": scene.triangles_built(),
            "triangles_drawn": scene.triangles_drawn(),
            "strategy": name,
            "limits": a.args.limits.to_string(),
            "meshlets_built": built,
            "meshlets_over_instances": per_instance,
            "descriptor": a.descriptor.to_string(),
            "device_bytes": pass.device_bytes(),
        });
        print_json(out, &ctx, cull, &a, &validation_errors, &rows)?;
    }
    if let (Some(p), false) = (&a.output, a.json) {
        say!("wrote {}", p.display());
    }
    report_validation(validation_errors, a.json)
}

/// `render --occlusion`: camera paths with two-phase occlusion culling, checked against the
/// frustum-and-cone render frame by frame.
fn run_occlusion(a: RenderArgs, scene: Scene, quiet: bool) -> Result<()> {
    use crate::render::occlusion::{slot_triangles, Policy};
    let name = &a.strategy;
    let meshlets = build_per_mesh(&a, &scene, quiet)?;
    let built: usize = meshlets.iter().map(|m| m.len()).sum();
    let ctx = Context::new(a.validate)?;
    if !ctx.id_check {
        bail!(crate::render::RenderError::NoIdCheck);
    }
    let pass = Pass::instanced(&ctx, &scene, &meshlets)
        .with_context(|| format!("{}: {name}", a.mesh.display()))?;
    let slots = slot_triangles(&scene, &meshlets);
    let (views, _) = cameras(&a, &scene.box_corners());
    let policy = if a.always_pyramid {
        Policy::ALWAYS
    } else {
        Policy::default()
    };
    let header = serde_json::json!({
        "mesh": a.mesh.display().to_string(),
        "meshes": scene.meshes.len(),
        "instances": scene.instances.len(),
        "triangles_built": scene.triangles_built(),
        "strategy": name,
        "limits": a.args.limits.to_string(),
        "meshlets_built": built,
        "frames_per_view": a.frames,
        "device_bytes_scene": pass.scene_bytes(),
    });
    let line = format!(
        "{}: {} meshes, {} instances, {} triangles built; {name}: {built} meshlets built",
        a.mesh.display(),
        scene.meshes.len(),
        scene.instances.len(),
        scene.triangles_built()
    );
    occlusion_paths(
        &a, &ctx, &pass, &views, &slots, policy, None, header, line, quiet,
    )
}

/// Runs every view's camera path with occlusion culling and reports it (`header`: the command's
/// own JSON fields; `line`: its first line of text); exit 1 unless every frame was exact.
#[allow(clippy::too_many_arguments)]
fn occlusion_paths(
    a: &RenderArgs,
    ctx: &Context,
    pass: &Pass,
    views: &[Camera],
    slots: &[u32],
    policy: crate::render::occlusion::Policy,
    lod: Option<crate::render::occlusion::LodCut>,
    mut header: serde_json::Value,
    line: String,
    quiet: bool,
) -> Result<()> {
    use crate::render::occlusion::{measure_path, Totals};
    let bar = super::bar(quiet || a.json, views.len() as u64);
    bar.set_message("camera paths");
    let measure = |i, cam: &Camera| {
        let path = measure_path(pass, cam, i, a.frames as usize, slots, policy, lod)?;
        bar.inc(1);
        Ok(path)
    };
    // The first path's last frame as the frustum-and-cone pass draws it: every frame of the path
    // is checked to be pixel for pixel what occlusion culling drew.
    let png = |cam: &Camera, p: &Path| {
        let last = *cam
            .approach(a.frames as usize)
            .last()
            .expect("a path has frames");
        let img = match lod {
            Some(c) => pass.render_lod_reference(
                &last,
                &last.lod_query(c.threshold, c.finest, true),
                Shading::Lit,
                false,
            )?,
            None => pass.render_reference(&last, Shading::Lit, false)?,
        };
        crate::render::write_png(p, WIDTH, HEIGHT, &img.pixels)
            .with_context(|| format!("{}: cannot write", p.display()))
    };
    // The paths are reported together once all are measured.
    let paths = each_view(a, views, measure, |_| None, png)?;
    bar.finish_and_clear();
    let mut total = Totals {
        images_identical: true,
        ..Default::default()
    };
    for p in &paths {
        total.add(&p.frames);
    }
    let validation_errors = ctx.validation.as_ref().map(|v| v.errors());
    if a.json {
        let mut out = serde_json::to_value(&total)?;
        let o = out.as_object_mut().expect("an object");
        for (k, v) in header.as_object_mut().expect("an object").iter() {
            o.insert(k.clone(), v.clone());
        }
        for (k, v) in [
            ("triangle_ratio", total.triangle_ratio()),
            ("oracle_ratio", total.oracle_ratio()),
            ("time_ratio", total.time_ratio()),
        ] {
            o.insert(k.into(), v.into());
        }
        print_json(out, ctx, true, a, &validation_errors, &paths)?;
    } else {
        say!(
            "{line}; {} frames per view, the first apart; device: {}",
            a.frames,
            ctx.name
        );
        for p in &paths {
            let t = &p.frames;
            say!(
                "view {}: triangles {} with occlusion, {} frustum+cone ({:.2}x), oracle {}; meshlets {:.2}x the oracle's; time {:.2}x ({} of {} frames without the pyramid); images {}",
                p.view,
                t.triangles_occlusion,
                t.triangles_frustum_cone,
                t.triangle_ratio(),
                t.triangles_oracle,
                t.oracle_ratio(),
                t.time_ratio(),
                t.frames_without_pyramid,
                t.frames,
                if t.images_identical && p.warm_up.images_identical { "identical" } else { "DIFFER" }
            );
        }
        say!(
            "all views: triangles {:.3}x frustum+cone, meshlets {:.3}x the oracle's, frame time {:.3}x",
            total.triangle_ratio(),
            total.oracle_ratio(),
            total.time_ratio()
        );
    }
    if let (Some(p), false) = (&a.output, a.json) {
        say!("wrote {} (the first path's last frame)", p.display());
    }
    let exact = paths
        .iter()
        .all(|p| p.frames.images_identical && p.warm_up.images_identical);
    if !exact {
        bail!("occlusion culling changed the image: a visible meshlet was culled");
    }
    report_validation(validation_errors, a.json)
}

/// One LOD view's measurements.
#[derive(serde::Serialize)]
struct LodRow {
    view: usize,
    distance_radii: f32,
    lod_ms: f64,
    full_detail_ms: f64,
    meshlets_not_selected: u32,
    meshlets_culled_frustum: u32,
    meshlets_culled_backface: u32,
    meshlets_drawn: u32,
    cpu_reference_drawn: usize,
    mesh_primitives_generated: Option<u64>,
    source_triangles: usize,
}

/// `render --lod`: the task shader selects the LOD cut per view.
fn run_lod(a: RenderArgs, quiet: bool) -> Result<()> {
    let s = crate::strategy::by_name(&a.strategy, &a.args.options())?;
    let m = load(&a.mesh, quiet)?;
    let level0 = a.clusters.import(&m, a.args.limits)?;
    let name = &match &level0 {
        Some(i) => format!(
            "{}{} (levels above by {})",
            i.name,
            i.split_note(),
            a.strategy
        ),
        None => a.strategy.clone(),
    };
    let pb = super::spinner(quiet || a.json, format!("building the LOD DAG with {name}"));
    let cfg = Default::default();
    let lod = match level0 {
        Some(i) => crate::lod::build_from(&m, i.meshlets, s.as_ref(), a.args.limits, &cfg),
        None => crate::lod::build(&m, s.as_ref(), a.args.limits, &cfg),
    };
    let flat = Flat::new(&m, &lod);
    pb.finish_and_clear();
    let levels = flat.levels();
    let loaded_levels = a.levels.map_or(levels, |n| (n as usize).min(levels));
    let finest = levels - loaded_levels;
    let ctx = Context::new(a.validate)?;
    let pass = Pass::with_lod(&ctx, &m, &flat)
        .with_context(|| format!("{}: {name} LOD", a.mesh.display()))?;
    if a.occlusion {
        // The cut and occlusion culling together, checked frame by frame as for a scene.
        if !ctx.id_check {
            bail!(crate::render::RenderError::NoIdCheck);
        }
        let slots: Vec<u32> = flat.records.iter().map(|r| r.triangles).collect();
        let (views, _) = cameras(&a, &m);
        let header = serde_json::json!({
            "mesh": a.mesh.display().to_string(),
            "triangles": m.triangle_count(),
            "strategy": name,
            "limits": a.args.limits.to_string(),
            "lod_levels": levels,
            "lod_levels_loaded": loaded_levels,
            "lod_meshlets": flat.meshlets.len(),
            "threshold_px": a.threshold,
            "frames_per_view": a.frames,
        });
        let line = format!(
            "{}: {} triangles, {name} LOD DAG: {levels} levels ({loaded_levels} loaded), {} meshlets, threshold {} px",
            a.mesh.display(),
            m.triangle_count(),
            flat.meshlets.len(),
            a.threshold
        );
        let cut = crate::render::occlusion::LodCut {
            threshold: a.threshold,
            finest,
        };
        return occlusion_paths(
            &a,
            &ctx,
            &pass,
            &views,
            &slots,
            crate::render::occlusion::Policy::ALWAYS,
            Some(cut),
            header,
            line,
            quiet,
        );
    }
    // Full detail through the same strategy's meshlets, for the time comparison.
    let full = Pass::new(&ctx, &m, &lod.levels[0].meshlets)?;
    if !a.json {
        say!(
            "{}: {} triangles, {name} LOD DAG: {levels} levels ({loaded_levels} loaded), {} meshlets; threshold {} px; device: {}",
            a.mesh.display(),
            m.triangle_count(),
            flat.meshlets.len(),
            a.threshold,
            ctx.name
        );
    }
    let cull = !a.no_cull;
    let (views, radius) = cameras(&a, &m);
    let measure = |i, cam: &Camera| -> Result<LodRow> {
        let q = cam.lod_query(a.threshold, finest, cull);
        let f = pass.render_lod(cam, &q, false, Shading::Lit)?;
        let how = Pipeline::Mesh {
            frustum: cull,
            cone: cull,
            colour_ids: false,
        };
        let full_frame = full.render(cam, how, Shading::Lit)?;
        let cpu = crate::lod::flat::select_meshlets(&flat, &q).len();
        Ok(LodRow {
            view: i,
            distance_radii: (cam.eye - cam.target).length() / radius,
            lod_ms: f.gpu_ns * 1e-6,
            full_detail_ms: full_frame.gpu_ns * 1e-6,
            meshlets_not_selected: f.not_selected,
            meshlets_culled_frustum: f.culled_frustum,
            meshlets_culled_backface: f.culled_cone,
            meshlets_drawn: f.drawn,
            cpu_reference_drawn: cpu,
            mesh_primitives_generated: f.queries.map(|q| q.primitives),
            source_triangles: m.triangle_count(),
        })
    };
    let line = |row: &LodRow| {
        let prims = row
            .mesh_primitives_generated
            .map(|p| format!("  {p} triangles drawn"))
            .unwrap_or_default();
        Some(format!(
            "view {} ({:.2} radii): LOD {:8.3} ms  full detail {:8.3} ms  meshlets drawn {} (CPU reference {}), culled: frustum {} backface {}{prims}",
            row.view,
            row.distance_radii,
            row.lod_ms,
            row.full_detail_ms,
            row.meshlets_drawn,
            row.cpu_reference_drawn,
            row.meshlets_culled_frustum,
            row.meshlets_culled_backface,
        ))
    };
    let png = |cam: &Camera, p: &Path| {
        let q = cam.lod_query(a.threshold, finest, cull);
        let img = pass.render_lod(cam, &q, true, Shading::Lit)?;
        crate::render::write_png(p, WIDTH, HEIGHT, &img.pixels)
            .with_context(|| format!("{}: cannot write", p.display()))
    };
    let rows = each_view(&a, &views, measure, line, png)?;
    let mismatch = rows
        .iter()
        .find(|r| r.meshlets_drawn as usize != r.cpu_reference_drawn);
    let validation_errors = ctx.validation.as_ref().map(|v| v.errors());
    if a.json {
        let out = serde_json::json!({
            "mesh": a.mesh.display().to_string(),
            "triangles": m.triangle_count(),
            "strategy": name,
            "limits": a.args.limits.to_string(),
            "levels": levels,
            "levels_loaded": loaded_levels,
            "meshlets": flat.meshlets.len(),
            "threshold_px": a.threshold,
        });
        print_json(out, &ctx, cull, &a, &validation_errors, &rows)?;
    } else if let Some(p) = &a.output {
        say!("wrote {} (coloured by meshlet)", p.display());
    }
    if let Some(r) = mismatch {
        bail!(
            "view {}: the task shader drew {} meshlets, the CPU reference selects {}",
            r.view,
            r.meshlets_drawn,
            r.cpu_reference_drawn
        );
    }
    report_validation(validation_errors, a.json)
}

/// One view of a compressed pass.
#[derive(serde::Serialize)]
struct CompressedRow {
    view: usize,
    distance_radii: f32,
    compressed_ms: f64,
    uncompressed_ms: f64,
    meshlets_culled_frustum: u32,
    meshlets_culled_backface: u32,
    meshlets_drawn: u32,
    identical_to_decoded_reference: bool,
}

/// `render --format F` / `--compressed FILE`: the shaders decode the compressed bytes.
fn run_compressed(a: RenderArgs, quiet: bool) -> Result<()> {
    use crate::render::compressed::{decoded_reference, prepare};
    let m = load(&a.mesh, quiet)?;
    // The baseline every mode prints: the split layout of MESH and its meshlets (`None`: those of
    // the file, measured once it is decoded).
    let (format, enc, what, source_split) = match (&a.compressed, a.format) {
        (Some(path), _) => {
            let data = crate::meshlet::io::read_file(path)?;
            let file = CompressedFile::from_bytes(&data, path)?;
            // The file must be an encoding of this mesh (and decode, which `prepare` repeats).
            file.check(&m, path)?;
            (file.format, file.encoded, path.display().to_string(), None)
        }
        (None, Some(format)) => {
            let tolerance = super::compress::tolerance(&m, a.tolerance, a.relative_tolerance)?;
            let i = meshlets_or_build(&m, &a.mesh, &a.strategy, &a.args, &a.clusters)?;
            let enc = format
                .encode(&m, &i.meshlets, tolerance)
                .map_err(|e| anyhow::anyhow!("{}: {e}", a.mesh.display()))?;
            let split =
                pack(&m, &i.meshlets, DescriptorFormat::Split)?.device_bytes(m.vertex_count());
            (
                format,
                enc,
                format!("{}{} meshlets", i.name, i.split_note()),
                Some(split),
            )
        }
        (None, None) => unreachable!("run_compressed needs --format or --compressed"),
    };
    let label = || match &a.compressed {
        Some(p) => p.display().to_string(),
        None => a.mesh.display().to_string(),
    };
    let upload = prepare(&enc, format).with_context(label)?;
    let (ref_mesh, ref_ml) = decoded_reference(&enc, format).with_context(label)?;
    // The decoded reference copies each meshlet's vertices; the meshlets' own words are the same
    // as the source's, so only the position array is counted at MESH's vertex count.
    let split_bytes = match source_split {
        Some(b) => b,
        None => pack(&ref_mesh, &ref_ml, DescriptorFormat::Split)?.device_bytes(m.vertex_count()),
    };
    let ctx = Context::new(a.validate)?;
    let pass = Pass::compressed(&ctx, &upload).with_context(label)?;
    let reference = Pass::new(&ctx, &ref_mesh, &ref_ml)?;
    let tris = upload.triangles.max(1) as f64;
    if !a.json {
        say!(
            "{}: {} triangles, {what} in {}: {} meshlets, {:.2} bytes per triangle resident (uncompressed split layout of the mesh and its meshlets: {:.2}; CPU-decoded reference drawn beside it: {:.2}); device: {}",
            a.mesh.display(),
            m.triangle_count(),
            format.name(),
            upload.meshlets(),
            upload.device_bytes() as f64 / tris,
            split_bytes as f64 / tris,
            reference.device_bytes() as f64 / tris,
            ctx.name
        );
    }
    let cull = !a.no_cull;
    let how = pass.native(cull);
    let reference_how = match how {
        Pipeline::Vertex => Pipeline::Vertex,
        _ => Pipeline::mesh(cull),
    };
    let (views, radius) = cameras(&a, &m);
    let measure = |i, cam: &Camera| -> Result<CompressedRow> {
        let f = pass.render(cam, how, Shading::Lit)?;
        let r = reference.render(cam, reference_how, Shading::Lit)?;
        // Exact comparison: the reference without culling (only laced wires carry culling data).
        let exact = match how {
            Pipeline::Vertex => f.pixels == r.pixels,
            _ => {
                let no_cull = Pipeline::mesh(false);
                let x = pass.render(cam, no_cull, Shading::Unlit)?;
                let y = reference.render(cam, no_cull, Shading::Unlit)?;
                x.pixels == y.pixels && f.pixels == pass.render(cam, no_cull, Shading::Lit)?.pixels
            }
        };
        Ok(CompressedRow {
            view: i,
            distance_radii: (cam.eye - cam.target).length() / radius,
            compressed_ms: f.gpu_ns * 1e-6,
            uncompressed_ms: r.gpu_ns * 1e-6,
            meshlets_culled_frustum: f.culled_frustum,
            meshlets_culled_backface: f.culled_cone,
            meshlets_drawn: f.drawn,
            identical_to_decoded_reference: exact,
        })
    };
    let line = |row: &CompressedRow| {
        Some(format!(
            "view {} ({:.2} radii): {} {:8.3} ms  uncompressed {:8.3} ms  culled: frustum {} backface {}  image {}",
            row.view,
            row.distance_radii,
            format.name(),
            row.compressed_ms,
            row.uncompressed_ms,
            row.meshlets_culled_frustum,
            row.meshlets_culled_backface,
            if row.identical_to_decoded_reference { "identical to the CPU-decoded reference" } else { "DIFFERS from the CPU-decoded reference" }
        ))
    };
    let png = |cam: &Camera, p: &Path| {
        let colour = match how {
            Pipeline::Vertex => Pipeline::Vertex,
            _ => Pipeline::mesh_ids(cull),
        };
        let img = pass.render(cam, colour, Shading::Lit)?;
        crate::render::write_png(p, WIDTH, HEIGHT, &img.pixels)
            .with_context(|| format!("{}: cannot write", p.display()))
    };
    let rows = each_view(&a, &views, measure, line, png)?;
    let validation_errors = ctx.validation.as_ref().map(|v| v.errors());
    if a.json {
        let out = serde_json::json!({
            "mesh": a.mesh.display().to_string(),
            "triangles": m.triangle_count(),
            "format": format.name(),
            "source": what,
            "meshlets": upload.meshlets(),
            "device_bytes": upload.device_bytes(),
            "uncompressed_device_bytes": split_bytes,
            "decoded_reference_device_bytes": reference.device_bytes(),
        });
        print_json(out, &ctx, cull, &a, &validation_errors, &rows)?;
    } else if let Some(p) = &a.output {
        say!("wrote {}", p.display());
    }
    if let Some(r) = rows.iter().find(|r| !r.identical_to_decoded_reference) {
        bail!(
            "view {}: the shader-decoded image differs from the CPU-decoded reference",
            r.view
        );
    }
    report_validation(validation_errors, a.json)
}

/// Runs every view of a render mode: `measure` draws view `i` into its row, `line` is the row's
/// text (printed as it comes unless `--json`), `png` writes the first view's image to
/// `--output`. The rows, in view order, for the JSON report.
fn each_view<R>(
    a: &RenderArgs,
    views: &[Camera],
    mut measure: impl FnMut(usize, &Camera) -> Result<R>,
    line: impl Fn(&R) -> Option<String>,
    png: impl Fn(&Camera, &Path) -> Result<()>,
) -> Result<Vec<R>> {
    let mut rows = Vec::with_capacity(views.len());
    for (i, cam) in views.iter().enumerate() {
        let row = measure(i, cam)?;
        if !a.json {
            if let Some(text) = line(&row) {
                say!("{text}");
            }
        }
        rows.push(row);
        if i == 0 {
            if let Some(p) = &a.output {
                png(cam, p)?;
            }
        }
    }
    Ok(rows)
}

/// The views of `render` (seeded random directions, framed unless `--distance`) and the mesh's
/// bounding radius (half the box diagonal) to express distances in.
fn cameras(a: &RenderArgs, m: &crate::mesh::Mesh) -> (Vec<Camera>, f32) {
    let aspect = WIDTH as f32 / HEIGHT as f32;
    let views = match a.distance {
        Some(d) => Camera::random_views(m, a.views as usize, a.seed, d),
        None => Camera::framed_views(
            m,
            a.views as usize,
            a.seed,
            aspect,
            crate::render::FRAME_FILL,
        ),
    };
    let (lo, hi) = m.bounding_box();
    (views, ((hi - lo).length() * 0.5).max(1e-6))
}

/// Prints a view report as JSON: `out` (the command's own fields) with the device, culling, PNG,
/// validation-layer errors and per-view rows every render mode reports.
fn print_json<T: std::fmt::Debug>(
    mut out: serde_json::Value,
    ctx: &Context,
    cull: bool,
    a: &RenderArgs,
    validation_errors: &Option<(u32, T)>,
    rows: &impl serde::Serialize,
) -> Result<()> {
    let o = out.as_object_mut().expect("a JSON object");
    o.insert("device".into(), ctx.name.clone().into());
    o.insert("culling".into(), cull.into());
    o.insert(
        "png".into(),
        a.output.as_ref().map(|p| p.display().to_string()).into(),
    );
    o.insert(
        "validation_errors".into(),
        validation_errors.as_ref().map(|e| e.0).into(),
    );
    o.insert("views".into(), serde_json::to_value(rows)?);
    say!("{}", serde_json::to_string_pretty(&out)?);
    Ok(())
}

/// Fails on validation-layer errors (when the layer ran), else says there were none.
fn report_validation<T: std::fmt::Debug>(errors: Option<(u32, T)>, json: bool) -> Result<()> {
    if let Some((errors, first)) = errors {
        if errors > 0 {
            bail!("the validation layer reported {errors} errors, first: {first:#?}");
        }
        if !json {
            say!("validation layer: no errors");
        }
    }
    Ok(())
}

//! `meshletlab bench gpu`: each GPU kernel family and the whole k-medoids on the GPU against the
//! CPU reference (one thread and rayon), for the bunny, igea, the dragon and the dragon subdivided
//! to 3.5 M and 14 M triangles; run time against error; the paper's Table 4 beside ours ->
//! results/gpu.md, results/gpu.csv, results/gpu_scaling.svg, results/gpu_time_vs_error.svg.
//!
//! Every GPU result is compared with the CPU's before its time is written: a row is only reported
//! if the outputs are identical.

use super::kmedoids::PAPER_TIMES;
use super::plot::{line_chart, Axes, Series};
use super::{machine_note, today};
use crate::adjacency::{dual_graph, vertex_triangles};
use crate::gpu::{self, timed as secs, Gpu};
use crate::mesh::{self, subdivide::subdivide, Mesh};
use crate::meshlet::{Limits, Meshlets};
use crate::strategy::kmedoids::{cluster, Config as KConfig};
use crate::strategy::{self, parallel};
use anyhow::{bail, Context, Result};
use indicatif::ProgressBar;
use std::fmt::Write as _;
use std::path::PathBuf;

/// What to run.
#[derive(Clone, Debug)]
pub struct Config {
    /// Folder of meshes.
    pub meshes: PathBuf,
    /// Output folder.
    pub out: PathBuf,
    /// Meshlet limits.
    pub limits: Limits,
    /// Above this many triangles, skip the GPU and one-thread k-medoids (rayon still runs).
    pub kmedoids_gpu_max: usize,
    /// Skip the subdivided dragons (a quick run).
    pub quick: bool,
    /// No progress output.
    pub quiet: bool,
}

struct Row {
    mesh: String,
    triangles: usize,
    adj_cpu: f64,
    adj_gpu: gpu::adjacency::Timing,
    km_cpu1: Option<f64>,
    km_rayon: f64,
    km_gpu: Option<(f64, gpu::adjacency::Timing, u32)>,
    meshlets: usize,
    iterations: u32,
    grow: Vec<GrowRow>,
}

/// One strategy's meshlets on one mesh, for the parallel-grower comparison.
struct GrowRow {
    what: String,
    meshlets: usize,
    tris_per: f64,
    verts_per: f64,
    seconds: f64,
    /// Waves and rounds (parallel grower only).
    depth: Option<(u32, u32)>,
}

impl GrowRow {
    fn new(what: &str, ml: &Meshlets, seconds: f64, depth: Option<(u32, u32)>) -> Self {
        let n = ml.len().max(1) as f64;
        Self {
            what: what.into(),
            meshlets: ml.len(),
            tris_per: ml.triangle_count() as f64 / n,
            verts_per: ml.vertices.len() as f64 / n,
            seconds,
            depth,
        }
    }
}

/// The seed-spacing sweep on the bunny: (spacing, CPU rayon row, GPU seconds).
type Sweep = Vec<(f64, GrowRow, f64)>;

/// Runs the benchmark and writes the results.
pub fn run(cfg: &Config) -> Result<()> {
    let g = Gpu::new()?;
    let say = |m: String| {
        if !cfg.quiet {
            eprintln!("{m}");
        }
    };
    say(format!("GPU: {}", g.describe()));
    let load = |stem: &str| -> Result<Mesh> {
        let p = cfg.meshes.join(format!("{stem}.ply.zst"));
        mesh::load(&p).with_context(|| format!("bench gpu needs {}", p.display()))
    };
    let dragon = load("stanford_dragon_vrip")?;
    let mut inputs: Vec<(String, Mesh)> = vec![
        ("stanford_bunny".into(), load("stanford_bunny")?),
        ("igea".into(), load("igea")?),
    ];
    if !cfg.quick {
        inputs.push((
            "dragon x4 (subdivided)".into(),
            subdivide(&dragon, 1).map_err(anyhow::Error::msg)?,
        ));
        inputs.push((
            "dragon x16 (subdivided)".into(),
            subdivide(&dragon, 2).map_err(anyhow::Error::msg)?,
        ));
    }
    inputs.insert(2, ("stanford_dragon_vrip".into(), dragon));
    let one = rayon::ThreadPoolBuilder::new().num_threads(1).build()?;
    let kc = KConfig::default();
    let mut rows = Vec::new();
    for (name, m) in &inputs {
        let t = m.triangle_count();
        let pb = if cfg.quiet {
            ProgressBar::hidden()
        } else {
            ProgressBar::new_spinner()
        };
        pb.enable_steady_tick(std::time::Duration::from_millis(200));
        pb.set_message(format!("{name} ({t} triangles): adjacency"));
        // Adjacency: CPU (serial by design), GPU; identical or no row.
        let ((vt, dual), adj_cpu) = secs(|| {
            let vt = vertex_triangles(m);
            let d = dual_graph(m, &vt);
            (vt, d)
        });
        let (host, adj_gpu) = gpu::adjacency::adjacency(&g, m)?;
        if host.vertex_triangles != vt || host.dual != dual {
            bail!("{name}: GPU adjacency differs from the CPU's");
        }
        drop((vt, host));
        pb.set_message(format!("{name} ({t} triangles): growers"));
        let grow = growers(&g, m, &dual, cfg.limits, small_grow(cfg, t), &one)
            .with_context(|| format!("{name}: parallel grower"))?;
        drop(dual);
        pb.set_message(format!("{name} ({t} triangles): k-medoids, rayon"));
        let (cr, km_rayon) = secs(|| cluster(m, cfg.limits, &kc));
        let small = t <= cfg.kmedoids_gpu_max;
        let km_cpu1 = if small {
            pb.set_message(format!("{name} ({t} triangles): k-medoids, one thread"));
            Some(secs(|| one.install(|| cluster(m, cfg.limits, &kc))).1)
        } else {
            None
        };
        let km_gpu = if small {
            pb.set_message(format!("{name} ({t} triangles): k-medoids, GPU"));
            let r = gpu::kmedoids::cluster(&g, m, cfg.limits, &kc)?;
            if r.clustering.labels != cr.labels || r.clustering.meshlets != cr.meshlets {
                bail!("{name}: GPU k-medoids differs from the CPU's");
            }
            Some((r.seconds, r.timing, r.large_updates))
        } else {
            None
        };
        pb.finish_and_clear();
        say(format!("{name}: adjacency cpu {adj_cpu:.3}s gpu kernel {:.3}s; k-medoids rayon {km_rayon:.2}s gpu {:?}", adj_gpu.kernel, km_gpu.map(|k| k.0)));
        rows.push(Row {
            mesh: name.clone(),
            triangles: t,
            adj_cpu,
            adj_gpu,
            km_cpu1,
            km_rayon,
            km_gpu,
            meshlets: cr.meshlets.len(),
            iterations: cr.iterations,
            grow,
        });
    }

    // Run time against error on the bunny: the objective after the initial clustering for
    // iteration caps 0..16, CPU (rayon) and GPU.
    let bunny = &inputs[0].1;
    let mut curve = Vec::new();
    for it in [0u32, 1, 2, 4, 8, 16] {
        let c = KConfig {
            max_iterations: it,
            ..kc
        };
        let (cpu, cs) = secs(|| cluster(bunny, cfg.limits, &c));
        let gr = gpu::kmedoids::cluster(&g, bunny, cfg.limits, &c)?;
        if gr.clustering.initial_mean_distance != cpu.initial_mean_distance {
            bail!("bunny, {it} iterations: GPU objective differs from the CPU's");
        }
        curve.push((
            it,
            cpu.initial_mean_distance,
            cpu.initial_seconds,
            cs,
            gr.seconds,
            gr.clustering.initial_seconds,
        ));
    }
    // Seed spacing against meshlet count and rounds (the parallel grower's time against error).
    let bunny_dual = dual_graph(bunny, &vertex_triangles(bunny));
    let mut sweep = Sweep::new();
    for spacing in [1.0, 2.0, 4.0, 8.0] {
        let (cpu, cs) = secs(|| parallel::grow(bunny, &bunny_dual, cfg.limits, spacing));
        let gr = gpu::grow::grow(&g, bunny, cfg.limits, spacing)?;
        if gr.owner != cpu.owner || gr.order != cpu.order {
            bail!("bunny, spacing {spacing}: GPU grower differs from the CPU's");
        }
        sweep.push((
            spacing,
            GrowRow::new("", &cpu.meshlets, cs, Some((cpu.waves, cpu.rounds))),
            gr.seconds,
        ));
    }
    write(cfg, &g, &rows, &curve, &sweep)
}

/// Whether the GPU and one-thread grower runs fit the benchmark's time (same cut as k-medoids).
fn small_grow(cfg: &Config, t: usize) -> bool {
    t <= cfg.kmedoids_gpu_max
}

/// The serial growers, meshoptimizer and the parallel grower (CPU one thread, rayon, GPU; the
/// GPU's result checked identical) on one mesh.
fn growers(
    g: &Gpu,
    m: &Mesh,
    dual: &crate::adjacency::Csr,
    limits: Limits,
    small: bool,
    one: &rayon::ThreadPool,
) -> Result<Vec<GrowRow>> {
    let mut out = Vec::new();
    for name in ["bsphere", "bsphere-coherent", "meshopt"] {
        let s = strategy::by_name(name, &strategy::Options::default())?;
        let (ml, secs_) = secs(|| s.build(m, limits));
        out.push(GrowRow::new(name, &ml, secs_, None));
    }
    let sp = parallel::DEFAULT_SPACING;
    let (cpu, cs) = secs(|| parallel::grow(m, dual, limits, sp));
    let depth = Some((cpu.waves, cpu.rounds));
    if small {
        let c1 = secs(|| one.install(|| parallel::grow(m, dual, limits, sp))).1;
        out.push(GrowRow::new(
            "bsphere-parallel, CPU 1 thread",
            &cpu.meshlets,
            c1,
            depth,
        ));
    }
    out.push(GrowRow::new(
        "bsphere-parallel, CPU rayon",
        &cpu.meshlets,
        cs,
        depth,
    ));
    if small {
        let gr = gpu::grow::grow(g, m, limits, sp)?;
        if gr.owner != cpu.owner || gr.order != cpu.order || gr.meshlets != cpu.meshlets {
            bail!("GPU parallel grower differs from the CPU's");
        }
        out.push(GrowRow::new(
            "bsphere-parallel, GPU",
            &gr.meshlets,
            gr.seconds,
            depth,
        ));
    }
    Ok(out)
}

type Curve = (u32, f64, f64, f64, f64, f64);

fn write(cfg: &Config, g: &Gpu, rows: &[Row], curve: &[Curve], sweep: &Sweep) -> Result<()> {
    std::fs::create_dir_all(&cfg.out)?;
    let opt =
        |x: Option<f64>, f: &dyn Fn(f64) -> String| x.map(f).unwrap_or_else(|| "skipped".into());
    let mut md = String::new();
    writeln!(md, "# GPU kernels against their CPU references\n")?;
    writeln!(
        md,
        "Generated by `meshletlab bench gpu` on {} — {}.",
        today(),
        machine_note()
    )?;
    writeln!(md, "GPU adapter: **{}**{}. Every GPU output below was compared with the CPU reference and is identical (adjacency CSR arrays; k-medoids labels and meshlets; parallel-grower claims, orders and meshlets); a difference aborts the benchmark.\n", g.describe(), if g.timestamps { "; kernel times from GPU timestamp queries" } else { "; no timestamp queries: kernel times are wall time" })?;
    writeln!(md, "Lavapipe is itself a CPU renderer on this machine's cores: a GPU/CPU ratio here compares LLVM-compiled compute shaders with native Rust on the same {} cores, not a GPU with a CPU.\n", std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1))?;
    writeln!(md, "## Adjacency (vertex -> triangle CSR + dual graph)\n")?;
    writeln!(md, "| mesh | triangles | CPU (1 thread) s | GPU kernel s | GPU upload s | GPU readback s | GPU Mtri/s (kernel) | GPU kernel / CPU |")?;
    writeln!(md, "|---|---:|---:|---:|---:|---:|---:|---:|")?;
    let mut csv = String::from("mesh,triangles,adjacency_cpu_s,adjacency_gpu_kernel_s,adjacency_gpu_upload_s,adjacency_gpu_readback_s,kmedoids_cpu1_s,kmedoids_rayon_s,kmedoids_gpu_s,kmedoids_gpu_kernel_s,meshlets,iterations\n");
    for r in rows {
        writeln!(
            md,
            "| {} | {} | {:.3} | {:.3} | {:.3} | {:.3} | {:.1} | {:.2}x |",
            r.mesh,
            r.triangles,
            r.adj_cpu,
            r.adj_gpu.kernel,
            r.adj_gpu.upload,
            r.adj_gpu.readback,
            r.triangles as f64 / r.adj_gpu.kernel / 1e6,
            r.adj_gpu.kernel / r.adj_cpu
        )?;
        writeln!(
            csv,
            "{},{},{:.6},{:.6},{:.6},{:.6},{},{:.4},{},{},{},{}",
            r.mesh,
            r.triangles,
            r.adj_cpu,
            r.adj_gpu.kernel,
            r.adj_gpu.upload,
            r.adj_gpu.readback,
            r.km_cpu1.map(|x| format!("{x:.4}")).unwrap_or_default(),
            r.km_rayon,
            r.km_gpu.map(|x| format!("{:.4}", x.0)).unwrap_or_default(),
            r.km_gpu
                .map(|x| format!("{:.4}", x.1.kernel))
                .unwrap_or_default(),
            r.meshlets,
            r.iterations
        )?;
    }
    writeln!(md, "\nTarget: >= 20 M triangles/s on lavapipe.\n")?;
    writeln!(
        md,
        "## k-medoids (fast mode, {}/{}), whole run including adjacency\n",
        cfg.limits.max_vertices, cfg.limits.max_triangles
    )?;
    writeln!(md, "| mesh | triangles | meshlets | iterations | CPU 1 thread s | CPU rayon s | GPU s | GPU kernel s | GPU / rayon | one-thread updates |")?;
    writeln!(md, "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|")?;
    for r in rows {
        writeln!(
            md,
            "| {} | {} | {} | {} | {} | {:.2} | {} | {} | {} | {} |",
            r.mesh,
            r.triangles,
            r.meshlets,
            r.iterations,
            opt(r.km_cpu1, &|x| format!("{x:.2}")),
            r.km_rayon,
            opt(r.km_gpu.map(|k| k.0), &|x| format!("{x:.2}")),
            opt(r.km_gpu.map(|k| k.1.kernel), &|x| format!("{x:.2}")),
            opt(r.km_gpu.map(|k| k.0 / r.km_rayon), &|x| format!("{x:.2}x")),
            r.km_gpu
                .map(|k| k.2.to_string())
                .unwrap_or_else(|| "-".into())
        )?;
    }
    writeln!(md, "\n\"skipped\": above {} triangles the GPU and one-thread runs are left out (`--kmedoids-gpu-max`) to keep the benchmark short; rayon runs on every mesh. Target: k-medoids on the 14 M-triangle mesh in under 5 minutes.\n", cfg.kmedoids_gpu_max)?;
    writeln!(
        md,
        "### Beside the paper's Table 4 (their k-medoids, their machine)\n"
    )?;
    writeln!(
        md,
        "| paper model | triangles | paper s | ours: nearest mesh | CPU rayon s | GPU s |"
    )?;
    writeln!(md, "|---|---:|---:|---|---:|---:|")?;
    for &(model, tris, s) in PAPER_TIMES {
        let near = rows
            .iter()
            .min_by_key(|r| (r.triangles as i64 - tris as i64).unsigned_abs())
            .context("no rows")?;
        writeln!(
            md,
            "| {model} | {tris} | {s:.1} | {} ({} triangles) | {:.2} | {} |",
            near.mesh,
            near.triangles,
            near.km_rayon,
            opt(near.km_gpu.map(|k| k.0), &|x| format!("{x:.2}"))
        )?;
    }
    writeln!(md, "\n## Run time against error (bunny)\n")?;
    writeln!(md, "The k-medoids objective (mean hop distance to the medoid after the initial clustering) for each iteration cap; GPU and CPU reach the same objective at every cap (checked).\n")?;
    writeln!(md, "| max iterations | objective (hops) | CPU rayon s (initial clustering) | CPU rayon s (whole run) | GPU s (initial clustering) | GPU s (whole run) |")?;
    writeln!(md, "|---:|---:|---:|---:|---:|---:|")?;
    for &(it, obj, ci, cw, gw, gi) in curve {
        writeln!(
            md,
            "| {it} | {obj:.4} | {ci:.3} | {cw:.3} | {gi:.3} | {gw:.3} |"
        )?;
    }
    writeln!(
        md,
        "\n## Parallel clustering: bsphere-parallel against the serial growers and meshoptimizer\n"
    )?;
    writeln!(md, "Many meshlets grow at once (grid seeds, one GPU workgroup per meshlet scoring its border by the bsphere rule, conflicts by `atomicMin` claims; see `src/strategy/parallel.rs`). GPU and CPU give identical claims, orders and meshlets (checked). Seed spacing {}. Waves and rounds are the parallel depth: every round is two dispatches over all meshlets of the wave.\n", parallel::DEFAULT_SPACING)?;
    writeln!(md, "| mesh | strategy | meshlets | triangles/meshlet | vertices/meshlet | waves / rounds | s |")?;
    writeln!(md, "|---|---|---:|---:|---:|---:|---:|")?;
    for r in rows {
        for gr in &r.grow {
            writeln!(
                md,
                "| {} | {} | {} | {:.1} | {:.1} | {} | {:.3} |",
                r.mesh,
                gr.what,
                gr.meshlets,
                gr.tris_per,
                gr.verts_per,
                gr.depth
                    .map(|(w, k)| format!("{w} / {k}"))
                    .unwrap_or_else(|| "-".into()),
                gr.seconds
            )?;
        }
    }
    writeln!(
        md,
        "\n### Seed spacing on the bunny: meshlet count against parallel depth\n"
    )?;
    writeln!(md, "| spacing (meshlets per cell) | meshlets | triangles/meshlet | waves | rounds | CPU rayon s | GPU s |")?;
    writeln!(md, "|---:|---:|---:|---:|---:|---:|---:|")?;
    for (sp, r, gs) in sweep {
        let (w, k) = r.depth.unwrap_or_default();
        writeln!(
            md,
            "| {sp} | {} | {:.1} | {w} | {k} | {:.3} | {gs:.3} |",
            r.meshlets, r.tris_per, r.seconds
        )?;
    }
    writeln!(
        md,
        "\n![scaling](gpu_scaling.svg)\n\n![time vs error](gpu_time_vs_error.svg)\n\n![grower](gpu_grower_sweep.svg)"
    )?;
    std::fs::write(cfg.out.join("gpu.md"), md)?;
    std::fs::write(cfg.out.join("gpu.csv"), csv)?;
    let pts = |f: &dyn Fn(&Row) -> Option<f64>| {
        rows.iter()
            .filter_map(|r| f(r).map(|y| (r.triangles as f64, y)))
            .collect::<Vec<_>>()
    };
    line_chart(
        &cfg.out.join("gpu_scaling.svg"),
        "k-medoids and adjacency run time against mesh size",
        "triangles (log)",
        "seconds",
        &[
            Series {
                label: "k-medoids CPU 1 thread".into(),
                points: pts(&|r| r.km_cpu1),
            },
            Series {
                label: "k-medoids CPU rayon".into(),
                points: pts(&|r| Some(r.km_rayon)),
            },
            Series {
                label: "k-medoids GPU (lavapipe)".into(),
                points: pts(&|r| r.km_gpu.map(|k| k.0)),
            },
            Series {
                label: "adjacency CPU".into(),
                points: pts(&|r| Some(r.adj_cpu)),
            },
            Series {
                label: "adjacency GPU kernel".into(),
                points: pts(&|r| Some(r.adj_gpu.kernel)),
            },
        ],
        Axes {
            log_x: true,
            ..Axes::default()
        },
    )?;
    line_chart(
        &cfg.out.join("gpu_time_vs_error.svg"),
        "bunny: k-medoids objective against run time (iteration caps 0..16)",
        "seconds (initial clustering)",
        "mean hops to medoid",
        &[
            Series {
                label: "CPU rayon".into(),
                points: curve.iter().map(|c| (c.2, c.1)).collect(),
            },
            Series {
                label: "GPU (lavapipe)".into(),
                points: curve.iter().map(|c| (c.5, c.1)).collect(),
            },
        ],
        Axes::default(),
    )?;
    line_chart(
        &cfg.out.join("gpu_grower_sweep.svg"),
        "bunny: bsphere-parallel meshlets against rounds (seed spacing 1, 2, 4, 8)",
        "growth rounds (parallel depth)",
        "meshlets",
        &[Series {
            label: "bsphere-parallel".into(),
            points: sweep
                .iter()
                .map(|(_, r, _)| (r.depth.unwrap_or_default().1 as f64, r.meshlets as f64))
                .collect(),
        }],
        Axes::default(),
    )?;
    Ok(())
}

//! CPU/GPU parity checks for one mesh, shared by `meshletlab parity` and the test suite: every
//! kernel family runs on both sides and the outputs are compared (integers exactly, floats within
//! the tolerance stated where they are compared).

use super::bounds::SphereF32;
use super::select::{Selector, ViewData};
use super::source::MeshSource;
use super::{timed, Gpu, GpuError};
use crate::adjacency::{dual_graph, side_flags, vertex_triangles, EdgeTable};
use crate::lod::flat::{select_meshlets, Flat, Query};
use crate::mesh::Mesh;
use crate::meshlet::{validate, Limits, Meshlets};
use crate::strategy::kmedoids::{self, Config, Mode};

/// One comparison.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Check {
    /// The kernel family.
    pub family: Family,
    /// What was compared.
    pub name: &'static str,
    /// `None` when identical (or within tolerance), else what differs.
    pub mismatch: Option<String>,
    /// CPU reference time in seconds.
    pub cpu_seconds: f64,
    /// GPU time in seconds (wall, uploads and readbacks included).
    pub gpu_seconds: f64,
}

fn first_difference<T: PartialEq + std::fmt::Debug>(
    what: &str,
    gpu: &[T],
    cpu: &[T],
) -> Option<String> {
    if gpu.len() != cpu.len() {
        return Some(format!(
            "{what}: GPU has {} entries, CPU {}",
            gpu.len(),
            cpu.len()
        ));
    }
    gpu.iter()
        .zip(cpu)
        .position(|(a, b)| a != b)
        .map(|i| format!("{what}[{i}]: GPU {:?}, CPU {:?}", gpu[i], cpu[i]))
}

fn check(
    family: Family,
    name: &'static str,
    cpu_seconds: f64,
    gpu_seconds: f64,
    diffs: Vec<Option<String>>,
) -> Check {
    Check {
        family,
        name,
        mismatch: diffs.into_iter().flatten().next(),
        cpu_seconds,
        gpu_seconds,
    }
}

/// Differences between the GPU's and the CPU's meshlets (descriptors, vertex and triangle lists),
/// and the GPU's validity.
fn meshlet_differences(
    mesh: &Mesh,
    limits: Limits,
    gpu: &Meshlets,
    cpu: &Meshlets,
) -> Vec<Option<String>> {
    vec![
        first_difference("meshlets", &gpu.meshlets, &cpu.meshlets),
        first_difference("meshlet vertices", &gpu.vertices, &cpu.vertices),
        first_difference("meshlet triangles", &gpu.triangles, &cpu.triangles),
        validate(mesh, gpu, limits)
            .err()
            .map(|e| format!("GPU meshlets invalid: {e}")),
    ]
}

/// The kernel families one parity run compares, in the order it runs them.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[cfg_attr(feature = "tool", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum Family {
    /// Vertex -> triangles, the dual graph and the side flags.
    Adjacency,
    /// The flat k-medoids (`kmedoids-flat`).
    KmedoidsFlat,
    /// `kmedoids-parallel`, at the default region size and at 1024-triangle regions.
    KmedoidsParallel,
    /// Bounding spheres of k-medoids meshlets.
    Bounds,
    /// The parallel grower (`bsphere-parallel`).
    Grower,
    /// LOD selection over a meshoptimizer-built DAG.
    Lod,
}

impl Family {
    /// Every family, in run order.
    pub const ALL: [Family; 6] = [
        Family::Adjacency,
        Family::KmedoidsFlat,
        Family::KmedoidsParallel,
        Family::Bounds,
        Family::Grower,
        Family::Lod,
    ];
}

/// Everything one parity run compared, kept for callers that check more (the stability suite).
pub struct Parity {
    /// One entry per kernel family run.
    pub checks: Vec<Check>,
    /// The CPU k-medoids meshlets whose spheres were compared: the flat method's, or when it was
    /// skipped `kmedoids-parallel`'s (empty when the bounds were skipped).
    pub meshlets: Meshlets,
    /// Their spheres from the GPU kernel.
    pub gpu_spheres: Vec<SphereF32>,
    /// Their spheres from the CPU mirror.
    pub cpu_spheres: Vec<SphereF32>,
}

/// Runs every kernel family on `mesh` on both sides and compares.
pub fn run(gpu: &Gpu, mesh: &Mesh, limits: Limits) -> Result<Parity, GpuError> {
    run_except(gpu, mesh, limits, &[])
}

/// [`run`] without the families in `skip` (a check a family needs from another, such as the
/// medoids the assignment starts from, is then computed on the CPU alone).
pub fn run_except(
    gpu: &Gpu,
    mesh: &Mesh,
    limits: Limits,
    skip: &[Family],
) -> Result<Parity, GpuError> {
    let runs = |f: Family| !skip.contains(&f);
    let mut out = Vec::new();
    let cfg = Config::default();
    // Adjacency (its CPU dual graph feeds the assignment and the grower).
    let ((vt, dual, flags), cpu_s) = timed(|| {
        let vt = vertex_triangles(mesh);
        let dual = dual_graph(mesh, &vt);
        let et = EdgeTable::with_vertex_triangles(mesh, &vt);
        let f = side_flags(mesh, &et);
        (vt, dual, f)
    });
    if runs(Family::Adjacency) {
        let (gpu_adj, gpu_s) = timed(|| super::adjacency::adjacency(gpu, mesh));
        let (host, _) = gpu_adj?;
        out.push(check(
            Family::Adjacency,
            "adjacency: vertex -> triangles, dual graph, side flags",
            cpu_s,
            gpu_s,
            vec![
                first_difference(
                    "vertex-triangle offsets",
                    &host.vertex_triangles.offsets,
                    &vt.offsets,
                ),
                first_difference(
                    "vertex-triangle items",
                    &host.vertex_triangles.items,
                    &vt.items,
                ),
                first_difference("dual offsets", &host.dual.offsets, &dual.offsets),
                first_difference("dual items", &host.dual.items, &dual.items),
                first_difference("side flags", &host.side_flags, &flags),
            ],
        ));
    }
    let flat = runs(Family::KmedoidsFlat)
        .then(|| check_flat(gpu, mesh, limits, &cfg))
        .transpose()?
        .map(|r| keep(&mut out, r));
    let parallel = runs(Family::KmedoidsParallel)
        .then(|| check_parallel(gpu, mesh, limits, &cfg))
        .transpose()?
        .map(|r| keep(&mut out, r));
    let (mut meshlets, mut gpu_spheres, mut cpu_spheres) = Default::default();
    if runs(Family::Bounds) {
        let ml = flat
            .or(parallel)
            .unwrap_or_else(|| kmedoids::cluster(mesh, limits, Mode::Parallel, &cfg).meshlets);
        let (spheres, check) = check_bounds(gpu, mesh, &ml)?;
        out.push(check);
        (meshlets, gpu_spheres, cpu_spheres) = (ml, spheres.0, spheres.1);
    }
    if runs(Family::Grower) {
        out.push(check_grower(gpu, mesh, &dual, limits)?);
    }
    if runs(Family::Lod) {
        // Over a DAG built on the k-medoids strategy's peer (meshopt, the LOD default).
        out.push(lod_selection(gpu, mesh, limits, LOD_VIEWS, 0x10d)?);
    }
    Ok(Parity {
        checks: out,
        meshlets,
        gpu_spheres,
        cpu_spheres,
    })
}

/// Records a family's check and passes on what later families read from it.
fn keep<T>(out: &mut Vec<Check>, (value, check): (T, Check)) -> T {
    out.push(check);
    value
}

/// The flat k-medoids on both sides; returns the CPU's meshlets.
fn check_flat(
    gpu: &Gpu,
    mesh: &Mesh,
    limits: Limits,
    cfg: &Config,
) -> Result<(Meshlets, Check), GpuError> {
    let (cpu, cpu_s) = timed(|| kmedoids::cluster(mesh, limits, Mode::Flat, cfg));
    let (g, gpu_s) = timed(|| super::kmedoids_flat::cluster(gpu, mesh, limits, &cfg.flat));
    let g = g?.clustering;
    let counts = |c: &kmedoids::Clustering| {
        [
            c.iterations,
            c.splits,
            c.initial_iterations,
            c.skipped_updates,
        ]
    };
    let check = check(
        Family::KmedoidsFlat,
        "k-medoids: medoids, labels, distances, counts, objective, meshlets",
        cpu_s,
        gpu_s,
        vec![
            first_difference("medoids", &g.medoids, &cpu.medoids),
            first_difference("labels", &g.labels, &cpu.labels),
            first_difference("distances", &g.distances, &cpu.distances),
            first_difference(
                "iterations/splits/initial iterations/skipped updates",
                &counts(&g),
                &counts(&cpu),
            ),
            (g.initial_mean_distance != cpu.initial_mean_distance).then(|| {
                format!(
                    "objective: GPU {}, CPU {}",
                    g.initial_mean_distance, cpu.initial_mean_distance
                )
            }),
        ]
        .into_iter()
        .chain(meshlet_differences(
            mesh,
            limits,
            &g.meshlets,
            &cpu.meshlets,
        ))
        .collect(),
    );
    Ok((cpu.meshlets, check))
}

/// kmedoids-parallel, at the default region size and at small regions (many per mesh, so the
/// per-region invocations and the bases between them are exercised): one check; returns the CPU's
/// meshlets at the default size.
fn check_parallel(
    gpu: &Gpu,
    mesh: &Mesh,
    limits: Limits,
    cfg: &Config,
) -> Result<(Meshlets, Check), GpuError> {
    let (mut diffs, mut cpu_total, mut gpu_total) = (Vec::new(), 0.0, 0.0);
    let mut first = None;
    for region_triangles in [cfg.parallel.region_triangles, 1024] {
        let mut rcfg = *cfg;
        rcfg.parallel.region_triangles = region_triangles;
        let (r_cpu, cpu_s) = timed(|| kmedoids::cluster(mesh, limits, Mode::Parallel, &rcfg));
        let (r_gpu, gpu_s) = timed(|| {
            let source = MeshSource::Host(mesh);
            super::kmedoids_parallel::cluster(gpu, source, limits, &rcfg.parallel, true)
        });
        let r_gpu = r_gpu?.0.clustering;
        cpu_total += cpu_s;
        gpu_total += gpu_s;
        diffs.extend([
            first_difference("medoids", &r_gpu.medoids, &r_cpu.medoids),
            first_difference("labels", &r_gpu.labels, &r_cpu.labels),
            first_difference("distances", &r_gpu.distances, &r_cpu.distances),
            (r_gpu.initial_mean_distance != r_cpu.initial_mean_distance).then(|| {
                format!(
                    "objective before the moves: GPU {}, CPU {}",
                    r_gpu.initial_mean_distance, r_cpu.initial_mean_distance
                )
            }),
            (r_gpu.iterations != r_cpu.iterations).then(|| {
                format!(
                    "rounds of moves: GPU {}, CPU {}",
                    r_gpu.iterations, r_cpu.iterations
                )
            }),
        ]);
        diffs.extend(meshlet_differences(
            mesh,
            limits,
            &r_gpu.meshlets,
            &r_cpu.meshlets,
        ));
        first.get_or_insert(r_cpu.meshlets);
    }
    let check = check(
            Family::KmedoidsParallel,
        "kmedoids-parallel: medoids, labels, distances, objective before the moves, their rounds, meshlets (default and 1024-triangle regions)",
        cpu_total,
        gpu_total,
        diffs,
    );
    Ok((first.expect("two region sizes ran"), check))
}

/// Bounding spheres of `ml` on both sides; returns (GPU, CPU) spheres.
#[allow(clippy::type_complexity)]
fn check_bounds(
    gpu: &Gpu,
    mesh: &Mesh,
    ml: &Meshlets,
) -> Result<((Vec<SphereF32>, Vec<SphereF32>), Check), GpuError> {
    let (cpu_spheres, cpu_s) = timed(|| {
        (0..ml.len())
            .map(|i| super::bounds::sphere_f32(mesh, ml, i))
            .collect::<Vec<_>>()
    });
    let (gs, gpu_s) = timed(|| super::bounds::spheres(gpu, mesh, ml));
    let (gs, _) = gs?;
    let outside = super::bounds::outside(mesh, ml, &gs);
    let check = check(
            Family::Bounds,
        "bounds: meshlet spheres (centre within 2 ulps, radius within 2^-16 + 2 ulps of the centre), conservative",
        cpu_s,
        gpu_s,
        vec![
            super::bounds::compare(mesh, ml, &gs),
            (outside > 0).then(|| format!("{outside} vertices outside their GPU sphere")),
            (super::bounds::outside(mesh, ml, &cpu_spheres) > 0)
                .then(|| "vertices outside their CPU sphere".to_string()),
        ],
    );
    Ok(((gs, cpu_spheres), check))
}

/// The parallel grower (bsphere scoring per meshlet, atomic claims) on both sides.
fn check_grower(
    gpu: &Gpu,
    mesh: &Mesh,
    dual: &crate::adjacency::Csr,
    limits: Limits,
) -> Result<Check, GpuError> {
    let spacing = crate::strategy::grow::DEFAULT_SPACING;
    let (cpu, cpu_s) = timed(|| crate::strategy::grow::grow(mesh, dual, limits, spacing));
    let (g, gpu_s) = timed(|| super::grow::grow(gpu, mesh, limits, spacing));
    let g = g?;
    Ok(check(
        Family::Grower,
        "parallel grower: claims, orders, waves, rounds, meshlets",
        cpu_s,
        gpu_s,
        vec![
            first_difference("claims (owner per triangle)", &g.owner, &cpu.owner),
            first_difference("orders", &g.order, &cpu.order),
            first_difference(
                "waves/rounds",
                &[g.waves, g.rounds],
                &[cpu.waves, cpu.rounds],
            ),
        ]
        .into_iter()
        .chain(meshlet_differences(
            mesh,
            limits,
            &g.meshlets,
            &cpu.meshlets,
        ))
        .collect(),
    ))
}

/// Views per mesh in the LOD selection check.
pub const LOD_VIEWS: usize = 1000;

/// `n` seeded selection queries around `mesh`: random directions at 1.5 to 48 bounding radii
/// (log-uniform), thresholds of 0.25 to 16 pixels at 720 rows and 60 degrees, a random finest loaded
/// level, and frustum and cone culling each on in half the views.
pub fn lod_queries(mesh: &Mesh, flat: &Flat, n: usize, seed: u64) -> Vec<Query> {
    let (lo, hi) = mesh.bounding_box();
    let centre = (lo + hi) * 0.5;
    let r = ((hi - lo).length() * 0.5).max(1e-6);
    let mut state = seed;
    let mut unit = || {
        state = crate::mesh::generate::splitmix64(state);
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    crate::mesh::generate::random_directions(n, seed)
        .into_iter()
        .map(|dir| {
            let dist = (1.5 * 32f64.powf(unit())) as f32;
            let pixels = (0.25 * 64f64.powf(unit())) as f32;
            let finest = ((unit() * flat.levels() as f64) as usize).min(flat.levels() - 1);
            let cam = crate::lod::camera::Camera::looking_at(mesh, centre + dir * r * dist);
            let mut q = cam.lod_query(pixels, finest, unit() < 0.5);
            q.cone = unit() < 0.5;
            q
        })
        .collect()
}

/// Builds the LOD DAG of `mesh` (meshoptimizer's splitter at `limits`), selects for `views` seeded
/// queries on the CPU ([`crate::lod::flat::select_meshlets`]) and with the kernel, and compares the drawn
/// sets exactly.
pub fn lod_selection(
    gpu: &Gpu,
    mesh: &Mesh,
    limits: Limits,
    views: usize,
    seed: u64,
) -> Result<Check, GpuError> {
    let strategy = crate::strategy::by_name("meshopt", &Default::default())
        .expect("the meshopt strategy exists");
    let lod = crate::lod::build(mesh, strategy.as_ref(), limits, &Default::default());
    let flat = Flat::new(mesh, &lod);
    let queries = lod_queries(mesh, &flat, views, seed);
    let (cpu, cpu_s) = timed(|| {
        queries
            .iter()
            .map(|q| select_meshlets(&flat, q))
            .collect::<Vec<_>>()
    });
    let data: Vec<ViewData> = queries
        .iter()
        .map(|q| ViewData::new(q, flat.loaded(q.finest)))
        .collect();
    let (g, gpu_s) = timed(|| Selector::new(gpu, &flat).select(&data));
    let (g, _) = g?;
    let drawn: usize = cpu.iter().map(Vec::len).sum();
    let diff = (0..queries.len())
        .find_map(|v| first_difference(&format!("view {v}: drawn meshlets"), &g[v], &cpu[v]));
    Ok(check(
        Family::Lod,
        "LOD selection: drawn meshlets (streamed LOD rule, frustum, cone) identical",
        cpu_s,
        gpu_s,
        vec![
            diff,
            (drawn == 0).then(|| format!("{views} views drew nothing: the check tests nothing")),
        ],
    ))
}

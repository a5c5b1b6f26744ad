//! CPU/GPU parity of every kernel family on lavapipe (or any Vulkan adapter).

mod common;

use meshletlab::adjacency::{dual_graph, side_flags, vertex_triangles, EdgeTable};
use meshletlab::gpu::{adjacency::adjacency, Gpu};
use meshletlab::mesh::{generate, Mesh};

fn gpu() -> Gpu {
    Gpu::new().expect("a Vulkan adapter (lavapipe: make setup)")
}

fn check_adjacency(gpu: &Gpu, name: &str, mesh: &Mesh) {
    let (host, _) = adjacency(gpu, mesh).unwrap();
    let vt = vertex_triangles(mesh);
    assert_eq!(host.vertex_triangles, vt, "{name}: vertex -> triangles");
    assert_eq!(host.dual, dual_graph(mesh, &vt), "{name}: dual graph");
    let et = EdgeTable::with_vertex_triangles(mesh, &vt);
    assert_eq!(host.side_flags, side_flags(mesh, &et), "{name}: side flags");
}

#[test]
fn adjacency_matches_cpu_on_generated_meshes() {
    let gpu = gpu();
    eprintln!("{}", gpu.describe());
    for seed in [1, 2] {
        for g in generate::demo_set(seed) {
            check_adjacency(&gpu, g.name, &g.mesh);
        }
    }
}

#[test]
fn scratch_dragon() {
    let gpu = gpu();
    let m = common::load("stanford_dragon_vrip");
    let (host, t) = adjacency(&gpu, &m).unwrap();
    eprintln!(
        "{t:?} {:.1} Mtri/s",
        m.triangle_count() as f64 / t.kernel / 1e6
    );
    let (vt, tc) = meshletlab::gpu::timed(|| vertex_triangles(&m));
    let (d, td) = meshletlab::gpu::timed(|| dual_graph(&m, &vt));
    eprintln!("cpu {tc} {td}");
    assert_eq!(host.dual, d);
}

fn check_kmedoids(gpu: &Gpu, name: &str, mesh: &Mesh, limits: meshletlab::meshlet::Limits) {
    use meshletlab::strategy::kmedoids::{cluster, Config};
    let cfg = Config::default();
    let cpu = cluster(mesh, limits, &cfg);
    let g = meshletlab::gpu::kmedoids::cluster(gpu, mesh, limits, &cfg).unwrap();
    let gc = &g.clustering;
    eprintln!(
        "{name}: cpu {:.3}s gpu {:.3}s ({:?}) large {} rounds {}",
        cpu.initial_seconds, g.seconds, g.timing, g.large_updates, g.bfs_rounds
    );
    assert_eq!(gc.medoids, cpu.medoids, "{name}: medoids");
    assert_eq!(gc.labels, cpu.labels, "{name}: labels");
    assert_eq!(gc.distances, cpu.distances, "{name}: distances");
    assert_eq!(
        (gc.iterations, gc.splits, gc.initial_iterations),
        (cpu.iterations, cpu.splits, cpu.initial_iterations),
        "{name}: counts"
    );
    assert_eq!(
        gc.initial_mean_distance, cpu.initial_mean_distance,
        "{name}: objective"
    );
    assert_eq!(gc.meshlets, cpu.meshlets, "{name}: meshlets");
    meshletlab::meshlet::validate(mesh, &gc.meshlets, limits).unwrap();
}

#[test]
fn kmedoids_matches_cpu() {
    let gpu = gpu();
    for g in generate::demo_set(3) {
        check_kmedoids(&gpu, g.name, &g.mesh, meshletlab::meshlet::Limits::DEFAULT);
    }
    check_kmedoids(
        &gpu,
        "bunny",
        &common::load("stanford_bunny"),
        meshletlab::meshlet::Limits::DEFAULT,
    );
}

#[test]
fn scratch_bunny_km() {
    let gpu = gpu();
    let m = common::load("stanford_bunny");
    let g = meshletlab::gpu::kmedoids::cluster(
        &gpu,
        &m,
        meshletlab::meshlet::Limits::DEFAULT,
        &Default::default(),
    )
    .unwrap();
    eprintln!("{:.3}", g.seconds);
}

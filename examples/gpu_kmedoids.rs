//! Run k-medoids on the GPU (wgpu; lavapipe where there is no GPU) beside the CPU reference and
//! compare, for the two methods with a GPU path, every step a kernel: `kmedoids-parallel` (the
//! region-parallel method) and `kmedoids-flat` (the plain data-parallel baseline). Medoids,
//! labels, distances and meshlets agree exactly, because the kernels use only exactly-rounded
//! integer and f32 +, -, x.
//!
//!     cargo run --example gpu_kmedoids --features gpu -- [MESH]

use meshletlab::gpu::{kmedoids_flat, kmedoids_parallel, source::MeshSource, Gpu};
use meshletlab::mesh;
use meshletlab::meshlet::{validate, Limits};
use meshletlab::strategy::kmedoids;
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mesh = match std::env::args().nth(1) {
        Some(path) => mesh::load(path.as_ref())?,
        None => mesh::generate::noisy_sphere(5, 0.3, 3),
    };
    let limits = Limits::new(64, 126)?;
    let cfg = kmedoids::Config::default();

    let gpu = Gpu::new()?;
    println!("device: {}", gpu.describe());
    let t = Instant::now();
    let cpu = kmedoids::cluster(&mesh, limits, kmedoids::Mode::Flat, &cfg);
    let cpu_s = t.elapsed().as_secs_f64();
    let run = kmedoids_flat::cluster(&gpu, &mesh, limits, &cfg.flat)?;
    let g = &run.clustering;
    validate(&mesh, &g.meshlets, limits)?;

    assert_eq!(g.medoids, cpu.medoids, "medoids");
    assert_eq!(g.labels, cpu.labels, "labels");
    assert_eq!(g.distances, cpu.distances, "distances");
    assert_eq!(g.meshlets, cpu.meshlets, "meshlets");
    println!(
        "kmedoids-flat: {} triangles -> {} meshlets in {} iterations and {} splits; CPU {:.1} ms, GPU {:.1} ms ({} BFS levels); identical",
        mesh.triangle_count(),
        g.meshlets.len(),
        g.iterations,
        g.splits,
        cpu_s * 1e3,
        run.seconds * 1e3,
        run.bfs_rounds,
    );

    let t = Instant::now();
    let cpu = kmedoids::cluster(&mesh, limits, kmedoids::Mode::Parallel, &cfg);
    let cpu_s = t.elapsed().as_secs_f64();
    let source = MeshSource::Host(&mesh);
    let (run, _) = kmedoids_parallel::cluster(&gpu, source, limits, &cfg.parallel, true)?;
    let g = &run.clustering;
    validate(&mesh, &g.meshlets, limits)?;
    assert_eq!(g.medoids, cpu.medoids, "kmedoids-parallel medoids");
    assert_eq!(g.labels, cpu.labels, "kmedoids-parallel labels");
    assert_eq!(g.distances, cpu.distances, "kmedoids-parallel distances");
    assert_eq!(g.meshlets, cpu.meshlets, "kmedoids-parallel meshlets");
    println!(
        "kmedoids-parallel: {} meshlets from {} regions; CPU {:.1} ms, GPU {:.1} ms; identical",
        g.meshlets.len(),
        run.regions,
        cpu_s * 1e3,
        run.seconds * 1e3,
    );
    Ok(())
}

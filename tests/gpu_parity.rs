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

//! Every strategy on the generated stress meshes (CAD-like parts with 128- and 400-segment fan
//! caps, a thin-strut lattice joined only through vertices, an open terrain) x the three limit
//! presets, and `partition` also at 128/128: each output validated, never below the triangle
//! bound, and identical on 1 and 4 threads. The shared real meshes have neither hubs of valence
//! 400 nor vertex-only joints; claims must hold on both.

mod common;

use meshletlab::mesh::generate::stress_set;
use meshletlab::meshlet::{validate, Limits};
use meshletlab::strategy::{self, Options};

#[test]
fn every_strategy_validates_on_every_stress_mesh_and_preset() {
    let mut opts = Options::default();
    // Paper-mode k-medoids finishes the fast way after a short budget: this test is about validity.
    opts.kmedoids.paper.budget = std::time::Duration::from_millis(200);
    let names: Vec<String> = strategy::NAMES
        .iter()
        .map(|n| n.to_string())
        .chain([
            "meshopt+refine-fast".to_string(),
            "kmedoids+refine-fast".to_string(),
        ])
        .collect();
    // `partition` also at 128/128, the count preset that PRESETS lacks.
    let count_only = [Limits::COUNT_PRESETS[2]];
    for g in stress_set(3) {
        for limits in Limits::PRESETS.iter().chain(&count_only).copied() {
            for name in &names {
                if !Limits::PRESETS.contains(&limits) && name != "partition" {
                    continue;
                }
                let s = strategy::by_name(name, &opts).unwrap();
                let ml = s.build(&g.mesh, limits);
                validate(&g.mesh, &ml, limits)
                    .unwrap_or_else(|e| panic!("{} {name} {limits}: {e}", g.name));
                assert!(
                    ml.len() * limits.max_triangles() as usize >= g.mesh.triangle_count(),
                    "{} {name} {limits}: below the triangle bound",
                    g.name
                );
            }
        }
    }
}

#[test]
fn stress_meshes_give_the_same_meshlets_on_any_thread_count() {
    let opts = Options::default();
    let (one, many) = (common::pool(1), common::pool(common::MANY_THREADS));
    for g in stress_set(3) {
        for name in strategy::NAMES
            .iter()
            .filter(|n| !strategy::SLOW.contains(n))
        {
            let s = strategy::by_name(name, &opts).unwrap();
            let a = one.install(|| s.build(&g.mesh, Limits::DEFAULT));
            let b = many.install(|| s.build(&g.mesh, Limits::DEFAULT));
            assert_eq!(a, b, "{} {name}", g.name);
        }
    }
}

/// The region method, `kmedoids-parallel`, with small regions, so every stress mesh is cut into
/// several (the default region holds a whole stress mesh): valid at every
/// preset, edge-connected clusters wherever the mesh is, and the same on 1 and many threads.
#[test]
fn region_methods_with_many_regions_on_every_stress_mesh() {
    use meshletlab::adjacency::{cluster_pieces, dual_graph, vertex_triangles};
    use meshletlab::strategy::kmedoids::{cluster, coarse::regions, Config, Mode};
    let mut cfg = Config::default();
    cfg.parallel.region_triangles = 1024;
    let (one, many) = (common::pool(1), common::pool(common::MANY_THREADS));
    for g in stress_set(3) {
        let dual = dual_graph(&g.mesh, &vertex_triangles(&g.mesh));
        assert!(regions(&g.mesh, &dual, 1024).1 >= 3, "{}", g.name);
        for (limits, mode) in Limits::PRESETS.into_iter().map(|l| (l, Mode::Parallel)) {
            let what = format!("{} {} {limits}", g.name, mode.name());
            let a = one.install(|| cluster(&g.mesh, limits, mode, &cfg));
            let b = many.install(|| cluster(&g.mesh, limits, mode, &cfg));
            assert_eq!(a.meshlets, b.meshlets, "{what}");
            assert_eq!(
                (&a.labels, &a.medoids, &a.distances),
                (&b.labels, &b.medoids, &b.distances),
                "{what}"
            );
            validate(&g.mesh, &a.meshlets, limits).unwrap_or_else(|e| panic!("{what}: {e}"));
            // Every cluster fits, so packing made one meshlet of each.
            assert_eq!(a.meshlets.len(), a.medoids.len(), "{what}");
            for (c, (own, mesh)) in cluster_pieces(&dual, &a.labels, a.medoids.len())
                .into_iter()
                .enumerate()
            {
                assert_eq!(own, mesh, "{what}: cluster {c} is split");
            }
        }
    }
}

//! Compressed meshlets: every codec through a round trip (the same triangles, winding kept up to
//! rotation), every decoded position within the tolerance, and every shared vertex decoded to the
//! same bits from every meshlet (crack-free), on every shared mesh and on generated meshes at
//! large offsets and scales.

mod common;

use meshletlab::compress::{self, meshopt_codec};
use meshletlab::mesh::{generate, Mesh};
use meshletlab::meshlet::{Limits, Meshlets};
use std::collections::HashMap;

/// A triangle up to rotation (winding kept).
fn canonical(t: [u32; 3]) -> [u32; 3] {
    let k = (0..3).min_by_key(|&k| t[k]).unwrap();
    [t[k], t[(k + 1) % 3], t[(k + 2) % 3]]
}

/// Round trip of the meshopt peer; returns bytes per triangle.
fn round_trip(name: &str, mesh: &Mesh, ml: &Meshlets, tolerance: f64) -> f64 {
    let enc = meshopt_codec::encode(mesh, ml, tolerance).unwrap();
    assert_eq!(enc.sizes.total(), enc.data.len() + 4 * enc.offsets.len());
    let mut seen: HashMap<u32, [f32; 3]> = HashMap::new();
    let mut worst = 0.0f64;
    for i in 0..ml.len() {
        let d = meshopt_codec::decode(&enc, i).unwrap_or_else(|e| panic!("{name}: {e}"));
        let mut want: Vec<[u32; 3]> = ml.global_triangles(i).map(canonical).collect();
        let mut got: Vec<[u32; 3]> = d
            .triangles
            .iter()
            .map(|t| canonical(t.map(|c| d.vertices[c as usize])))
            .collect();
        want.sort_unstable();
        got.sort_unstable();
        assert_eq!(got, want, "{name}: meshlet {i} triangles differ");
        for (k, &v) in d.vertices.iter().enumerate() {
            let p = d.positions[k];
            let o = mesh.positions[v as usize];
            let err = (0..3)
                .map(|a| (p[a] as f64 - o[a] as f64).abs())
                .fold(0.0, f64::max);
            worst = worst.max(err);
            // The grid's half step, plus the f32 rounding of the decoded value itself.
            let ulp = o.iter().fold(0.0f64, |m, x| m.max(x.abs() as f64)) * f32::EPSILON as f64;
            assert!(
                err <= tolerance + ulp,
                "{name}: vertex {v} off by {err} > {tolerance}"
            );
            let first = *seen.entry(v).or_insert(p);
            assert_eq!(
                first, p,
                "{name}: vertex {v} decodes differently in meshlet {i}"
            );
        }
    }
    let bpt = enc.sizes.total() as f64 / mesh.triangle_count() as f64;
    println!(
        "{name}: {} meshlets, {bpt:.2} bytes/triangle ({:?}), max error {:.2e} of tolerance {tolerance:.2e}",
        ml.len(),
        enc.sizes,
        worst
    );
    bpt
}

fn meshlets(mesh: &Mesh, limits: Limits) -> Meshlets {
    meshletlab::strategy::by_name("meshopt", &Default::default())
        .unwrap()
        .build(mesh, limits)
}

#[test]
fn meshopt_codec_round_trips_every_shared_mesh() {
    let l128 = Limits::new(128, 128).unwrap();
    for f in common::mesh_files() {
        let m = meshletlab::mesh::load(&f).unwrap();
        let name = f.file_name().unwrap().to_string_lossy().to_string();
        let bpt = round_trip(
            &name,
            &m,
            &meshlets(&m, l128),
            compress::paper_tolerance(&m),
        );
        // Positions at 14 bits and meshoptimizer's 11-12 bits of topology per triangle: a few
        // bytes per triangle, far below the 12 + 6 of an indexed f32 mesh.
        assert!(bpt > 1.0 && bpt < 8.0, "{name}: {bpt} bytes per triangle");
    }
}

#[test]
fn meshopt_codec_holds_the_tolerance_far_from_the_origin_and_at_any_scale() {
    let base = generate::noisy_sphere(3, 0.2, 9);
    for (offset, scale) in [(0.0, 1.0), (1e6, 1.0), (0.0, 1e-6), (0.0, 1e6), (1e3, 1e-3)] {
        let mut m = base.clone();
        for p in &mut m.positions {
            *p = p.map(|x| (x as f64 * scale + offset) as f32);
        }
        for limits in [Limits::DEFAULT, Limits::new(128, 128).unwrap()] {
            let name = format!("offset {offset} scale {scale} {limits}");
            round_trip(
                &name,
                &m,
                &meshlets(&m, limits),
                compress::paper_tolerance(&m),
            );
        }
    }
}

//! Compress meshlets with laced wires (Mlakar et al. 2024) and decode every one back: each
//! decoded meshlet has its source triangles, and every position is within the tolerance.
//!
//!     cargo run --example laced_wires -- [MESH]
//!
//! Needs only the core: works with `--no-default-features`.

use meshletlab::compress::{laced, paper_tolerance};
use meshletlab::mesh;
use meshletlab::meshlet::Limits;
use meshletlab::strategy::{Kind, Options};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mesh = match std::env::args().nth(1) {
        Some(path) => mesh::load(path.as_ref())?,
        None => mesh::generate::knot_tube(160, 24, 5),
    };
    // Laced wires store at most 64 vertices per meshlet; 64/84 with qem is the paper's setting.
    let limits = Limits::new(64, 84)?;
    let meshlets = Kind::Qem.strategy(&Options::default()).build(&mesh, limits);
    let tolerance = paper_tolerance(&mesh); // 14-bit quantisation of the bounding box
    let enc = laced::encode(&mesh, &meshlets, tolerance)?;
    let s = &enc.sizes;
    let t = mesh.triangle_count() as f64;
    println!(
        "{} meshlets, {} triangles -> {} bytes, {:.2} bytes/triangle (connectivity {:.2}, positions {:.2})",
        meshlets.len(),
        mesh.triangle_count(),
        s.total(),
        s.total() as f64 / t,
        s.connectivity as f64 / t,
        s.positions as f64 / t,
    );

    let mut worst = 0.0f64;
    for i in 0..meshlets.len() {
        let d = laced::decode(&enc, i)?;
        // Same triangles as the source meshlet, as sets of source vertex triples up to rotation.
        let canon = |t: [u32; 3]| {
            let r = (0..3).min_by_key(|&k| t[k]).unwrap();
            [t[r], t[(r + 1) % 3], t[(r + 2) % 3]]
        };
        let mut got: Vec<_> = d
            .triangles
            .iter()
            .map(|t| canon(t.map(|c| d.vertices[c as usize])))
            .collect();
        let mut want: Vec<_> = meshlets.global_triangles(i).map(canon).collect();
        got.sort_unstable();
        want.sort_unstable();
        assert_eq!(got, want, "meshlet {i}");
        for (v, p) in d.vertices.iter().zip(&d.positions) {
            let src = mesh.positions()[*v as usize];
            for a in 0..3 {
                worst = worst.max((p[a] as f64 - src[a] as f64).abs());
            }
        }
        // The culling record decodes on its own, without the topology.
        let c = laced::culling(&enc, i)?;
        assert!(c.radius > 0.0);
    }
    assert!(
        worst <= tolerance,
        "largest error {worst} over tolerance {tolerance}"
    );
    println!("every meshlet decodes back; largest position error {worst:.3e} (tolerance {tolerance:.3e})");
    Ok(())
}

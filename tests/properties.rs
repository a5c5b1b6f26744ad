//! Property tests on random small meshes, including degenerate, duplicated and non-manifold
//! triangles and coincident vertices: every strategy's output validates, bounds are conservative,
//! and the PLY reader never panics.

use glam::DVec3;
use meshletlab::mesh::{ply, Mesh};
use meshletlab::meshlet::{bounds, validate, Limits};
use meshletlab::strategy::{self, Options};
use proptest::prelude::*;

/// Random meshes: positions on a coarse grid (so coincident points and zero-area triangles happen),
/// indices drawn from a small vertex set (so repeats, duplicates and non-manifold edges happen).
fn arb_mesh() -> impl Strategy<Value = Mesh> {
    (3usize..40).prop_flat_map(|n| {
        let pos = prop::collection::vec(prop::array::uniform3(-4i32..5), n);
        let tris = prop::collection::vec(prop::array::uniform3(0..n as u32), 1..300);
        (pos, tris).prop_map(|(p, t)| {
            let positions: Vec<[f32; 3]> =
                p.into_iter().map(|q| q.map(|c| c as f32 * 0.25)).collect();
            let indices: Vec<u32> = t.into_iter().flatten().collect();
            Mesh::from_slices(&positions, &indices, "random").unwrap()
        })
    })
}

fn arb_limits() -> impl Strategy<Value = Limits> {
    (3u32..=40, 1u32..=64).prop_map(|(v, t)| Limits::new(v, t).unwrap())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 96, ..ProptestConfig::default() })]

    #[test]
    fn every_strategy_places_every_triangle(m in arb_mesh(), limits in arb_limits()) {
        prop_assert!(m.validate().is_ok());
        for s in strategy::all(&Options::default()) {
            let ml = s.build(&m, limits);
            if let Err(e) = validate(&m, &ml, limits) {
                return Err(TestCaseError::fail(format!("{}: {e}", s.name())));
            }
        }
    }

    #[test]
    fn bounds_are_conservative(m in arb_mesh(), limits in arb_limits(), cams in prop::collection::vec(prop::array::uniform3(-8.0f32..8.0), 16)) {
        let ml = strategy::by_name("nvidia+tipsify", &Options::default()).unwrap().build(&m, limits);
        for (i, b) in bounds::compute_bounds(&m, &ml).iter().enumerate() {
            let c = DVec3::from_array(b.sphere.center.map(f64::from));
            prop_assert!(b.sphere.radius.is_finite() && b.cone.cutoff.is_finite());
            prop_assert!(b.cone.apex.iter().chain(&b.cone.axis).all(|x| x.is_finite()));
            for &v in ml.meshlet_vertices(i) {
                let p = DVec3::from_array(m.positions()[v as usize].map(f64::from));
                prop_assert!((p - c).length() <= b.sphere.radius as f64);
            }
            for cam in &cams {
                if b.cone.culls(*cam) {
                    let camd = DVec3::from_array(cam.map(f64::from));
                    for t in ml.global_triangles(i) {
                        let p = t.map(|v| DVec3::from_array(m.positions()[v as usize].map(f64::from)));
                        let n = (p[1] - p[0]).cross(p[2] - p[0]);
                        prop_assert!(n.dot(p[0] - camd) >= 0.0, "meshlet {} culled with a front face", i);
                    }
                }
            }
        }
    }

    #[test]
    fn ply_round_trips(m in arb_mesh()) {
        let mut buf = Vec::new();
        ply::write_binary(m.positions(), m.indices(), &mut buf).unwrap();
        prop_assert_eq!(ply::parse(&buf).unwrap(), (m.positions().to_vec(), m.indices().to_vec()));
    }

    #[test]
    fn ply_reader_never_panics_on_corrupted_files(m in arb_mesh(), flips in prop::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 1..8), cut in any::<prop::sample::Index>()) {
        let mut buf = Vec::new();
        ply::write_binary(m.positions(), m.indices(), &mut buf).unwrap();
        for (at, byte) in flips {
            let i = at.index(buf.len());
            buf[i] = byte;
        }
        let end = cut.index(buf.len() + 1);
        // Any outcome but a panic is fine; a success must be a valid mesh or a typed error later.
        if let Ok((p, i)) = ply::parse(&buf[..end]) {
            let _ = Mesh::new(p, i, "corrupted".as_ref());
        }
    }
}

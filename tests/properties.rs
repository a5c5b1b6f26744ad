//! Property tests on random small meshes, including degenerate, duplicated and non-manifold
//! triangles and coincident vertices: every strategy's output validates, bounds are conservative,
//! the PLY reader never panics, and arrays of any kind through the public API give values or typed
//! errors.

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

/// Arrays as an engine might hand them over, invalid ones included: any f32 (NaN, infinities,
/// huge values), indices up to two past the vertex count, limits from 0 to past 256, meshlets
/// whose ranges, counts and corners may or may not fit, any tolerance sign and size.
fn arb_arrays() -> impl Strategy<Value = meshletlab::fuzz::library::Arrays> {
    use meshletlab::meshlet::Meshlet;
    let coordinate = prop_oneof![
        4 => (-8i32..8).prop_map(|c| c as f32 * 0.5),
        1 => any::<f32>(),
    ];
    (1usize..24).prop_flat_map(move |n| {
        let positions = prop::collection::vec(prop::array::uniform3(coordinate.clone()), n);
        let indices = prop::collection::vec(0..n as u32 + 2, 0..120);
        let meshlet = (0u32..6, 0u32..12, 0u32..8, 0u32..6).prop_map(|(vo, to, vc, tc)| Meshlet {
            vertex_offset: vo,
            triangle_offset: to,
            vertex_count: vc,
            triangle_count: tc,
        });
        let meshlets = prop::collection::vec(meshlet, 0..4);
        let vertices = prop::collection::vec(0..n as u32 + 1, 0..16);
        let triangles = prop::collection::vec(0u8..8, 0..30);
        let header = (
            (0u32..300, 0u32..300),
            any::<u32>(),
            any::<u32>(),
            any::<f32>(),
        );
        (header, positions, indices, meshlets, vertices, triangles).prop_map(
            |(
                (limits, strategy, codec, tolerance),
                positions,
                indices,
                meshlets,
                vertices,
                triangles,
            )| {
                meshletlab::fuzz::library::Arrays {
                    limits,
                    strategy,
                    codec,
                    tolerance,
                    positions,
                    indices,
                    meshlets,
                    vertices,
                    triangles,
                }
            },
        )
    })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    /// Every strategy, the bounds, every descriptor layout, every codec and the LOD build, driven
    /// through the public constructors with arbitrary arrays: a value or a typed error, never a
    /// panic, and the constructors refuse exactly what breaks their invariants.
    #[test]
    fn arbitrary_arrays_give_values_or_typed_errors(a in arb_arrays()) {
        use meshletlab::fuzz::library::{drive, LABEL};
        use meshletlab::mesh::MeshErrorKind;
        use meshletlab::meshlet::Meshlets;
        let outcome = drive(&a);
        prop_assert!(outcome.is_ok(), "{:?}", outcome);
        let limits_ok = (3..=256).contains(&a.limits.0) && (1..=256).contains(&a.limits.1);
        prop_assert_eq!(Limits::new(a.limits.0, a.limits.1).is_ok(), limits_ok);
        let mesh = Mesh::from_slices(&a.positions, &a.indices, LABEL);
        let n = a.positions.len();
        let finite = a.positions.iter().flatten().all(|c| c.is_finite());
        let in_range = a.indices.iter().all(|&i| (i as usize) < n);
        let whole = !a.indices.is_empty() && a.indices.len() % 3 == 0;
        prop_assert_eq!(mesh.is_ok(), finite && in_range && whole);
        if let Err(e) = &mesh {
            prop_assert!(e.to_string().starts_with(LABEL));
            if finite && whole && !in_range {
                prop_assert!(matches!(e.kind, MeshErrorKind::IndexOutOfRange { .. }), "{}", e);
            }
        }
        if let Ok(mesh) = &mesh {
            let fits = a.meshlets.iter().all(|m| {
                let v_end = (m.vertex_offset + m.vertex_count) as usize;
                let t_end = (m.triangle_offset + 3 * m.triangle_count) as usize;
                v_end <= a.vertices.len()
                    && t_end <= a.triangles.len()
                    && a.vertices[m.vertex_offset as usize..v_end].iter().all(|&v| (v as usize) < n)
                    && a.triangles[m.triangle_offset as usize..t_end]
                        .iter()
                        .all(|&c| (c as u32) < m.vertex_count)
            });
            let made = Meshlets::new(mesh, a.meshlets.clone(), a.vertices.clone(), a.triangles.clone());
            prop_assert_eq!(made.is_ok(), fits);
        }
    }
}

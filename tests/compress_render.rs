//! Compressed meshlets drawn from their encoded bytes on lavapipe (`make setup`): every format the
//! shaders decode gives the image of the uncompressed pass drawn with the CPU-decoded positions
//! and meshlets, culling through laced wires' records removes nothing visible, the validation
//! layer stays silent, and a corrupted buffer is refused on the CPU before upload.

mod common;

use meshletlab::compress::laced::culling;
use meshletlab::compress::Codec;
use meshletlab::compress::{paper_tolerance, Encoded};
use meshletlab::mesh::Mesh;
use meshletlab::meshlet::{Limits, Meshlets};
use meshletlab::render::compressed::{decoded_reference, prepare, Decoder, Upload, FORMATS};
use meshletlab::render::{
    differing_pixels, Camera, Context, Drawn, Pass, Pipeline, RenderError, Shading,
};
use meshletlab::strategy::{self, Options};

fn meshlets(mesh: &Mesh, name: &str, limits: Limits) -> Meshlets {
    strategy::by_name(name, &Options::default())
        .unwrap()
        .build(mesh, limits)
}

const IDS: Pipeline = Pipeline::mesh_ids(false);
const CULL: Pipeline = Pipeline::mesh(true);
const NO_CULL: Pipeline = Pipeline::mesh(false);

/// Draws `enc` and its decoded reference from every view and compares; returns the meshlets the
/// laced-wire records culled (frustum, cone) over the views.
fn check(ctx: &Context, what: &str, enc: &Encoded, format: Codec, views: &[Camera]) -> (u32, u32) {
    let up = prepare(enc, format).unwrap();
    let pass = Pass::compressed(ctx, &up).unwrap();
    let culled = check_pass(ctx, what, enc, &up, &pass, views);
    if format == Codec::LacedWires && ctx.mesh_subgroups {
        // The decoder without subgroup operations, for devices that lack them in mesh shaders.
        let pass = Pass::compressed_with(ctx, &up, false).unwrap();
        let what = format!("{what} (workgroup-memory scans)");
        assert_eq!(check_pass(ctx, &what, enc, &up, &pass, views), culled);
    }
    culled
}

fn check_pass(
    ctx: &Context,
    what: &str,
    enc: &Encoded,
    up: &Upload,
    pass: &Pass,
    views: &[Camera],
) -> (u32, u32) {
    let format = up.format;
    let mut compared = 0;
    let (rmesh, rml) = decoded_reference(enc, format).unwrap();
    let reference = Pass::new(ctx, &rmesh, &rml).unwrap();
    let vertex = matches!(pass.drawn(), Drawn::Compressed(_, Decoder::Vertex));
    let (mut frustum, mut cone) = (0, 0);
    for (i, v) in views.iter().enumerate() {
        let tag = format!("{what} {} view {i}", format.name());
        // Coverage and depth, then shading: the same positions, triangles, corner order and draw
        // order as the reference, so the images are identical, not merely close.
        for shading in [Shading::Unlit, Shading::Lit] {
            let (got, want) = if vertex {
                (
                    pass.render(v, Pipeline::Vertex, shading).unwrap(),
                    reference.render(v, Pipeline::Vertex, shading).unwrap(),
                )
            } else {
                (
                    pass.render(v, IDS, shading).unwrap(),
                    reference.render(v, IDS, shading).unwrap(),
                )
            };
            assert_eq!(
                differing_pixels(&got.pixels, &want.pixels),
                0,
                "{tag} {shading:?}"
            );
            let background = &got.pixels[..4];
            let drawn = got
                .pixels
                .chunks_exact(4)
                .filter(|p| p != &background)
                .count();
            // The far views see the mesh (a close view inside a closed part may see nothing).
            assert!(drawn > 1000 || i >= 2, "{tag}: {drawn} pixels drawn");
            if let Some(q) = got.queries.filter(|_| !vertex) {
                assert_eq!(q.primitives as usize, up.triangles, "{tag}: primitives");
            }
        }
        if vertex {
            assert!(matches!(
                pass.render(v, NO_CULL, Shading::Lit),
                Err(RenderError::NoShaderDecoder(_))
            ));
            continue;
        }
        // Culling on equals culling off (the other mesh formats have no culling data: nothing culled).
        let a = pass.render(v, CULL, Shading::Lit).unwrap();
        let b = pass.render(v, NO_CULL, Shading::Lit).unwrap();
        assert_eq!(
            differing_pixels(&a.pixels, &b.pixels),
            0,
            "{tag}: culling changed the image"
        );
        assert_eq!(
            a.culled_frustum + a.culled_cone + a.drawn,
            up.meshlets() as u32,
            "{tag}"
        );
        assert_eq!(b.drawn, up.meshlets() as u32, "{tag}");
        if format != Codec::LacedWires {
            assert_eq!(a.drawn, up.meshlets() as u32, "{tag}");
        } else if a.culled_frustum == 0 {
            // The task shader reads the culling records as the CPU does: its cone test culls what
            // laced::Culling::backfacing culls, up to f32 decoding at the cone's edge (the shader
            // widens the radius by 1e-4, so it may keep a few more).
            let cpu = (0..up.meshlets())
                .filter(|&m| culling(enc, m).unwrap().backfacing(v.eye.to_array()))
                .count() as i64;
            let gpu = a.culled_cone as i64;
            compared += 1;
            assert!(
                (gpu - cpu).abs() <= 2 + cpu / 100 && (cpu == 0 || gpu > 0),
                "{tag}: the task shader culled {gpu} by the cone, the CPU records {cpu}"
            );
        }
        frustum += a.culled_frustum;
        cone += a.culled_cone;
    }
    assert!(
        format != Codec::LacedWires || compared > 0 || views.len() < 2,
        "{what}: no view without frustum culling to compare the cone culling with"
    );
    (frustum, cone)
}

#[test]
fn every_shader_decoded_format_draws_its_cpu_decoded_reference() {
    let ctx = Context::new(true).expect("lavapipe with VK_EXT_mesh_shader (make setup)");
    for (name, strat, limits) in [
        ("stanford_bunny", "meshopt", Limits::DEFAULT),
        ("fandisk", "kmedoids", Limits::new(64, 84).unwrap()),
        ("stanford_bunny", "meshopt", Limits::new(64, 256).unwrap()),
    ] {
        let mesh = common::load(name);
        let ml = meshlets(&mesh, strat, limits);
        // Around the mesh (cone culling) and from inside its bounds (frustum culling).
        let mut views = Camera::random_views(&mesh, 2, 7, 2.5);
        views.extend(Camera::random_views(&mesh, 2, 11, 0.6));
        let what = format!("{name} {strat} {limits}");
        for format in FORMATS {
            if format != Codec::LacedWires
                && limits.max_triangles() > 126
                && format != Codec::ScCompact
            {
                continue;
            }
            let enc = format.encode(&mesh, &ml, paper_tolerance(&mesh)).unwrap();
            let (frustum, cone) = check(&ctx, &what, &enc, format, &views);
            if format == Codec::LacedWires {
                assert!(frustum > 0 && cone > 0, "{what}: laced-wire records culled {frustum} by the frustum, {cone} by the cone");
            }
        }
    }
    let (errors, first) = ctx.validation.as_ref().unwrap().errors();
    assert_eq!(errors, 0, "validation layer errors: {first:#?}");
}

#[test]
fn damaged_buffers_are_refused_before_upload_or_drawn_exactly_as_they_decode() {
    let ctx = Context::new(true).expect("lavapipe with VK_EXT_mesh_shader (make setup)");
    let mesh = common::load("fandisk");
    let ml = meshlets(&mesh, "meshopt", Limits::DEFAULT);
    let view = Camera::random_views(&mesh, 1, 3, 2.5);
    let mut state = 0x5eed_u64;
    // Positions take most of a compact record, and any bits there decode: flips land in both
    // kinds of byte, and both outcomes must show up.
    let (mut total_refused, mut total_drawn) = (0, 0);
    for format in FORMATS {
        let enc = format.encode(&mesh, &ml, paper_tolerance(&mesh)).unwrap();
        // Truncated: refused, with the meshlet named.
        let mut cut = enc.clone();
        cut.data.truncate(enc.data.len() / 2);
        let err = prepare(&cut, format).unwrap_err();
        assert!(
            matches!(err, RenderError::Corrupt(_)),
            "{}: {err}",
            format.name()
        );
        assert!(err.to_string().contains("meshlet"), "{err}");
        for _ in 0..16 {
            state = meshletlab::mesh::generate::splitmix64(state);
            let mut bad = enc.clone();
            let at = (state >> 8) as usize % bad.data.len();
            bad.data[at] ^= (state as u8).max(1);
            match prepare(&bad, format) {
                Err(RenderError::Corrupt(_)) => total_refused += 1,
                Err(e) => panic!("{}: byte {at}: {e}", format.name()),
                // Whatever the CPU accepts, the shaders draw exactly as the CPU decodes it.
                Ok(_) => {
                    check(&ctx, &format!("damaged at byte {at}"), &bad, format, &view);
                    total_drawn += 1;
                }
            }
        }
    }
    assert!(
        total_refused > 0 && total_drawn > 0,
        "{total_refused} refused, {total_drawn} drawn"
    );
    let (errors, first) = ctx.validation.as_ref().unwrap().errors();
    assert_eq!(errors, 0, "validation layer errors: {first:#?}");
}

#[test]
fn formats_without_a_shader_decoder_say_so() {
    let mesh = common::load("fandisk");
    let ml = meshlets(&mesh, "meshopt", Limits::DEFAULT);
    for format in [Codec::Meshopt, Codec::Sc, Codec::Gi] {
        let enc = format.encode(&mesh, &ml, paper_tolerance(&mesh)).unwrap();
        let err = prepare(&enc, format).unwrap_err();
        assert!(matches!(err, RenderError::NoShaderDecoder(_)), "{err}");
        assert!(err.to_string().contains("laced-wires"), "{err}");
    }
}

#[test]
fn laced_wire_task_culling_never_removes_a_visible_triangle() {
    let ctx = Context::new(false).expect("lavapipe with VK_EXT_mesh_shader (make setup)");
    for name in ["stanford_bunny", "stellarium_gaspra"] {
        let mesh = common::load(name);
        let ml = meshlets(&mesh, "meshopt", Limits::DEFAULT);
        let enc = Codec::LacedWires
            .encode(&mesh, &ml, paper_tolerance(&mesh))
            .unwrap();
        let pass = Pass::compressed(&ctx, &prepare(&enc, Codec::LacedWires).unwrap()).unwrap();
        // Many seeded views, from inside the bounds (frustum culling) to far out (cone culling).
        let mut views = Vec::new();
        for (k, distance) in [0.5f32, 0.8, 1.2, 2.0, 3.5].into_iter().enumerate() {
            views.extend(Camera::random_views(&mesh, 5, 100 + k as u64, distance));
        }
        let (mut frustum, mut cone) = (0, 0);
        for (i, v) in views.iter().enumerate() {
            let a = pass.render(v, CULL, Shading::Lit).unwrap();
            let b = pass.render(v, NO_CULL, Shading::Lit).unwrap();
            assert_eq!(
                differing_pixels(&a.pixels, &b.pixels),
                0,
                "{name} view {i}: culling changed the image"
            );
            frustum += a.culled_frustum;
            cone += a.culled_cone;
        }
        assert!(frustum > 0 && cone > 0, "{name}: {frustum} {cone}");
    }
}

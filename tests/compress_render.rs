//! Compressed meshlets drawn from their encoded bytes on lavapipe (`make setup`): every format the
//! shaders decode gives the image of the uncompressed pass drawn with the CPU-decoded positions
//! and meshlets, culling through laced wires' records removes nothing visible, the validation
//! layer stays silent, and a corrupted buffer is refused on the CPU before upload.

mod common;

use meshletlab::compress::file::Format;
use meshletlab::compress::{paper_tolerance, Encoded};
use meshletlab::mesh::Mesh;
use meshletlab::meshlet::{Limits, Meshlets};
use meshletlab::render::compressed::{decoded_reference, prepare, Decoder, FORMATS};
use meshletlab::render::{
    differing_pixels, Camera, Context, Drawn, Pass, Pipeline, RenderError, Shading,
};
use meshletlab::strategy::{self, Options};

fn meshlets(mesh: &Mesh, name: &str, limits: Limits) -> Meshlets {
    strategy::by_name(name, &Options::default())
        .unwrap()
        .build(mesh, limits)
}

const IDS: Pipeline = Pipeline::Mesh {
    frustum: false,
    cone: false,
    colour_ids: true,
};
const CULL: Pipeline = Pipeline::Mesh {
    frustum: true,
    cone: true,
    colour_ids: false,
};
const NO_CULL: Pipeline = Pipeline::Mesh {
    frustum: false,
    cone: false,
    colour_ids: false,
};

/// Draws `enc` and its decoded reference from every view and compares; returns the meshlets the
/// laced-wire records culled (frustum, cone) over the views.
fn check(
    ctx: &Context,
    what: &str,
    mesh: &Mesh,
    enc: &Encoded,
    format: Format,
    views: &[Camera],
) -> (u32, u32) {
    let up = prepare(enc, format).unwrap();
    let pass = Pass::compressed(ctx, &up).unwrap();
    let (rmesh, rml) = decoded_reference(mesh, enc, format).unwrap();
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
        if format != Format::LacedWires {
            assert_eq!(a.drawn, up.meshlets() as u32, "{tag}");
        }
        frustum += a.culled_frustum;
        cone += a.culled_cone;
    }
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
            if format != Format::LacedWires
                && limits.max_triangles > 126
                && format != Format::ScCompact
            {
                continue;
            }
            let enc = format.encode(&mesh, &ml, paper_tolerance(&mesh)).unwrap();
            let (frustum, cone) = check(&ctx, &what, &mesh, &enc, format, &views);
            if format == Format::LacedWires {
                assert!(frustum > 0 && cone > 0, "{what}: laced-wire records culled {frustum} by the frustum, {cone} by the cone");
            }
        }
    }
    let (errors, first) = ctx.validation.as_ref().unwrap().errors();
    assert_eq!(errors, 0, "validation layer errors: {first:#?}");
}

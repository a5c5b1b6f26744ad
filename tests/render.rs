//! The mesh-shader pass on lavapipe (installed by `make setup`): SPIR-V validity, mesh pipeline
//! against the vertex pipeline, culling against no culling, task-shader counters, and zero
//! validation-layer errors over the whole run.

mod common;

use meshletlab::meshlet::descriptor::DescriptorFormat;
use meshletlab::meshlet::{Limits, Meshlets};
use meshletlab::render::{
    differing_pixels, max_channel_difference, Camera, Context, Pass, Pipeline, Shading, SHADERS,
};
use meshletlab::strategy::{self, Options};

#[test]
fn every_shader_is_valid_spirv() {
    let dir = std::env::temp_dir().join(format!("meshletlab-spv-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let shaders = meshletlab::render::interface::Shader::all();
    assert_eq!(shaders.len(), SHADERS.len());
    for (shader, spv) in shaders.iter().zip(SHADERS) {
        let name = shader.label();
        assert!(
            !spv.is_empty(),
            "{name}: not compiled (glslangValidator missing at build time)"
        );
        let p = dir.join("shader.spv");
        std::fs::write(&p, spv).unwrap();
        let out = std::process::Command::new("spirv-val")
            .args(["--target-env", "vulkan1.3"])
            .arg(&p)
            .output()
            .expect("spirv-val runs (make setup installs spirv-tools)");
        assert!(
            out.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}

const MESH_CULL: Pipeline = Pipeline::Mesh {
    frustum: true,
    cone: true,
    colour_ids: false,
};
const MESH_NO_CULL: Pipeline = Pipeline::Mesh {
    frustum: false,
    cone: false,
    colour_ids: false,
};

fn sorted(ids: &[u32]) -> Vec<u32> {
    let mut v = ids.to_vec();
    v.sort_unstable();
    v
}

fn meshlets(mesh: &meshletlab::mesh::Mesh, name: &str, limits: Limits) -> Meshlets {
    strategy::by_name(name, &Options::default())
        .unwrap()
        .build(mesh, limits)
}

/// Everything the pass promises, for one mesh, strategy and set of cameras.
fn check_views(
    ctx: &Context,
    mesh: &meshletlab::mesh::Mesh,
    ml: &Meshlets,
    views: &[Camera],
    format: DescriptorFormat,
) -> (u32, u32) {
    let pass = Pass::with_format(ctx, mesh, ml, format).unwrap();
    let (mut frustum, mut cone) = (0, 0);
    for (i, v) in views.iter().enumerate() {
        // Coverage and depth: the two pipelines rasterise exactly the same samples.
        let a = pass.render(v, MESH_CULL, Shading::Unlit).unwrap();
        let b = pass.render(v, Pipeline::Vertex, Shading::Unlit).unwrap();
        assert_eq!(
            differing_pixels(&a.pixels, &b.pixels),
            0,
            "view {i}: coverage differs"
        );
        assert!(
            a.pixels.chunks_exact(4).any(|p| p == [255; 4]),
            "view {i}: nothing drawn"
        );
        // Lit: the normal comes from screen-space derivatives of the interpolated position, which
        // lavapipe sets up (and clips at the near plane) separately for vertex- and mesh-shader
        // outputs. Last-bit differences move far views by a level on a few dozen pixels; close
        // views, whose triangles cross the near plane, by up to 3 levels on about 0.5 % of the
        // image. Allowed: under 1 % of the pixels, by at most 16 levels.
        let a = pass.render(v, MESH_CULL, Shading::Lit).unwrap();
        let b = pass.render(v, Pipeline::Vertex, Shading::Lit).unwrap();
        let (n, most) = (
            differing_pixels(&a.pixels, &b.pixels),
            max_channel_difference(&a.pixels, &b.pixels),
        );
        assert!(
            n * 100 < a.pixels.len() / 4 && most <= 16,
            "view {i}: lit images differ by {most} levels on {n} pixels"
        );
        // Culling never removes a visible triangle.
        let c = pass.render(v, MESH_NO_CULL, Shading::Lit).unwrap();
        assert_eq!(
            differing_pixels(&a.pixels, &c.pixels),
            0,
            "view {i}: culling changed the image"
        );
        assert_eq!(a.culled_frustum + a.culled_cone + a.drawn, ml.len() as u32);
        assert_eq!(
            (c.culled_frustum, c.culled_cone, c.drawn),
            (0, 0, ml.len() as u32)
        );
        assert!(a.gpu_ns > 0.0);
        // Triangle counters: present exactly when meshlets were culled, and never above the mesh.
        assert_eq!(a.culled_triangles[0] > 0, a.culled_frustum > 0);
        assert_eq!(a.culled_triangles[1] > 0, a.culled_cone > 0);
        assert!(a.culled_triangles.iter().sum::<u32>() as usize <= ml.triangle_count());
        // Mesh queries (lavapipe has them): every meshlet's triangles are emitted without culling,
        // exactly the survivors' with it; one task invocation per meshlet slot.
        let (qa, qc) = (
            a.queries.expect("mesh queries"),
            c.queries.expect("mesh queries"),
        );
        assert_eq!(qc.primitives as usize, ml.triangle_count(), "view {i}");
        assert_eq!(
            qa.primitives as usize,
            ml.triangle_count() - a.culled_triangles.iter().sum::<u32>() as usize
        );
        let slots = (ml.len() as u64).div_ceil(32) * 32;
        assert_eq!((qa.task_invocations, qc.task_invocations), (slots, slots));
        assert!(qc.mesh_invocations >= ml.len() as u64);
        assert!(qa.mesh_invocations < qc.mesh_invocations || a.drawn == c.drawn);
        frustum += a.culled_frustum;
        cone += a.culled_cone;
    }
    (frustum, cone)
}

#[test]
fn mesh_shaders_match_the_vertex_pipeline_and_culling_removes_nothing_visible() {
    let ctx = Context::new(true).expect("lavapipe with VK_EXT_mesh_shader (make setup)");
    let bunny = common::load("stanford_bunny");
    // Views around the mesh (cone culling) and from close up inside its bounds (frustum culling).
    let mut views = Camera::random_views(&bunny, 3, 7, 2.5);
    views.extend(Camera::random_views(&bunny, 2, 11, 0.6));
    for name in ["meshopt", "bsphere-parallel", "kmedoids"] {
        let ml = meshlets(&bunny, name, Limits::DEFAULT);
        let (frustum, cone) = check_views(&ctx, &bunny, &ml, &views, DescriptorFormat::Split);
        assert!(cone > 0, "{name}: the normal cone never culled");
        assert!(frustum > 0, "{name}: the frustum never culled");
    }
    // Limits above 64/126 take the 256/256 mesh shader.
    let ml = meshlets(&bunny, "meshopt", Limits::new(128, 256).unwrap());
    check_views(&ctx, &bunny, &ml, &views[..2], DescriptorFormat::Split);
    let (errors, first) = ctx.validation.as_ref().unwrap().errors();
    assert_eq!(errors, 0, "validation layer errors: {first:#?}");
}

#[test]
fn every_descriptor_format_draws_the_same_meshlets() {
    let ctx = Context::new(true).expect("lavapipe with VK_EXT_mesh_shader (make setup)");
    let bunny = common::load("stanford_bunny");
    let mut views = Camera::random_views(&bunny, 2, 7, 2.5);
    views.extend(Camera::random_views(&bunny, 2, 11, 0.6));
    let colour_ids = Pipeline::Mesh {
        frustum: false,
        cone: false,
        colour_ids: true,
    };
    for (name, limits) in [
        ("meshopt", Limits::DEFAULT),
        ("kmedoids", Limits::DEFAULT),
        ("meshopt", Limits::new(256, 256).unwrap()),
    ] {
        let ml = meshlets(&bunny, name, limits);
        let split = Pass::new(&ctx, &bunny, &ml).unwrap();
        let reference: Vec<_> = views
            .iter()
            .map(|v| split.render(v, colour_ids, Shading::Lit).unwrap().pixels)
            .collect();
        let (split_frustum, split_cone) =
            check_views(&ctx, &bunny, &ml, &views, DescriptorFormat::Split);
        for format in [
            DescriptorFormat::NvidiaA,
            DescriptorFormat::NvidiaB,
            DescriptorFormat::Monolithic,
        ] {
            // Decoding: every meshlet's vertices, triangles and id come out as the split layout's,
            // so the meshlet-coloured images are identical.
            let pass = Pass::with_format(&ctx, &bunny, &ml, format).unwrap();
            assert_eq!(pass.format(), format);
            for (v, want) in views.iter().zip(&reference) {
                let got = pass.render(v, colour_ids, Shading::Lit).unwrap();
                assert_eq!(
                    differing_pixels(&got.pixels, want),
                    0,
                    "{name} {limits} {format}"
                );
            }
            // Culling through this layout's bounds is safe and counted (check_views), and
            // quantised bounds cull no more than exact ones.
            let (frustum, cone) = check_views(&ctx, &bunny, &ml, &views, format);
            assert!(
                cone > 0 && frustum > 0,
                "{name} {limits} {format}: {frustum} {cone}"
            );
            if format.quantised() {
                assert!(cone <= split_cone, "{format}: {cone} > {split_cone}");
            } else {
                assert_eq!((frustum, cone), (split_frustum, split_cone), "{format}");
            }
        }
    }
    let (errors, first) = ctx.validation.as_ref().unwrap().errors();
    assert_eq!(errors, 0, "validation layer errors: {first:#?}");
}

#[test]
fn random_views_are_seeded_and_look_at_the_mesh() {
    let bunny = common::load("stanford_bunny");
    let a = Camera::random_views(&bunny, 5, 3, 2.5);
    assert_eq!(a, Camera::random_views(&bunny, 5, 3, 2.5));
    assert_ne!(a, Camera::random_views(&bunny, 5, 4, 2.5));
    let (lo, hi) = bunny.bounding_box();
    for c in &a {
        assert!((c.target - (lo + hi) * 0.5).length() < 1e-6);
        assert!(c.near > 0.0 && c.far > c.near);
    }
}

/// Cluster LOD in the task shader: at a sub-pixel threshold the cut looks like full detail; the
/// task shader's drawn meshlets (recorded by the shader, id by id) are exactly the CPU reference's (LOD rule, frustum, cone), for
/// every view and streaming prefix; far views draw far fewer triangles.
#[test]
fn lod_task_shader_matches_the_cpu_cut_and_full_detail_at_sub_pixel_threshold() {
    use meshletlab::lod::{self, flat};
    let ctx = Context::new(true).expect("lavapipe with VK_EXT_mesh_shader (make setup)");
    for name in ["stanford_bunny", "fandisk"] {
        let m = common::load(name);
        let s = strategy::by_name("meshopt", &Options::default()).unwrap();
        let dag = lod::build(&m, s.as_ref(), Limits::DEFAULT, &Default::default());
        let fl = flat::Flat::new(&m, &dag);
        let pass = Pass::with_lod(&ctx, &m, &fl).unwrap();
        let full = Pass::new(&ctx, &m, &dag.levels[0].meshlets).unwrap();
        let aspect = meshletlab::render::WIDTH as f32 / meshletlab::render::HEIGHT as f32;
        let mut views = Camera::framed_views(&m, 3, 5, aspect, meshletlab::render::FRAME_FILL);
        views.extend(Camera::random_views(&m, 2, 9, 0.6));
        let mut coarse = 0;
        for (i, cam) in views.iter().enumerate() {
            let q = cam.lod_query(0.5, 0, true);
            let (a, ids) = pass.render_lod_ids(cam, &q, Shading::Unlit).unwrap();
            let b = full.render(cam, MESH_CULL, Shading::Unlit).unwrap();
            let cpu = flat::select_meshlets(&fl, &q);
            // The very meshlets the task shader launched, not only as many.
            assert_eq!(ids, sorted(&cpu), "{name} view {i}: drawn set");
            assert_eq!(a.drawn as usize, cpu.len(), "{name} view {i}");
            coarse += cpu
                .iter()
                .filter(|&&m| fl.records[m as usize].level > 0)
                .count();
            assert_eq!(
                a.not_selected + a.culled_frustum + a.culled_cone + a.drawn,
                fl.meshlets.len() as u32
            );
            // Coverage within half a pixel of the source's silhouette: only edge pixels change.
            let covered = b.pixels.chunks_exact(4).filter(|p| p[0] > 0x40).count();
            let n = differing_pixels(&a.pixels, &b.pixels);
            println!("{name} view {i}: {n} of {covered} covered pixels differ at 0.5 px");
            assert!(covered > 1000, "{name} view {i}: mesh barely visible");
            // Stated tolerance: 1 % of the covered pixels (measured: at most 0.2 %).
            assert!(
                n * 100 <= covered,
                "{name} view {i}: {n} pixels differ from full detail (of {covered})"
            );
        }
        assert!(
            coarse > 0,
            "{name}: no coarser level drawn: the test compares nothing"
        );
        // Far away with a coarse threshold: the cut is coarse, and streaming prefixes too agree
        // with the CPU.
        let far = Camera::random_views(&m, 2, 3, 24.0);
        for cam in &far {
            for finest in 0..fl.levels() {
                let q = cam.lod_query(2.0, finest, true);
                let (a, ids) = pass.render_lod_ids(cam, &q, Shading::Lit).unwrap();
                let cpu = flat::select_meshlets(&fl, &q);
                assert_eq!(ids, sorted(&cpu), "{name}: drawn set, levels from {finest}");
                assert_eq!(a.drawn as usize, cpu.len());
                assert_eq!(
                    a.not_selected + a.culled_frustum + a.culled_cone + a.drawn,
                    fl.loaded(finest) as u32
                );
            }
            let q = cam.lod_query(2.0, 0, false);
            let a = pass.render_lod(cam, &q, false, Shading::Lit).unwrap();
            let prims = a.queries.expect("mesh queries").primitives as usize;
            assert!(
                prims * 8 < m.triangle_count(),
                "{name}: {prims} triangles drawn from 24 radii"
            );
        }
    }
    let (errors, first) = ctx.validation.as_ref().unwrap().errors();
    assert_eq!(errors, 0, "validation layer errors: {first:#?}");
}

/// The validation layer's counter fires: a deliberate misuse (a buffer of size 0, which
/// VUID-VkBufferCreateInfo-size-00912 forbids) is counted, so "0 errors" elsewhere means something.
#[test]
fn the_validation_layer_counts_a_deliberate_misuse() {
    use ash::vk;
    let ctx = Context::new(true).expect("lavapipe with VK_EXT_mesh_shader (make setup)");
    let v = ctx
        .validation
        .as_ref()
        .expect("the Khronos validation layer (make setup installs it)");
    assert_eq!(
        v.errors().0,
        0,
        "errors before the misuse: {:#?}",
        v.errors().1
    );
    let info = vk::BufferCreateInfo::default()
        .size(0)
        .usage(vk::BufferUsageFlags::STORAGE_BUFFER);
    // SAFETY: `ctx.device` is a live device; the invalid size is the point of the test (the layer
    // reports it, lavapipe creates a buffer regardless), and the buffer is destroyed at once.
    if let Ok(b) = unsafe { ctx.device.create_buffer(&info, None) } {
        // SAFETY: `b` was just created on this device and is not in use.
        unsafe { ctx.device.destroy_buffer(b, None) };
    }
    let (errors, first) = v.errors();
    assert!(errors >= 1, "the misuse was not counted");
    assert!(
        first.iter().any(|m| m.contains("00912")),
        "not the expected message: {first:#?}"
    );
}

/// An instanced scene (`gen:scene-small`: nine instances of two meshes, one mirrored, one
/// stretched unevenly) drawn per instance: the same samples as the vertex pipeline, culling that
/// removes nothing visible, counters that add up over the instances, and, against the scene baked
/// into one mesh, the same picture (a wrong front face or transform would show other surfaces).
#[test]
fn an_instanced_scene_draws_what_its_baked_mesh_draws() {
    use meshletlab::mesh::{load_scene, Instance, Scene};
    let ctx = Context::new(true).expect("lavapipe with VK_EXT_mesh_shader (make setup)");
    let small = load_scene("gen:scene-small".as_ref()).unwrap();
    assert!(small.instances().iter().any(Instance::mirrored));
    // One mirrored instance alone: a wrong front face would show the far, inner side.
    let mirrored = Scene::new(
        vec![small.meshes()[0].clone()],
        vec![Instance {
            mesh: 0,
            transform: glam::Mat4::from_scale_rotation_translation(
                glam::Vec3::new(-1.0, 1.2, 0.9),
                glam::Quat::from_rotation_y(0.4),
                glam::Vec3::new(0.5, 0.0, 0.0),
            ),
        }],
        "mirrored",
    )
    .unwrap();
    for scene in [&small, &mirrored] {
        let corners = scene.box_corners();
        let mut views = Camera::random_views(&corners, 3, 7, 2.5);
        views.extend(Camera::random_views(&corners, 2, 11, 0.5));
        // From a corner, looking along one edge: the instances away from it are outside.
        let (lo, hi) = corners.bounding_box();
        views.extend((scene.instances().len() > 1).then_some(Camera {
            eye: hi + (hi - lo) * 0.02,
            target: hi - glam::Vec3::X * (hi - lo).x,
            near: 0.01,
            far: 100.0,
        }));
        let ml: Vec<Meshlets> = scene
            .meshes()
            .iter()
            .map(|m| meshlets(m, "meshopt", Limits::DEFAULT))
            .collect();
        let total: u32 = scene
            .instances()
            .iter()
            .map(|i| ml[i.mesh as usize].len() as u32)
            .sum();
        let pass = Pass::instanced(&ctx, scene, &ml).unwrap();
        assert_eq!(pass.instance_count(), scene.instances().len());
        let baked = scene.flatten();
        let baked_pass =
            Pass::new(&ctx, &baked, &meshlets(&baked, "meshopt", Limits::DEFAULT)).unwrap();
        let (mut culled, mut culled_instances) = (0, 0);
        for (i, v) in views.iter().enumerate() {
            let a = pass.render(v, MESH_CULL, Shading::Unlit).unwrap();
            let b = pass.render(v, Pipeline::Vertex, Shading::Unlit).unwrap();
            assert_eq!(
                differing_pixels(&a.pixels, &b.pixels),
                0,
                "view {i}: coverage differs"
            );
            let a = pass.render(v, MESH_CULL, Shading::Lit).unwrap();
            let c = pass.render(v, MESH_NO_CULL, Shading::Lit).unwrap();
            assert_eq!(
                differing_pixels(&a.pixels, &c.pixels),
                0,
                "view {i}: culling changed the image"
            );
            assert_eq!(
                (c.culled_frustum, c.culled_cone, c.culled_instances, c.drawn),
                (0, 0, 0, total)
            );
            assert!(a.drawn + a.culled_frustum + a.culled_cone <= total);
            culled += a.culled_frustum + a.culled_cone;
            culled_instances += a.culled_instances;
            // The baked mesh went through f32 transforms on the CPU, the instances on the GPU:
            // last-bit differences move silhouettes by a pixel here and there and, where
            // triangles cross the near plane, shade a few percent of the pixels a few levels
            // apart. A wrong front face or transform changes the surface seen: far more pixels
            // by far more.
            let d = baked_pass.render(v, MESH_NO_CULL, Shading::Lit).unwrap();
            let n = c
                .pixels
                .chunks_exact(4)
                .zip(d.pixels.chunks_exact(4))
                .filter(|(x, y)| x.iter().zip(y.iter()).any(|(p, q)| p.abs_diff(*q) > 24))
                .count();
            let covered = d
                .pixels
                .chunks_exact(4)
                .filter(|p| p[..3] != d.pixels[..3])
                .count();
            assert!(
                covered > 1000,
                "view {i}: the scene is hardly in the picture"
            );
            assert!(
                n * 200 < covered,
                "view {i}: {n} of {covered} pixels differ from the baked scene"
            );
        }
        assert!(culled > 0, "nothing culled");
        if scene.instances().len() > 1 {
            assert!(
                culled_instances > 0,
                "no instance left the frustum in the close views"
            );
        }
    }
    let (errors, first) = ctx.validation.as_ref().unwrap().errors();
    assert_eq!(errors, 0, "validation layer errors: {first:#?}");
}

/// Two-phase occlusion culling along a camera path: every frame's depth samples and (depth, slot)
/// id image equal those of the frustum-and-cone render, the pyramid hides a share of the scene,
/// and a pyramid read at a single texel is caught by the same check.
#[test]
fn occlusion_culling_hides_nothing_and_the_check_catches_a_wrong_pyramid() {
    let ctx = Context::new(true).expect("lavapipe with VK_EXT_mesh_shader (make setup)");
    let scene = meshletlab::mesh::load_scene("gen:scene-small".as_ref()).unwrap();
    let ml: Vec<Meshlets> = scene
        .meshes()
        .iter()
        .map(|m| meshlets(m, "meshopt", Limits::DEFAULT))
        .collect();
    let pass = Pass::instanced(&ctx, &scene, &ml).unwrap();
    let corners = scene.box_corners();
    let views = Camera::random_views(&corners, 2, 5, 1.6);
    let (mut occluded, mut triangles, mut reference_triangles) = (0, 0, 0);
    for (v, view) in views.iter().enumerate() {
        pass.reset_visibility();
        for (f, cam) in view.approach(4).iter().enumerate() {
            let occ = pass.render_occlusion(cam, Shading::Unlit, true).unwrap();
            let full = pass.render_reference(cam, Shading::Unlit, true).unwrap();
            let (a, b) = (
                occ.checked.as_ref().unwrap(),
                full.checked.as_ref().unwrap(),
            );
            assert_eq!(a.differences(b), (0, 0), "view {v} frame {f}");
            assert!(
                a.ids.iter().any(|&x| x != u64::MAX),
                "view {v} frame {f}: empty image"
            );
            assert_eq!(differing_pixels(&occ.pixels, &full.pixels), 0);
            if f > 0 {
                occluded += occ.occluded;
                triangles += occ.triangles();
                reference_triangles += full.triangles();
            } else {
                assert_eq!(
                    occ.drawn_early, 0,
                    "nothing was visible before the first frame"
                );
            }
            // Every meshlet that owns a pixel was drawn.
            assert!(a.owners().len() as u32 <= occ.drawn());
        }
    }
    assert!(
        occluded > 0 && triangles < reference_triangles,
        "the pyramid hid nothing"
    );
    // A pyramid read at one pixel instead of the texels covering the footprint hides visible
    // meshlets: caught.
    let mut caught = 0;
    for view in &views {
        pass.reset_visibility();
        for cam in view.approach(4) {
            let occ = pass.render_occlusion_one_texel(&cam, true).unwrap();
            let full = pass.render_reference(&cam, Shading::Unlit, true).unwrap();
            let (d, i) = occ.checked.unwrap().differences(&full.checked.unwrap());
            caught += d + i;
        }
    }
    assert!(caught > 0, "a non-conservative pyramid went unnoticed");
    let (errors, first) = ctx.validation.as_ref().unwrap().errors();
    assert_eq!(errors, 0, "validation layer errors: {first:#?}");
}

/// The LOD cut and occlusion culling together: the early phase tests against the previous frame's
/// pyramid (visibility words do not survive a change of cut), the late phase against this frame's;
/// every frame's depth samples and id image equal those of the cut drawn with frustum and cone
/// culling alone, and the cut drawn is the CPU's minus what the pyramid hid.
#[test]
fn occlusion_culling_with_a_lod_cut_hides_nothing() {
    use meshletlab::lod::{self, flat};
    let ctx = Context::new(true).expect("lavapipe with VK_EXT_mesh_shader (make setup)");
    let m = meshletlab::mesh::load_scene("gen:scene-small".as_ref())
        .unwrap()
        .flatten();
    let s = strategy::by_name("meshopt", &Options::default()).unwrap();
    let dag = lod::build(&m, s.as_ref(), Limits::DEFAULT, &Default::default());
    let fl = flat::Flat::new(&m, &dag);
    let pass = Pass::with_lod(&ctx, &m, &fl).unwrap();
    let mut occluded = 0;
    for view in Camera::random_views(&m, 2, 5, 1.6) {
        pass.reset_visibility();
        for (f, cam) in view.approach(4).iter().enumerate() {
            // A threshold that makes the cut change along the path.
            let q = cam.lod_query(4.0, 0, true);
            let occ = pass
                .render_lod_occlusion(cam, &q, Shading::Unlit, true)
                .unwrap();
            let full = pass
                .render_lod_reference(cam, &q, Shading::Unlit, true)
                .unwrap();
            let (a, b) = (
                occ.checked.as_ref().unwrap(),
                full.checked.as_ref().unwrap(),
            );
            assert_eq!(a.differences(b), (0, 0), "frame {f}");
            assert_eq!(
                full.drawn() as usize,
                flat::select_meshlets(&fl, &q).len(),
                "frame {f}"
            );
            assert!(occ.drawn() <= full.drawn());
            if f > 0 {
                occluded += occ.occluded;
            }
        }
    }
    assert!(occluded > 0, "the pyramid hid nothing");
}

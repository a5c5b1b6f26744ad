//! Occlusion culling measured along camera paths: what `render --occlusion` and `bench render`
//! report.
//!
//! Each view becomes a short path closing in on it ([`Camera::approach`]); the first frame starts
//! from nothing visible and warms the visibility up, so it is reported apart. The path is run
//! twice: once timed (shaded, with occlusion culling and, frame by frame, the frustum-and-cone
//! render it is compared with), and once through the exactness check (id shader): every frame's
//! depth samples and (depth, slot) id image with occlusion culling must equal those without. The
//! oracle is the set of (instance, meshlet) slots that own at least one sample of the id image:
//! what a perfect culler would draw.

use super::{Camera, Pass, RenderError, Shading};
use serde::Serialize;

/// When a frame builds the pyramid: occlusion culling is a lazy stage, skipped where it does not
/// pay. A frame whose pyramid hid less than `min_share` of the triangles it tested (the first
/// frame, built from an empty early phase, does not count) makes the following frames one-phase
/// (frustum and cone only, no pyramid, visibility still recorded), until `probe_every` of them
/// have passed and a frame tries the pyramid again.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Policy {
    /// Share of the tested triangles the pyramid must hide to be built for the next frame.
    pub min_share: f64,
    /// One-phase frames before the pyramid is tried again.
    pub probe_every: u32,
}

impl Policy {
    /// The pyramid in every frame.
    pub const ALWAYS: Policy = Policy {
        min_share: 0.0,
        probe_every: 0,
    };
}

impl Default for Policy {
    /// On lavapipe the pyramid and the second phase cost about a quarter of a 720p frame of a
    /// mesh drawn whole (results/render.md, the mesh alone), so the pyramid has to hide at least a
    /// fifth of the triangles to pay; a probe every 4th frame notices a scene that starts hiding
    /// more. A GPU builds the pyramid in a fraction of that, and could take a lower share.
    fn default() -> Self {
        Self {
            min_share: 0.2,
            probe_every: 4,
        }
    }
}

/// Sums over frames of one path (or several).
#[derive(Clone, Debug, Default, Serialize)]
pub struct Totals {
    /// Frames summed.
    pub frames: u32,
    /// Of those, frames drawn in one phase without a pyramid ([`Policy`]).
    pub frames_without_pyramid: u32,
    /// Triangles drawn with occlusion culling (both phases).
    pub triangles_occlusion: u64,
    /// Triangles drawn with frustum and cone culling alone.
    pub triangles_frustum_cone: u64,
    /// Triangles of the meshlets that own a sample.
    pub triangles_oracle: u64,
    /// Meshlets drawn with occlusion culling.
    pub meshlets_occlusion: u64,
    /// Meshlets drawn with frustum and cone culling alone.
    pub meshlets_frustum_cone: u64,
    /// Meshlets that own a sample.
    pub meshlets_oracle: u64,
    /// Meshlets and triangles drawn by the early phase (visible in the previous frame).
    pub meshlets_early: u64,
    /// See `meshlets_early`.
    pub triangles_early: u64,
    /// Meshlets and triangles drawn by the late phase (newly visible).
    pub meshlets_late: u64,
    /// See `meshlets_late`.
    pub triangles_late: u64,
    /// Instances skipped whole by the frustum (host).
    pub instances_culled_frustum: u64,
    /// Instances found wholly behind the pyramid (late phase; their meshlets are in
    /// `meshlets_occluded`).
    pub instances_occluded: u64,
    /// Meshlets skipped by the frustum, the normal cone and the pyramid (late phase).
    pub meshlets_culled_frustum: u64,
    /// See `meshlets_culled_frustum`.
    pub meshlets_culled_cone: u64,
    /// See `meshlets_culled_frustum`.
    pub meshlets_occluded: u64,
    /// GPU milliseconds of the early phase, the pyramid and the late phase.
    pub early_ms: f64,
    /// See `early_ms`.
    pub pyramid_ms: f64,
    /// See `early_ms`.
    pub late_ms: f64,
    /// GPU milliseconds of the frames with occlusion culling (the three above).
    pub frame_ms_occlusion: f64,
    /// GPU milliseconds of the frames with frustum and cone culling alone.
    pub frame_ms_frustum_cone: f64,
    /// Depth samples and id samples that differ between the two renders (0 when exact).
    pub depth_samples_differing: u64,
    /// See `depth_samples_differing`.
    pub id_samples_differing: u64,
    /// Whether every frame's depth samples and id image were identical.
    pub images_identical: bool,
}

impl Totals {
    fn new() -> Self {
        Self {
            images_identical: true,
            ..Default::default()
        }
    }

    /// Adds `o`.
    pub fn add(&mut self, o: &Totals) {
        self.frames += o.frames;
        self.frames_without_pyramid += o.frames_without_pyramid;
        self.triangles_occlusion += o.triangles_occlusion;
        self.triangles_frustum_cone += o.triangles_frustum_cone;
        self.triangles_oracle += o.triangles_oracle;
        self.meshlets_occlusion += o.meshlets_occlusion;
        self.meshlets_frustum_cone += o.meshlets_frustum_cone;
        self.meshlets_oracle += o.meshlets_oracle;
        self.meshlets_early += o.meshlets_early;
        self.triangles_early += o.triangles_early;
        self.meshlets_late += o.meshlets_late;
        self.triangles_late += o.triangles_late;
        self.instances_culled_frustum += o.instances_culled_frustum;
        self.instances_occluded += o.instances_occluded;
        self.meshlets_culled_frustum += o.meshlets_culled_frustum;
        self.meshlets_culled_cone += o.meshlets_culled_cone;
        self.meshlets_occluded += o.meshlets_occluded;
        self.early_ms += o.early_ms;
        self.pyramid_ms += o.pyramid_ms;
        self.late_ms += o.late_ms;
        self.frame_ms_occlusion += o.frame_ms_occlusion;
        self.frame_ms_frustum_cone += o.frame_ms_frustum_cone;
        self.depth_samples_differing += o.depth_samples_differing;
        self.id_samples_differing += o.id_samples_differing;
        self.images_identical &= o.images_identical;
    }

    /// Triangles drawn with occlusion culling over those with frustum and cone culling alone.
    pub fn triangle_ratio(&self) -> f64 {
        self.triangles_occlusion as f64 / self.triangles_frustum_cone.max(1) as f64
    }

    /// Meshlets drawn with occlusion culling over the oracle's.
    pub fn oracle_ratio(&self) -> f64 {
        self.meshlets_occlusion as f64 / self.meshlets_oracle.max(1) as f64
    }

    /// Frame time with occlusion culling over frame time without.
    pub fn time_ratio(&self) -> f64 {
        self.frame_ms_occlusion / self.frame_ms_frustum_cone.max(1e-9)
    }
}

/// One view's path: the warm-up frame and the frames after it.
#[derive(Clone, Debug, Serialize)]
pub struct ViewPath {
    /// The view's index.
    pub view: usize,
    /// The first frame (nothing visible before it).
    pub warm_up: Totals,
    /// Every later frame, summed.
    pub frames: Totals,
}

/// The triangle count of every (instance, meshlet) slot of `scene` drawn with `meshlets` (one set
/// per mesh), in slot order: instances in order, each its mesh's meshlets.
pub fn slot_triangles(
    scene: &crate::mesh::Scene,
    meshlets: &[crate::meshlet::Meshlets],
) -> Vec<u32> {
    scene
        .instances
        .iter()
        .flat_map(|i| {
            meshlets[i.mesh as usize]
                .meshlets
                .iter()
                .map(|m| m.triangle_count)
        })
        .collect()
}

/// A LOD pass's cut: the error threshold in pixels and the finest level loaded.
#[derive(Clone, Copy, Debug)]
pub struct LodCut {
    /// Error threshold in pixels.
    pub threshold: f32,
    /// Finest level loaded.
    pub finest: usize,
}

/// Runs `view`'s path of `frames` frames on `pass` (timed, then checked), building the pyramid
/// as `policy` says (every frame for a LOD pass, given its `lod` cut); `slot_triangles[s]` is the
/// triangle count of (instance, meshlet) slot `s` (for the oracle's triangles).
pub fn measure_path(
    pass: &Pass,
    view: &Camera,
    index: usize,
    frames: usize,
    slot_triangles: &[u32],
    policy: Policy,
    lod: Option<LodCut>,
) -> Result<ViewPath, RenderError> {
    let occlusion = |cam: &Camera, shading, check, build: bool| match lod {
        Some(c) => pass.render_lod_occlusion(
            cam,
            &cam.lod_query(c.threshold, c.finest, true),
            shading,
            check,
        ),
        None if build => pass.render_occlusion(cam, shading, check),
        None => pass.render_without_pyramid(cam, shading, check),
    };
    let reference = |cam: &Camera, shading, check| match lod {
        Some(c) => pass.render_lod_reference(
            cam,
            &cam.lod_query(c.threshold, c.finest, true),
            shading,
            check,
        ),
        None => pass.render_reference(cam, shading, check),
    };
    let policy = if lod.is_some() {
        Policy::ALWAYS
    } else {
        policy
    };
    let path = view.approach(frames.max(1));
    let mut totals = [Totals::new(), Totals::new()];
    let mut drawn = Vec::with_capacity(path.len());
    // Per frame: whether it builds the pyramid (the checked run replays the timed run's choices).
    let mut pyramid = Vec::with_capacity(path.len());
    let (mut build, mut skipped) = (true, 0);
    pass.reset_visibility();
    for (f, cam) in path.iter().enumerate() {
        pyramid.push(build);
        let occ = occlusion(cam, Shading::Lit, false, build)?;
        if !build {
            skipped += 1;
            build = skipped >= policy.probe_every;
        } else if occ.drawn_early > 0 {
            // A pyramid from an empty early phase (the first frame) hides nothing: no evidence.
            let hidden = occ.culled_triangles[2] as f64;
            build = hidden / (hidden + occ.triangles() as f64).max(1.0) >= policy.min_share;
            skipped = 0;
        }
        let full = reference(cam, Shading::Lit, false)?;
        drawn.push((occ.drawn_early, occ.drawn_late, occ.occluded));
        let t = &mut totals[usize::from(f > 0)];
        t.frames += 1;
        t.frames_without_pyramid += u32::from(!pyramid[f]);
        t.triangles_occlusion += occ.triangles() as u64;
        t.triangles_frustum_cone += full.triangles() as u64;
        t.meshlets_occlusion += occ.drawn() as u64;
        t.meshlets_frustum_cone += full.drawn() as u64;
        t.meshlets_early += occ.drawn_early as u64;
        t.triangles_early += occ.triangles_early as u64;
        t.meshlets_late += occ.drawn_late as u64;
        t.triangles_late += occ.triangles_late as u64;
        t.instances_culled_frustum += occ.culled_instances as u64;
        t.instances_occluded += occ.occluded_instances as u64;
        t.meshlets_culled_frustum += occ.culled_frustum as u64;
        t.meshlets_culled_cone += occ.culled_cone as u64;
        t.meshlets_occluded += occ.occluded as u64;
        t.early_ms += occ.early_ns * 1e-6;
        t.pyramid_ms += occ.pyramid_ns * 1e-6;
        t.late_ms += occ.late_ns * 1e-6;
        t.frame_ms_occlusion += occ.gpu_ns() * 1e-6;
        t.frame_ms_frustum_cone += full.gpu_ns() * 1e-6;
    }
    // The same path through the check: the same visibility, so the same draws, which is checked.
    pass.reset_visibility();
    for (f, cam) in path.iter().enumerate() {
        let occ = occlusion(cam, Shading::Unlit, true, pyramid[f])?;
        let full = reference(cam, Shading::Unlit, true)?;
        assert_eq!(
            (occ.drawn_early, occ.drawn_late, occ.occluded),
            drawn[f],
            "the checked run of a path drew what the timed run did"
        );
        let (a, b) = (
            occ.checked.expect("checked"),
            full.checked.expect("checked"),
        );
        let (depth, ids) = a.differences(&b);
        let owners = b.owners();
        let t = &mut totals[usize::from(f > 0)];
        t.depth_samples_differing += depth as u64;
        t.id_samples_differing += ids as u64;
        t.images_identical &= depth == 0 && ids == 0;
        t.meshlets_oracle += owners.len() as u64;
        t.triangles_oracle += owners
            .iter()
            .map(|&s| slot_triangles.get(s as usize).copied().unwrap_or(0) as u64)
            .sum::<u64>();
    }
    let [warm_up, frames] = totals;
    Ok(ViewPath {
        view: index,
        warm_up,
        frames,
    })
}

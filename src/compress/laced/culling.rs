//! Laced wires' culling record (Mlakar et al. 2024, §4.1): 8 bytes per meshlet that the task
//! shader reads before any wire, a coarse bounding sphere and a normal cone of the *decoded*
//! positions and triangles, so culling is conservative for what is drawn. The fields and their
//! bits are [`super::layout`]'s `CULLING` table; the shader reads the same table as GLSL
//! constants.

use super::layout::{
    AXIS_X, AXIS_Y, CENTER_BITS, CENTRE_X, CENTRE_Y, CENTRE_Z, CULL, CULLING, CULLING_AT, CUTOFF,
    RADIUS, RADIUS_STEPS,
};
use crate::compress::{dequantise, DecodeError, Encoded};
use crate::meshlet::Meshlets;

/// A meshlet's culling data as its 8 culling bytes decode: a bounding sphere of its decoded
/// positions and a normal cone of its decoded triangles.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Culling {
    /// Sphere centre.
    pub center: [f32; 3],
    /// Sphere radius.
    pub radius: f32,
    /// Unit cone axis.
    pub axis: [f32; 3],
    /// Sine of the cone's half-angle; 1 = never culls.
    pub cutoff: f32,
}

impl Culling {
    /// The task shader's backface test without an apex (meshoptimizer's sphere-centre variant,
    /// as [`crate::meshlet::descriptor::QuantisedBounds::backfacing`]): cull when
    /// `dot(c - eye, axis) > cutoff |c - eye| + r`.
    pub fn backfacing(&self, camera: [f32; 3]) -> bool {
        crate::meshlet::descriptor::sphere_cone_backfacing(
            glam::Vec3::from_array(self.center),
            self.radius,
            glam::Vec3::from_array(self.axis),
            self.cutoff,
            camera,
        )
    }
}

/// Centre grid shift and the radius scale for grid width `g` at exponent `e`.
pub(super) fn cull_scale(g: u32, e: i32) -> (u32, f64) {
    let shift = g.saturating_sub(CENTER_BITS);
    // The largest radius code is twice the grid's extent: no sphere of the mesh is larger.
    (shift, ((e + g as i32 + 1) as f64).exp2())
}

/// Meshlet `i`'s culling record, from the positions the decoder returns, so the bounds hold for
/// what is drawn: 10-bit centre per axis on the coarsened grid, an 8-bit radius code (eighths of
/// an octave below twice the grid extent, rounded up), the octahedral axis (2 x 8 bits) and the
/// sine of the half-angle measured around the decoded axis (8 bits, rounded up; 255 = never).
pub(super) fn culling_record(
    ml: &Meshlets,
    i: usize,
    grid: &(impl Fn(u32) -> [i64; 3] + Sync),
    origin: [f32; 3],
    e: i32,
    g: u32,
) -> u64 {
    let lv = ml.meshlet_vertices(i);
    let pos = |v: u32| {
        let q = grid(v);
        glam::DVec3::from_array([0, 1, 2].map(|a| dequantise(q[a], origin[a], e) as f64))
    };
    let (shift, top) = cull_scale(g, e);
    let mut lo = [i64::MAX; 3];
    let mut hi = [i64::MIN; 3];
    for &v in lv {
        let q = grid(v);
        for a in 0..3 {
            lo[a] = lo[a].min(q[a]);
            hi[a] = hi[a].max(q[a]);
        }
    }
    let cc = [0, 1, 2].map(|a| {
        (((lo[a] + hi[a]) as f64 / 2.0 / (shift as f64).exp2()).round() as i64)
            .clamp(0, (1 << CENTER_BITS) - 1)
    });
    let c =
        glam::DVec3::from_array([0, 1, 2].map(|a| dequantise(cc[a] << shift, origin[a], e) as f64));
    let r = lv
        .iter()
        .map(|&v| (pos(v) - c).length())
        .fold(0.0, f64::max);
    // Round up, with room for the f32 decode of the radius.
    let k = if r > 0.0 {
        ((r * (1.0 + 1e-5) / top).log2() * RADIUS_STEPS + 255.0)
            .ceil()
            .clamp(0.0, 255.0) as u64
    } else {
        0
    };
    // Normal cone of the decoded triangles (degenerate ones face nowhere and are skipped).
    let normals: Vec<glam::DVec3> = ml
        .global_triangles(i)
        .filter_map(|t| {
            let [a, b, c] = t.map(pos);
            (b - a).cross(c - a).try_normalize()
        })
        .collect();
    // Axis: the centre of the smallest sphere around the normals' tips (as the meshlet bounds
    // do), which gives the narrowest cone; the mean normal was measured to widen it (dragon,
    // meshopt 64/126: mean cutoff 0.65 against 0.42, and 40 % fewer meshlets culled).
    let centre = crate::meshlet::bounds::min_sphere(&normals).0;
    let never = (0u64, 0u64, 255u64);
    let (ox, oy, cut) = match centre.try_normalize() {
        None => never,
        Some(axis) => {
            let (_, qx, qy) = crate::meshlet::descriptor::octahedral_code(axis);
            let decoded = crate::meshlet::descriptor::decode_octahedral(qx, qy);
            let theta = normals
                .iter()
                .map(|n| n.dot(decoded).clamp(-1.0, 1.0).acos())
                .fold(0.0, f64::max)
                + crate::meshlet::descriptor::AXIS_MARGIN;
            if theta >= std::f64::consts::FRAC_PI_2 {
                never
            } else {
                (
                    qx as u8 as u64,
                    qy as u8 as u64,
                    (theta.sin() * 255.0).ceil().min(255.0) as u64,
                )
            }
        }
    };
    let values = [cc[0] as u64, cc[1] as u64, cc[2] as u64, k, ox, oy, cut];
    CULLING
        .iter()
        .zip(values)
        .fold(0, |x, (f, v)| x | f.place(v))
}

/// Decodes meshlet `i`'s culling record (without touching its triangles or wires).
pub fn culling(enc: &Encoded, i: usize) -> Result<Culling, DecodeError> {
    if i >= enc.offsets.len() {
        return Err(DecodeError::OutOfRange(i));
    }
    let s = super::section(enc, i)?;
    let at = CULLING_AT + CULL * i;
    let b = enc.data.get(at..at + CULL).ok_or(DecodeError::Truncated {
        meshlet: i,
        what: "culling record",
    })?;
    let x = u64::from_le_bytes(b.try_into().expect("8 bytes"));
    let (shift, top) = cull_scale(s.g, enc.exponent);
    let center = [CENTRE_X, CENTRE_Y, CENTRE_Z].map(|f| f.get(x) as i64);
    let center = [0, 1, 2].map(|a| dequantise(center[a] << shift, enc.origin[a], enc.exponent));
    let k = RADIUS.get(x) as f64;
    let radius = if k == 0.0 {
        0.0
    } else {
        (top * ((k - 255.0) / RADIUS_STEPS).exp2()) as f32
    };
    let cut = CUTOFF.get(x);
    let axis = crate::meshlet::descriptor::decode_octahedral(
        AXIS_X.get(x) as u8 as i8,
        AXIS_Y.get(x) as u8 as i8,
    );
    Ok(Culling {
        center,
        radius,
        axis: [axis.x as f32, axis.y as f32, axis.z as f32],
        cutoff: cut as f32 / 255.0,
    })
}

//! GPU meshlet descriptors: the four layouts of Jensen et al. 2023 §2 (Tables 1–2), packed for the
//! mesh-shader pass (`glsl/descriptors.glsl` reads them) and unpacked again on the CPU for the
//! round-trip tests.
//!
//! | format | per meshlet | culling data | where the vertices come from |
//! |---|---|---|---|
//! | [`DescriptorFormat::Split`] | task descriptor (48 B: f32 sphere, cone apex, axis, cutoff) + mesh descriptor (16 B) | exact | global index buffer (u32) |
//! | [`DescriptorFormat::NvidiaA`] | 16 B: 20-bit offsets, 48-bit quantised box, 24-bit cone | quantised | global index buffer (u32) |
//! | [`DescriptorFormat::NvidiaB`] | 16 B: 32-bit offset into one pack buffer, vertex pack byte, quantised box and cone | quantised | 16-bit global indices where a meshlet's fit, else 32-bit |
//! | [`DescriptorFormat::Monolithic`] | one block: bounds, counts, copied positions, triangles | exact | per-meshlet vertex copies, no index buffer |
//!
//! Quantisation is conservative: the decoded box holds every vertex of its meshlet and the decoded
//! cone holds every triangle normal, so a meshlet culled with quantised data is also culled with
//! exact data (the converse does not hold: quantised culling skips less).
//!
//! The box is 8 bits per axis relative to the object's box (NVIDIA's UNORM8 layout). The cone axis is
//! octahedral-encoded in two signed bytes and the cutoff (sine of the normals' half-angle) in one
//! unsigned byte, rounded up after widening the angle by the axis' quantisation error. Without an
//! apex the task shader uses meshoptimizer's sphere-centre test (see [`QuantisedBounds::backfacing`]).

use super::bounds::{compute_bounds, MeshletBounds};
use super::Meshlets;
use crate::mesh::Mesh;
use glam::DVec3;
use std::fmt;
use std::str::FromStr;
use thiserror::Error;

/// A descriptor layout.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub enum DescriptorFormat {
    /// Separate task (culling) and mesh (offsets, counts) descriptors, full-precision bounds.
    #[default]
    Split,
    /// NVIDIA's 128-bit `MeshletDesc`: 20-bit offsets, quantised box and cone.
    NvidiaA,
    /// NVIDIA's 128-bit packed descriptor: one 32-bit offset into a buffer holding each meshlet's
    /// vertex indices (16-bit where they fit) followed by its triangles.
    NvidiaB,
    /// One self-contained block per meshlet with copies of its vertex positions.
    Monolithic,
}

impl DescriptorFormat {
    /// Every format, in table order.
    pub const ALL: [DescriptorFormat; 4] = [
        DescriptorFormat::Split,
        DescriptorFormat::NvidiaA,
        DescriptorFormat::NvidiaB,
        DescriptorFormat::Monolithic,
    ];

    /// Name on the command line and in results.
    pub fn name(self) -> &'static str {
        match self {
            DescriptorFormat::Split => "split",
            DescriptorFormat::NvidiaA => "nvidia-a",
            DescriptorFormat::NvidiaB => "nvidia-b",
            DescriptorFormat::Monolithic => "monolithic",
        }
    }

    /// The `DESC` value the shaders are compiled with (build.rs, glsl/descriptors.glsl).
    pub fn shader_id(self) -> u32 {
        self as u32
    }

    /// Whether culling uses quantised (looser) bounds.
    pub fn quantised(self) -> bool {
        matches!(self, DescriptorFormat::NvidiaA | DescriptorFormat::NvidiaB)
    }
}

impl fmt::Display for DescriptorFormat {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for DescriptorFormat {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        DescriptorFormat::ALL
            .into_iter()
            .find(|f| f.name() == s)
            .ok_or_else(|| {
                format!("unknown descriptor format '{s}' (split, nvidia-a, nvidia-b, monolithic)")
            })
    }
}

/// A meshlet does not fit a format's fixed-width fields.
#[derive(Debug, Error, PartialEq, Eq)]
pub enum DescriptorError {
    /// An offset or count is wider than its field.
    #[error("{format} descriptor: meshlet {meshlet} needs {what} = {value}, which does not fit the format's {bits}-bit field (use the split or nvidia-b format for meshes this large)")]
    FieldOverflow {
        /// The format.
        format: DescriptorFormat,
        /// The meshlet.
        meshlet: usize,
        /// The field.
        what: &'static str,
        /// The value that does not fit.
        value: u64,
        /// The field's width.
        bits: u32,
    },
}

/// The object box that the 8-bit meshlet boxes are relative to: axis `k` of code `q` decodes to
/// `min[k] + q * step[k]`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct ObjectBox {
    /// Lower corner.
    pub min: [f32; 3],
    /// Size of one of the 255 steps per axis.
    pub step: [f32; 3],
}

/// Culling data as a quantised descriptor decodes it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct QuantisedBounds {
    /// Box lower corner.
    pub min: [f32; 3],
    /// Box upper corner.
    pub max: [f32; 3],
    /// Unit cone axis (decoded from the octahedral code).
    pub axis: [f32; 3],
    /// Sine of the cone's half-angle; 1 = never culls.
    pub cutoff: f32,
}

impl QuantisedBounds {
    /// The task shader's backface test without an apex (meshoptimizer's sphere-centre variant, on
    /// the sphere around the box): cull when `dot(c - eye, axis) > cutoff |c - eye| + r`. Every point
    /// p of the sphere is seen within asin(r / |c - eye|) of the centre direction, so every normal is
    /// then more than 90 degrees from every view ray (sin(a + b) <= sin a + sin b).
    pub fn backfacing(&self, camera: [f32; 3]) -> bool {
        let (lo, hi) = (
            glam::Vec3::from_array(self.min),
            glam::Vec3::from_array(self.max),
        );
        sphere_cone_backfacing(
            (lo + hi) * 0.5,
            (hi - lo).length() * 0.5,
            glam::Vec3::from_array(self.axis),
            self.cutoff,
            camera,
        )
    }
}

/// The apex-free backface test (meshoptimizer's sphere-centre variant) as a task shader runs it
/// in f32: cull when `dot(c - eye, axis) > cutoff |c - eye| + r` (plus a 1e-5 relative margin for
/// the f32 arithmetic); a cutoff of 1 never culls. Used by every culling record without an apex.
pub fn sphere_cone_backfacing(
    center: glam::Vec3,
    radius: f32,
    axis: glam::Vec3,
    cutoff: f32,
    camera: [f32; 3],
) -> bool {
    if cutoff >= 1.0 {
        return false;
    }
    let d = center - glam::Vec3::from_array(camera);
    let len = d.length();
    d.dot(axis) > cutoff * len + radius + 1e-5 * len
}

/// One meshlet as read back from a packed buffer.
#[derive(Clone, Debug, PartialEq)]
pub struct DecodedDescriptor {
    /// Global vertex indices (every format except monolithic).
    pub vertices: Option<Vec<u32>>,
    /// Copied vertex positions (monolithic only).
    pub positions: Option<Vec<[f32; 3]>>,
    /// Local triangle corners, three per triangle.
    pub triangles: Vec<u8>,
    /// Exact bounds (split, monolithic) or quantised ones (NVIDIA A and B).
    pub cull: Cull,
}

/// The culling data a format carries.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Cull {
    /// Full-precision sphere and apex cone.
    Exact(MeshletBounds),
    /// 8-bit box and 24-bit cone.
    Quantised(QuantisedBounds),
}

/// Meshlets packed in one [`DescriptorFormat`], as the shaders read them (buffer bindings 1–4).
#[derive(Clone, Debug, PartialEq)]
pub struct Packed {
    /// The layout.
    pub format: DescriptorFormat,
    /// Number of meshlets.
    pub count: usize,
    /// Binding 1: four words per meshlet (split's mesh descriptor, NVIDIA A and B), or one block
    /// offset per meshlet (monolithic).
    pub descriptors: Vec<u32>,
    /// Binding 2: global vertex indices (split, A), the pack buffer (B) or the blocks (monolithic).
    pub data: Vec<u32>,
    /// Binding 3: local triangle corners, four bytes per word (split, A; empty otherwise).
    pub triangles: Vec<u32>,
    /// Binding 4: split's task descriptors, three vec4 per meshlet (empty otherwise).
    pub task: Vec<[f32; 4]>,
    /// The box the quantised bounds are relative to (A, B).
    pub object: ObjectBox,
}

/// Words of a monolithic block header: 12 bound floats, then the vertex and triangle counts.
const BLOCK_HEADER: usize = 13;
/// NVIDIA A's offset fields.
const A_OFFSET_BITS: u32 = 20;

fn overflow(
    format: DescriptorFormat,
    meshlet: usize,
    what: &'static str,
    value: u64,
    bits: u32,
) -> DescriptorError {
    DescriptorError::FieldOverflow {
        format,
        meshlet,
        what,
        value,
        bits,
    }
}

/// Packs `ml` (meshlets of `mesh`) in `format`; bounds are computed here.
pub fn pack(
    mesh: &Mesh,
    ml: &Meshlets,
    format: DescriptorFormat,
) -> Result<Packed, DescriptorError> {
    pack_with_bounds(mesh, ml, &compute_bounds(mesh, ml), format)
}

/// Packs with bounds already computed (one per meshlet).
pub fn pack_with_bounds(
    mesh: &Mesh,
    ml: &Meshlets,
    bounds: &[MeshletBounds],
    format: DescriptorFormat,
) -> Result<Packed, DescriptorError> {
    assert_eq!(bounds.len(), ml.len(), "one bounds entry per meshlet");
    let object = object_box(mesh);
    let mut p = Packed {
        format,
        count: ml.len(),
        descriptors: Vec::new(),
        data: Vec::new(),
        triangles: Vec::new(),
        task: Vec::new(),
        object,
    };
    for (i, m) in ml.meshlets.iter().enumerate() {
        let tris = ml.meshlet_triangles(i);
        let verts = ml.meshlet_vertices(i);
        match format {
            DescriptorFormat::Split => {
                p.descriptors.extend([
                    m.vertex_offset,
                    m.triangle_offset,
                    m.vertex_count,
                    m.triangle_count,
                ]);
                p.task.extend(exact_words(&bounds[i], m.triangle_count));
            }
            DescriptorFormat::NvidiaA => {
                let (bx, by, cone) = quantise(mesh, &object, verts, &bounds[i], m);
                let prim_begin = p.triangles.len() as u64;
                for (value, what) in [
                    (m.vertex_offset as u64, "vertexBegin"),
                    (prim_begin, "primBegin (words)"),
                ] {
                    if value >= 1 << A_OFFSET_BITS {
                        return Err(overflow(format, i, what, value, A_OFFSET_BITS));
                    }
                }
                let [ox, oy, cut] = cone;
                p.descriptors.extend([
                    bx,
                    by,
                    m.vertex_offset | (ox as u32) << 20 | (cut as u32 & 0xf) << 28,
                    prim_begin as u32 | (oy as u32) << 20 | (cut as u32 >> 4) << 28,
                ]);
                push_bytes(&mut p.triangles, tris);
            }
            DescriptorFormat::NvidiaB => {
                let (bx, by, cone) = quantise(mesh, &object, verts, &bounds[i], m);
                let offset = p.data.len() as u64;
                if offset > u32::MAX as u64 {
                    return Err(overflow(format, i, "packOffset", offset, 32));
                }
                // 16-bit indices when every index of this meshlet fits (NVIDIA's vertex pack).
                let pack: u8 = if verts.iter().all(|&v| v <= u16::MAX as u32) {
                    2
                } else {
                    1
                };
                if pack == 2 {
                    p.data.extend(
                        verts
                            .chunks(2)
                            .map(|c| c[0] | c.get(1).map_or(0, |&v| v << 16)),
                    );
                } else {
                    p.data.extend_from_slice(verts);
                }
                push_bytes(&mut p.data, tris);
                let [ox, oy, cut] = cone;
                p.descriptors.extend([
                    bx,
                    by,
                    ox as u32 | (oy as u32) << 8 | (cut as u32) << 16 | (pack as u32) << 24,
                    offset as u32,
                ]);
            }
            DescriptorFormat::Monolithic => {
                p.descriptors.push(p.data.len() as u32);
                let header = exact_words(&bounds[i], 0);
                p.data
                    .extend(header.iter().flatten().take(12).map(|f| f.to_bits()));
                p.data.push(m.vertex_count | m.triangle_count << 16);
                for &v in verts {
                    p.data
                        .extend(mesh.positions[v as usize].iter().map(|f| f.to_bits()));
                }
                push_bytes(&mut p.data, tris);
                if p.data.len() > u32::MAX as usize {
                    return Err(overflow(format, i, "block offset", p.data.len() as u64, 32));
                }
            }
        }
    }
    match format {
        DescriptorFormat::Split => {
            p.data = ml.vertices.clone();
            p.triangles = Vec::with_capacity(ml.triangles.len().div_ceil(4));
            push_bytes(&mut p.triangles, &ml.triangles);
        }
        DescriptorFormat::NvidiaA => p.data = ml.vertices.clone(),
        DescriptorFormat::NvidiaB | DescriptorFormat::Monolithic => {}
    }
    Ok(p)
}

/// Split's task descriptor: (sphere centre, radius), (apex, cutoff), (axis, triangle count as bits).
fn exact_words(b: &MeshletBounds, triangles: u32) -> [[f32; 4]; 3] {
    let (s, c) = (b.sphere, b.cone);
    [
        [s.center[0], s.center[1], s.center[2], s.radius],
        [c.apex[0], c.apex[1], c.apex[2], c.cutoff],
        [c.axis[0], c.axis[1], c.axis[2], f32::from_bits(triangles)],
    ]
}

/// Appends bytes four to a word (little-endian), padding the last word with zeros.
fn push_bytes(words: &mut Vec<u32>, bytes: &[u8]) {
    words.extend(bytes.chunks(4).map(|c| {
        let mut w = [0u8; 4];
        w[..c.len()].copy_from_slice(c);
        u32::from_le_bytes(w)
    }));
}

/// The mesh's box; the step is rounded up until code 255 decodes (in f32, fused or not) to at least
/// the upper corner.
pub fn object_box(mesh: &Mesh) -> ObjectBox {
    let (lo, hi) = mesh.bounding_box();
    let (lo, hi) = (lo.to_array(), hi.to_array());
    let step = [0, 1, 2].map(|k| {
        let mut s = ((hi[k] as f64 - lo[k] as f64) / 255.0) as f32;
        while (s as f64) * 255.0 < hi[k] as f64 - lo[k] as f64 || lo[k] + 255.0 * s < hi[k] {
            s = s.next_up();
        }
        s
    });
    ObjectBox { min: lo, step }
}

/// Slack that the encoder leaves around a decoded box coordinate, so that f32 decoding in any
/// order (with or without fused multiply-add) still encloses: a few ulps of the box magnitude.
fn decode_slack(object: &ObjectBox, k: usize) -> f64 {
    let magnitude = object.min[k].abs() as f64 + 255.0 * object.step[k] as f64;
    magnitude * 4.0 * f32::EPSILON as f64
}

/// DecodedDescriptor box coordinate, exactly (f64 holds the f32 product and sum without rounding here).
fn decode_coord(object: &ObjectBox, k: usize, q: u32) -> f64 {
    object.min[k] as f64 + q as f64 * object.step[k] as f64
}

/// The largest code whose decoded coordinate is at least `slack` below `v` (0 if none).
fn quantise_down(object: &ObjectBox, k: usize, v: f32) -> u32 {
    let slack = decode_slack(object, k);
    let step = object.step[k] as f64;
    let mut q = if step > 0.0 {
        (((v as f64 - object.min[k] as f64) / step)
            .floor()
            .clamp(0.0, 255.0)) as u32
    } else {
        0
    };
    while q > 0 && decode_coord(object, k, q) > v as f64 - slack {
        q -= 1;
    }
    q
}

/// The smallest code whose decoded coordinate is at least `slack` above `v` (255 if none).
fn quantise_up(object: &ObjectBox, k: usize, v: f32) -> u32 {
    let slack = decode_slack(object, k);
    let step = object.step[k] as f64;
    let mut q = if step > 0.0 {
        (((v as f64 - object.min[k] as f64) / step)
            .ceil()
            .clamp(0.0, 255.0)) as u32
    } else {
        255
    };
    while q < 255 && decode_coord(object, k, q) < v as f64 + slack {
        q += 1;
    }
    q
}

/// Quantised box words (x: min codes and vertex count - 1, y: max codes and triangle count - 1) and
/// the cone bytes [octahedral x, octahedral y, cutoff].
fn quantise(
    mesh: &Mesh,
    object: &ObjectBox,
    verts: &[u32],
    b: &MeshletBounds,
    m: &super::Meshlet,
) -> (u32, u32, [u8; 3]) {
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    for &v in verts {
        let p = mesh.positions[v as usize];
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    // Counts minus one, as NVIDIA stores them (the validator rejects empty meshlets).
    let mut bx = m.vertex_count.saturating_sub(1) << 24;
    let mut by = m.triangle_count.saturating_sub(1) << 24;
    for k in 0..3 {
        bx |= quantise_down(object, k, lo[k]) << (8 * k);
        by |= quantise_up(object, k, hi[k]) << (8 * k);
    }
    (bx, by, quantise_cone(b))
}

/// Decodes an octahedral axis code (signed bytes) in f64, as the shader does in f32.
pub fn decode_octahedral(x: i8, y: i8) -> DVec3 {
    let (x, y) = (x as f64 / 127.0, y as f64 / 127.0);
    let z = 1.0 - x.abs() - y.abs();
    let (x, y) = if z < 0.0 {
        ((1.0 - y.abs()) * x.signum(), (1.0 - x.abs()) * y.signum())
    } else {
        (x, y)
    };
    DVec3::new(x, y, z).normalize()
}

/// Extra angle (radians) on top of the measured axis error: covers the shader's f32 decode and
/// normalise (about 1e-7) a thousand times over, at no measurable culling cost.
pub(crate) const AXIS_MARGIN: f64 = 1e-4;

/// The cone as [octahedral x, octahedral y, cutoff code]; cutoff code 255 never culls.
fn quantise_cone(b: &MeshletBounds) -> [u8; 3] {
    let c = b.cone;
    if !c.can_cull() {
        return [0, 0, 255];
    }
    let axis = DVec3::new(c.axis[0] as f64, c.axis[1] as f64, c.axis[2] as f64).normalize();
    let (err, qx, qy) = octahedral_code(axis);
    // Widen the half-angle by the axis error: every normal within theta of the true axis is within
    // theta + err of the decoded one.
    let theta = (c.cutoff as f64).min(1.0).asin() + err + AXIS_MARGIN;
    if theta >= std::f64::consts::FRAC_PI_2 {
        return [0, 0, 255];
    }
    let code = (theta.sin() * 255.0).ceil().min(255.0) as u8;
    [qx as u8, qy as u8, code]
}

/// The octahedral code (signed bytes) nearest a unit axis: (angle error in radians, x, y).
pub fn octahedral_code(axis: DVec3) -> (f64, i8, i8) {
    // Octahedral projection, then the best of the (up to) four neighbouring codes.
    let l1 = axis.x.abs() + axis.y.abs() + axis.z.abs();
    let (mut px, mut py) = (axis.x / l1, axis.y / l1);
    if axis.z < 0.0 {
        let (ax, ay) = (px.abs(), py.abs());
        px = (1.0 - ay) * if px >= 0.0 { 1.0 } else { -1.0 };
        py = (1.0 - ax) * if py >= 0.0 { 1.0 } else { -1.0 };
    }
    let mut best = (f64::INFINITY, 0i8, 0i8);
    for qx in [(px * 127.0).floor(), (px * 127.0).ceil()] {
        for qy in [(py * 127.0).floor(), (py * 127.0).ceil()] {
            let (qx, qy) = (qx.clamp(-127.0, 127.0) as i8, qy.clamp(-127.0, 127.0) as i8);
            let err = decode_octahedral(qx, qy).dot(axis).clamp(-1.0, 1.0).acos();
            if err < best.0 {
                best = (err, qx, qy);
            }
        }
    }
    best
}

fn cone_bytes(ox: u32, oy: u32, cut: u32) -> ([f32; 3], f32) {
    let axis = decode_octahedral(ox as u8 as i8, oy as u8 as i8);
    (
        [axis.x as f32, axis.y as f32, axis.z as f32],
        cut as f32 / 255.0,
    )
}

impl Packed {
    /// Bytes on the device for the meshlets of a mesh with `vertex_count` vertices: the packed
    /// buffers, plus the global position array (12 bytes a vertex) for every format that indexes
    /// it (monolithic copies positions instead).
    pub fn device_bytes(&self, vertex_count: usize) -> usize {
        let words = self.descriptors.len() + self.data.len() + self.triangles.len();
        let positions = if self.format == DescriptorFormat::Monolithic {
            0
        } else {
            12 * vertex_count
        };
        4 * words + 16 * self.task.len() + positions
    }

    /// Reads meshlet `i` back, mirroring the shaders' decoding.
    pub fn decode(&self, i: usize) -> DecodedDescriptor {
        let byte = |words: &[u32], k: usize| (words[k / 4] >> (8 * (k % 4))) as u8;
        let bytes = |words: &[u32], start: usize, n: usize| -> Vec<u8> {
            (start..start + n).map(|k| byte(words, k)).collect()
        };
        let floats =
            |words: &[u32]| -> Vec<f32> { words.iter().map(|&w| f32::from_bits(w)).collect() };
        match self.format {
            DescriptorFormat::Split => {
                let d = &self.descriptors[4 * i..4 * i + 4];
                let (vo, to, vc, tc) = (d[0] as usize, d[1] as usize, d[2] as usize, d[3] as usize);
                let t = &self.task[3 * i..3 * i + 3];
                DecodedDescriptor {
                    vertices: Some(self.data[vo..vo + vc].to_vec()),
                    positions: None,
                    triangles: bytes(&self.triangles, to, 3 * tc),
                    cull: Cull::Exact(exact_bounds(&[t[0], t[1], t[2]])),
                }
            }
            DescriptorFormat::NvidiaA | DescriptorFormat::NvidiaB => {
                let d = &self.descriptors[4 * i..4 * i + 4];
                let vc = (d[0] >> 24) as usize + 1;
                let tc = (d[1] >> 24) as usize + 1;
                let (vertices, triangles, (axis, cutoff)) =
                    if self.format == DescriptorFormat::NvidiaA {
                        let vb = (d[2] & 0xfffff) as usize;
                        let pb = (d[3] & 0xfffff) as usize;
                        (
                            self.data[vb..vb + vc].to_vec(),
                            bytes(&self.triangles, 4 * pb, 3 * tc),
                            cone_bytes(
                                (d[2] >> 20) & 0xff,
                                (d[3] >> 20) & 0xff,
                                d[2] >> 28 | (d[3] >> 28) << 4,
                            ),
                        )
                    } else {
                        let off = d[3] as usize;
                        let pack = (d[2] >> 24) as usize;
                        let vertices: Vec<u32> = (0..vc)
                            .map(|k| {
                                if pack == 2 {
                                    (self.data[off + k / 2] >> (16 * (k % 2))) & 0xffff
                                } else {
                                    self.data[off + k]
                                }
                            })
                            .collect();
                        let vwords = if pack == 2 { vc.div_ceil(2) } else { vc };
                        (
                            vertices,
                            bytes(&self.data, 4 * (off + vwords), 3 * tc),
                            cone_bytes(d[2] & 0xff, (d[2] >> 8) & 0xff, (d[2] >> 16) & 0xff),
                        )
                    };
                let o = &self.object;
                let code = |w: u32, k: usize| (w >> (8 * k)) & 0xff;
                let min = [0, 1, 2].map(|k| o.min[k] + code(d[0], k) as f32 * o.step[k]);
                let max = [0, 1, 2].map(|k| o.min[k] + code(d[1], k) as f32 * o.step[k]);
                DecodedDescriptor {
                    vertices: Some(vertices),
                    positions: None,
                    triangles,
                    cull: Cull::Quantised(QuantisedBounds {
                        min,
                        max,
                        axis,
                        cutoff,
                    }),
                }
            }
            DescriptorFormat::Monolithic => {
                let off = self.descriptors[i] as usize;
                let h = floats(&self.data[off..off + 12]);
                let counts = self.data[off + 12];
                let (vc, tc) = ((counts & 0xffff) as usize, (counts >> 16) as usize);
                let pos = off + BLOCK_HEADER;
                let positions = floats(&self.data[pos..pos + 3 * vc])
                    .chunks_exact(3)
                    .map(|p| [p[0], p[1], p[2]])
                    .collect();
                let quad = |k: usize| [h[4 * k], h[4 * k + 1], h[4 * k + 2], h[4 * k + 3]];
                DecodedDescriptor {
                    vertices: None,
                    positions: Some(positions),
                    triangles: bytes(&self.data, 4 * (pos + 3 * vc), 3 * tc),
                    cull: Cull::Exact(exact_bounds(&[quad(0), quad(1), quad(2)])),
                }
            }
        }
    }
}

fn exact_bounds(t: &[[f32; 4]; 3]) -> MeshletBounds {
    use super::bounds::{Cone, Sphere};
    MeshletBounds {
        sphere: Sphere {
            center: [t[0][0], t[0][1], t[0][2]],
            radius: t[0][3],
        },
        cone: Cone {
            apex: [t[1][0], t[1][1], t[1][2]],
            axis: [t[2][0], t[2][1], t[2][2]],
            cutoff: t[1][3],
        },
    }
}

#[cfg(test)]
mod tests {
    // The tests walk several arrays in step by meshlet index.
    #![allow(clippy::needless_range_loop)]
    use super::*;
    use crate::mesh::generate;
    use crate::meshlet::{Limits, Meshlet};

    fn sample() -> (Mesh, Meshlets) {
        let mesh = generate::noisy_sphere(5, 0.0, 7);
        let ml = crate::strategy::by_name("meshopt", &Default::default())
            .unwrap()
            .build(&mesh, Limits::DEFAULT);
        (mesh, ml)
    }

    #[test]
    fn format_names_round_trip() {
        for f in DescriptorFormat::ALL {
            assert_eq!(f.name().parse::<DescriptorFormat>().unwrap(), f);
        }
        assert!("nvidia".parse::<DescriptorFormat>().is_err());
    }

    #[test]
    fn every_format_round_trips_topology() {
        let (mesh, ml) = sample();
        let bounds = compute_bounds(&mesh, &ml);
        for f in DescriptorFormat::ALL {
            let p = pack_with_bounds(&mesh, &ml, &bounds, f).unwrap();
            assert_eq!(p.count, ml.len());
            for i in 0..ml.len() {
                let d = p.decode(i);
                assert_eq!(d.triangles, ml.meshlet_triangles(i), "{f} meshlet {i}");
                match f {
                    DescriptorFormat::Monolithic => {
                        let want: Vec<[f32; 3]> = ml
                            .meshlet_vertices(i)
                            .iter()
                            .map(|&v| mesh.positions[v as usize])
                            .collect();
                        assert_eq!(d.positions.as_deref(), Some(&want[..]), "{f} meshlet {i}");
                    }
                    _ => assert_eq!(d.vertices.as_deref(), Some(ml.meshlet_vertices(i))),
                }
                if !f.quantised() {
                    assert_eq!(d.cull, Cull::Exact(bounds[i]), "{f} meshlet {i}");
                }
            }
        }
    }

    #[test]
    fn b_uses_16_bit_indices_only_where_they_fit() {
        // A grid with more than 65536 vertices: early meshlets pack to 16 bits, late ones cannot.
        let mesh = generate::terrain(300, 1);
        assert!(mesh.positions.len() > 70_000);
        let ml = crate::strategy::by_name("nvidia", &Default::default())
            .unwrap()
            .build(&mesh, Limits::DEFAULT);
        let p = pack(&mesh, &ml, DescriptorFormat::NvidiaB).unwrap();
        let packs: Vec<u32> = (0..ml.len())
            .map(|i| p.descriptors[4 * i + 2] >> 24)
            .collect();
        assert!(packs.contains(&2) && packs.contains(&1));
        for i in 0..ml.len() {
            let fits = ml.meshlet_vertices(i).iter().all(|&v| v < 65536);
            assert_eq!(packs[i] == 2, fits);
            assert_eq!(
                p.decode(i).vertices.as_deref(),
                Some(ml.meshlet_vertices(i))
            );
        }
        // Smaller than A, which stores every index in 32 bits.
        let a = pack(&mesh, &ml, DescriptorFormat::NvidiaA).unwrap();
        assert!(p.device_bytes(mesh.positions.len()) < a.device_bytes(mesh.positions.len()));
    }

    #[test]
    fn quantised_box_holds_every_vertex_and_cone_every_normal() {
        let meshes = [
            ("sphere", generate::noisy_sphere(5, 0.0, 3)),
            ("terrain", generate::terrain(120, 3)),
            ("noisy-sphere", generate::noisy_sphere(5, 0.15, 3)),
            ("knot-tube", generate::knot_tube(320, 24, 3)),
        ];
        for (name, mesh) in meshes {
            let ml = crate::strategy::by_name("bsphere", &Default::default())
                .unwrap()
                .build(&mesh, Limits::DEFAULT);
            for f in [DescriptorFormat::NvidiaA, DescriptorFormat::NvidiaB] {
                let p = pack(&mesh, &ml, f).unwrap();
                let mut culling = 0;
                for i in 0..ml.len() {
                    let Cull::Quantised(q) = p.decode(i).cull else {
                        panic!("{f}: quantised bounds expected")
                    };
                    for &v in ml.meshlet_vertices(i) {
                        let pt = mesh.positions[v as usize];
                        for k in 0..3 {
                            assert!(q.min[k] <= pt[k] && pt[k] <= q.max[k], "{name} {f} {i}");
                        }
                    }
                    if q.cutoff < 1.0 {
                        culling += 1;
                        let cos = (1.0 - (q.cutoff as f64).powi(2)).sqrt();
                        let axis = DVec3::from_array(q.axis.map(|x| x as f64));
                        for t in ml.global_triangles(i) {
                            let [a, b, c] = t.map(|v| {
                                DVec3::from_array(mesh.positions[v as usize].map(|x| x as f64))
                            });
                            let n = (b - a).cross(c - a);
                            if n.length() > 0.0 {
                                assert!(
                                    n.normalize().dot(axis) >= cos - 1e-9,
                                    "{name} {f} meshlet {i}"
                                );
                            }
                        }
                    }
                }
                if name == "sphere" || name == "terrain" {
                    assert!(
                        culling * 2 > ml.len(),
                        "{name} {f}: only {culling} cones can cull"
                    );
                }
            }
        }
    }

    #[test]
    fn quantised_backface_test_is_conservative() {
        let (mesh, ml) = sample();
        let p = pack(&mesh, &ml, DescriptorFormat::NvidiaA).unwrap();
        let exact = compute_bounds(&mesh, &ml);
        // Eyes of the paper's random-view protocol (`lod::camera::Camera::random_views`) at 2 radii.
        let (lo, hi) = mesh.bounding_box();
        let (centre, r) = ((lo + hi) * 0.5, ((hi - lo).length() * 0.5).max(1e-6));
        let eyes: Vec<glam::Vec3> = crate::mesh::generate::random_directions(40, 5)
            .into_iter()
            .map(|dir| centre + dir * r * 2.0)
            .collect();
        let (mut culled, mut exact_culled) = (0, 0);
        for v in &eyes {
            let eye = v.to_array();
            for i in 0..ml.len() {
                let Cull::Quantised(q) = p.decode(i).cull else {
                    unreachable!()
                };
                exact_culled += exact[i].cone.culls(eye) as usize;
                if q.backfacing(eye) {
                    culled += 1;
                    // Every triangle faces away from the eye.
                    for t in ml.global_triangles(i) {
                        let [a, b, c] = t.map(|v| {
                            DVec3::from_array(mesh.positions[v as usize].map(|x| x as f64))
                        });
                        let n = (b - a).cross(c - a);
                        let e = DVec3::from_array(eye.map(|x| x as f64));
                        assert!(
                            n.dot(a - e) >= 0.0,
                            "meshlet {i} culled while facing the eye"
                        );
                    }
                }
            }
        }
        // It still culls, though less than the apex test.
        assert!(
            culled > 0 && culled <= exact_culled,
            "{culled} vs {exact_culled}"
        );
    }

    #[test]
    fn nvidia_a_offsets_overflow_is_an_error() {
        // 400k one-triangle meshlets over one triangle: 1.2 M vertex entries > 2^20.
        let mesh = Mesh {
            positions: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            indices: vec![0, 1, 2],
        };
        let n = 400_000;
        let ml = Meshlets {
            meshlets: (0..n)
                .map(|i| Meshlet {
                    vertex_offset: 3 * i,
                    triangle_offset: 3 * i,
                    vertex_count: 3,
                    triangle_count: 1,
                })
                .collect(),
            vertices: [0, 1, 2].repeat(n as usize),
            triangles: [0, 1, 2].repeat(n as usize),
        };
        let bounds = vec![
            compute_bounds(
                &mesh,
                &Meshlets {
                    meshlets: vec![ml.meshlets[0]],
                    vertices: vec![0, 1, 2],
                    triangles: vec![0, 1, 2],
                }
            )[0];
            n as usize
        ];
        let err = pack_with_bounds(&mesh, &ml, &bounds, DescriptorFormat::NvidiaA).unwrap_err();
        assert!(
            matches!(
                err,
                DescriptorError::FieldOverflow { what: "vertexBegin", bits: 20, meshlet, .. } if meshlet == (1 << 20) / 3 + 1
            ),
            "{err}"
        );
        assert!(err.to_string().contains("20-bit"));
        // B's 32-bit offset holds it.
        assert!(pack_with_bounds(&mesh, &ml, &bounds, DescriptorFormat::NvidiaB).is_ok());
    }
}

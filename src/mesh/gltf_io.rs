//! glTF 2.0 (.gltf and .glb): all triangle primitives of all meshes, node transforms applied; and a
//! GLB writer for [`crate::meshlet::export`].
//!
//! The default scene (or every scene when none is marked default) is walked from its roots; each
//! mesh instance is baked with its world transform, and mirrored instances (negative determinant)
//! get their winding flipped so front faces stay front faces. Meshes that no node instances are
//! added untransformed, so every mesh in the file appears at least once. Triangle strips and fans
//! are unrolled; point and line primitives are skipped.
//!
//! **Validated here, not by the `gltf` crate.** The crate's own validation and accessor readers
//! index arrays without bounds checks and subtract before checking (a primitive naming an accessor
//! past the end of `accessors`, a GLB header length below 12 or an accessor count of 0 panic inside
//! it, and a POSITION accessor of the wrong type is read as garbage). So only its serde types are
//! used: the JSON is deserialised without validation, and this module follows every index with a
//! bounds check, reads every accessor with checked arithmetic against the bytes present, checks
//! component types, and enforces the spec's rule that nodes form trees (a cycle or a node reached
//! twice is an error, so instancing cannot blow up exponentially). The baked output may be at most
//! [`MAX_EXPANSION`] times the input plus [`EXPANSION_SLACK`] bytes: one accessor named by many
//! primitives or meshes instanced by many nodes cannot allocate without bound.
//!
//! **What the glTF ecosystem writes.** Positions may be quantised (`KHR_mesh_quantization`: byte,
//! unsigned byte, short or unsigned short, normalised or not), dequantised per the spec and then
//! transformed by their nodes, where gltfpack and glTF-Transform put the dequantisation scale and
//! offset. Buffer views may be meshopt-compressed (`EXT_meshopt_compression` and its KHR successor,
//! decoded by meshoptimizer itself: see `gltf_meshopt`). Accessors are read per the spec: sparse
//! substitution over the base values, and an accessor without a bufferView starts from zeros. A
//! required extension outside [`READ_EXTENSIONS`] and [`GEOMETRY_NEUTRAL`] is refused up front with
//! its name ([`MeshErrorKind::UnsupportedExtension`]), before any buffer is read, so a file never
//! fails later with an error that blames something else; Draco (`KHR_draco_mesh_compression`) is
//! refused that way, with the command that decompresses it.

use super::error::{parse_err, MeshErrorKind};
use super::gltf_meshopt;
use glam::{Mat4, Quat, Vec3};
use gltf::json::{self, accessor::ComponentType, accessor::Type, mesh::Mode, validation::Checked};
use std::borrow::Cow;
use std::cell::{Cell, OnceCell};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::rc::Rc;

/// Extensions this reader applies to the geometry it reads.
pub const READ_EXTENSIONS: [&str; 4] = [
    "KHR_mesh_quantization",
    INSTANCING,
    gltf_meshopt::EXTENSIONS[0],
    gltf_meshopt::EXTENSIONS[1],
];

/// Prefixes of extensions that change only materials, textures, lights or metadata: positions and
/// triangles are the same without them, so a file that requires one (gltfpack's `-tc` requires
/// `KHR_texture_basisu`) still loads. Anything else that is required and not read is refused.
pub const GEOMETRY_NEUTRAL: [&str; 6] = [
    "KHR_materials_",
    "KHR_texture_",
    "EXT_texture_",
    "KHR_lights_",
    "EXT_lights_",
    "KHR_xmp",
];

/// Draco's extension: refused, with how to get a file this reader takes.
const DRACO: &str = "KHR_draco_mesh_compression";
const DRACO_HINT: &str = "; decompress it first, e.g. `gltf-transform cp IN.glb OUT.glb` \
    (glTF-Transform decodes Draco and writes the geometry uncompressed) or re-export without Draco";

/// Refuses a required extension that is neither read nor geometry-neutral, naming it.
fn check_required(root: &json::Root) -> Result<(), MeshErrorKind> {
    for name in &root.extensions_required {
        let read = READ_EXTENSIONS.contains(&name.as_str());
        let neutral = GEOMETRY_NEUTRAL.iter().any(|p| name.starts_with(p));
        if read || neutral {
            continue;
        }
        let hint = match name.as_str() {
            DRACO => DRACO_HINT.to_string(),
            _ => format!(
                " (it reads {}, and ignores extensions that change only materials, textures or lights)",
                READ_EXTENSIONS.join(", ")
            ),
        };
        return Err(MeshErrorKind::UnsupportedExtension {
            name: name.clone(),
            hint,
        });
    }
    Ok(())
}

/// `EXT_mesh_gpu_instancing`: a node's mesh placed once per entry of its TRANSLATION, ROTATION
/// and SCALE accessors, each after the node's own transform.
pub const INSTANCING: &str = "EXT_mesh_gpu_instancing";

/// Baked positions and indices may take at most this many times the file's bytes (plus
/// [`EXPANSION_SLACK`]); real files instance far less, a hostile one could ask for any amount.
pub const MAX_EXPANSION: u64 = 64;
/// Bytes of baked output allowed on top of [`MAX_EXPANSION`] times the input.
pub const EXPANSION_SLACK: u64 = 16 << 20;

const GLB_MAGIC: &[u8; 4] = b"glTF";
const CHUNK_JSON: u32 = 0x4E4F_534A;
const CHUNK_BIN: u32 = 0x004E_4942;

/// Parses a .gltf or .glb file; `base` resolves external buffer URIs.
pub fn parse(data: &[u8], base: Option<&Path>) -> Result<(Vec<[f32; 3]>, Vec<u32>), MeshErrorKind> {
    let doc = Document::parse(data, base)?;
    let instances = doc.instances()?;
    doc.check_budget(&instances)?;
    let mut positions = Vec::new();
    let mut indices = Vec::new();
    for (mesh, world) in instances {
        doc.append_mesh(mesh, world, &mut positions, &mut indices)?;
    }
    Ok((positions, indices))
}

/// Each instanced mesh once (untransformed positions and indices, in the order instances first
/// name them) and every instance as (index into that list, world transform): what a renderer
/// draws per instance. The budget counts the meshes once and each instance's transform, so many
/// instances of small meshes are not refused as [`parse`] (which bakes them all) would.
#[allow(clippy::type_complexity)]
pub fn parse_scene(
    data: &[u8],
    base: Option<&Path>,
) -> Result<(Vec<(Vec<[f32; 3]>, Vec<u32>)>, Vec<(u32, Mat4)>), MeshErrorKind> {
    let doc = Document::parse(data, base)?;
    let instances = doc.instances()?;
    let mut slot = vec![u32::MAX; doc.root.meshes.len()];
    let mut unique = Vec::new();
    let mut placed = Vec::with_capacity(instances.len());
    for &(mesh, world) in &instances {
        if !world.is_finite() {
            return Err(parse_err(
                format!("mesh {mesh}"),
                "an instance's transform is not finite",
            ));
        }
        if slot[mesh] == u32::MAX {
            slot[mesh] = unique.len() as u32;
            unique.push((mesh, Mat4::IDENTITY));
        }
        placed.push((slot[mesh], world));
    }
    doc.check_budget(&unique)?;
    doc.spend(64 * placed.len() as u64, "instances")?;
    let mut meshes = Vec::with_capacity(unique.len());
    for (mesh, _) in unique {
        let (mut positions, mut indices) = (Vec::new(), Vec::new());
        doc.append_mesh(mesh, Mat4::IDENTITY, &mut positions, &mut indices)?;
        meshes.push((positions, indices));
    }
    Ok((meshes, placed))
}

/// `COLOR_0` of every triangle primitive, in the order [`parse`] emits their vertices (RGBA; RGB gets
/// alpha 1). Float, normalised u8 and normalised u16 colours are read. A primitive without colours
/// is an error: this is for files whose colours matter, such as `meshletlab export`'s.
pub fn colours(data: &[u8], base: Option<&Path>) -> Result<Vec<[f32; 4]>, MeshErrorKind> {
    let doc = Document::parse(data, base)?;
    let instances = doc.instances()?;
    doc.check_budget(&instances)?;
    let mut out = Vec::new();
    for (mesh, _) in instances {
        for (pi, p) in doc.root.meshes[mesh].primitives.iter().enumerate() {
            let Some((vertices, _)) = doc.primitive_size(p)? else {
                continue;
            };
            let loc = format!("mesh {mesh} primitive {pi}");
            let a = p
                .attributes
                .get(&Checked::Valid(json::mesh::Semantic::Colors(0)))
                .ok_or_else(|| parse_err(&loc, "no COLOR_0"))?;
            let acc = doc.accessor(a.value(), &loc)?;
            if acc.count as u64 != vertices {
                return Err(parse_err(
                    &loc,
                    format!("COLOR_0 has {} entries for {vertices} vertices", acc.count),
                ));
            }
            let n = match acc.ty {
                Type::Vec3 => 3,
                Type::Vec4 => 4,
                _ => return Err(parse_err(&loc, "COLOR_0 is not VEC3 or VEC4")),
            };
            let colour_type = match acc.component {
                ComponentType::F32 => true,
                ComponentType::U8 | ComponentType::U16 => acc.normalized,
                _ => false,
            };
            if !colour_type {
                return Err(parse_err(&loc, "COLOR_0 component type"));
            }
            let raw = acc.read_f32(n)?;
            out.extend(raw.chunks_exact(n).map(|c| {
                let mut rgba = [1.0; 4];
                rgba[..n].copy_from_slice(c);
                rgba
            }));
        }
    }
    Ok(out)
}

/// Writes a GLB container: the JSON chunk padded with spaces, the binary chunk with zeros.
pub fn write_glb(json: &[u8], bin: &[u8]) -> Vec<u8> {
    let pad4 = |n: usize| n.div_ceil(4) * 4;
    let (jl, bl) = (pad4(json.len()), pad4(bin.len()));
    let total = 12 + 8 + jl + if bin.is_empty() { 0 } else { 8 + bl };
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(GLB_MAGIC);
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(jl as u32).to_le_bytes());
    out.extend_from_slice(&CHUNK_JSON.to_le_bytes());
    out.extend_from_slice(json);
    out.resize(20 + jl, b' ');
    if !bin.is_empty() {
        out.extend_from_slice(&(bl as u32).to_le_bytes());
        out.extend_from_slice(&CHUNK_BIN.to_le_bytes());
        out.extend_from_slice(bin);
        out.resize(total, 0);
    }
    out
}

/// Splits a GLB container into its JSON chunk and optional binary chunk, checking every length.
fn split_glb(data: &[u8]) -> Result<(&[u8], Option<&[u8]>), MeshErrorKind> {
    let u32_at = |at: usize| -> Result<u32, MeshErrorKind> {
        data.get(at..at + 4)
            .map(|b| u32::from_le_bytes(b.try_into().expect("4 bytes")))
            .ok_or_else(|| MeshErrorKind::Truncated(format!("GLB ends at byte {}", data.len())))
    };
    let version = u32_at(4)?;
    if version != 2 {
        return Err(MeshErrorKind::Unsupported(format!("GLB version {version}")));
    }
    let total = u32_at(8)? as usize;
    if total > data.len() {
        return Err(MeshErrorKind::Truncated(format!(
            "GLB header says {total} bytes, the file has {}",
            data.len()
        )));
    }
    if total < 20 {
        return Err(parse_err(
            "GLB header",
            format!("length {total} is too small"),
        ));
    }
    let data = &data[..total];
    let mut chunks = Vec::new();
    let mut at = 12usize;
    while at < data.len() {
        let len = u32_at(at)? as usize;
        let ty = u32_at(at + 4)?;
        let body = data
            .get(at + 8..)
            .and_then(|d| d.get(..len))
            .ok_or_else(|| {
                MeshErrorKind::Truncated(format!(
                    "GLB chunk at byte {at} announces {len} bytes past the end"
                ))
            })?;
        chunks.push((ty, body));
        at += 8 + len.div_ceil(4) * 4;
    }
    match chunks.as_slice() {
        [(CHUNK_JSON, j)] => Ok((j, None)),
        [(CHUNK_JSON, j), (CHUNK_BIN, b), ..] => Ok((j, Some(b))),
        [(CHUNK_JSON, j), ..] => Ok((j, None)),
        _ => Err(parse_err("GLB", "the first chunk is not JSON")),
    }
}

/// A deserialised (unvalidated) glTF document and its buffers.
struct Document {
    root: json::Root,
    /// Buffer bytes, loaded up front (each checked against its declared length). Shared, so a
    /// file whose buffers all name the GLB chunk or one external file holds its bytes once.
    buffers: Vec<Rc<[u8]>>,
    /// Bytes read: the file and each distinct external buffer file (what the budget scales with).
    input_bytes: u64,
    /// Buffers marked as a meshopt fallback: no bytes were loaded for them.
    fallback: Vec<bool>,
    /// Meshopt-compressed buffer views, decoded on first use (in 4-byte words).
    decoded: Vec<OnceCell<Vec<u32>>>,
    /// Bytes decoded or materialised so far, against [`Document::budget`].
    spent: Cell<u64>,
}

/// An accessor checked for range against its buffer view: element `i` starts at `data[i * stride]`.
struct Accessor<'a> {
    /// The view's bytes, or a dense copy when the accessor is sparse or has no bufferView.
    data: Cow<'a, [u8]>,
    count: usize,
    stride: usize,
    component: ComponentType,
    ty: Type,
    normalized: bool,
    loc: String,
}

fn component_size(c: ComponentType) -> usize {
    match c {
        ComponentType::I8 | ComponentType::U8 => 1,
        ComponentType::I16 | ComponentType::U16 => 2,
        ComponentType::U32 | ComponentType::F32 => 4,
    }
}

fn type_len(t: Type) -> usize {
    match t {
        Type::Scalar => 1,
        Type::Vec2 => 2,
        Type::Vec3 => 3,
        Type::Vec4 | Type::Mat2 => 4,
        Type::Mat3 => 9,
        Type::Mat4 => 16,
    }
}

impl Accessor<'_> {
    /// Component values as f32, `n` per element (components read little-endian). Integers are
    /// taken as is, or, when the accessor is normalised, mapped to [0, 1] (unsigned) or [-1, 1]
    /// (signed) by the glTF spec's formulas: `c / 255`, `max(c / 127, -1)`, `c / 65535`,
    /// `max(c / 32767, -1)`.
    fn read_f32(&self, n: usize) -> Result<Vec<f32>, MeshErrorKind> {
        let size = component_size(self.component);
        let norm = self.normalized;
        let mut out = Vec::with_capacity(self.count * n);
        for i in 0..self.count {
            let e = &self.data[i * self.stride..];
            for c in 0..n {
                let b = &e[c * size..(c + 1) * size];
                out.push(match self.component {
                    ComponentType::F32 => f32::from_le_bytes(b.try_into().expect("4 bytes")),
                    ComponentType::U8 if norm => b[0] as f32 / 255.0,
                    ComponentType::U8 => b[0] as f32,
                    ComponentType::I8 if norm => (b[0] as i8 as f32 / 127.0).max(-1.0),
                    ComponentType::I8 => b[0] as i8 as f32,
                    ComponentType::U16 if norm => u16::from_le_bytes([b[0], b[1]]) as f32 / 65535.0,
                    ComponentType::U16 => u16::from_le_bytes([b[0], b[1]]) as f32,
                    ComponentType::I16 if norm => {
                        (i16::from_le_bytes([b[0], b[1]]) as f32 / 32767.0).max(-1.0)
                    }
                    ComponentType::I16 => i16::from_le_bytes([b[0], b[1]]) as f32,
                    ComponentType::U32 => u32::from_le_bytes(b.try_into().expect("4 bytes")) as f32,
                });
            }
        }
        Ok(out)
    }

    /// Unsigned integer scalars (index buffers).
    fn read_indices(&self) -> Result<Vec<u32>, MeshErrorKind> {
        if self.ty != Type::Scalar || self.normalized {
            return Err(parse_err(
                &self.loc,
                "indices must be non-normalised SCALAR",
            ));
        }
        let at = |i: usize| &self.data[i * self.stride..];
        Ok(match self.component {
            ComponentType::U8 => (0..self.count).map(|i| at(i)[0] as u32).collect(),
            ComponentType::U16 => (0..self.count)
                .map(|i| u16::from_le_bytes([at(i)[0], at(i)[1]]) as u32)
                .collect(),
            ComponentType::U32 => (0..self.count)
                .map(|i| u32::from_le_bytes(at(i)[..4].try_into().expect("4 bytes")))
                .collect(),
            c => {
                return Err(parse_err(
                    &self.loc,
                    format!("indices of component type {c:?} (u8, u16 or u32 required)"),
                ))
            }
        })
    }
}

impl Document {
    /// Refuses instancing that would bake more than [`MAX_EXPANSION`] times the input (the file and
    /// its external buffers) plus [`EXPANSION_SLACK`]; sizes are summed before anything is allocated.
    fn check_budget(&self, instances: &[(usize, Mat4)]) -> Result<(), MeshErrorKind> {
        let budget = self.budget();
        let mut out_bytes = 0u64;
        for (mesh, _) in instances {
            for p in &self.root.meshes[*mesh].primitives {
                if let Some((v, i)) = self.primitive_size(p)? {
                    out_bytes = out_bytes
                        .saturating_add(v.saturating_mul(12))
                        .saturating_add(i.saturating_mul(4));
                }
            }
            if out_bytes > budget {
                return Err(MeshErrorKind::TooLarge(format!(
                    "meshes and node instancing expand to more than {budget} bytes of vertices and \
                     indices ({MAX_EXPANSION}x the input plus {} MiB)",
                    EXPANSION_SLACK >> 20
                )));
            }
        }
        Ok(())
    }

    /// Bytes of output (baked geometry, decoded views, dense accessor copies) a file may ask for.
    fn budget(&self) -> u64 {
        self.input_bytes
            .saturating_mul(MAX_EXPANSION)
            .saturating_add(EXPANSION_SLACK)
    }

    /// Counts `bytes` more of decoded or materialised data against the budget, before allocating.
    fn spend(&self, bytes: u64, loc: &str) -> Result<(), MeshErrorKind> {
        let total = self.spent.get().saturating_add(bytes);
        if total > self.budget() {
            return Err(MeshErrorKind::TooLarge(format!(
                "{loc}: decoded data would exceed {} bytes ({MAX_EXPANSION}x the input plus {} MiB)",
                self.budget(),
                EXPANSION_SLACK >> 20
            )));
        }
        self.spent.set(total);
        Ok(())
    }

    fn parse(data: &[u8], base: Option<&Path>) -> Result<Self, MeshErrorKind> {
        let (json_bytes, blob) = if data.starts_with(GLB_MAGIC) {
            split_glb(data)?
        } else {
            (data, None)
        };
        let root: json::Root = serde_json::from_slice(json_bytes)
            .map_err(|e| parse_err("glTF JSON", e.to_string()))?;
        check_required(&root)?;
        let blob: Option<Rc<[u8]>> = blob.map(Rc::from);
        let mut files = HashMap::new();
        let fallback: Vec<bool> = root
            .buffers
            .iter()
            .map(|b| {
                b.extensions
                    .as_ref()
                    .is_some_and(|e| gltf_meshopt::is_fallback(&e.others))
            })
            .collect();
        let buffers = root
            .buffers
            .iter()
            .enumerate()
            .map(|(i, b)| match fallback[i] {
                // The extension lets a decoder ignore the fallback: it may not even exist.
                true => Ok(Rc::from(&[][..])),
                false => load_buffer(i, b, blob.as_ref(), base, &mut files),
            })
            .collect::<Result<_, _>>()?;
        let external: u64 = files.values().map(|f| f.len() as u64).sum();
        Ok(Self {
            decoded: root.buffer_views.iter().map(|_| OnceCell::new()).collect(),
            root,
            buffers,
            input_bytes: data.len() as u64 + external,
            fallback,
            spent: Cell::new(0),
        })
    }

    /// Mesh instances to bake: (mesh index, world transform), in a fixed order.
    fn instances(&self) -> Result<Vec<(usize, Mat4)>, MeshErrorKind> {
        let r = &self.root;
        let scenes: Vec<usize> = match &r.scene {
            Some(s) => {
                let s = s.value();
                if s >= r.scenes.len() {
                    return Err(parse_err(
                        "scene",
                        format!("default scene {s} does not exist"),
                    ));
                }
                vec![s]
            }
            None => (0..r.scenes.len()).collect(),
        };
        let mut reached = vec![false; r.nodes.len()];
        let mut out = Vec::new();
        let mut instanced = vec![false; r.meshes.len()];
        for s in scenes {
            // A root already drawn from an earlier scene is skipped; one listed twice in the same
            // scene is reached twice below, which the spec forbids.
            let mut stack: Vec<(usize, Mat4)> = Vec::new();
            for n in r.scenes[s].nodes.iter().rev() {
                let n = self.node_index(n.value(), &format!("scene {s}"))?;
                if !reached[n] {
                    stack.push((n, Mat4::IDENTITY));
                }
            }
            while let Some((n, parent)) = stack.pop() {
                // glTF nodes form trees: reaching a node twice means a cycle or a shared child.
                if reached[n] {
                    return Err(parse_err(
                        format!("node {n}"),
                        "reached twice: glTF nodes must form trees (cycle or shared child)",
                    ));
                }
                reached[n] = true;
                let node = &r.nodes[n];
                let world = parent * local_transform(node);
                if let Some(m) = &node.mesh {
                    let m = m.value();
                    if m >= r.meshes.len() {
                        return Err(parse_err(
                            format!("node {n}"),
                            format!("mesh {m} does not exist"),
                        ));
                    }
                    instanced[m] = true;
                    match self.gpu_instances(node, n)? {
                        Some(each) => out.extend(each.into_iter().map(|t| (m, world * t))),
                        None => out.push((m, world)),
                    }
                }
                for c in node.children.iter().flatten().rev() {
                    stack.push((self.node_index(c.value(), &format!("node {n}"))?, world));
                }
            }
        }
        out.extend(
            (0..r.meshes.len())
                .filter(|&m| !instanced[m])
                .map(|m| (m, Mat4::IDENTITY)),
        );
        Ok(out)
    }

    /// The transforms `EXT_mesh_gpu_instancing` gives node `n` (translation * rotation * scale
    /// per entry), or `None` without the extension.
    fn gpu_instances(
        &self,
        node: &json::Node,
        n: usize,
    ) -> Result<Option<Vec<Mat4>>, MeshErrorKind> {
        let Some(ext) = node
            .extensions
            .as_ref()
            .and_then(|e| e.others.get(INSTANCING))
        else {
            return Ok(None);
        };
        let loc = format!("node {n} {INSTANCING}");
        let attributes = ext
            .get("attributes")
            .and_then(|a| a.as_object())
            .ok_or_else(|| parse_err(&loc, "no attributes object"))?;
        let mut count = None;
        let mut read = |name: &str, ty: Type| -> Result<Option<Vec<f32>>, MeshErrorKind> {
            let Some(index) = attributes.get(name) else {
                return Ok(None);
            };
            let index = index
                .as_u64()
                .ok_or_else(|| parse_err(&loc, format!("{name} is not an accessor index")))?;
            let acc = self.accessor(usize::try_from(index).unwrap_or(usize::MAX), &loc)?;
            if acc.ty != ty {
                return Err(parse_err(
                    &loc,
                    format!("{name} must be {ty:?}, found {:?}", acc.ty),
                ));
            }
            if *count.get_or_insert(acc.count) != acc.count {
                return Err(parse_err(&loc, "attributes of different counts"));
            }
            self.spend(acc.count as u64 * 64, &loc)?;
            acc.read_f32(type_len(ty)).map(Some)
        };
        let t = read("TRANSLATION", Type::Vec3)?;
        let r = read("ROTATION", Type::Vec4)?;
        let s = read("SCALE", Type::Vec3)?;
        let count = count.ok_or_else(|| parse_err(&loc, "no TRANSLATION, ROTATION or SCALE"))?;
        let at3 = |v: &Option<Vec<f32>>, i: usize, d: f32| {
            v.as_ref()
                .map_or(Vec3::splat(d), |v| Vec3::from_slice(&v[3 * i..3 * i + 3]))
        };
        Ok(Some(
            (0..count)
                .map(|i| {
                    let q = r.as_ref().map_or(Quat::IDENTITY, |r| {
                        Quat::from_slice(&r[4 * i..4 * i + 4]).normalize()
                    });
                    Mat4::from_scale_rotation_translation(at3(&s, i, 1.0), q, at3(&t, i, 0.0))
                })
                .collect(),
        ))
    }

    fn node_index(&self, n: usize, loc: &str) -> Result<usize, MeshErrorKind> {
        if n < self.root.nodes.len() {
            Ok(n)
        } else {
            Err(parse_err(loc, format!("node {n} does not exist")))
        }
    }

    /// The bytes of buffer view `vi` (decoded, if it is meshopt-compressed) and its byteStride.
    fn view(&self, vi: usize, loc: &str) -> Result<(&[u8], Option<usize>), MeshErrorKind> {
        let v = self
            .root
            .buffer_views
            .get(vi)
            .ok_or_else(|| parse_err(loc, format!("bufferView {vi} does not exist")))?;
        let vloc = format!("{loc} bufferView {vi}");
        let too_far = || {
            MeshErrorKind::Truncated(format!(
                "{vloc}: reaches past the end of its buffer or decoded data"
            ))
        };
        let stride = v.byte_stride.map(|s| s.0);
        let length = usize::try_from(v.byte_length.0).map_err(|_| too_far())?;
        let compressed = match &v.extensions {
            Some(e) => gltf_meshopt::compressed_view(&e.others, &vloc)?,
            None => None,
        };
        if let Some(c) = compressed {
            let cell = &self.decoded[vi];
            let words = match cell.get() {
                Some(w) => w,
                None => {
                    self.spend(c.decoded_len(&vloc)?, &vloc)?;
                    let stream =
                        self.buffer_range(c.buffer, c.byte_offset, c.byte_length, &vloc)?;
                    let w = c.decode(stream, &vloc)?;
                    cell.get_or_init(|| w)
                }
            };
            let decoded =
                &bytemuck::cast_slice::<u32, u8>(words)[..(c.count * c.byte_stride) as usize];
            return Ok((decoded.get(..length).ok_or_else(too_far)?, stride));
        }
        let bi = v.buffer.value();
        if self.fallback.get(bi) == Some(&true) {
            return Err(parse_err(
                &vloc,
                format!(
                    "lies in buffer {bi}, a meshopt fallback that holds no data, and is not compressed itself"
                ),
            ));
        }
        let off = v.byte_offset.map(|o| o.0).unwrap_or(0);
        Ok((self.buffer_range(bi, off, v.byte_length.0, &vloc)?, stride))
    }

    /// Bytes `offset..offset + length` of buffer `bi`, range-checked.
    fn buffer_range(
        &self,
        bi: usize,
        offset: u64,
        length: u64,
        loc: &str,
    ) -> Result<&[u8], MeshErrorKind> {
        let buffer = self
            .buffers
            .get(bi)
            .ok_or_else(|| parse_err(loc, format!("buffer {bi} does not exist")))?;
        offset
            .checked_add(length)
            .and_then(|end| Some(usize::try_from(offset).ok()?..usize::try_from(end).ok()?))
            .and_then(|r| buffer.get(r))
            .ok_or_else(|| {
                MeshErrorKind::Truncated(format!("{loc}: reaches past the end of buffer {bi}"))
            })
    }

    /// Accessor `i`, with its bytes range-checked against its view and buffer; a sparse accessor,
    /// or one without a bufferView, comes back as a dense copy with the substitutions applied.
    fn accessor(&self, i: usize, loc: &str) -> Result<Accessor<'_>, MeshErrorKind> {
        let loc = format!("{loc} accessor {i}");
        let a = self
            .root
            .accessors
            .get(i)
            .ok_or_else(|| parse_err(&loc, "does not exist"))?;
        let (Checked::Valid(component), Checked::Valid(ty)) = (&a.component_type, &a.type_) else {
            return Err(parse_err(&loc, "invalid componentType or type"));
        };
        let (component, ty) = (component.0, *ty);
        let elem = component_size(component) * type_len(ty);
        let count = usize::try_from(a.count.0).map_err(|_| parse_err(&loc, "count too large"))?;
        let too_far = || {
            MeshErrorKind::Truncated(format!(
                "{loc}: reaches past the end of its buffer view or buffer"
            ))
        };
        let dense_len = count.checked_mul(elem).ok_or_else(too_far)?;
        // The base values: a range of the view, element `k` at `k * stride`.
        let base = match &a.buffer_view {
            None => None,
            Some(view) => {
                let (view_bytes, stride) = self.view(view.value(), &loc)?;
                let stride = stride.unwrap_or(elem);
                if stride < elem {
                    return Err(parse_err(
                        &loc,
                        format!("byteStride {stride} < element size {elem}"),
                    ));
                }
                let a_off = usize::try_from(a.byte_offset.map(|o| o.0).unwrap_or(0))
                    .map_err(|_| too_far())?;
                let span = match count {
                    0 => 0,
                    c => (c - 1)
                        .checked_mul(stride)
                        .and_then(|x| x.checked_add(elem))
                        .ok_or_else(too_far)?,
                };
                let data = a_off
                    .checked_add(span)
                    .and_then(|end| view_bytes.get(a_off..end))
                    .ok_or_else(too_far)?;
                Some((data, stride))
            }
        };
        let (data, stride) = match (base, &a.sparse) {
            (Some((data, stride)), None) => (Cow::Borrowed(data), stride),
            (base, sparse) => {
                // Zeros (no bufferView) or the base values, packed; then the substitutions.
                self.spend(dense_len as u64, &loc)?;
                let mut dense = vec![0u8; dense_len];
                if let Some((data, stride)) = base {
                    for (k, e) in dense.chunks_exact_mut(elem).enumerate() {
                        e.copy_from_slice(&data[k * stride..k * stride + elem]);
                    }
                }
                if let Some(sp) = sparse {
                    self.substitute(sp, &mut dense, elem, &loc)?;
                }
                (Cow::Owned(dense), elem)
            }
        };
        Ok(Accessor {
            data,
            count,
            stride,
            component,
            ty,
            normalized: a.normalized,
            loc,
        })
    }

    /// Writes a sparse accessor's values over `dense` (elements of `elem` bytes). The spec's rules
    /// are checked: indices strictly increasing and below the accessor's count.
    fn substitute(
        &self,
        sp: &json::accessor::sparse::Sparse,
        dense: &mut [u8],
        elem: usize,
        loc: &str,
    ) -> Result<(), MeshErrorKind> {
        let loc = format!("{loc} sparse");
        let count = dense.len() / elem;
        let n = usize::try_from(sp.count.0)
            .ok()
            .filter(|&n| n <= count)
            .ok_or_else(|| {
                parse_err(
                    &loc,
                    format!("count {} exceeds the accessor's {count}", sp.count.0),
                )
            })?;
        let isize_ = match &sp.indices.component_type {
            Checked::Valid(c) => match c.0 {
                ComponentType::U8 => 1,
                ComponentType::U16 => 2,
                ComponentType::U32 => 4,
                c => return Err(parse_err(&loc, format!("indices of component type {c:?}"))),
            },
            Checked::Invalid => return Err(parse_err(&loc, "invalid indices componentType")),
        };
        let range =
            |view: usize, off: u64, width: usize, what: &str| -> Result<&[u8], MeshErrorKind> {
                let (bytes, _) = self.view(view, &loc)?;
                usize::try_from(off)
                    .ok()
                    .and_then(|o| Some(o..o.checked_add(n.checked_mul(width)?)?))
                    .and_then(|r| bytes.get(r))
                    .ok_or_else(|| {
                        MeshErrorKind::Truncated(format!(
                            "{loc}: {what} reach past the end of their view"
                        ))
                    })
            };
        let indices = range(
            sp.indices.buffer_view.value(),
            sp.indices.byte_offset.0,
            isize_,
            "indices",
        )?;
        let values = range(
            sp.values.buffer_view.value(),
            sp.values.byte_offset.0,
            elem,
            "values",
        )?;
        let mut last: Option<usize> = None;
        for (k, (ib, v)) in indices
            .chunks_exact(isize_)
            .zip(values.chunks_exact(elem))
            .enumerate()
        {
            let mut word = [0u8; 4];
            word[..isize_].copy_from_slice(ib);
            let t = u32::from_le_bytes(word) as usize;
            if t >= count || last.is_some_and(|l| t <= l) {
                return Err(parse_err(
                    &loc,
                    format!(
                        "index {k} is {t}: indices must increase strictly and stay below {count}"
                    ),
                ));
            }
            last = Some(t);
            dense[t * elem..(t + 1) * elem].copy_from_slice(v);
        }
        Ok(())
    }

    /// (vertices, indices after unrolling) of a triangle primitive, `None` for points and lines.
    fn primitive_size(
        &self,
        p: &json::mesh::Primitive,
    ) -> Result<Option<(u64, u64)>, MeshErrorKind> {
        let mode = match p.mode {
            Checked::Valid(m) => m,
            Checked::Invalid => return Err(parse_err("primitive", "invalid mode")),
        };
        if !matches!(
            mode,
            Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
        ) {
            return Ok(None);
        }
        let count = |i: usize| -> Result<u64, MeshErrorKind> {
            Ok(self
                .root
                .accessors
                .get(i)
                .ok_or_else(|| parse_err("primitive", format!("accessor {i} does not exist")))?
                .count
                .0)
        };
        let pos = p
            .attributes
            .get(&Checked::Valid(json::mesh::Semantic::Positions))
            .ok_or_else(|| parse_err("primitive", "triangle primitive without POSITION"))?;
        let v = count(pos.value())?;
        let n = match &p.indices {
            Some(i) => count(i.value())?,
            None => v,
        };
        let i = match mode {
            Mode::Triangles => n,
            _ => n.saturating_sub(2).saturating_mul(3),
        };
        Ok(Some((v, i)))
    }

    fn append_mesh(
        &self,
        mesh: usize,
        world: Mat4,
        positions: &mut Vec<[f32; 3]>,
        indices: &mut Vec<u32>,
    ) -> Result<(), MeshErrorKind> {
        let flip = world.determinant() < 0.0;
        for (pi, prim) in self.root.meshes[mesh].primitives.iter().enumerate() {
            if self.primitive_size(prim)?.is_none() {
                continue;
            }
            let loc = format!("mesh {mesh} primitive {pi}");
            let pa = prim
                .attributes
                .get(&Checked::Valid(json::mesh::Semantic::Positions))
                .expect("checked by primitive_size");
            let draco = prim
                .extensions
                .as_ref()
                .is_some_and(|e| e.others.contains_key(DRACO));
            if draco
                && self
                    .root
                    .accessors
                    .get(pa.value())
                    .is_some_and(|a| a.buffer_view.is_none())
            {
                // Its accessors would read as zeros: only the Draco stream holds the geometry.
                return Err(MeshErrorKind::UnsupportedExtension {
                    name: DRACO.into(),
                    hint: format!("{DRACO_HINT} ({loc} has no uncompressed fallback)"),
                });
            }
            let acc = self.accessor(pa.value(), &loc)?;
            // Float, or the integer types KHR_mesh_quantization allows (normalised or not).
            let position_type = matches!(
                acc.component,
                ComponentType::F32
                    | ComponentType::I8
                    | ComponentType::U8
                    | ComponentType::I16
                    | ComponentType::U16
            );
            if acc.ty != Type::Vec3 || !position_type {
                return Err(MeshErrorKind::Unsupported(format!(
                    "{loc}: POSITION must be VEC3 of float, or of byte or short (KHR_mesh_quantization); found {:?} of {:?}",
                    acc.ty, acc.component
                )));
            }
            let base = positions.len();
            let n = acc.count as u32;
            if (base as u64 + acc.count as u64) > u32::MAX as u64 {
                return Err(MeshErrorKind::TooLarge("more than 2^32 vertices".into()));
            }
            let raw = acc.read_f32(3)?;
            positions.extend(raw.chunks_exact(3).map(|p| {
                world
                    .transform_point3(Vec3::new(p[0], p[1], p[2]))
                    .to_array()
            }));
            let local: Vec<u32> = match &prim.indices {
                Some(i) => self.accessor(i.value(), &loc)?.read_indices()?,
                None => (0..n).collect(),
            };
            if let Some(&bad) = local.iter().find(|&&i| i >= n) {
                return Err(parse_err(
                    &loc,
                    format!("index {bad} out of range ({n} vertices)"),
                ));
            }
            let mode = match prim.mode {
                Checked::Valid(m) => m,
                Checked::Invalid => unreachable!("checked by primitive_size"),
            };
            let mut push = |a: u32, b: u32, c: u32| {
                let (a, b, c) = (a + base as u32, b + base as u32, c + base as u32);
                indices.extend_from_slice(&if flip { [a, c, b] } else { [a, b, c] });
            };
            match mode {
                Mode::Triangles => {
                    if !local.len().is_multiple_of(3) {
                        return Err(parse_err(
                            &loc,
                            format!("{} indices is not a multiple of 3", local.len()),
                        ));
                    }
                    for t in local.chunks_exact(3) {
                        push(t[0], t[1], t[2]);
                    }
                }
                Mode::TriangleStrip => {
                    for i in 2..local.len() {
                        if i % 2 == 0 {
                            push(local[i - 2], local[i - 1], local[i]);
                        } else {
                            push(local[i - 1], local[i - 2], local[i]);
                        }
                    }
                }
                _ => {
                    for i in 2..local.len() {
                        push(local[0], local[i - 1], local[i]);
                    }
                }
            }
        }
        Ok(())
    }
}

/// A node's local transform: its matrix, or translation * rotation * scale.
fn local_transform(n: &json::Node) -> Mat4 {
    if let Some(m) = n.matrix {
        return Mat4::from_cols_array(&m);
    }
    let t = n.translation.map(Vec3::from_array).unwrap_or(Vec3::ZERO);
    let r = n
        .rotation
        .map(|q| Quat::from_array(q.0))
        .unwrap_or(Quat::IDENTITY);
    let s = n.scale.map(Vec3::from_array).unwrap_or(Vec3::ONE);
    Mat4::from_scale_rotation_translation(s, r, t)
}

/// Bytes of one buffer: the GLB binary chunk, a base64 `data:` URI, or a regular file next to the
/// glTF (read once however many buffers name it, and only if it is a regular file).
fn load_buffer(
    i: usize,
    b: &json::Buffer,
    blob: Option<&Rc<[u8]>>,
    base: Option<&Path>,
    files: &mut HashMap<PathBuf, Rc<[u8]>>,
) -> Result<Rc<[u8]>, MeshErrorKind> {
    use base64::Engine as _;
    use std::io::Read as _;
    let loc = || format!("buffer {i}");
    let declared = b.byte_length.0;
    let bytes = match b.uri.as_deref() {
        None => blob
            .ok_or_else(|| parse_err(loc(), "refers to a GLB binary chunk that is missing"))?
            .clone(),
        Some(uri) if uri.starts_with("data:") => {
            let (_, payload) = uri
                .split_once(";base64,")
                .ok_or_else(|| parse_err(loc(), "data URI is not base64"))?;
            base64::engine::general_purpose::STANDARD
                .decode(payload)
                .map_err(|e| parse_err(loc(), format!("bad base64: {e}")))?
                .into()
        }
        Some(uri) => {
            let rel = percent_decode(uri);
            // Only files beside the glTF (or below it): an absolute path or `..` could reach
            // anything on the machine (/proc/kcore reads as a huge regular file).
            let p = Path::new(&rel);
            if p.is_absolute()
                || p.components().any(|c| {
                    !matches!(
                        c,
                        std::path::Component::Normal(_) | std::path::Component::CurDir
                    )
                })
            {
                return Err(MeshErrorKind::Unsupported(format!(
                    "{}: URI '{uri}' is not a relative path below the glTF's folder",
                    loc()
                )));
            }
            let path = base
                .map(|d| d.join(&rel))
                .unwrap_or_else(|| rel.clone().into());
            if let Some(b) = files.get(&path) {
                b.clone()
            } else {
                let cannot =
                    |e: String| parse_err(loc(), format!("cannot read '{}': {e}", path.display()));
                let f = std::fs::File::open(&path).map_err(|e| cannot(e.to_string()))?;
                let meta = f.metadata().map_err(|e| cannot(e.to_string()))?;
                // A device or pipe (/dev/zero) could feed bytes forever.
                if !meta.is_file() {
                    return Err(cannot("not a regular file".into()));
                }
                let mut v = Vec::new();
                f.take(meta.len())
                    .read_to_end(&mut v)
                    .map_err(|e| cannot(e.to_string()))?;
                let v: Rc<[u8]> = v.into();
                files.insert(path, v.clone());
                v
            }
        }
    };
    if (bytes.len() as u64) < declared {
        return Err(MeshErrorKind::Truncated(format!(
            "{} has {} bytes, {declared} declared",
            loc(),
            bytes.len(),
        )));
    }
    Ok(bytes)
}

/// Decodes %XX escapes in a relative URI (file names with spaces are written as %20).
fn percent_decode(s: &str) -> String {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        let hex = |c: u8| (c as char).to_digit(16);
        if b[i] == b'%' && i + 2 < b.len() {
            if let (Some(h), Some(l)) = (hex(b[i + 1]), hex(b[i + 2])) {
                out.push((h * 16 + l) as u8);
                i += 3;
                continue;
            }
        }
        out.push(b[i]);
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

//! The seed files the mutations start from: small valid files of every format, written here with the
//! offsets of their structure (line and record boundaries, header numbers, float fields) so that
//! mutations can aim at them. Every seed loads as a valid mesh (a unit test checks it).

use super::Target;
use crate::compress::Codec;
use crate::mesh::Mesh;
use crate::meshlet::io::MeshletFile;
use serde_json::{json, Value};

/// Where a number or float sits in a seed.
#[derive(Clone, Copy, Debug)]
pub enum Field {
    /// Bytes `start..end` of a text file hold the number's characters.
    Text {
        /// First byte.
        start: usize,
        /// One past the last byte.
        end: usize,
    },
    /// A binary number of `width` bytes at `at`, big-endian if `be`.
    Bin {
        /// First byte.
        at: usize,
        /// Width in bytes (1, 2, 4 or 8).
        width: u8,
        /// Big-endian.
        be: bool,
    },
}

/// The parts of a glTF seed, so JSON-aware mutations can edit the document and re-assemble it.
#[derive(Clone, Debug)]
pub struct GltfParts {
    /// The JSON document (buffer 0 has no URI; [`GltfParts::assemble`] adds a data URI for .gltf).
    pub json: Value,
    /// Buffer 0's bytes.
    pub bin: Vec<u8>,
    /// Offsets of the position floats in `bin`.
    pub floats: Vec<usize>,
    /// GLB container (else .gltf with a base64 data URI).
    pub glb: bool,
}

impl GltfParts {
    /// The file bytes for `json` text and `bin` (pretty JSON, so whitespace separates tokens).
    pub fn assemble_text(&self, json_text: &[u8], bin: &[u8]) -> Vec<u8> {
        if self.glb {
            crate::mesh::gltf_io::write_glb(json_text, bin)
        } else {
            json_text.to_vec()
        }
    }

    /// JSON text of `json` with buffer 0 pointing at `bin` the way the container needs.
    pub fn json_text(&self, json: &Value, bin: &[u8]) -> Vec<u8> {
        use base64::Engine as _;
        let mut j = json.clone();
        if !self.glb {
            if let Some(b) = j.pointer_mut("/buffers/0") {
                if let Some(o) = b.as_object_mut() {
                    o.insert(
                        "uri".into(),
                        Value::String(format!(
                            "data:application/octet-stream;base64,{}",
                            base64::engine::general_purpose::STANDARD.encode(bin)
                        )),
                    );
                }
            }
        }
        serde_json::to_vec_pretty(&j).expect("a Value always serialises")
    }

    /// The whole file for a (possibly edited) document and buffer.
    pub fn assemble(&self, json: &Value, bin: &[u8]) -> Vec<u8> {
        self.assemble_text(&self.json_text(json, bin), bin)
    }
}

/// One seed file.
#[derive(Clone, Debug)]
pub struct Seed {
    /// Short label ("ply-le/normals-strips").
    pub name: String,
    /// Its format.
    pub target: Target,
    /// The file.
    pub bytes: Vec<u8>,
    /// Structural offsets (line ends, record starts, chunk edges) where truncation is interesting.
    pub boundaries: Vec<usize>,
    /// Header numbers and counts.
    pub numbers: Vec<Field>,
    /// Float fields (coordinates).
    pub floats: Vec<Field>,
    /// Bytes `..text_end` are text (the whole file for text formats, the header for binary PLY and
    /// binary STL).
    pub text_end: usize,
    /// glTF parts, for glTF and GLB seeds.
    pub gltf: Option<GltfParts>,
}

/// Every seed, and the mesh the meshlet-file seeds were built from.
pub struct Corpus {
    /// The seeds, grouped by target in [`Target::ALL`] order.
    pub seeds: Vec<Seed>,
    /// Source mesh of the meshlet-file seeds (what `check` validates them against).
    pub meshlet_source: Mesh,
}

impl Corpus {
    /// Builds the corpus (deterministic; a few milliseconds).
    pub fn new() -> Self {
        let (pos, quads) = grid(5, 4);
        let mut seeds = Vec::new();
        for (t, enc) in [
            (Target::PlyAscii, Enc::Ascii),
            (Target::PlyLe, Enc::Le),
            (Target::PlyBe, Enc::Be),
        ] {
            for spec in [
                PlySpec::default(),
                PlySpec {
                    normals: true,
                    colours: true,
                    double: true,
                    polygons: true,
                    count: "uint8",
                    item: "uint32",
                    strips: true,
                    extra: true,
                },
            ] {
                seeds.push(ply(t, enc, &spec, &pos, &quads));
            }
        }
        seeds.push(obj(&pos, &quads, false));
        seeds.push(obj(&pos, &quads, true));
        for glb in [false, true] {
            seeds.push(gltf(&pos, &quads, glb));
            seeds.push(gltf_quantised(&pos, &quads, glb));
            seeds.push(gltf_meshopt(&pos, &quads, glb));
            seeds.push(gltf_instanced(&pos, &quads, glb));
        }
        for rich in [false, true] {
            seeds.push(stl_ascii(&pos, &quads, rich));
            seeds.push(stl_binary(&pos, &quads, rich));
        }
        let meshlet_source = Mesh {
            positions: pos.clone(),
            indices: quads
                .iter()
                .flat_map(|q| [q[0], q[1], q[2], q[0], q[2], q[3]])
                .collect(),
        };
        for (strategy, limits) in [("nvidia", (8u32, 6u32)), ("meshopt", (16, 12))] {
            seeds.push(meshlet_seed(&meshlet_source, strategy, limits));
        }
        seeds.push(lod_seed(&meshlet_source));
        seeds.extend(cluster_seeds(&meshlet_source));
        for f in Codec::ALL {
            seeds.push(compressed_seed(&meshlet_source, f));
        }
        for (name, bytes, layout) in super::library::seeds(&meshlet_source) {
            let u32f = |at: usize| Field::Bin {
                at,
                width: 4,
                be: false,
            };
            seeds.push(Seed {
                name,
                target: Target::Library,
                boundaries: layout.boundaries,
                numbers: layout.numbers.into_iter().map(u32f).collect(),
                floats: layout.floats.into_iter().map(u32f).collect(),
                text_end: 0,
                gltf: None,
                bytes,
            });
        }
        Self {
            seeds,
            meshlet_source,
        }
    }

    /// The seeds of one target (for [`Target::Zst`]: the seeds that are compressed).
    pub fn of(&self, t: Target) -> Vec<&Seed> {
        let inner = |s: &&Seed| match t {
            Target::Zst => matches!(
                s.target,
                Target::PlyAscii | Target::PlyLe | Target::Obj | Target::Glb | Target::StlBinary
            ),
            _ => s.target == t,
        };
        self.seeds.iter().filter(inner).collect()
    }
}

impl Default for Corpus {
    fn default() -> Self {
        Self::new()
    }
}

/// An `n` x `n` height field: positions and counter-clockwise quads.
fn grid(n: u32, seed: u64) -> (Vec<[f32; 3]>, Vec<[u32; 4]>) {
    let mut pos = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let h = crate::mesh::generate::splitmix64(seed ^ (j * n + i) as u64);
            pos.push([i as f32, j as f32, (h >> 40) as f32 / (1u64 << 24) as f32]);
        }
    }
    let mut quads = Vec::new();
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            let v = j * n + i;
            quads.push([v, v + 1, v + 1 + n, v + n]);
        }
    }
    (pos, quads)
}

#[derive(Clone, Copy, PartialEq)]
enum Enc {
    Ascii,
    Le,
    Be,
}

struct PlySpec {
    normals: bool,
    colours: bool,
    double: bool,
    polygons: bool,
    count: &'static str,
    item: &'static str,
    strips: bool,
    extra: bool,
}

impl Default for PlySpec {
    fn default() -> Self {
        Self {
            normals: false,
            colours: false,
            double: false,
            polygons: false,
            count: "uchar",
            item: "int",
            strips: false,
            extra: false,
        }
    }
}

/// Appends text or a binary scalar, noting where it went.
struct Writer {
    out: Vec<u8>,
    enc: Enc,
    boundaries: Vec<usize>,
    numbers: Vec<Field>,
    floats: Vec<Field>,
}

impl Writer {
    /// The written file as a seed of `target`; bytes below `text_end` are text.
    fn into_seed(self, name: String, target: Target, text_end: usize) -> Seed {
        Seed {
            name,
            target,
            bytes: self.out,
            boundaries: self.boundaries,
            numbers: self.numbers,
            floats: self.floats,
            text_end,
            gltf: None,
        }
    }

    fn text(&mut self, s: &str) {
        self.out.extend_from_slice(s.as_bytes());
    }
    fn line(&mut self, s: &str) {
        self.text(s);
        self.text("\n");
        self.boundaries.push(self.out.len());
    }
    /// A header line whose last token is a number.
    fn header_count(&mut self, prefix: &str, n: usize) {
        self.text(prefix);
        let start = self.out.len();
        self.text(&n.to_string());
        self.numbers.push(Field::Text {
            start,
            end: self.out.len(),
        });
        self.line("");
    }
    /// One body value of PLY type `ty`; `float` marks coordinates, `number` list counts.
    fn value(&mut self, ty: &str, v: f64, float: bool, number: bool) {
        let start = self.out.len();
        let width: u8 = match ty {
            "uchar" | "uint8" | "char" | "int8" => 1,
            "ushort" | "uint16" | "short" | "int16" => 2,
            "double" | "float64" => 8,
            _ => 4,
        };
        match self.enc {
            Enc::Ascii => {
                if self.out.last().is_some_and(|&c| c != b'\n') {
                    self.text(" ");
                }
                let start = self.out.len();
                self.text(&if float {
                    format!("{v}")
                } else {
                    format!("{}", v as i64)
                });
                let f = Field::Text {
                    start,
                    end: self.out.len(),
                };
                if float {
                    self.floats.push(f);
                }
                if number {
                    self.numbers.push(f);
                }
            }
            Enc::Le | Enc::Be => {
                let be = self.enc == Enc::Be;
                let bytes: Vec<u8> = match ty {
                    "float" | "float32" => {
                        let b = (v as f32).to_le_bytes();
                        b.to_vec()
                    }
                    "double" | "float64" => v.to_le_bytes().to_vec(),
                    _ => (v as i64).to_le_bytes()[..width as usize].to_vec(),
                };
                let mut bytes = bytes;
                if be {
                    bytes.reverse();
                }
                self.out.extend_from_slice(&bytes);
                let f = Field::Bin {
                    at: start,
                    width,
                    be,
                };
                if float && ty.starts_with('f') {
                    self.floats.push(f);
                }
                if number {
                    self.numbers.push(f);
                }
            }
        }
    }
    fn end_record(&mut self) {
        if self.enc == Enc::Ascii {
            self.text("\n");
        }
        self.boundaries.push(self.out.len());
    }
}

fn ply(t: Target, enc: Enc, s: &PlySpec, pos: &[[f32; 3]], quads: &[[u32; 4]]) -> Seed {
    let mut w = Writer {
        out: Vec::new(),
        enc,
        boundaries: Vec::new(),
        numbers: Vec::new(),
        floats: Vec::new(),
    };
    w.line("ply");
    w.line(match enc {
        Enc::Ascii => "format ascii 1.0",
        Enc::Le => "format binary_little_endian 1.0",
        Enc::Be => "format binary_big_endian 1.0",
    });
    w.line("comment meshletlab fuzz seed");
    let coord = if s.double { "double" } else { "float" };
    w.header_count("element vertex ", pos.len());
    for c in ["x", "y", "z"] {
        w.line(&format!("property {coord} {c}"));
    }
    if s.normals {
        for c in ["nx", "ny", "nz"] {
            w.line(&format!("property float {c}"));
        }
    }
    if s.colours {
        for c in ["red", "green", "blue"] {
            w.line(&format!("property uchar {c}"));
        }
    }
    // Polygons: quads as they are, or each split into two triangles.
    let faces: Vec<Vec<u32>> = if s.polygons {
        quads.iter().map(|q| q.to_vec()).collect()
    } else {
        quads
            .iter()
            .flat_map(|q| [vec![q[0], q[1], q[2]], vec![q[0], q[2], q[3]]])
            .collect()
    };
    // With strips, the last row of quads goes into one strip instead of faces.
    let (faces, strip): (Vec<Vec<u32>>, Vec<i64>) = if s.strips {
        let keep = faces.len() - faces.len() / 4;
        let strip = vec![0, 5, 1, 6, 2, 7, -1, 3, 8, 4, 9];
        (faces[..keep].to_vec(), strip)
    } else {
        (faces, Vec::new())
    };
    w.header_count("element face ", faces.len());
    w.line(&format!(
        "property list {} {} vertex_indices",
        s.count, s.item
    ));
    if s.strips {
        w.header_count("element tristrips ", 1);
        w.line("property list int int vertex_indices");
    }
    if s.extra {
        w.header_count("element material ", 2);
        w.line("property uchar id");
        w.line("property list uchar float weights");
    }
    w.line("end_header");
    let body = w.out.len();
    for (v, p) in pos.iter().enumerate() {
        for c in p {
            w.value(coord, *c as f64, true, false);
        }
        if s.normals {
            for c in [0.0, 0.0, 1.0] {
                w.value("float", c, true, false);
            }
        }
        if s.colours {
            for c in [v * 7, v * 13, v * 29] {
                w.value("uchar", (c % 256) as f64, false, false);
            }
        }
        w.end_record();
    }
    for f in &faces {
        w.value(s.count, f.len() as f64, false, true);
        for &i in f {
            w.value(s.item, i as f64, false, false);
        }
        w.end_record();
    }
    if s.strips {
        w.value("int", strip.len() as f64, false, true);
        for &i in &strip {
            w.value("int", i as f64, false, false);
        }
        w.end_record();
    }
    if s.extra {
        for m in 0..2 {
            w.value("uchar", m as f64, false, false);
            w.value("uchar", 2.0, false, true);
            w.value("float", 0.5, true, false);
            w.value("float", 0.25, true, false);
            w.end_record();
        }
    }
    let text_end = if enc == Enc::Ascii { w.out.len() } else { body };
    let variant = if s.normals {
        "props-polygons-strips"
    } else {
        "plain"
    };
    w.into_seed(format!("{}/{variant}", t.name()), t, text_end)
}

fn obj(pos: &[[f32; 3]], quads: &[[u32; 4]], rich: bool) -> Seed {
    let mut w = Writer {
        out: Vec::new(),
        enc: Enc::Ascii,
        boundaries: Vec::new(),
        numbers: Vec::new(),
        floats: Vec::new(),
    };
    w.line("# meshletlab fuzz seed");
    if rich {
        w.line("mtllib none.mtl");
        w.line("o first");
    }
    for p in pos {
        w.text("v");
        for c in p {
            w.value("float", *c as f64, true, false);
        }
        w.end_record();
        if rich {
            w.line("vn 0 0 1");
            w.line("vt 0.5 0.5");
        }
    }
    let n = pos.len() as i64;
    for (k, q) in quads.iter().enumerate() {
        if rich && k == quads.len() / 2 {
            w.line("g second");
            w.line("usemtl none");
            w.line("s 1");
        }
        w.text("f");
        for &i in q {
            // Rich: negative (relative) indices for every other face, and v/vt/vn triples.
            let idx = if rich && k % 2 == 1 {
                i as i64 - n
            } else {
                i as i64 + 1
            };
            w.value("int", idx as f64, false, true);
            if rich {
                w.text(&format!("/{idx}/{idx}"));
            }
        }
        w.end_record();
    }
    let variant = if rich {
        "groups-normals-negative"
    } else {
        "plain"
    };
    let end = w.out.len();
    w.into_seed(format!("obj/{variant}"), Target::Obj, end)
}

/// The grid's quads as counter-clockwise triangles.
fn triangles(quads: &[[u32; 4]]) -> Vec<[u32; 3]> {
    quads
        .iter()
        .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
        .collect()
}

/// Unit normal of a triangle (what an exporter writes; the reader ignores it).
fn normal(p: [[f32; 3]; 3]) -> [f32; 3] {
    let [a, b, c] = p.map(glam::Vec3::from_array);
    (b - a).cross(c - a).normalize_or_zero().to_array()
}

/// An ASCII STL of the grid. Rich: CRLF line ends, tabs, upper-case keywords, two solids (the
/// second without a name), and x = 0 written as -0 in every other facet (welded with 0).
fn stl_ascii(pos: &[[f32; 3]], quads: &[[u32; 4]], rich: bool) -> Seed {
    let mut w = Writer {
        out: Vec::new(),
        enc: Enc::Ascii,
        boundaries: Vec::new(),
        numbers: Vec::new(),
        floats: Vec::new(),
    };
    let eol = |w: &mut Writer| {
        if rich {
            w.text("\r");
        }
        w.end_record();
    };
    let tris = triangles(quads);
    let half = if rich { tris.len() / 2 } else { tris.len() };
    for (part, solid) in [&tris[..half], &tris[half..]].into_iter().enumerate() {
        if solid.is_empty() {
            continue;
        }
        let kw = |s: &str| {
            if part == 1 {
                s.to_ascii_uppercase()
            } else {
                s.to_string()
            }
        };
        let indent = if rich { "\t" } else { "  " };
        w.text(&kw(if part == 0 {
            "solid meshletlab fuzz seed"
        } else {
            "solid"
        }));
        eol(&mut w);
        for (f, t) in solid.iter().enumerate() {
            let p = t.map(|v| pos[v as usize]);
            w.text(&kw("facet normal"));
            for c in normal(p) {
                w.value("float", c as f64, true, false);
            }
            eol(&mut w);
            w.text(&format!("{indent}{}", kw("outer loop")));
            eol(&mut w);
            for c in p {
                w.text(&format!("{indent}{indent}{}", kw("vertex")));
                for (k, &x) in c.iter().enumerate() {
                    let x = if rich && k == 0 && x == 0.0 && f % 2 == 1 {
                        -0.0
                    } else {
                        x
                    };
                    w.value("float", x as f64, true, false);
                }
                eol(&mut w);
            }
            w.text(&format!("{indent}{}", kw("endloop")));
            eol(&mut w);
            w.text(&kw("endfacet"));
            eol(&mut w);
        }
        w.text(&kw(if part == 0 {
            "endsolid meshletlab fuzz seed"
        } else {
            "endsolid"
        }));
        eol(&mut w);
    }
    let variant = if rich {
        "crlf-upper-two-solids"
    } else {
        "plain"
    };
    let end = w.out.len();
    w.into_seed(format!("stl-ascii/{variant}"), Target::StlAscii, end)
}

/// A binary STL of the grid: the facet count and every normal and corner float marked. Solid: the
/// header begins with "solid" (as many exporters write it), padded with spaces, and the attribute
/// words hold colours; else a header padded with NULs and zero attribute words.
fn stl_binary(pos: &[[f32; 3]], quads: &[[u32; 4]], solid: bool) -> Seed {
    let tris = triangles(quads);
    let mut bytes = vec![if solid { b' ' } else { 0 }; 80];
    let name: &[u8] = if solid {
        b"solid meshletlab fuzz seed"
    } else {
        b"binary STL, meshletlab fuzz seed"
    };
    bytes[..name.len()].copy_from_slice(name);
    bytes.extend_from_slice(&(tris.len() as u32).to_le_bytes());
    let mut boundaries = vec![80, 84];
    let mut floats = Vec::new();
    for (f, t) in tris.iter().enumerate() {
        let p = t.map(|v| pos[v as usize]);
        boundaries.extend([bytes.len(), bytes.len() + 12, bytes.len() + 48]);
        for c in std::iter::once(normal(p)).chain(p).flatten() {
            floats.push(Field::Bin {
                at: bytes.len(),
                width: 4,
                be: false,
            });
            bytes.extend_from_slice(&c.to_le_bytes());
        }
        let attribute = if solid { 0x8000 | (f as u16 * 997) } else { 0 };
        bytes.extend_from_slice(&attribute.to_le_bytes());
    }
    boundaries.push(bytes.len());
    Seed {
        name: format!(
            "stl-binary/{}",
            if solid { "solid-header" } else { "plain" }
        ),
        target: Target::StlBinary,
        bytes,
        boundaries,
        numbers: vec![Field::Bin {
            at: 80,
            width: 4,
            be: false,
        }],
        floats,
        text_end: 80,
        gltf: None,
    }
}

/// A glTF scene: node 0 (rotated) has children 1 (mesh 0, indexed u16 triangles) and 2 (mesh 1, a
/// mirrored u8-indexed strip); positions are interleaved with a pad (stride 16).
fn gltf(pos: &[[f32; 3]], quads: &[[u32; 4]], glb: bool) -> Seed {
    let mut bin = Vec::new();
    let mut floats = Vec::new();
    for p in pos {
        for c in p {
            floats.push(bin.len());
            bin.extend_from_slice(&c.to_le_bytes());
        }
        bin.extend_from_slice(&[0u8; 4]);
    }
    let pos_len = bin.len();
    let tris: Vec<u16> = quads
        .iter()
        .flat_map(|q| [q[0], q[1], q[2], q[0], q[2], q[3]])
        .map(|i| i as u16)
        .collect();
    for t in &tris {
        bin.extend_from_slice(&t.to_le_bytes());
    }
    let tri_len = bin.len() - pos_len;
    align4(&mut bin);
    let strip_at = bin.len();
    let strip: [u8; 6] = [0, 5, 1, 6, 2, 7];
    bin.extend_from_slice(&strip);
    align4(&mut bin);
    let (lo, hi) = pos
        .iter()
        .fold(([f32::MAX; 3], [f32::MIN; 3]), |(mut lo, mut hi), p| {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
            (lo, hi)
        });
    let doc = json!({
        "asset": {"version": "2.0", "generator": "meshletlab fuzz seed"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [
            {"children": [1, 2], "rotation": [0.0, 0.38268343, 0.0, 0.9238795]},
            {"mesh": 0, "translation": [1.0, 2.0, 3.0]},
            {"mesh": 1, "scale": [-1.0, 1.0, 1.0]}
        ],
        "meshes": [
            {"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "mode": 4}]},
            {"primitives": [{"attributes": {"POSITION": 0}, "indices": 2, "mode": 5}]}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": pos.len(), "type": "VEC3", "min": lo, "max": hi},
            {"bufferView": 1, "componentType": 5123, "count": tris.len(), "type": "SCALAR"},
            {"bufferView": 2, "componentType": 5121, "count": strip.len(), "type": "SCALAR"}
        ],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": pos_len, "byteStride": 16},
            {"buffer": 0, "byteOffset": pos_len, "byteLength": tri_len},
            {"buffer": 0, "byteOffset": strip_at, "byteLength": strip.len()}
        ],
        "buffers": [{"byteLength": bin.len()}]
    });
    gltf_seed("scene", doc, bin, floats, glb)
}

/// An instanced scene: mesh 0 placed by two nodes (one mirrored) and by a third node's
/// `EXT_mesh_gpu_instancing` (three instances: f32 translations, normalised i16 rotations, f32
/// scales), so both the baking reader and the scene reader see node and GPU instancing.
fn gltf_instanced(pos: &[[f32; 3]], quads: &[[u32; 4]], glb: bool) -> Seed {
    let mut bin = Vec::new();
    let mut floats = Vec::new();
    let mut push_f32 = |bin: &mut Vec<u8>, v: f32| {
        floats.push(bin.len());
        bin.extend_from_slice(&v.to_le_bytes());
    };
    for p in pos {
        for &c in p {
            push_f32(&mut bin, c);
        }
    }
    let pos_len = bin.len();
    let tris: Vec<u32> = quads
        .iter()
        .flat_map(|q| [q[0], q[1], q[2], q[0], q[2], q[3]])
        .collect();
    for t in &tris {
        bin.extend_from_slice(&t.to_le_bytes());
    }
    let translations_at = bin.len();
    for k in 0..3 {
        for c in [2.0 * k as f32, 0.5, -1.0] {
            push_f32(&mut bin, c);
        }
    }
    let rotations_at = bin.len();
    // Unit quaternions as normalised i16: identity, a quarter turn about y, a half turn about x.
    for q in [[0i16, 0, 0, 32767], [0, 23170, 0, 23170], [32767, 0, 0, 0]] {
        for c in q {
            bin.extend_from_slice(&c.to_le_bytes());
        }
    }
    let scales_at = bin.len();
    for s in [[1.0f32, 1.0, 1.0], [0.5, 2.0, 1.0], [-1.0, 1.0, 1.0]] {
        for c in s {
            push_f32(&mut bin, c);
        }
    }
    let end = bin.len();
    let (lo, hi) = pos
        .iter()
        .fold(([f32::MAX; 3], [f32::MIN; 3]), |(mut lo, mut hi), p| {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
            (lo, hi)
        });
    let doc = json!({
        "asset": {"version": "2.0", "generator": "meshletlab fuzz seed"},
        "extensionsUsed": ["EXT_mesh_gpu_instancing"],
        "extensionsRequired": ["EXT_mesh_gpu_instancing"],
        "scene": 0,
        "scenes": [{"nodes": [0, 1, 2]}],
        "nodes": [
            {"mesh": 0},
            {"mesh": 0, "scale": [-1.0, 1.0, 1.0], "translation": [0.0, 3.0, 0.0]},
            {"mesh": 0, "translation": [0.0, 0.0, 4.0], "extensions": {"EXT_mesh_gpu_instancing":
                {"attributes": {"TRANSLATION": 2, "ROTATION": 3, "SCALE": 4}}}}
        ],
        "meshes": [
            {"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "mode": 4}]}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": pos.len(), "type": "VEC3", "min": lo, "max": hi},
            {"bufferView": 1, "componentType": 5125, "count": tris.len(), "type": "SCALAR"},
            {"bufferView": 2, "componentType": 5126, "count": 3, "type": "VEC3"},
            {"bufferView": 3, "componentType": 5122, "normalized": true, "count": 3, "type": "VEC4"},
            {"bufferView": 4, "componentType": 5126, "count": 3, "type": "VEC3"}
        ],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": pos_len},
            {"buffer": 0, "byteOffset": pos_len, "byteLength": translations_at - pos_len},
            {"buffer": 0, "byteOffset": translations_at, "byteLength": rotations_at - translations_at},
            {"buffer": 0, "byteOffset": rotations_at, "byteLength": scales_at - rotations_at},
            {"buffer": 0, "byteOffset": scales_at, "byteLength": end - scales_at}
        ],
        "buffers": [{"byteLength": bin.len()}]
    });
    gltf_seed("instanced", doc, bin, floats, glb)
}

/// Pads `bin` with zeros to a multiple of 4 bytes (glTF aligns every view's start).
fn align4(bin: &mut Vec<u8>) {
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
}

/// The scene of [`gltf`] (same nodes, so the node-graph mutations apply) with quantised positions
/// (KHR_mesh_quantization): mesh 0 reads normalised i16 positions (stride 8) with two vertices
/// moved by a sparse substitution, mesh 1's strip reads an accessor without a bufferView whose
/// strip vertices come from sparse values alone. The node scale dequantises.
fn gltf_quantised(pos: &[[f32; 3]], quads: &[[u32; 4]], glb: bool) -> Seed {
    const SCALE: f32 = 4.0;
    let q = |p: &[f32; 3]| p.map(|c| (c / SCALE * 32767.0).round() as i16);
    let mut bin = Vec::new();
    for p in pos {
        for c in q(p) {
            bin.extend_from_slice(&c.to_le_bytes());
        }
        bin.extend_from_slice(&[0u8; 2]);
    }
    let pos_len = bin.len();
    for t in quads
        .iter()
        .flat_map(|q| [q[0], q[1], q[2], q[0], q[2], q[3]])
    {
        bin.extend_from_slice(&(t as u16).to_le_bytes());
    }
    let tri_len = bin.len() - pos_len;
    align4(&mut bin);
    // Mesh 0's substitution: vertices 1 and 6 lifted by 0.5 (strictly increasing u8 indices).
    let moved_at = bin.len();
    bin.extend_from_slice(&[1u8, 6]);
    align4(&mut bin);
    let moved_values_at = bin.len();
    for v in [1usize, 6] {
        let mut p = pos[v];
        p[2] += 0.5;
        bin.extend(q(&p).iter().flat_map(|c| c.to_le_bytes()));
    }
    align4(&mut bin);
    // Mesh 1's strip vertices, with u16 indices.
    let strip: [u16; 6] = [0, 1, 2, 5, 6, 7];
    let strip_at = bin.len();
    bin.extend(strip.iter().flat_map(|i| i.to_le_bytes()));
    align4(&mut bin);
    let strip_values_at = bin.len();
    for &v in &strip {
        bin.extend(q(&pos[v as usize]).iter().flat_map(|c| c.to_le_bytes()));
    }
    align4(&mut bin);
    let strip_order_at = bin.len();
    let order: [u8; 6] = [0, 5, 1, 6, 2, 7];
    bin.extend_from_slice(&order);
    align4(&mut bin);
    let doc = json!({
        "asset": {"version": "2.0", "generator": "meshletlab fuzz seed"},
        "extensionsUsed": ["KHR_mesh_quantization"],
        "extensionsRequired": ["KHR_mesh_quantization"],
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [
            {"children": [1, 2], "rotation": [0.0, 0.38268343, 0.0, 0.9238795]},
            {"mesh": 0, "translation": [1.0, 2.0, 3.0], "scale": [SCALE, SCALE, SCALE]},
            {"mesh": 1, "scale": [-SCALE, SCALE, SCALE]}
        ],
        "meshes": [
            {"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "mode": 4}]},
            {"primitives": [{"attributes": {"POSITION": 2}, "indices": 3, "mode": 5}]}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5122, "normalized": true, "count": pos.len(), "type": "VEC3",
             "sparse": {"count": 2, "indices": {"bufferView": 2, "componentType": 5121},
                        "values": {"bufferView": 3}}},
            {"bufferView": 1, "componentType": 5123, "count": tri_len / 2, "type": "SCALAR"},
            {"componentType": 5122, "normalized": true, "count": 8, "type": "VEC3",
             "sparse": {"count": strip.len(), "indices": {"bufferView": 4, "componentType": 5123},
                        "values": {"bufferView": 5}}},
            {"bufferView": 6, "componentType": 5121, "count": order.len(), "type": "SCALAR"}
        ],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": pos_len, "byteStride": 8},
            {"buffer": 0, "byteOffset": pos_len, "byteLength": tri_len},
            {"buffer": 0, "byteOffset": moved_at, "byteLength": 2},
            {"buffer": 0, "byteOffset": moved_values_at, "byteLength": 12},
            {"buffer": 0, "byteOffset": strip_at, "byteLength": 12},
            {"buffer": 0, "byteOffset": strip_values_at, "byteLength": 36},
            {"buffer": 0, "byteOffset": strip_order_at, "byteLength": order.len()}
        ],
        "buffers": [{"byteLength": bin.len()}]
    });
    gltf_seed("quantised", doc, bin, Vec::new(), glb)
}

/// The scene of [`gltf`] with every view meshopt-compressed (EXT_meshopt_compression, by
/// meshoptimizer's encoders): mesh 0 reads u16 positions (ATTRIBUTES, stride 8) and triangles
/// (TRIANGLES); mesh 1's strip reads float positions through the EXPONENTIAL filter and an index
/// sequence (INDICES). The uncompressed views lie in buffer 1, a fallback without data.
fn gltf_meshopt(pos: &[[f32; 3]], quads: &[[u32; 4]], glb: bool) -> Seed {
    const SCALE: f32 = 1e-3;
    let quantised: Vec<[u16; 4]> = pos
        .iter()
        .map(|p| {
            let [x, y, z] = p.map(|c| (c / SCALE).round() as u16);
            [x, y, z, 0]
        })
        .collect();
    let tris: Vec<u32> = quads
        .iter()
        .flat_map(|q| [q[0], q[1], q[2], q[0], q[2], q[3]])
        .collect();
    let strip: [u32; 6] = [0, 5, 1, 6, 2, 7];
    let exp = meshopt::encode_filter_exp(pos, 15, meshopt::EncodeExpMode::SharedVector);
    let streams = [
        meshopt::encode_vertex_buffer(&quantised).expect("encodes"),
        meshopt::encode_index_buffer(&tris, pos.len()).expect("encodes"),
        meshopt::encode_vertex_buffer(&exp).expect("encodes"),
        meshopt::encode_index_sequence(&strip, pos.len()).expect("encodes"),
    ];
    // (mode, filter, stride, count) of each stream, in the order above.
    let shapes = [
        ("ATTRIBUTES", "NONE", 8, pos.len()),
        ("TRIANGLES", "NONE", 2, tris.len()),
        ("ATTRIBUTES", "EXPONENTIAL", 12, pos.len()),
        ("INDICES", "NONE", 2, strip.len()),
    ];
    let mut bin = Vec::new();
    let mut fallback_len = 0;
    let mut views = Vec::new();
    for (stream, (mode, filter, stride, count)) in streams.iter().zip(shapes) {
        let ext = json!({"buffer": 0, "byteOffset": bin.len(), "byteLength": stream.len(),
                         "byteStride": stride, "count": count, "mode": mode, "filter": filter});
        let mut view = json!({"buffer": 1, "byteOffset": fallback_len, "byteLength": stride * count,
                              "extensions": {"EXT_meshopt_compression": ext}});
        if mode == "ATTRIBUTES" {
            view["byteStride"] = stride.into();
        }
        views.push(view);
        bin.extend_from_slice(stream);
        align4(&mut bin);
        fallback_len += (stride * count).div_ceil(4) * 4;
    }
    let doc = json!({
        "asset": {"version": "2.0", "generator": "meshletlab fuzz seed"},
        "extensionsUsed": ["EXT_meshopt_compression", "KHR_mesh_quantization"],
        "extensionsRequired": ["EXT_meshopt_compression", "KHR_mesh_quantization"],
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [
            {"children": [1, 2], "rotation": [0.0, 0.38268343, 0.0, 0.9238795]},
            {"mesh": 0, "translation": [1.0, 2.0, 3.0], "scale": [SCALE, SCALE, SCALE]},
            {"mesh": 1, "scale": [-1.0, 1.0, 1.0]}
        ],
        "meshes": [
            {"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "mode": 4}]},
            {"primitives": [{"attributes": {"POSITION": 2}, "indices": 3, "mode": 5}]}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5123, "count": pos.len(), "type": "VEC3"},
            {"bufferView": 1, "componentType": 5123, "count": tris.len(), "type": "SCALAR"},
            {"bufferView": 2, "componentType": 5126, "count": pos.len(), "type": "VEC3"},
            {"bufferView": 3, "componentType": 5123, "count": strip.len(), "type": "SCALAR"}
        ],
        "bufferViews": views,
        "buffers": [
            {"byteLength": bin.len()},
            {"byteLength": fallback_len, "extensions": {"EXT_meshopt_compression": {"fallback": true}}}
        ]
    });
    gltf_seed("meshopt", doc, bin, Vec::new(), glb)
}

/// A glTF or GLB seed from its document and buffer 0, with the offsets of its structure.
fn gltf_seed(name: &str, doc: Value, bin: Vec<u8>, floats: Vec<usize>, glb: bool) -> Seed {
    let parts = GltfParts {
        json: doc,
        bin,
        floats,
        glb,
    };
    let text = parts.json_text(&parts.json, &parts.bin);
    let bytes = parts.assemble_text(&text, &parts.bin);
    let mut boundaries: Vec<usize> = Vec::new();
    let json_at = if glb { 20 } else { 0 };
    boundaries.extend(
        text.iter()
            .enumerate()
            .filter(|(_, &c)| c == b'\n')
            .map(|(i, _)| json_at + i + 1),
    );
    let mut numbers = Vec::new();
    if glb {
        let bin_at = 20 + text.len().div_ceil(4) * 4;
        boundaries.extend([
            4,
            8,
            12,
            16,
            20,
            bin_at,
            bin_at + 4,
            bin_at + 8,
            bytes.len(),
        ]);
        for at in [8, 12, bin_at] {
            numbers.push(Field::Bin {
                at,
                width: 4,
                be: false,
            });
        }
    }
    Seed {
        name: format!("{}/{name}", if glb { "glb" } else { "gltf" }),
        target: if glb { Target::Glb } else { Target::Gltf },
        text_end: if glb { 0 } else { bytes.len() },
        bytes,
        boundaries,
        numbers,
        floats: Vec::new(),
        gltf: Some(parts),
    }
}

/// `--labels` and `--meshlets` seeds: meshoptimizer's meshlets at 16/12 (each cluster fits)
/// and at 32/24 (each is over 16/12, so `--split` runs) as text and `.npy` (int64) ids, and the
/// 16/12 ones as an `.npz`.
fn cluster_seeds(m: &Mesh) -> Vec<Seed> {
    use crate::strategy::labels::triangle_labels;
    use crate::strategy::Strategy as _;
    let bare = |name: String, target: Target, bytes: Vec<u8>| Seed {
        name,
        target,
        boundaries: Vec::new(),
        numbers: Vec::new(),
        floats: Vec::new(),
        text_end: 0,
        gltf: None,
        bytes,
    };
    let mut out = Vec::new();
    for (v, t) in [(16u32, 12u32), (32, 24)] {
        let limits = crate::meshlet::Limits::new(v, t).expect("valid seed limits");
        let ml = crate::strategy::Meshopt { cone_weight: 0.0 }.build(m, limits);
        let labels = triangle_labels(m, &ml).expect("meshopt's meshlets are valid");
        let mut text = bare(format!("labels/text-{v}-{t}"), Target::Labels, Vec::new());
        for l in &labels {
            let start = text.bytes.len();
            text.bytes.extend_from_slice(format!("{l}\n").as_bytes());
            text.numbers.push(Field::Text {
                start,
                end: text.bytes.len() - 1,
            });
            text.boundaries.push(text.bytes.len());
        }
        text.text_end = text.bytes.len();
        out.push(text);
        let wide: Vec<i64> = labels.iter().map(|&l| l as i64).collect();
        let bytes = crate::meshlet::npy::write(&[wide.len() as u64], &wide);
        let mut npy = bare(format!("labels/npy-{v}-{t}"), Target::Labels, bytes);
        // The header is text up to its newline, then eight bytes an id.
        let data = npy
            .bytes
            .iter()
            .position(|&b| b == b'\n')
            .map_or(0, |i| i + 1);
        npy.text_end = data;
        npy.boundaries = vec![6, 8, 10, data, data + 8, npy.bytes.len() - 8];
        npy.numbers = (0..4)
            .map(|k| Field::Bin {
                at: data + 8 * k,
                width: 8,
                be: false,
            })
            .chain([Field::Bin {
                at: 8,
                width: 2,
                be: false,
            }])
            .collect();
        out.push(npy);
        if (v, t) == (16, 12) {
            let bytes = crate::meshlet::npz::to_npz(&ml);
            let mut npz = bare("npz/meshopt-16-12".into(), Target::Npz, bytes);
            // The first local header: sizes at 18 and 22, name length at 26.
            npz.numbers = [18, 22, 26]
                .map(|at| Field::Bin {
                    at,
                    width: if at == 26 { 2 } else { 4 },
                    be: false,
                })
                .to_vec();
            npz.boundaries = vec![30, 60, 128, npz.bytes.len() / 2, npz.bytes.len() - 22];
            out.push(npz);
        }
    }
    out
}

fn meshlet_seed(m: &Mesh, strategy: &str, (v, t): (u32, u32)) -> Seed {
    let limits = crate::meshlet::Limits::new(v, t).expect("valid seed limits");
    let s = crate::strategy::by_name(strategy, &Default::default()).expect("known strategy");
    let f = MeshletFile {
        limits,
        source_vertices: m.vertex_count() as u32,
        source_triangles: m.triangle_count() as u32,
        fingerprint: m.fingerprint(),
        strategy: strategy.to_string(),
        meshlets: s.build(m, limits),
    };
    let bytes = f.to_bytes();
    let u32f = |at: usize| Field::Bin {
        at,
        width: 4,
        be: false,
    };
    // Header: limits, source counts, name length, then the three array counts after the name.
    let after_name = 36 + strategy.len();
    let mut numbers: Vec<Field> = [
        8,
        12,
        16,
        20,
        32,
        after_name,
        after_name + 4,
        after_name + 8,
    ]
    .into_iter()
    .map(u32f)
    .collect();
    let records = after_name + 12;
    let mut boundaries = vec![8, 16, 24, 32, 36, after_name, records];
    for k in 0..f.meshlets.meshlets.len() {
        boundaries.push(records + 16 * k);
        numbers.extend((0..4).map(|j| u32f(records + 16 * k + 4 * j)));
    }
    let verts = records + 16 * f.meshlets.meshlets.len();
    boundaries.extend([verts, verts + 4 * f.meshlets.vertices.len(), bytes.len()]);
    Seed {
        name: format!("meshlet/{strategy}"),
        target: Target::Meshlet,
        bytes,
        boundaries,
        numbers,
        floats: Vec::new(),
        text_end: 0,
        gltf: None,
    }
}

/// A LOD file of the grid at 8/8 (several levels), with its header and level fields marked.
fn lod_seed(m: &Mesh) -> Seed {
    use crate::lod::{self, io::LodFile};
    let limits = crate::meshlet::Limits::new(8, 8).expect("valid seed limits");
    let s = crate::strategy::by_name("meshopt", &Default::default()).expect("known strategy");
    let cfg = lod::Config {
        group_size: 4,
        ..Default::default()
    };
    let f = LodFile {
        source_vertices: m.vertex_count() as u32,
        source_triangles: m.triangle_count() as u32,
        fingerprint: m.fingerprint(),
        lod: lod::build(m, s.as_ref(), limits, &cfg),
    };
    let bytes = f.to_bytes();
    let u32f = |at: usize| Field::Bin {
        at,
        width: 4,
        be: false,
    };
    let name = 36 + f.lod.strategy.len();
    let mut numbers: Vec<Field> = [8, 12, 16, 20, 32, name, name + 4]
        .into_iter()
        .map(u32f)
        .collect();
    let groups = name + 8;
    let mut boundaries = vec![8, 16, 24, 32, 36, name, groups];
    let mut at = groups + 24 * f.lod.groups.len();
    numbers.extend((groups..at).step_by(4).map(u32f));
    for l in f.lod.levels.iter().rev() {
        boundaries.push(at);
        numbers.extend((0..6).map(|k| u32f(at + 4 * k)));
        let ml = &l.meshlets;
        let meshlets = at + 24;
        let info = meshlets + 16 * ml.len();
        numbers.extend((meshlets..info).step_by(4).map(u32f));
        // Group references inside the LOD data.
        numbers.extend((0..ml.len()).map(|k| u32f(info + 44 * k + 40)));
        at = info + 44 * ml.len() + 4 * ml.vertices.len() + ml.triangles.len();
        boundaries.extend([meshlets, info, info + 44 * ml.len()]);
    }
    boundaries.push(bytes.len());
    // Floats: every LOD record's bounds and errors.
    let mut floats = Vec::new();
    let mut at = groups + 24 * f.lod.groups.len();
    for l in f.lod.levels.iter().rev() {
        let info = at + 24 + 16 * l.meshlets.len();
        for k in 0..l.meshlets.len() {
            floats.extend((0..10).map(|j| Field::Bin {
                at: info + 44 * k + 4 * j,
                width: 4,
                be: false,
            }));
        }
        at = info
            + 44 * l.meshlets.len()
            + 4 * l.meshlets.vertices.len()
            + l.meshlets.triangles.len();
    }
    Seed {
        name: "lod/meshopt-8-8".into(),
        target: Target::Lod,
        bytes,
        boundaries,
        numbers,
        floats,
        text_end: 0,
        gltf: None,
    }
}

/// A compressed-meshlet file of the grid (meshoptimizer's codec or laced wires at 16/12), with
/// its header, offset table, provenance tables and every record's (or the section's) header
/// fields marked.
fn compressed_seed(m: &Mesh, format: Codec) -> Seed {
    use crate::compress::file;
    let limits = crate::meshlet::Limits::new(16, 12).expect("valid seed limits");
    let s = crate::strategy::by_name("meshopt", &Default::default()).expect("known strategy");
    let tolerance = crate::compress::paper_tolerance(m);
    let encoded = format
        .encode(m, &s.build(m, limits), tolerance)
        .expect("seed encodes");
    let f = file::CompressedFile::new(m, format, tolerance, encoded);
    let bytes = f.to_bytes();
    let u32f = |at: usize| Field::Bin {
        at,
        width: 4,
        be: false,
    };
    // Header: magic 0, format 8, counts 12 and 16, fingerprint 20, tolerance 28, exponent 36,
    // origin 40, meshlet count 52, offsets 56.
    let count_at = 52;
    let offsets = count_at + 4;
    let n = f.encoded.offsets.len();
    let data = offsets + 4 * n + 4;
    let mut numbers: Vec<Field> = [8, 12, 16, 36, count_at, data - 4]
        .into_iter()
        .map(u32f)
        .collect();
    numbers.extend((offsets..data - 4).step_by(4).map(u32f));
    let mut boundaries = vec![8, 12, 20, 28, 36, 40, count_at, offsets, data - 4, data];
    let mut floats: Vec<Field> = (0..3).map(|k| u32f(40 + 4 * k)).collect();
    floats.push(Field::Bin {
        at: 28,
        width: 8,
        be: false,
    });
    for &o in &f.encoded.offsets {
        let r = data + o as usize;
        boundaries.push(r);
        if format == Codec::Meshopt {
            // Counts and bit widths are bytes; the anchor and the connectivity length are numbers.
            boundaries.push(r + 19);
            numbers.extend((0..3).map(|k| u32f(r + 5 + 4 * k)));
            numbers.push(Field::Bin {
                at: r + 17,
                width: 2,
                be: false,
            });
        }
    }
    if format != Codec::Meshopt {
        // Section header: meshlet, wire and corner counts, widths, table and first-wire offsets.
        numbers.extend([0, 4, 8, 12, 16, 20].map(|k| u32f(data + k)));
        boundaries.extend([data + 12, data + 16, data + 24]);
    }
    // Provenance tables after the data.
    let tables = data + f.encoded.data.len();
    let second = tables + 4 + 4 * f.encoded.wire_base.len();
    numbers.extend([u32f(tables), u32f(second)]);
    boundaries.extend([tables, tables + 4, second, second + 4]);
    boundaries.push(bytes.len());
    let name = format!("compressed/{}-16-12", format.name());
    Seed {
        name,
        target: Target::Compressed,
        bytes,
        boundaries,
        numbers,
        floats,
        text_end: 0,
        gltf: None,
    }
}

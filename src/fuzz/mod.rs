//! A seeded mutation fuzzer over every file reader: PLY (ASCII, binary little and big endian), OBJ,
//! glTF, GLB, STL (ASCII and binary), zstd-compressed files, the meshlet file (`check`), the LOD
//! file (`lod-check`), the compressed-meshlet file (`check`), the label files (text and `.npy`,
//! `--labels`) and the `.npz` meshlets (`--meshlets`); and, as target `library`, the
//! arrays an engine hands the library's constructors, on through its strategies, bounds, codecs and
//! LOD build ([`library`]).
//!
//! Case `k` of a run with seed `s` is a pure function of `(s, k)`: a target format, a seed file of
//! that format ([`corpus`]) and a mutation ([`mutate`]): bit flips, truncation at structural
//! boundaries, header numbers replaced by 0 / 1 / 2^31 / 2^32-1 / 2^32 / negative / huge values,
//! duplicated chunks, NaN / infinity / denormals in float fields, deleted or repeated tokens,
//! out-of-range JSON indices, wrong JSON types, broken node trees, zeroed ranges, or several of the
//! byte-level ones stacked. For `.zst`, half the cases mutate the file before compressing it (the
//! inner parsers through the zstd path) and half mutate the compressed stream.
//!
//! Each case must load as a valid mesh or fail with a typed error. The cases run in child processes
//! (`meshletlab fuzz-worker`, see [`harness`]) so that nothing a reader does can take the run down:
//! a panic is caught and counted; a case that runs longer than [`HANG_SECONDS`] is a hang (the
//! parent kills a worker that stops answering); and while a case runs the worker's allocator
//! ([`alloc::LimitAlloc`]) refuses to let live heap pass [`memory_bound`] of the input's size, so an
//! allocation a header asked for aborts the worker instead of taking the machine's memory, and the
//! parent reports it as over the limit.
//!
//! No reader is wrapped in `catch_unwind` outside this harness: the harness catches panics only to
//! count them, and the count must be 0.

pub mod alloc;
pub mod corpus;
pub mod harness;
pub mod library;
pub mod mutate;

use crate::mesh::{self, MeshErrorKind};
use crate::meshlet::io::MeshletFile;
use corpus::{Corpus, Seed};
use mutate::Rng;
use serde::Serialize;
use std::path::Path;

/// A case that runs longer than this counts as a hang (the cases are a few kilobytes).
pub const HANG_SECONDS: f64 = 2.0;

/// Most live heap one case may reach: 64 MiB plus 256 times the bytes the reader sees (for `.zst`
/// the larger of the compressed and decompressed sizes). The readers need about 30x at worst
/// (a PLY strip of one-byte indices becomes 12 bytes per triangle, doubled while a vector grows).
pub fn memory_bound(input_bytes: usize) -> usize {
    (64 << 20) + 256 * input_bytes
}

/// A file format the fuzzer feeds.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
pub enum Target {
    /// PLY, ASCII.
    PlyAscii,
    /// PLY, binary little-endian.
    PlyLe,
    /// PLY, binary big-endian.
    PlyBe,
    /// Wavefront OBJ.
    Obj,
    /// glTF JSON with an embedded (data URI) buffer.
    Gltf,
    /// Binary glTF.
    Glb,
    /// STL, ASCII.
    StlAscii,
    /// STL, binary.
    StlBinary,
    /// zstd-compressed PLY, OBJ, GLB or binary STL.
    Zst,
    /// The meshlet file, read and checked against its mesh (`meshletlab check`).
    Meshlet,
    /// The cluster-LOD file, read and checked against its mesh (`meshletlab lod-check`).
    Lod,
    /// The compressed-meshlet file, read and every meshlet decoded (`meshletlab check`).
    Compressed,
    /// A label file (text or `.npy`), read for the meshlet files' source mesh and packed
    /// (`--labels`, with and without `--split`).
    Labels,
    /// Meshlets as an `.npz`, read against that mesh and held to limits (`--meshlets`).
    Npz,
    /// The library's public API on framed arrays ([`library`]).
    Library,
}

impl Target {
    /// Every target, in report order.
    pub const ALL: [Target; 15] = [
        Target::PlyAscii,
        Target::PlyLe,
        Target::PlyBe,
        Target::Obj,
        Target::Gltf,
        Target::Glb,
        Target::StlAscii,
        Target::StlBinary,
        Target::Zst,
        Target::Meshlet,
        Target::Lod,
        Target::Compressed,
        Target::Labels,
        Target::Npz,
        Target::Library,
    ];

    /// Short name.
    pub fn name(self) -> &'static str {
        match self {
            Target::PlyAscii => "ply-ascii",
            Target::PlyLe => "ply-le",
            Target::PlyBe => "ply-be",
            Target::Obj => "obj",
            Target::Gltf => "gltf",
            Target::Glb => "glb",
            Target::StlAscii => "stl-ascii",
            Target::StlBinary => "stl-binary",
            Target::Zst => "zst",
            Target::Meshlet => "meshlet",
            Target::Lod => "lod",
            Target::Compressed => "compressed",
            Target::Labels => "labels",
            Target::Npz => "npz",
            Target::Library => "library",
        }
    }

    fn extension(self) -> &'static str {
        match self {
            Target::PlyAscii | Target::PlyLe | Target::PlyBe => "ply",
            Target::Obj => "obj",
            Target::Gltf => "gltf",
            Target::Glb => "glb",
            Target::StlAscii | Target::StlBinary => "stl",
            Target::Zst => "zst",
            Target::Meshlet => "mlt",
            Target::Lod => "lod",
            Target::Compressed => "cmp",
            Target::Labels => "labels",
            Target::Npz => "npz",
            Target::Library => "lib",
        }
    }
}

/// A mutation kind.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
pub enum Mutation {
    /// 1-8 random bit flips.
    Flip,
    /// Cut at a line, record, chunk or field boundary (or a byte either side; sometimes anywhere).
    Truncate,
    /// A header number or count replaced by 0, 1, 2^31, 2^32-1, 2^32, a negative or a huge value.
    HeaderNumber,
    /// A chunk copied and inserted.
    Duplicate,
    /// NaN, infinities, denormals, -0 or out-of-range values in float fields.
    FloatSpecial,
    /// 1-3 tokens deleted.
    TokenDelete,
    /// 1-3 tokens repeated.
    TokenRepeat,
    /// A JSON integer set out of range.
    JsonIndex,
    /// A JSON value replaced by one of another type.
    JsonType,
    /// Node cycles, shared children, a 40-level diamond, a 3,000-deep chain.
    JsonCycle,
    /// A range set to zero.
    ZeroRange,
    /// 2-4 byte-level mutations in a row.
    Stacked,
}

impl Mutation {
    /// Every mutation, in report order.
    pub const ALL: [Mutation; 12] = [
        Mutation::Flip,
        Mutation::Truncate,
        Mutation::HeaderNumber,
        Mutation::Duplicate,
        Mutation::FloatSpecial,
        Mutation::TokenDelete,
        Mutation::TokenRepeat,
        Mutation::JsonIndex,
        Mutation::JsonType,
        Mutation::JsonCycle,
        Mutation::ZeroRange,
        Mutation::Stacked,
    ];

    /// Short name.
    pub fn name(self) -> &'static str {
        match self {
            Mutation::Flip => "flip",
            Mutation::Truncate => "truncate",
            Mutation::HeaderNumber => "header-number",
            Mutation::Duplicate => "duplicate",
            Mutation::FloatSpecial => "float-special",
            Mutation::TokenDelete => "token-delete",
            Mutation::TokenRepeat => "token-repeat",
            Mutation::JsonIndex => "json-index",
            Mutation::JsonType => "json-type",
            Mutation::JsonCycle => "json-cycle",
            Mutation::ZeroRange => "zero-range",
            Mutation::Stacked => "stacked",
        }
    }

    /// Whether the mutation means something for `t`'s files.
    pub fn applies(self, t: Target) -> bool {
        let gltf = matches!(t, Target::Gltf | Target::Glb);
        match self {
            Mutation::JsonIndex | Mutation::JsonType | Mutation::JsonCycle => gltf,
            // Text exists in every format but the meshlet, LOD and compressed files and the
            // library's arrays (binary PLY and STL: the header; GLB: JSON).
            Mutation::TokenDelete | Mutation::TokenRepeat => !matches!(
                t,
                Target::Meshlet | Target::Lod | Target::Compressed | Target::Npz | Target::Library
            ),
            // Neither holds floats.
            Mutation::FloatSpecial => !matches!(t, Target::Meshlet | Target::Labels | Target::Npz),
            _ => true,
        }
    }
}

/// One generated case.
pub struct Case {
    /// Its index in the run.
    pub index: u64,
    /// Format.
    pub target: Target,
    /// Mutation.
    pub mutation: Mutation,
    /// The seed file it came from.
    pub seed_name: String,
    /// File name given to the reader (its extension picks the format).
    pub file_name: String,
    /// The mutated file.
    pub bytes: Vec<u8>,
}

/// Case `index` of the run with seed `run_seed`.
pub fn case(corpus: &Corpus, run_seed: u64, index: u64) -> Case {
    let mut rng = Rng(run_seed ^ index.wrapping_mul(0x9E37_79B9_7F4A_7C15));
    rng.next_u64();
    let target = Target::ALL[rng.below(Target::ALL.len())];
    let muts: Vec<Mutation> = Mutation::ALL
        .into_iter()
        .filter(|m| m.applies(target))
        .collect();
    let mutation = *rng.pick(&muts);
    let seeds = corpus.of(target);
    let seed: &&Seed = rng.pick(&seeds);
    let seed: &Seed = seed;
    let (bytes, file_name) = if target == Target::Zst {
        let inner_name = format!("case.{}.zst", seed.target.extension());
        let bytes = if rng.chance(0.5) || !mutation.applies(seed.target) {
            // Mutate the compressed stream; zstd's frame header fields are its "numbers".
            let z = zstd::stream::encode_all(&seed.bytes[..], 1).expect("in-memory zstd");
            let zs = Seed {
                name: seed.name.clone(),
                target: Target::Zst,
                boundaries: vec![4, 5, 6, 10, 14, z.len().saturating_sub(4)],
                numbers: [(4, 1), (5, 1), (6, 4), (6, 8)]
                    .into_iter()
                    .map(|(at, width)| corpus::Field::Bin {
                        at,
                        width,
                        be: false,
                    })
                    .collect(),
                floats: Vec::new(),
                text_end: 0,
                gltf: None,
                bytes: z,
            };
            let byte_level = match mutation {
                Mutation::FloatSpecial | Mutation::TokenDelete | Mutation::TokenRepeat => {
                    Mutation::Flip
                }
                m => m,
            };
            mutate::apply(byte_level, &zs, &mut rng)
        } else {
            let inner = mutate::apply(mutation, seed, &mut rng);
            zstd::stream::encode_all(&inner[..], 1).expect("in-memory zstd")
        };
        (bytes, inner_name)
    } else {
        (
            mutate::apply(mutation, seed, &mut rng),
            format!("case.{}", target.extension()),
        )
    };
    Case {
        index,
        target,
        mutation,
        seed_name: seed.name.clone(),
        file_name,
        bytes,
    }
}

/// What reading one case gave.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Outcome {
    /// A valid mesh (or a meshlet file that passes `check`).
    Valid,
    /// A typed error; the kind's name.
    Error(&'static str),
}

/// The name of a mesh error kind (for the report's error-kind table).
pub fn kind_name(k: &MeshErrorKind) -> &'static str {
    match k {
        MeshErrorKind::Io(_) => "io",
        MeshErrorKind::IsDirectory => "is-directory",
        MeshErrorKind::Write(_) => "write",
        MeshErrorKind::UnknownFormat => "unknown-format",
        MeshErrorKind::UnknownGenerated(_) => "unknown-generated",
        MeshErrorKind::Decompress(_) => "decompress",
        MeshErrorKind::Parse { .. } => "parse",
        MeshErrorKind::Truncated(_) => "truncated",
        MeshErrorKind::CountMismatch(_) => "count-mismatch",
        MeshErrorKind::Unsupported(_) => "unsupported",
        MeshErrorKind::UnsupportedExtension { .. } => "unsupported-extension",
        MeshErrorKind::NonFinite { .. } => "non-finite",
        MeshErrorKind::IndexOutOfRange { .. } => "index-out-of-range",
        MeshErrorKind::Empty(_) => "empty",
        MeshErrorKind::TooLarge(_) => "too-large",
    }
}

/// Reads one case the way the CLI would (`stats` for meshes, `check` for meshlet files). Errors
/// must name the file: that is checked here too (a typed error without the name is a defect).
pub fn read(case: &Case, corpus: &Corpus) -> Result<Outcome, String> {
    let path = Path::new(&case.file_name);
    let named = |msg: String| -> Result<(), String> {
        if msg.starts_with(&case.file_name) {
            Ok(())
        } else {
            Err(format!("error does not name the file: {msg}"))
        }
    };
    if case.target == Target::Library {
        return library::drive(&library::Arrays::decode(&case.bytes));
    }
    if case.target == Target::Compressed {
        use crate::compress::file::CompressedFile;
        return match CompressedFile::from_bytes(&case.bytes, path)
            .and_then(|f| f.check(&corpus.meshlet_source, path))
        {
            Ok(_) => Ok(Outcome::Valid),
            Err(e) => named(e.to_string()).map(|_| Outcome::Error("compressed-file")),
        };
    }
    if case.target == Target::Lod {
        return match crate::lod::io::LodFile::from_bytes(&case.bytes, path)
            .and_then(|f| f.check(&corpus.meshlet_source, path))
        {
            Ok(()) => Ok(Outcome::Valid),
            Err(e) => named(e.to_string()).map(|_| Outcome::Error("lod-file")),
        };
    }
    if case.target == Target::Labels {
        return read_labels(case, corpus).or_else(|e| named(e).map(|_| Outcome::Error("labels")));
    }
    if case.target == Target::Npz {
        let m = &corpus.meshlet_source;
        let limits = crate::meshlet::Limits::new(16, 12).expect("valid limits");
        return match crate::meshlet::npz::meshlets_from_bytes(&case.bytes, path, m) {
            Ok(ml) => {
                // Over the limits: refused without --split, divided with it.
                if crate::strategy::labels::split_meshlets(m, ml.clone(), limits, false).is_err() {
                    let (ml, _) = crate::strategy::labels::split_meshlets(m, ml, limits, true)
                        .map_err(|e| format!("--split refused: {e}"))?;
                    crate::meshlet::validate(m, &ml, limits)
                        .map_err(|e| format!("--split made invalid meshlets: {e}"))?;
                }
                Ok(Outcome::Valid)
            }
            Err(e) => named(e.to_string()).map(|_| Outcome::Error("npz")),
        };
    }
    if case.target == Target::Meshlet {
        return match MeshletFile::from_bytes(&case.bytes, path)
            .and_then(|f| f.check(&corpus.meshlet_source, path))
        {
            Ok(()) => Ok(Outcome::Valid),
            Err(e) => named(e.to_string()).map(|_| Outcome::Error("meshlet-file")),
        };
    }
    let baked = mesh::load_bytes(&case.bytes, path);
    if matches!(case.target, Target::Gltf | Target::Glb) {
        // The scene reader (instances kept apart) takes the same bytes: it may accept what
        // baking refuses as too large, never panic, and names the file when it refuses.
        if let Err(e) = mesh::scene_from_bytes(&case.bytes, path) {
            named(e.to_string())?;
        }
    }
    match baked {
        Ok(_) => Ok(Outcome::Valid),
        Err(e) => named(e.to_string()).map(|_| Outcome::Error(kind_name(&e.kind))),
    }
}

/// `--labels` on a case: the ids parsed for the corpus mesh, packed at 16/12; a clustering
/// over the limits must be refused without `--split` and packed valid with it. `Err` carries
/// the message of a typed refusal (which must name the file); a wrong packing is a defect.
fn read_labels(case: &Case, corpus: &Corpus) -> Result<Outcome, String> {
    use crate::strategy::labels::{file::parse_labels, from_labels, LabelsError};
    let m = &corpus.meshlet_source;
    let limits = crate::meshlet::Limits::new(16, 12).expect("valid limits");
    let ids = parse_labels(&case.bytes, m.triangle_count())
        .map_err(|e| format!("{}: {e}", case.file_name))?;
    let c = match from_labels(m, &ids, limits, false) {
        Ok(c) => c,
        Err(LabelsError::OverLimits { .. }) => from_labels(m, &ids, limits, true)
            .map_err(|e| format!("defect: --split refused: {e}"))
            .and_then(|c| {
                (c.split > 0)
                    .then_some(c)
                    .ok_or("defect: nothing split".into())
            })?,
        Err(e) => return Err(format!("defect: {e}")),
    };
    crate::meshlet::validate(m, &c.meshlets, limits)
        .map_err(|e| format!("defect: invalid meshlets from labels: {e}"))?;
    Ok(Outcome::Valid)
}

/// The bytes the reader of `case` sees: for `.zst` the larger of the compressed and the
/// decompressed size (the memory bound is proportional to it).
pub fn input_size(case: &Case) -> usize {
    if case.target == Target::Zst {
        if let Ok(d) = mesh::decompress(&case.bytes) {
            return d.len().max(case.bytes.len());
        }
    }
    case.bytes.len()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_seed_is_valid_and_cases_are_deterministic() {
        let c = Corpus::new();
        for s in &c.seeds {
            let case = Case {
                index: 0,
                target: s.target,
                mutation: Mutation::Flip,
                seed_name: s.name.clone(),
                file_name: format!("seed.{}", s.target.extension()),
                bytes: s.bytes.clone(),
            };
            assert_eq!(read(&case, &c), Ok(Outcome::Valid), "seed {}", s.name);
        }
        for t in Target::ALL {
            assert!(!c.of(t).is_empty(), "no seed for {}", t.name());
        }
        for k in 0..200 {
            let (a, b) = (case(&c, 7, k), case(&c, 7, k));
            assert_eq!(a.bytes, b.bytes);
            assert!(a.mutation.applies(a.target));
        }
    }

    #[test]
    fn the_instanced_seed_keeps_its_five_instances_of_one_mesh() {
        let c = Corpus::new();
        for glb in ["gltf", "glb"] {
            let s = c
                .seeds
                .iter()
                .find(|s| s.name == format!("{glb}/instanced"))
                .unwrap();
            let path = format!("seed.{}", s.target.extension());
            let scene = crate::mesh::scene_from_bytes(&s.bytes, Path::new(&path)).unwrap();
            assert_eq!((scene.meshes.len(), scene.instances.len()), (1, 5));
            assert_eq!(scene.instances.iter().filter(|i| i.mirrored()).count(), 2);
            let baked = crate::mesh::load_bytes(&s.bytes, Path::new(&path)).unwrap();
            assert_eq!(baked.triangle_count(), 5 * scene.meshes[0].triangle_count());
            assert_eq!(baked, scene.flatten());
        }
    }

    #[test]
    fn quantised_and_meshopt_seeds_decode_to_the_plain_scene() {
        let c = Corpus::new();
        let load = |name: &str| {
            let s = c.seeds.iter().find(|s| s.name == name).expect(name);
            crate::mesh::load_bytes(
                &s.bytes,
                Path::new(&format!("seed.{}", s.target.extension())),
            )
            .unwrap()
        };
        for glb in ["gltf", "glb"] {
            let plain = load(&format!("{glb}/scene"));
            for (variant, tolerance) in [("quantised", 4.0 / 32767.0), ("meshopt", 1e-3)] {
                let m = load(&format!("{glb}/{variant}"));
                assert_eq!(m.triangle_count(), plain.triangle_count(), "{variant}");
                let mut moved = 0;
                for t in 0..m.triangle_count() {
                    // meshoptimizer's index codec may rotate a triangle's corners (winding kept).
                    let mut tri = m.triangle(t);
                    let p = plain.triangle(t);
                    for _ in 0..2 {
                        if (m.position(tri[0]) - plain.position(p[0])).length() <= 0.6 {
                            break;
                        }
                        tri.rotate_left(1);
                    }
                    for (a, b) in tri.into_iter().zip(p) {
                        let d = (m.position(a) - plain.position(b)).length();
                        // The sparse substitution lifts two vertices by 0.5 (before rotation).
                        if variant == "quantised" && (d - 0.5).abs() < tolerance * 2.0 {
                            moved += 1;
                        } else {
                            assert!(d <= tolerance * 2.0, "{glb}/{variant} triangle {t}: {d}");
                        }
                    }
                }
                if variant == "quantised" {
                    // Vertices 1 and 6 are corners of 3 and 6 grid triangles.
                    assert_eq!(moved, 9, "{glb}: corners moved by the sparse accessor");
                }
            }
        }
    }

    #[test]
    fn mutations_change_the_file() {
        let c = Corpus::new();
        let mut changed = 0;
        for k in 0..500 {
            let x = case(&c, 1, k);
            let seed = c.seeds.iter().find(|s| s.name == x.seed_name).unwrap();
            if x.target != Target::Zst && x.bytes != seed.bytes {
                changed += 1;
            }
        }
        // A few mutations can be no-ops (a zero range over zeros); almost all must not be.
        assert!(
            changed > 400,
            "only {changed} of ~440 non-zst cases changed"
        );
    }
}

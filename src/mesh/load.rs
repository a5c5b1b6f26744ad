//! MeshFormat dispatch by file extension, with in-process zstd decompression of `*.zst`.

use super::error::{MeshError, MeshErrorKind};
use super::scene::{Instance, Scene};
use super::{generate, gltf_io, obj, ply, stl, Mesh};
use std::path::Path;

/// A supported mesh container.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MeshFormat {
    /// Stanford PLY, ASCII or binary.
    Ply,
    /// Wavefront OBJ.
    Obj,
    /// glTF 2.0 JSON with external or embedded buffers.
    Gltf,
    /// glTF 2.0 binary container.
    Glb,
    /// STL, ASCII or binary (vertices welded by exact position).
    Stl,
}

impl MeshFormat {
    /// MeshFormat of a file name (case-insensitive; a trailing `.zst` is looked through) and whether it is
    /// zstd-compressed.
    pub fn of(path: &Path) -> Option<(MeshFormat, bool)> {
        let name = path.file_name()?.to_string_lossy().to_ascii_lowercase();
        let (stem, zst) = match name.strip_suffix(".zst") {
            Some(s) => (s.to_string(), true),
            None => (name, false),
        };
        let ext = Path::new(&stem).extension()?.to_str()?.to_string();
        let f = match ext.as_str() {
            "ply" => MeshFormat::Ply,
            "obj" => MeshFormat::Obj,
            "gltf" => MeshFormat::Gltf,
            "glb" => MeshFormat::Glb,
            "stl" => MeshFormat::Stl,
            _ => return None,
        };
        Some((f, zst))
    }
}

/// Prefix of a path that names a generated mesh instead of a file: `gen:cad-part-400` is
/// [`super::generate::named`]`("cad-part-400")`, so every command and bench takes the in-tree stress
/// meshes where it takes a file.
pub const GENERATED_PREFIX: &str = "gen:";

/// Loads and validates a mesh from a file, or generates one named `gen:NAME`. Errors name the file.
pub fn load(path: &Path) -> Result<Mesh, MeshError> {
    if let Some(name) = path.to_str().and_then(|p| p.strip_prefix(GENERATED_PREFIX)) {
        if let Some(scene) = generate::named_scene(name) {
            return Ok(scene.flatten());
        }
        return generate::named(name).ok_or_else(|| {
            MeshError::new(
                path,
                MeshErrorKind::UnknownGenerated(
                    [generate::NAMES, generate::SCENE_NAMES].concat().join(", "),
                ),
            )
        });
    }
    // Before the format: a folder named `x.ply` is no PLY file, and `/tmp` no unknown format.
    if path.is_dir() {
        return Err(MeshError::new(path, MeshErrorKind::IsDirectory));
    }
    if MeshFormat::of(path).is_none() {
        return Err(MeshError::new(path, MeshErrorKind::UnknownFormat));
    }
    load_bytes(&read(path)?, path)
}

/// The bytes of the file at `path`; a directory is refused by name rather than as a read error.
fn read(path: &Path) -> Result<Vec<u8>, MeshError> {
    if path.is_dir() {
        return Err(MeshError::new(path, MeshErrorKind::IsDirectory));
    }
    std::fs::read(path).map_err(|e| MeshError::new(path, MeshErrorKind::Io(e)))
}

/// Loads and validates a mesh from bytes; `path` picks the format and labels errors (and is the base
/// for a glTF file's external buffers).
pub fn load_bytes(bytes: &[u8], path: &Path) -> Result<Mesh, MeshError> {
    let err = |k| MeshError::new(path, k);
    let (format, zst) = MeshFormat::of(path).ok_or_else(|| err(MeshErrorKind::UnknownFormat))?;
    let data = plain(bytes, zst).map_err(err)?;
    let data = &data[..];
    let (positions, indices) = match format {
        MeshFormat::Ply => ply::parse(data),
        MeshFormat::Obj => obj::parse(data),
        MeshFormat::Stl => stl::parse(data),
        MeshFormat::Gltf | MeshFormat::Glb => gltf_io::parse(data, path.parent()),
    }
    .map_err(err)?;
    Mesh::new(positions, indices, path)
}

/// Loads a scene: a glTF file's meshes and instances, a generated scene (`gen:NAME`, one of
/// [`generate::SCENE_NAMES`]), or any other mesh placed once. Errors name the file.
pub fn load_scene(path: &Path) -> Result<Scene, MeshError> {
    if let Some(name) = path.to_str().and_then(|p| p.strip_prefix(GENERATED_PREFIX)) {
        if let Some(scene) = generate::named_scene(name) {
            return Ok(scene);
        }
        return load(path).map(Scene::single);
    }
    let gltf = matches!(
        MeshFormat::of(path),
        Some((MeshFormat::Gltf | MeshFormat::Glb, _))
    );
    if !gltf {
        return load(path).map(Scene::single);
    }
    scene_from_bytes(&read(path)?, path)
}

/// [`load_scene`] of a glTF file's bytes (`path` labels errors and resolves external buffers).
pub fn scene_from_bytes(bytes: &[u8], path: &Path) -> Result<Scene, MeshError> {
    let err = |k| MeshError::new(path, k);
    let Some((MeshFormat::Gltf | MeshFormat::Glb, zst)) = MeshFormat::of(path) else {
        return load_bytes(bytes, path).map(Scene::single);
    };
    let data = plain(bytes, zst).map_err(err)?;
    let data = &data[..];
    let (meshes, instances) = gltf_io::parse_scene(data, path.parent()).map_err(err)?;
    // Meshes without triangles (points, lines) place nothing: dropped with their instances, as
    // baking drops them; a scene with no triangle at all is empty.
    let mut slot = vec![u32::MAX; meshes.len()];
    let mut kept = Vec::new();
    for (k, (p, i)) in meshes.into_iter().enumerate() {
        if !i.is_empty() {
            slot[k] = kept.len() as u32;
            kept.push(Mesh::new(p, i, path)?);
        }
    }
    if kept.is_empty() {
        return Err(err(MeshErrorKind::Empty("no triangle in any mesh".into())));
    }
    Ok(Scene {
        meshes: kept,
        instances: instances
            .into_iter()
            .filter(|&(mesh, _)| slot[mesh as usize] != u32::MAX)
            .map(|(mesh, transform)| Instance {
                mesh: slot[mesh as usize],
                transform,
            })
            .collect(),
    })
}

/// The bytes a reader parses: `bytes` decompressed when the name ends in `.zst`.
fn plain(bytes: &[u8], zst: bool) -> Result<std::borrow::Cow<'_, [u8]>, MeshErrorKind> {
    Ok(if zst {
        std::borrow::Cow::Owned(decompress(bytes)?)
    } else {
        std::borrow::Cow::Borrowed(bytes)
    })
}

/// A `.zst` input may decompress to at most this many times its size (plus [`ZSTD_SLACK`]). Real
/// meshes compress 2-3x; a few hundred bytes of zstd can otherwise announce gigabytes.
pub const MAX_ZSTD_RATIO: u64 = 1024;
/// Decompressed bytes allowed on top of [`MAX_ZSTD_RATIO`] times the compressed size.
pub const ZSTD_SLACK: u64 = 1 << 20;

/// Decompresses a zstd stream, refusing output beyond [`MAX_ZSTD_RATIO`] (a decompression bomb
/// becomes a typed error, not an allocation).
pub fn decompress(bytes: &[u8]) -> Result<Vec<u8>, MeshErrorKind> {
    use std::io::Read as _;
    let cap = (bytes.len() as u64)
        .saturating_mul(MAX_ZSTD_RATIO)
        .saturating_add(ZSTD_SLACK);
    let dec = zstd::stream::read::Decoder::new(bytes)
        .map_err(|e| MeshErrorKind::Decompress(e.to_string()))?;
    let mut out = Vec::new();
    dec.take(cap + 1)
        .read_to_end(&mut out)
        .map_err(|e| MeshErrorKind::Decompress(e.to_string()))?;
    if out.len() as u64 > cap {
        return Err(MeshErrorKind::TooLarge(format!(
            "zstd stream expands to more than {cap} bytes ({MAX_ZSTD_RATIO}x its size; a decompression bomb?)"
        )));
    }
    Ok(out)
}

/// Writes a mesh as binary PLY, zstd-compressed when the name ends in `.zst` (atomically: an
/// interrupted write leaves the previous file). A failure is [`MeshErrorKind::Write`] (or
/// [`MeshErrorKind::IsDirectory`]), never a read error.
pub fn save_ply(mesh: &Mesh, path: &Path) -> Result<(), MeshError> {
    if path.is_dir() {
        return Err(MeshError::new(path, MeshErrorKind::IsDirectory));
    }
    let zst = path
        .to_string_lossy()
        .to_ascii_lowercase()
        .ends_with(".zst");
    crate::atomic::write_with(path, |file| {
        if zst {
            let mut enc = zstd::stream::Encoder::new(file, 3)?;
            ply::write_binary(&mesh.positions, &mesh.indices, &mut enc)?;
            enc.finish()?;
            Ok(())
        } else {
            ply::write_binary(&mesh.positions, &mesh.indices, file)
        }
    })
    .map_err(|e| MeshError::new(path, MeshErrorKind::Write(e)))
}

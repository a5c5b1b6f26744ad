//! Meshlets in meshoptimizer's layout as a numpy `.npz` (what `np.savez` writes, and what the
//! Python module's `save_npz` writes): `meshlets` (M x 4 integers: vertex offset, triangle
//! offset, vertex count, triangle count), `vertices` (global vertex indices) and `triangles`
//! (three local corners per triangle, bytes). Offsets may leave gaps (meshoptimizer pads each
//! meshlet's corners to 4 bytes); any integer dtype reads, compressed (`np.savez_compressed`) or
//! not. [`load_meshlets`] also takes the project's own meshlet file, told apart by its magic.

use super::io::{read_file, write_file, FileError, MeshletFile};
use super::npy::{read_integers, write};
use super::{validate, Limits, Meshlet, Meshlets};
use crate::mesh::Mesh;
use std::io::{Cursor, Read, Write};
use std::path::Path;

/// The `.npz` bytes of `ml` (stored, not compressed: numpy's `np.savez`).
pub fn to_npz(ml: &Meshlets) -> Vec<u8> {
    let rows: Vec<u32> = ml
        .meshlets()
        .iter()
        .flat_map(|m| {
            [
                m.vertex_offset,
                m.triangle_offset,
                m.vertex_count,
                m.triangle_count,
            ]
        })
        .collect();
    let arrays = [
        ("meshlets.npy", write(&[ml.len() as u64, 4], &rows)),
        (
            "vertices.npy",
            write(&[ml.vertices().len() as u64], ml.vertices()),
        ),
        (
            "triangles.npy",
            write(&[ml.triangles().len() as u64], ml.triangles()),
        ),
    ];
    let mut zip = zip::ZipWriter::new(Cursor::new(Vec::new()));
    let options = zip::write::SimpleFileOptions::default()
        .compression_method(zip::CompressionMethod::Stored)
        .large_file(true);
    for (name, bytes) in arrays {
        zip.start_file(name, options)
            .and_then(|()| Ok(zip.write_all(&bytes)?))
            .expect("writing to memory cannot fail");
    }
    zip.finish()
        .expect("writing to memory cannot fail")
        .into_inner()
}

/// Writes `ml` to `path` as an `.npz` (atomically).
pub fn save_npz(path: &Path, ml: &Meshlets) -> Result<(), FileError> {
    write_file(path, &to_npz(ml))
}

/// Reads meshlets for `mesh` from `path`: an `.npz` as above or the project's meshlet file
/// (whose source must be `mesh`). The result covers every triangle exactly once and keeps
/// within 256/256; the caller checks its own limits.
pub fn load_meshlets(path: &Path, mesh: &Mesh) -> Result<Meshlets, FileError> {
    meshlets_from_bytes(&read_file(path)?, path, mesh)
}

/// [`load_meshlets`] on bytes already read; `path` names the file in errors.
pub fn meshlets_from_bytes(bytes: &[u8], path: &Path, mesh: &Mesh) -> Result<Meshlets, FileError> {
    let err = |message: String| FileError {
        path: path.to_path_buf(),
        message,
    };
    let ml = if bytes.starts_with(b"MLTLAB01") {
        let f = MeshletFile::from_bytes(bytes, path)?;
        f.check(mesh, path)?;
        f.meshlets
    } else if bytes.starts_with(b"PK") {
        from_npz(bytes, mesh).map_err(err)?
    } else {
        return Err(err(
            "neither an .npz of meshlets nor a meshletlab meshlet file".into(),
        ));
    };
    validate(mesh, &ml, Limits::MAX).map_err(|e| err(format!("not the mesh's meshlets: {e}")))?;
    Ok(ml)
}

/// Parses `.npz` bytes against `mesh` (ranges, corners and vertex ids checked).
pub fn from_npz(bytes: &[u8], mesh: &Mesh) -> Result<Meshlets, String> {
    let mut zip =
        zip::ZipArchive::new(Cursor::new(bytes)).map_err(|e| format!("not an .npz: {e}"))?;
    // A valid collection has at most one meshlet per triangle and about three vertex entries
    // and three corner bytes per triangle; the bound leaves room for padding and caps what a
    // small compressed file can make us inflate.
    let t = mesh.triangle_count() as u64;
    let rows = read_entry(&mut zip, "meshlets", 4 * t)?;
    if rows.shape.len() != 2 || rows.shape[1] != 4 {
        return Err(format!("meshlets has shape {:?}, not (M, 4)", rows.shape));
    }
    let vertices = narrow(read_entry(&mut zip, "vertices", 16 * t + 1024)?, "vertices")?;
    let triangles = narrow(
        read_entry(&mut zip, "triangles", 16 * t + 1024)?,
        "triangles",
    )?;
    let rows: Vec<u32> = narrow(rows, "meshlets")?;
    let meshlets = rows
        .chunks_exact(4)
        .map(|r| Meshlet {
            vertex_offset: r[0],
            triangle_offset: r[1],
            vertex_count: r[2],
            triangle_count: r[3],
        })
        .collect();
    Meshlets::new(mesh, meshlets, vertices, triangles).map_err(|e| e.to_string())
}

/// One array of the archive (`NAME.npy`, or `NAME` as some writers name it), 1-D or, for
/// `meshlets`, 2-D, of at most `max_len` elements.
fn read_entry(
    zip: &mut zip::ZipArchive<Cursor<&[u8]>>,
    name: &str,
    max_len: u64,
) -> Result<super::npy::IntArray, String> {
    let file_name = [format!("{name}.npy"), name.to_string()]
        .into_iter()
        .find(|n| zip.index_for_name(n).is_some())
        .ok_or_else(|| {
            format!(
                "no array '{name}' (an .npz of meshlets holds meshlets, vertices and triangles)"
            )
        })?;
    let mut entry = zip
        .by_name(&file_name)
        .map_err(|e| format!("{name}: {e}"))?;
    // Header (at most 64 KiB in numpy's formats) plus eight bytes an element.
    let cap = max_len * 8 + 65_536;
    let mut bytes = Vec::new();
    (&mut entry)
        .take(cap + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| format!("{name}: cannot inflate: {e}"))?;
    if bytes.len() as u64 > cap {
        return Err(format!("{name}: larger than {max_len} elements"));
    }
    let a = read_integers(&bytes, max_len).map_err(|e| format!("{name}: {e}"))?;
    if a.shape.len() != 1 && name != "meshlets" {
        return Err(format!("{name} has shape {:?}, not one axis", a.shape));
    }
    Ok(a)
}

/// The values as `T` (u32 or u8), or the first one out of its range.
fn narrow<T: TryFrom<u64>>(a: super::npy::IntArray, name: &str) -> Result<Vec<T>, String> {
    a.values
        .iter()
        .enumerate()
        .map(|(i, &v)| {
            T::try_from(v).map_err(|_| {
                format!(
                    "{name}: element {i} ({v}) does not fit {}",
                    std::any::type_name::<T>()
                )
            })
        })
        .collect()
}

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
    let rows = ml.meshlet_rows();
    let arrays = [
        ("meshlets.npy", write(&[ml.len() as u64, 4], rows)),
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
    Meshlets::new(mesh, Meshlet::from_rows(&rows), vertices, triangles).map_err(|e| e.to_string())
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

#[cfg(test)]
mod tests {
    use super::super::npy::read_integers;
    use super::*;
    use crate::strategy::Strategy as _;

    /// A version-1 `.npy` of `data` (raw element bytes) under a hand-written header.
    fn npy(descr: &str, fortran: bool, shape: &str, data: &[u8]) -> Vec<u8> {
        let f = if fortran { "True" } else { "False" };
        let mut h = format!("{{'descr': '{descr}', 'fortran_order': {f}, 'shape': {shape}, }}");
        while (11 + h.len()) % 64 != 0 {
            h.push(' ');
        }
        h.push('\n');
        let mut out = b"\x93NUMPY\x01\x00".to_vec();
        out.extend_from_slice(&(h.len() as u16).to_le_bytes());
        out.extend_from_slice(h.as_bytes());
        out.extend_from_slice(data);
        out
    }

    #[test]
    fn every_integer_dtype_and_byte_order_reads_and_floats_do_not() {
        let want = [3u64, 0, 250];
        let cases: [(&str, Vec<u8>); 8] = [
            ("|u1", vec![3, 0, 250]),
            (
                "<u2",
                [3u16, 0, 250]
                    .iter()
                    .flat_map(|v| v.to_le_bytes())
                    .collect(),
            ),
            (
                ">u4",
                [3u32, 0, 250]
                    .iter()
                    .flat_map(|v| v.to_be_bytes())
                    .collect(),
            ),
            (
                "<u8",
                [3u64, 0, 250]
                    .iter()
                    .flat_map(|v| v.to_le_bytes())
                    .collect(),
            ),
            (
                "<i2",
                [3i16, 0, 250]
                    .iter()
                    .flat_map(|v| v.to_le_bytes())
                    .collect(),
            ),
            (
                ">i4",
                [3i32, 0, 250]
                    .iter()
                    .flat_map(|v| v.to_be_bytes())
                    .collect(),
            ),
            (
                "<i8",
                [3i64, 0, 250]
                    .iter()
                    .flat_map(|v| v.to_le_bytes())
                    .collect(),
            ),
            (
                ">i8",
                [3i64, 0, 250]
                    .iter()
                    .flat_map(|v| v.to_be_bytes())
                    .collect(),
            ),
        ];
        for (descr, data) in cases {
            let a = read_integers(&npy(descr, false, "(3,)", &data), 3).unwrap();
            assert_eq!((a.shape, a.values), (vec![3], want.to_vec()), "{descr}");
        }
        let neg = npy("|i1", false, "(3,)", &[1, 0xFF, 2]);
        let e = read_integers(&neg, 3).err().unwrap();
        assert!(e.contains("element 1 is negative (-1)"), "{e}");
        let float = npy("<f4", false, "(1,)", &1f32.to_le_bytes());
        assert!(read_integers(&float, 1)
            .err()
            .unwrap()
            .contains("not integers"));
        // Column-major 2 x 2 reads back row-major.
        let f = npy("|u1", true, "(2, 2)", &[1, 3, 2, 4]);
        assert_eq!(read_integers(&f, 4).unwrap().values, vec![1, 2, 3, 4]);
        // Lies about the size are refused before any allocation.
        let short = npy("<u4", false, "(1000,)", &[0; 8]);
        assert!(read_integers(&short, 1000)
            .err()
            .unwrap()
            .contains("bytes follow"));
        let huge = npy("<u4", false, "(4294967296, 4294967296)", &[]);
        assert!(read_integers(&huge, 1000)
            .err()
            .unwrap()
            .contains("larger than"));
    }

    #[test]
    fn npz_reads_what_numpy_writes_compressed_or_not_and_refuses_broken_archives() {
        let m = crate::mesh::generate::noisy_sphere(2, 0.1, 1);
        let ml = crate::strategy::Meshopt { cone_weight: 0.0 }.build(&m, Limits::DEFAULT);
        assert_eq!(from_npz(&to_npz(&ml), &m).unwrap(), ml);
        // np.savez_compressed: deflated members; and int64 arrays, as numpy makes by default.
        let wide = |v: &[u64]| {
            v.iter()
                .flat_map(|x| (*x as i64).to_le_bytes())
                .collect::<Vec<_>>()
        };
        let rows: Vec<u64> = ml
            .meshlets()
            .iter()
            .flat_map(|x| {
                [
                    x.vertex_offset,
                    x.triangle_offset,
                    x.vertex_count,
                    x.triangle_count,
                ]
            })
            .map(u64::from)
            .collect();
        let verts: Vec<u64> = ml.vertices().iter().map(|&v| v as u64).collect();
        let tris: Vec<u64> = ml.triangles().iter().map(|&v| v as u64).collect();
        let members = [
            (
                "meshlets.npy",
                npy("<i8", false, &format!("({}, 4)", ml.len()), &wide(&rows)),
            ),
            (
                "vertices.npy",
                npy("<i8", false, &format!("({},)", verts.len()), &wide(&verts)),
            ),
            (
                "triangles.npy",
                npy("<i8", false, &format!("({},)", tris.len()), &wide(&tris)),
            ),
        ];
        let archive = |members: &[(&str, Vec<u8>)]| {
            let mut z = zip::ZipWriter::new(Cursor::new(Vec::new()));
            let o = zip::write::SimpleFileOptions::default()
                .compression_method(zip::CompressionMethod::Deflated);
            for (name, bytes) in members {
                z.start_file(*name, o).unwrap();
                z.write_all(bytes).unwrap();
            }
            z.finish().unwrap().into_inner()
        };
        assert_eq!(from_npz(&archive(&members), &m).unwrap(), ml);
        // A missing array, a wrong shape, a corner over 255, a range past the end.
        let e = from_npz(&archive(&members[..2]), &m).unwrap_err();
        assert!(e.contains("no array 'triangles'"), "{e}");
        let mut flat = members.clone();
        flat[0].1 = npy("<i8", false, &format!("({},)", rows.len()), &wide(&rows));
        assert!(from_npz(&archive(&flat), &m)
            .unwrap_err()
            .contains("not (M, 4)"));
        let mut big = members.clone();
        let mut t = tris.clone();
        t[0] = 300;
        big[2].1 = npy("<i8", false, &format!("({},)", t.len()), &wide(&t));
        assert!(from_npz(&archive(&big), &m)
            .unwrap_err()
            .contains("(300) does not fit u8"));
        let mut past = members.clone();
        let mut r = rows.clone();
        r[1] = 1 << 30;
        past[0].1 = npy("<i8", false, &format!("({}, 4)", ml.len()), &wide(&r));
        let e = from_npz(&archive(&past), &m).unwrap_err();
        assert!(e.contains("meshlet 0"), "{e}");
        let cut = to_npz(&ml);
        assert!(from_npz(&cut[..cut.len() / 2], &m)
            .unwrap_err()
            .contains("not an .npz"));
    }
}

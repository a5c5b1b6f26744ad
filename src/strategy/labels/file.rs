//! Label files: one cluster id per triangle, in the order the mesh loads (PLY and STL: file
//! order; OBJ: faces in file order, polygons fanned; glTF: primitives in node order, each
//! primitive's triangles in index order). Two forms, told apart by content:
//! - text: one non-negative integer per line (trailing blank lines allowed);
//! - numpy `.npy`: a 1-D array (or one column) of any integer dtype.
//!
//! The length is checked against the mesh before the ids are kept, and every error names the file.

use crate::meshlet::io::{read_file, write_file, FileError};
use crate::meshlet::npy;
use std::path::Path;

/// Reads the cluster ids of a mesh of `triangles` triangles from `path`.
pub fn read_labels(path: &Path, triangles: usize) -> Result<Vec<u64>, FileError> {
    let bytes = read_file(path)?;
    parse_labels(&bytes, triangles).map_err(|message| FileError {
        path: path.to_path_buf(),
        message,
    })
}

/// [`read_labels`] on bytes already read.
pub fn parse_labels(bytes: &[u8], triangles: usize) -> Result<Vec<u64>, String> {
    let labels = if bytes.starts_with(b"\x93NUMPY") {
        let a = npy::read_integers(bytes, triangles as u64)?;
        let column = a.shape.len() == 2 && a.shape[1] == 1;
        if a.shape.len() != 1 && !column {
            return Err(format!(
                "array of shape {:?}: cluster ids are one axis (one id per triangle)",
                a.shape
            ));
        }
        a.values
    } else {
        parse_text(bytes, triangles)?
    };
    if labels.len() != triangles {
        let found = match labels.len() > triangles {
            true => format!("more than {triangles}"),
            false => labels.len().to_string(),
        };
        return Err(format!(
            "{found} cluster ids for a mesh of {triangles} triangles (one id per triangle, in the order the mesh loads)"
        ));
    }
    Ok(labels)
}

/// Text labels: a line each; stops at the first line past `triangles`.
fn parse_text(bytes: &[u8], triangles: usize) -> Result<Vec<u64>, String> {
    let text = std::str::from_utf8(bytes).map_err(|e| {
        format!(
            "neither a .npy array nor text (not UTF-8 at byte {})",
            e.valid_up_to()
        )
    })?;
    let body = text.trim_end();
    let mut labels = Vec::new();
    if body.is_empty() {
        return Ok(labels);
    }
    for (i, line) in body.lines().enumerate() {
        if labels.len() == triangles {
            labels.push(0);
            break;
        }
        let s = line.trim();
        let id = s.parse::<u64>().map_err(|_| match s.strip_prefix('-') {
            Some(rest) if rest.parse::<u64>().is_ok() => {
                format!("line {}: negative cluster id {s}", i + 1)
            }
            _ if s.is_empty() => format!("line {}: empty (one cluster id per line)", i + 1),
            _ => format!(
                "line {}: '{}' is not a cluster id (a non-negative integer)",
                i + 1,
                s.chars().take(40).collect::<String>()
            ),
        })?;
        labels.push(id);
    }
    Ok(labels)
}

/// Writes per-triangle cluster ids to `path`: `.npy` (u32) when the name ends so, text otherwise.
pub fn write_labels(path: &Path, labels: &[u32]) -> Result<(), FileError> {
    let npy = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("npy"));
    let bytes = if npy {
        npy::write(&[labels.len() as u64], labels)
    } else {
        let mut s = String::with_capacity(labels.len() * 5);
        for l in labels {
            s.push_str(&l.to_string());
            s.push('\n');
        }
        s.into_bytes()
    };
    write_file(path, &bytes)
}

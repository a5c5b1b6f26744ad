//! Typed errors for mesh files, read or written. Every error names the file it is about.

use std::path::PathBuf;
use thiserror::Error;

/// An error reading or validating a mesh; `Display` is one readable line that starts with the file name.
#[derive(Debug, Error)]
#[error("{}: {kind}", path.display())]
pub struct MeshError {
    /// The file the error is about (or a label such as `<generated>` for in-memory meshes).
    pub path: PathBuf,
    /// What went wrong, with the line or element where it applies.
    pub kind: MeshErrorKind,
}

/// What went wrong while reading or validating a mesh.
#[derive(Debug, Error)]
pub enum MeshErrorKind {
    /// The file could not be opened or read.
    #[error("cannot read file: {0}")]
    Io(#[from] std::io::Error),
    /// The path names a directory, not a mesh file.
    #[error("is a directory")]
    IsDirectory,
    /// The file could not be written (the folder is missing or read-only, the disk is full, ...).
    #[error("cannot write: {0}")]
    Write(std::io::Error),
    /// The file extension names no supported format.
    #[error(
        "unknown mesh format (expected .ply, .obj, .stl, .gltf or .glb, optionally with .zst)"
    )]
    UnknownFormat,
    /// A `gen:NAME` path whose name is not a generated mesh; holds the names there are.
    #[error("no generated mesh of that name (there are: {0})")]
    UnknownGenerated(String),
    /// The zstd stream is corrupt or truncated.
    #[error("zstd decompression failed: {0}")]
    Decompress(String),
    /// The syntax of the file is wrong at a known place.
    #[error("{location}: {message}")]
    Parse {
        /// Where: "line 12", "face 40", "header line 3", ...
        location: String,
        /// What is wrong there.
        message: String,
    },
    /// The file ends before the data its header announces.
    #[error("file is truncated: {0}")]
    Truncated(String),
    /// The body holds more (or other) data than the header announces.
    #[error("header and body disagree: {0}")]
    CountMismatch(String),
    /// A valid but unsupported feature (property type, primitive mode, ...).
    #[error("unsupported: {0}")]
    Unsupported(String),
    /// The file requires a glTF extension this reader does not apply (named in
    /// `extensionsRequired`, or found where reading on without it would give wrong geometry).
    #[error("requires glTF extension {name}, which meshletlab does not read{hint}")]
    UnsupportedExtension {
        /// The extension's name, as the file spells it.
        name: String,
        /// What to do about it (empty, or text starting with "; ").
        hint: String,
    },
    /// A vertex coordinate is NaN or infinite.
    #[error("vertex {vertex} has a non-finite coordinate ({value})")]
    NonFinite {
        /// Vertex number (0-based, in file order).
        vertex: usize,
        /// The offending value as text.
        value: String,
    },
    /// A triangle references a vertex that does not exist.
    #[error(
        "triangle {triangle} references vertex {index}, but there are only {vertex_count} vertices"
    )]
    IndexOutOfRange {
        /// Triangle number (0-based, after triangulation).
        triangle: usize,
        /// The offending index.
        index: i64,
        /// Number of vertices in the mesh.
        vertex_count: usize,
    },
    /// The mesh has no triangles (or no vertices).
    #[error("mesh is empty: {0}")]
    Empty(String),
    /// The mesh is larger than this tool supports (u32 indices).
    #[error("mesh too large: {0}")]
    TooLarge(String),
}

impl MeshError {
    /// Creates an error for `path`.
    pub fn new(path: impl Into<PathBuf>, kind: MeshErrorKind) -> Self {
        Self {
            path: path.into(),
            kind,
        }
    }
}

/// Shorthand for a parse error at a location.
#[cfg(feature = "io")]
pub(crate) fn parse_err(location: impl Into<String>, message: impl Into<String>) -> MeshErrorKind {
    MeshErrorKind::Parse {
        location: location.into(),
        message: message.into(),
    }
}

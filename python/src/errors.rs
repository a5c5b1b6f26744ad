//! The module's errors: one Rust value per Python exception class. The classes live in
//! `meshletlab/_errors.py`, where each also derives from the built-in a caller would catch
//! (`ValueError`, `OSError`, ...), which `create_exception!` cannot express.

use pyo3::prelude::*;
use pyo3::types::PyType;

/// Which `meshletlab` exception class to raise.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// `MeshError`: arrays or a file that make no valid mesh.
    Mesh,
    /// `LimitsError`: limits outside 3..=256 vertices, 1..=256 triangles.
    Limits,
    /// `StrategyError`: a name that no strategy (or no GPU strategy) answers to.
    Strategy,
    /// `OptionError`: an unknown keyword, or a value of the wrong type or range.
    Option,
    /// `ValidationError`: meshlets that are not a valid partition of the mesh.
    Validation,
    /// `LabelsError`: cluster ids that make no meshlets.
    Labels,
    /// `FileError`: a meshlet, LOD, label or output file that cannot be read or written.
    File,
    /// `CompressError`: meshlets a codec cannot encode, or a bad tolerance.
    Compress,
    /// `GpuError`: no adapter, a device fault, or a module built without the `gpu` feature.
    Gpu,
}

impl Kind {
    fn class(self) -> &'static str {
        match self {
            Kind::Mesh => "MeshError",
            Kind::Limits => "LimitsError",
            Kind::Strategy => "StrategyError",
            Kind::Option => "OptionError",
            Kind::Validation => "ValidationError",
            Kind::Labels => "LabelsError",
            Kind::File => "FileError",
            Kind::Compress => "CompressError",
            Kind::Gpu => "GpuError",
        }
    }
}

/// An error of the module: its class and message. Built without the GIL (inside a build),
/// raised as a Python exception when it crosses back.
#[derive(Debug)]
pub struct Fail {
    /// The class.
    pub kind: Kind,
    /// The message (the crate's `Display` where the crate refused).
    pub message: String,
}

/// Shorthand for a [`Fail`].
pub fn fail(kind: Kind, message: impl Into<String>) -> Fail {
    Fail {
        kind,
        message: message.into(),
    }
}

/// A crate error as a [`Fail`] of `kind`, its message the crate's.
pub fn crate_error(kind: Kind) -> impl Fn(&dyn std::fmt::Display) -> Fail {
    move |e| fail(kind, e.to_string())
}

impl From<Fail> for PyErr {
    fn from(f: Fail) -> PyErr {
        Python::attach(|py| {
            let class = py
                .import("meshletlab._errors")
                .and_then(|m| m.getattr(f.kind.class()))
                .and_then(|c| Ok(c.cast_into::<PyType>()?));
            match class {
                Ok(class) => PyErr::from_type(class, f.message),
                // The package is installed with the extension; without it, still say what failed.
                Err(e) => pyo3::exceptions::PyRuntimeError::new_err(format!(
                    "{} (and meshletlab._errors could not be imported: {e})",
                    f.message
                )),
            }
        })
    }
}

/// A result whose error is a [`Fail`].
pub type Result<T> = std::result::Result<T, Fail>;

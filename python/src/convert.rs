//! numpy arrays in, Rust vectors out: one pass over each array in its logical (C) order, whatever
//! its strides, with the dtype and every value checked before the crate sees it.

use crate::errors::{fail, Kind, Result};
use numpy::{PyArrayDyn, PyArrayMethods, PyUntypedArray, PyUntypedArrayMethods};
use pyo3::prelude::*;

/// `obj` as an ndarray: itself, or `numpy.asarray(obj)` for a list or any other array-like.
pub fn ndarray<'py>(obj: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyUntypedArray>> {
    if let Ok(a) = obj.cast::<PyUntypedArray>() {
        return Ok(a.clone());
    }
    let a = obj.py().import("numpy")?.call_method1("asarray", (obj,))?;
    Ok(a.cast_into::<PyUntypedArray>()?)
}

/// The dtype's name, for messages.
fn dtype_name(a: &Bound<'_, PyUntypedArray>) -> String {
    a.dtype()
        .str()
        .map(|s| s.to_string())
        .unwrap_or_else(|_| "?".into())
}

/// Vertex positions from an (n, 3) float32 or float64 array; float64 is rounded to float32 (a
/// value past f32's range becomes infinite, which the mesh's own check then refuses).
pub fn positions(a: &Bound<'_, PyUntypedArray>, label: &str) -> Result<Vec<[f32; 3]>> {
    if a.ndim() != 2 || a.shape()[1] != 3 {
        return Err(fail(
            Kind::Mesh,
            format!(
                "{label}: positions must have shape (n, 3), not {:?}",
                a.shape()
            ),
        ));
    }
    macro_rules! rows {
        ($t:ty) => {
            if let Ok(t) = a.cast::<PyArrayDyn<$t>>() {
                let view = t
                    .try_readonly()
                    .map_err(|e| fail(Kind::Mesh, format!("{label}: positions: {e}")))?;
                let view = view.as_array();
                let flat: Vec<f32> = view.iter().map(|&x| x as f32).collect();
                return Ok(flat.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect());
            }
        };
    }
    rows!(f32);
    rows!(f64);
    Err(fail(
        Kind::Mesh,
        format!(
            "{label}: positions must be float32 or float64, not {}",
            dtype_name(a)
        ),
    ))
}

/// Every value of an integer array (any of numpy's eight integer dtypes), in C order, through
/// `each(position, value)`, which checks and converts it. `what` names the array in messages.
pub fn integers<R>(
    a: &Bound<'_, PyUntypedArray>,
    what: &str,
    kind: Kind,
    mut each: impl FnMut(usize, i128) -> Result<R>,
) -> Result<Vec<R>> {
    macro_rules! values {
        ($($t:ty),*) => {$(
            if let Ok(t) = a.cast::<PyArrayDyn<$t>>() {
                let view = t
                    .try_readonly()
                    .map_err(|e| fail(kind, format!("{what}: {e}")))?;
                let view = view.as_array();
                let mut out = Vec::with_capacity(view.len());
                for (i, &v) in view.iter().enumerate() {
                    out.push(each(i, i128::from(v))?);
                }
                return Ok(out);
            }
        )*};
    }
    values!(i8, i16, i32, i64, u8, u16, u32, u64);
    Err(fail(
        kind,
        format!("{what} must be an integer array, not {}", dtype_name(a)),
    ))
}

/// Triangle indices from an (m, 3) or flat integer array: each in 0..2^32.
pub fn indices(a: &Bound<'_, PyUntypedArray>, label: &str) -> Result<Vec<u32>> {
    let shape = a.shape();
    let ok = match shape {
        [n] => n % 3 == 0,
        [_, 3] => true,
        _ => false,
    };
    if !ok {
        return Err(fail(
            Kind::Mesh,
            format!(
                "{label}: indices must have shape (m, 3), or (3m,) flat, not {:?}",
                shape
            ),
        ));
    }
    integers(a, &format!("{label}: indices"), Kind::Mesh, |i, v| {
        u32::try_from(v).map_err(|_| {
            fail(
                Kind::Mesh,
                format!(
                    "{label}: index {v} (triangle {}, corner {}) is not a vertex index (0 to 2^32 - 1)",
                    i / 3,
                    i % 3
                ),
            )
        })
    })
}

/// Cluster ids, one per triangle: a 1-D (or one-column) integer array of non-negative values.
pub fn labels(a: &Bound<'_, PyUntypedArray>) -> Result<Vec<u64>> {
    let shape = a.shape();
    if !matches!(shape, [_] | [_, 1]) {
        return Err(fail(
            Kind::Labels,
            format!(
                "labels must be one axis (one cluster id per triangle), not of shape {:?}",
                shape
            ),
        ));
    }
    integers(a, "labels", Kind::Labels, |i, v| {
        u64::try_from(v).map_err(|_| {
            fail(
                Kind::Labels,
                format!("labels[{i}] = {v}: cluster ids are non-negative integers"),
            )
        })
    })
}

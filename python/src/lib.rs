//! `meshletlab._meshletlab`: the crate's core for Python, over numpy arrays. The pure-Python
//! package `meshletlab` (python/meshletlab/) re-exports it, adds the `lod` namespace and defines
//! the exception classes (`_errors.py`).
//!
//! Every long call (loading, building, clustering from labels, validating, measuring, LOD,
//! compression) runs with the GIL released. Every error is a `meshletlab.Error` subclass whose
//! message is the crate's.

mod classes;
mod convert;
mod errors;
mod extra;
mod options;

use classes::{limits, PyMesh, PyMeshlets};
use errors::{crate_error, fail, Kind};
use meshletlab::mesh::Mesh;
use meshletlab::meshlet::bounds::compute_bounds;
use meshletlab::meshlet::{Limits, Meshlets, Metrics};
use numpy::{PyArray1, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyList, PyString};
use std::path::PathBuf;
use std::time::Instant;

/// Loads a mesh file (PLY, OBJ, STL, glTF/GLB, optionally `.zst`), or generates `gen:NAME`.
#[pyfunction]
fn load(py: Python<'_>, path: PathBuf) -> PyResult<PyMesh> {
    let mesh = py
        .detach(|| meshletlab::mesh::load(&path))
        .map_err(|e| crate_error(Kind::Mesh)(&e))?;
    Ok(PyMesh {
        mesh,
        name: path.display().to_string(),
    })
}

/// Builds meshlets with strategy `strategy` within `limits`; `options` are the command line's
/// strategy options (`cone_weight=0.25`, `local_order=True`, ...). `device="gpu"` runs a GPU
/// strategy's kernels (a module built with the `gpu` feature).
#[pyfunction]
#[pyo3(signature = (mesh, strategy = "kmedoids", limits = None, device = "cpu", **options))]
fn build(
    py: Python<'_>,
    mesh: &Bound<'_, PyMesh>,
    strategy: &str,
    limits: Option<&Bound<'_, PyAny>>,
    device: &str,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<PyMeshlets> {
    let limits = self::limits(limits)?;
    let opts = options::parse("build", options)?;
    let m = &mesh.get().mesh;
    let (ml, ms) = match device {
        "cpu" => {
            let s = meshletlab::strategy::by_name(strategy, &opts)
                .map_err(|e| crate_error(Kind::Strategy)(&e))?;
            py.detach(|| {
                let t0 = Instant::now();
                let ml = s.build(m, limits);
                (ml, t0.elapsed().as_secs_f64() * 1e3)
            })
        }
        "gpu" => py.detach(|| extra::gpu_build(m, strategy, limits, &opts))?,
        _ => {
            return Err(fail(
                Kind::Option,
                format!("device must be 'cpu' or 'gpu', not '{device}'"),
            )
            .into())
        }
    };
    Ok(PyMeshlets {
        meshlets: ml,
        limits,
        mesh: mesh.clone().unbind(),
        source: strategy.to_string(),
        build_ms: Some(ms),
        clusters: None,
    })
}

/// Meshlets from a clustering made elsewhere: `labels[t]` is triangle `t`'s cluster id (any
/// non-negative integers, gaps allowed). A cluster over `limits` is a `LabelsError`, or with
/// `split=True` is divided by meshoptimizer (as the command line's `--split`).
#[pyfunction]
#[pyo3(signature = (mesh, labels, split = false, limits = None))]
fn from_labels(
    py: Python<'_>,
    mesh: &Bound<'_, PyMesh>,
    labels: &Bound<'_, PyAny>,
    split: bool,
    limits: Option<&Bound<'_, PyAny>>,
) -> PyResult<PyMeshlets> {
    let limits = self::limits(limits)?;
    let labels = convert::labels(&convert::ndarray(labels)?)?;
    let m = &mesh.get().mesh;
    let c = py
        .detach(|| meshletlab::strategy::labels::from_labels(m, &labels, limits, split))
        .map_err(|e| crate_error(Kind::Labels)(&e))?;
    Ok(PyMeshlets {
        meshlets: c.meshlets,
        limits,
        mesh: mesh.clone().unbind(),
        source: "labels".into(),
        build_ms: None,
        clusters: Some((c.clusters, c.split)),
    })
}

/// Reads a label file for `mesh` (text, one id per line, or `.npy`) as a uint64 array.
#[pyfunction]
fn read_labels<'py>(
    py: Python<'py>,
    path: PathBuf,
    mesh: &Bound<'py, PyMesh>,
) -> PyResult<Bound<'py, PyArray1<u64>>> {
    let t = mesh.get().mesh.triangle_count();
    let labels = py
        .detach(|| meshletlab::strategy::labels::file::read_labels(&path, t))
        .map_err(|e| crate_error(Kind::File)(&e))?;
    Ok(PyArray1::from_vec(py, labels))
}

/// Writes cluster ids (values below 2^32) to `path`: `.npy` when the name ends so, else text.
#[pyfunction]
fn write_labels(py: Python<'_>, path: PathBuf, labels: &Bound<'_, PyAny>) -> PyResult<()> {
    let a = convert::ndarray(labels)?;
    let ids = convert::integers(&a, "labels", Kind::Labels, |i, v| {
        u32::try_from(v).map_err(|_| {
            fail(
                Kind::Labels,
                format!("labels[{i}] = {v}: a label file holds ids in 0..2^32"),
            )
        })
    })?;
    py.detach(|| meshletlab::strategy::labels::file::write_labels(&path, &ids))
        .map_err(|e| crate_error(Kind::File)(&e).into())
}

/// Reads meshlets of `mesh` from an `.npz` (the layout `save_npz` writes) or a meshlet file
/// written by `meshletlab build`.
#[pyfunction]
#[pyo3(signature = (path, mesh, limits = None))]
fn load_meshlets(
    py: Python<'_>,
    path: PathBuf,
    mesh: &Bound<'_, PyMesh>,
    limits: Option<&Bound<'_, PyAny>>,
) -> PyResult<PyMeshlets> {
    let limits = self::limits(limits)?;
    let m = &mesh.get().mesh;
    let ml = py
        .detach(|| meshletlab::meshlet::npz::load_meshlets(&path, m))
        .map_err(|e| crate_error(Kind::File)(&e))?;
    Ok(PyMeshlets {
        meshlets: ml,
        limits,
        mesh: mesh.clone().unbind(),
        source: path.display().to_string(),
        build_ms: None,
        clusters: None,
    })
}

/// Raises `ValidationError` with the first rule `meshlets` break as a partition of `mesh`
/// within their limits (or `limits`, when given).
#[pyfunction]
#[pyo3(signature = (mesh, meshlets, limits = None))]
fn validate(
    py: Python<'_>,
    mesh: &Bound<'_, PyMesh>,
    meshlets: &Bound<'_, PyMeshlets>,
    limits: Option<&Bound<'_, PyAny>>,
) -> PyResult<()> {
    let ml = meshlets.get();
    let l = match limits {
        Some(_) => self::limits(limits)?,
        None => ml.limits,
    };
    let m = &mesh.get().mesh;
    py.detach(|| meshletlab::meshlet::validate(m, &ml.meshlets, l))
        .map_err(|e| crate_error(Kind::Validation)(&e).into())
}

/// The mesh and the meshlets after the check every measuring function makes first.
fn checked<'a>(
    mesh: &'a Bound<'_, PyMesh>,
    meshlets: &'a Bound<'_, PyMeshlets>,
) -> errors::Result<(&'a Mesh, &'a Meshlets, Limits)> {
    let m = &mesh.get().mesh;
    let ml = meshlets.get();
    Ok((m, ml.checked(m)?, ml.limits))
}

/// A JSON value as Python objects (for the metrics and sizes the crate serialises).
fn to_py<'py>(py: Python<'py>, v: &serde_json::Value) -> PyResult<Bound<'py, PyAny>> {
    use serde_json::Value as V;
    Ok(match v {
        V::Null => py.None().into_bound(py),
        V::Bool(b) => PyBool::new(py, *b).to_owned().into_any(),
        V::Number(n) => match (n.as_u64(), n.as_i64()) {
            (Some(u), _) => u.into_pyobject(py)?.into_any(),
            (None, Some(i)) => i.into_pyobject(py)?.into_any(),
            _ => n.as_f64().unwrap_or(f64::NAN).into_pyobject(py)?.into_any(),
        },
        V::String(s) => PyString::new(py, s).into_any(),
        V::Array(a) => {
            let items = a
                .iter()
                .map(|x| to_py(py, x))
                .collect::<PyResult<Vec<_>>>()?;
            PyList::new(py, items)?.into_any()
        }
        V::Object(o) => {
            let d = PyDict::new(py);
            for (k, x) in o {
                d.set_item(k, to_py(py, x)?)?;
            }
            d.into_any()
        }
    })
}

/// Any serialisable value of the crate as Python objects.
fn serialised<'py>(py: Python<'py>, v: &impl serde::Serialize) -> PyResult<Bound<'py, PyAny>> {
    let json = serde_json::to_value(v)
        .map_err(|e| pyo3::exceptions::PyRuntimeError::new_err(e.to_string()))?;
    to_py(py, &json)
}

/// The quality metrics of `meshlets`, as `meshletlab stats --json` reports each strategy's:
/// `meshlets`, mean vertices and triangles, fills, histograms, sphere radius, flatness, cone
/// culling, duplication, connectivity and `build_ms` (None unless built by `build`).
#[pyfunction]
fn metrics<'py>(
    py: Python<'py>,
    mesh: &Bound<'py, PyMesh>,
    meshlets: &Bound<'py, PyMeshlets>,
) -> PyResult<Bound<'py, PyAny>> {
    let (m, ml, limits) = checked(mesh, meshlets)?;
    let built = meshlets
        .get()
        .build_ms
        .map(|ms| std::time::Duration::from_secs_f64(ms / 1e3));
    let metrics = py.detach(|| {
        let bounds = compute_bounds(m, ml);
        Metrics::compute(m, ml, limits, &bounds, built)
    });
    serialised(py, &metrics)
}

/// Culling bounds per meshlet: a dict of arrays `center` (M, 3), `radius` (M,) of the bounding
/// spheres and `cone_apex` (M, 3), `cone_axis` (M, 3), `cone_cutoff` (M,) of the normal cones
/// (a cutoff of 1 never culls).
#[pyfunction]
fn bounds<'py>(
    py: Python<'py>,
    mesh: &Bound<'py, PyMesh>,
    meshlets: &Bound<'py, PyMeshlets>,
) -> PyResult<Bound<'py, PyDict>> {
    let (m, ml, _) = checked(mesh, meshlets)?;
    let b = py.detach(|| compute_bounds(m, ml));
    let n = b.len();
    let d = PyDict::new(py);
    let vec3 = |f: &dyn Fn(&meshletlab::meshlet::MeshletBounds) -> [f32; 3]| {
        let flat: Vec<f32> = b.iter().flat_map(f).collect();
        PyArray1::from_vec(py, flat).reshape([n, 3])
    };
    let scalar = |f: &dyn Fn(&meshletlab::meshlet::MeshletBounds) -> f32| {
        PyArray1::from_vec(py, b.iter().map(f).collect())
    };
    d.set_item("center", vec3(&|x| x.sphere.center)?)?;
    d.set_item("radius", scalar(&|x| x.sphere.radius))?;
    d.set_item("cone_apex", vec3(&|x| x.cone.apex)?)?;
    d.set_item("cone_axis", vec3(&|x| x.cone.axis)?)?;
    d.set_item("cone_cutoff", scalar(&|x| x.cone.cutoff))?;
    Ok(d)
}

/// The meshlets as a binary glTF with one flat colour per meshlet: written to `path` when given
/// (atomically), else returned as bytes.
#[pyfunction]
#[pyo3(signature = (mesh, meshlets, path = None))]
fn export_glb<'py>(
    py: Python<'py>,
    mesh: &Bound<'py, PyMesh>,
    meshlets: &Bound<'py, PyMeshlets>,
    path: Option<PathBuf>,
) -> PyResult<Option<Bound<'py, pyo3::types::PyBytes>>> {
    let (m, ml, _) = checked(mesh, meshlets)?;
    let bytes = py.detach(|| meshletlab::meshlet::export::glb(m, ml));
    match path {
        None => Ok(Some(pyo3::types::PyBytes::new(py, &bytes))),
        Some(p) => {
            py.detach(|| meshletlab::atomic::write(&p, &bytes))
                .map_err(|e| fail(Kind::File, format!("{}: cannot write: {e}", p.display())))?;
            Ok(None)
        }
    }
}

/// Every strategy name `build` takes (each also with `+refine`, `+refine-fast`, `+refine-max`
/// or `+partition`).
#[pyfunction]
fn strategies() -> Vec<&'static str> {
    meshletlab::strategy::NAMES.to_vec()
}

/// The module: its classes, functions and build facts.
#[pymodule]
fn _meshletlab(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyMesh>()?;
    m.add_class::<PyMeshlets>()?;
    m.add_class::<extra::PyCompressed>()?;
    m.add_class::<extra::PyLod>()?;
    m.add_class::<extra::PyLodLevel>()?;
    m.add_function(wrap_pyfunction!(load, m)?)?;
    m.add_function(wrap_pyfunction!(build, m)?)?;
    m.add_function(wrap_pyfunction!(from_labels, m)?)?;
    m.add_function(wrap_pyfunction!(read_labels, m)?)?;
    m.add_function(wrap_pyfunction!(write_labels, m)?)?;
    m.add_function(wrap_pyfunction!(load_meshlets, m)?)?;
    m.add_function(wrap_pyfunction!(validate, m)?)?;
    m.add_function(wrap_pyfunction!(metrics, m)?)?;
    m.add_function(wrap_pyfunction!(bounds, m)?)?;
    m.add_function(wrap_pyfunction!(export_glb, m)?)?;
    m.add_function(wrap_pyfunction!(strategies, m)?)?;
    m.add_function(wrap_pyfunction!(extra::compress, m)?)?;
    m.add_function(wrap_pyfunction!(extra::lod_build, m)?)?;
    m.add_function(wrap_pyfunction!(extra::gpu_strategies, m)?)?;
    m.add("GPU", cfg!(feature = "gpu"))?;
    m.add("STRATEGY_OPTIONS", options::NAMES.to_vec())?;
    Ok(())
}

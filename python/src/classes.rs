//! The two objects every call passes around: `Mesh` (the crate's checked mesh, copied in once)
//! and `Meshlets` (the crate's meshlets with the limits they were made for and their mesh).

use crate::convert;
use crate::errors::{crate_error, fail, Kind, Result};
use meshletlab::mesh::Mesh;
use meshletlab::meshlet::{validate, Limits, Meshlet, Meshlets};
use numpy::{PyArray1, PyArray2, PyArrayMethods};
use pyo3::prelude::*;
use std::path::PathBuf;

/// A triangle mesh: positions (n, 3) and triangles (m, 3), checked on construction (finite
/// positions, indices in range, at least one triangle).
#[pyclass(frozen, name = "Mesh", module = "meshletlab")]
pub struct PyMesh {
    /// The mesh.
    pub mesh: Mesh,
    /// What errors call it: the file, or the name given.
    pub name: String,
}

#[pymethods]
impl PyMesh {
    /// A mesh from numpy arrays: `positions` (n, 3) float32 or float64, `indices` (m, 3) or flat,
    /// any integer dtype. The arrays are copied once, into the mesh.
    #[new]
    #[pyo3(signature = (positions, indices, name = "<arrays>"))]
    fn new(
        py: Python<'_>,
        positions: &Bound<'_, PyAny>,
        indices: &Bound<'_, PyAny>,
        name: &str,
    ) -> PyResult<Self> {
        let p = convert::positions(&convert::ndarray(positions)?, name)?;
        let i = convert::indices(&convert::ndarray(indices)?, name)?;
        let mesh = py
            .detach(|| Mesh::new(p, i, name.as_ref()))
            .map_err(|e| crate_error(Kind::Mesh)(&e))?;
        Ok(PyMesh {
            mesh,
            name: name.to_string(),
        })
    }

    /// Vertex positions, (n, 3) float32 (a copy).
    #[getter]
    fn positions<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f32>>> {
        let flat = self.mesh.positions().as_flattened();
        PyArray1::from_slice(py, flat).reshape([self.mesh.vertex_count(), 3])
    }

    /// Triangles, (m, 3) uint32 (a copy).
    #[getter]
    fn indices<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<u32>>> {
        PyArray1::from_slice(py, self.mesh.indices()).reshape([self.mesh.triangle_count(), 3])
    }

    /// Number of vertices.
    #[getter]
    fn vertex_count(&self) -> usize {
        self.mesh.vertex_count()
    }

    /// Number of triangles.
    #[getter]
    fn triangle_count(&self) -> usize {
        self.mesh.triangle_count()
    }

    /// The file it was loaded from, or the name it was given.
    #[getter]
    fn name(&self) -> &str {
        &self.name
    }

    fn __repr__(&self) -> String {
        format!(
            "Mesh('{}', {} vertices, {} triangles)",
            self.name,
            self.mesh.vertex_count(),
            self.mesh.triangle_count()
        )
    }
}

/// Meshlets of a mesh in meshoptimizer's layout, with the limits they were made for.
#[pyclass(frozen, name = "Meshlets", module = "meshletlab")]
pub struct PyMeshlets {
    /// The meshlets.
    pub meshlets: Meshlets,
    /// The limits they were made for (the metrics' histograms and `validate` use them).
    pub limits: Limits,
    /// Their mesh.
    pub mesh: Py<PyMesh>,
    /// What made them: a strategy name, `labels`, or a file.
    pub source: String,
    /// Build wall time in ms, when they were built here.
    pub build_ms: Option<f64>,
    /// From labels: distinct cluster ids, and clusters divided by meshopt.
    pub clusters: Option<(usize, usize)>,
}

impl PyMeshlets {
    /// Checks that these meshlets are a valid partition of `mesh` within their limits: every
    /// function that reads them with a mesh calls it first, so another mesh's meshlets are a
    /// `ValidationError`, never an index out of range.
    pub fn checked(&self, mesh: &Mesh) -> Result<&Meshlets> {
        validate(mesh, &self.meshlets, self.limits).map_err(|e| {
            fail(
                Kind::Validation,
                format!("meshlets of {} for this mesh: {e}", self.source),
            )
        })?;
        Ok(&self.meshlets)
    }
}

/// `limits` as the crate's: a (vertices, triangles) pair or `"V/T"` text; `None` is 64/126.
pub fn limits(v: Option<&Bound<'_, PyAny>>) -> Result<Limits> {
    let Some(v) = v else {
        return Ok(Limits::DEFAULT);
    };
    if let Ok(s) = v.extract::<String>() {
        return s.parse().map_err(|e| crate_error(Kind::Limits)(&e));
    }
    let (mv, mt): (i64, i64) = v.extract().map_err(|_| {
        fail(
            Kind::Limits,
            "limits must be a (max_vertices, max_triangles) pair of integers or text like '64/126'",
        )
    })?;
    let clamp = |x: i64| u32::try_from(x).unwrap_or(u32::MAX);
    // A negative count is out of range like a large one; the crate's message says which.
    let (mv, mt) = (
        if mv < 0 { 0 } else { clamp(mv) },
        if mt < 0 { 0 } else { clamp(mt) },
    );
    Limits::new(mv, mt).map_err(|e| crate_error(Kind::Limits)(&e))
}

#[pymethods]
impl PyMeshlets {
    /// Meshlets made elsewhere, from the three arrays in meshoptimizer's layout (`meshlets`
    /// M x 4: vertex offset, triangle offset, vertex count, triangle count; `vertices`; `triangles`,
    /// three local corners per triangle), checked against `mesh` and `limits`.
    #[new]
    #[pyo3(signature = (mesh, meshlets, vertices, triangles, limits = None))]
    fn new(
        mesh: &Bound<'_, PyMesh>,
        meshlets: &Bound<'_, PyAny>,
        vertices: &Bound<'_, PyAny>,
        triangles: &Bound<'_, PyAny>,
        limits: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let limits = self::limits(limits)?;
        let rows = convert::ndarray(meshlets)?;
        if !matches!(numpy::PyUntypedArrayMethods::shape(&rows), [_, 4]) {
            return Err(fail(Kind::Validation, "meshlets must have shape (M, 4)").into());
        }
        let u32_of = |what: &'static str| {
            move |i: usize, v: i128| {
                u32::try_from(v)
                    .map_err(|_| fail(Kind::Validation, format!("{what}[{i}] = {v} is not a u32")))
            }
        };
        let rows = convert::integers(&rows, "meshlets", Kind::Validation, u32_of("meshlets"))?;
        let vertices = convert::integers(
            &convert::ndarray(vertices)?,
            "vertices",
            Kind::Validation,
            u32_of("vertices"),
        )?;
        let triangles = convert::integers(
            &convert::ndarray(triangles)?,
            "triangles",
            Kind::Validation,
            |i, v| {
                u8::try_from(v).map_err(|_| {
                    fail(
                        Kind::Validation,
                        format!("triangles[{i}] = {v} is not a u8 corner"),
                    )
                })
            },
        )?;
        let records = Meshlet::from_rows(&rows);
        let m = &mesh.get().mesh;
        let ml = Meshlets::new(m, records, vertices, triangles)
            .map_err(|e| crate_error(Kind::Validation)(&e))?;
        // Whether they cover the mesh within the limits is `validate`'s question, not this one's.
        Ok(PyMeshlets {
            meshlets: ml,
            limits,
            mesh: mesh.clone().unbind(),
            source: "arrays".into(),
            build_ms: None,
            clusters: None,
        })
    }

    /// M x 4 uint32: vertex offset, triangle offset (bytes of `triangles`), vertex count,
    /// triangle count (a copy).
    #[getter]
    fn meshlets<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<u32>>> {
        let rows = self.meshlets.meshlet_rows().to_vec();
        PyArray1::from_vec(py, rows).reshape([self.meshlets.len(), 4])
    }

    /// Global vertex indices, uint32 (a copy).
    #[getter]
    fn vertices<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<u32>> {
        PyArray1::from_slice(py, self.meshlets.vertices())
    }

    /// Local triangle corners, three per triangle, uint8 (a copy).
    #[getter]
    fn triangles<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<u8>> {
        PyArray1::from_slice(py, self.meshlets.triangles())
    }

    /// The limits they were made for, (max_vertices, max_triangles).
    #[getter]
    fn limits(&self) -> (u32, u32) {
        (self.limits.max_vertices(), self.limits.max_triangles())
    }

    /// Their mesh.
    #[getter]
    fn mesh(&self, py: Python<'_>) -> Py<PyMesh> {
        self.mesh.clone_ref(py)
    }

    /// What made them: the strategy's name, `labels`, `arrays` or the file they were read from.
    #[getter]
    fn source(&self) -> &str {
        &self.source
    }

    /// Build wall time in milliseconds, or None when they were not built by `build`.
    #[getter]
    fn build_ms(&self) -> Option<f64> {
        self.build_ms
    }

    /// From `from_labels`: the distinct cluster ids (else None).
    #[getter]
    fn clusters(&self) -> Option<usize> {
        self.clusters.map(|c| c.0)
    }

    /// From `from_labels`: the clusters over the limits that meshopt divided (else None).
    #[getter]
    fn split_clusters(&self) -> Option<usize> {
        self.clusters.map(|c| c.1)
    }

    /// Each of the mesh's triangles' meshlet index, uint32: labels `from_labels` reads back.
    fn triangle_labels<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray1<u32>>> {
        let mesh = &self.mesh.get().mesh;
        let labels = py
            .detach(|| meshletlab::strategy::labels::triangle_labels(mesh, &self.meshlets))
            .map_err(|e| crate_error(Kind::Validation)(&e))?;
        Ok(PyArray1::from_vec(py, labels))
    }

    /// Writes the three arrays to `path` as an `.npz` (`np.load` reads it; so does
    /// `meshletlab stats MESH --meshlets PATH`).
    fn save_npz(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        py.detach(|| meshletlab::meshlet::npz::save_npz(&path, &self.meshlets))
            .map_err(|e| crate_error(Kind::File)(&e).into())
    }

    fn __len__(&self) -> usize {
        self.meshlets.len()
    }

    fn __repr__(&self) -> String {
        format!(
            "Meshlets({} meshlets of {} triangles, limits {}, from {})",
            self.meshlets.len(),
            self.meshlets.triangle_count(),
            self.limits,
            self.source
        )
    }
}

//! What comes after building: compression, the cluster-LOD DAG, and the GPU builds.

use crate::classes::{limits, PyMesh, PyMeshlets};
use crate::errors::{crate_error, fail, Kind, Result};
use meshletlab::compress::file::CompressedFile;
use meshletlab::compress::Codec;
use meshletlab::lod::io::LodFile;
use meshletlab::lod::Lod;
use meshletlab::meshlet::{Limits, Meshlets};
use meshletlab::strategy::Options;
use numpy::{PyArray1, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};
use std::path::PathBuf;

/// The strategies `build(..., device="gpu")` runs; empty when the module was built without the
/// `gpu` feature.
#[pyfunction]
pub fn gpu_strategies() -> Vec<&'static str> {
    #[cfg(feature = "gpu")]
    return meshletlab::gpu::build::GPU_STRATEGIES
        .iter()
        .map(|k| k.name())
        .collect();
    #[cfg(not(feature = "gpu"))]
    Vec::new()
}

/// One device for the whole process: opening it costs far more than a small build, and it keeps
/// the compiled kernels between builds.
#[cfg(feature = "gpu")]
static GPU: std::sync::OnceLock<meshletlab::gpu::Gpu> = std::sync::OnceLock::new();

/// Builds on the GPU: the meshlets and the wall time in ms.
#[cfg(feature = "gpu")]
pub fn gpu_build(
    mesh: &meshletlab::mesh::Mesh,
    name: &str,
    limits: Limits,
    opts: &Options,
) -> Result<(Meshlets, f64)> {
    use meshletlab::gpu::{build, Gpu};
    let gpu_err = crate_error(Kind::Gpu);
    // The name is checked before a device is opened: a typo needs no adapter to be reported.
    build::gpu_kind(name).map_err(|e| crate_error(Kind::Strategy)(&e))?;
    let gpu = match GPU.get() {
        Some(g) => g,
        None => {
            let g = Gpu::new().map_err(|e| gpu_err(&e))?;
            GPU.get_or_init(|| g)
        }
    };
    let b = build::build(gpu, name, mesh, limits, opts).map_err(|e| gpu_err(&e))?;
    Ok((b.meshlets, b.seconds * 1e3))
}

/// Without the `gpu` feature: the error saying so.
#[cfg(not(feature = "gpu"))]
pub fn gpu_build(
    _mesh: &meshletlab::mesh::Mesh,
    _name: &str,
    _limits: Limits,
    _opts: &Options,
) -> Result<(Meshlets, f64)> {
    Err(fail(
        Kind::Gpu,
        "device='gpu': this meshletlab module was built without GPU support (build it with the \
         'gpu' feature: maturin's --features gpu)",
    ))
}

/// Compressed meshlets: the bytes of a compressed-meshlet file (`meshletlab check` and
/// `render --compressed` read it), checked by decoding every meshlet on the way.
#[pyclass(frozen, name = "Compressed", module = "meshletlab")]
pub struct PyCompressed {
    file: CompressedFile,
    max_error: f64,
    meshlets: usize,
}

#[pymethods]
impl PyCompressed {
    /// The codec, as the command line names it.
    #[getter]
    fn format(&self) -> String {
        self.file.format.name()
    }

    /// The position tolerance the encoding keeps.
    #[getter]
    fn tolerance(&self) -> f64 {
        self.file.tolerance
    }

    /// The largest distance (per axis) of a decoded position from the mesh's.
    #[getter]
    fn max_error(&self) -> f64 {
        self.max_error
    }

    /// Bytes by part: `connectivity`, `positions`, `headers` (of which `geometry_headers`),
    /// `culling`, `padding`, and `total`.
    #[getter]
    fn sizes<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let s = self.file.encoded.sizes;
        let d = PyDict::new(py);
        d.set_item("connectivity", s.connectivity)?;
        d.set_item("positions", s.positions)?;
        d.set_item("headers", s.headers)?;
        d.set_item("geometry_headers", s.geometry_headers)?;
        d.set_item("culling", s.culling)?;
        d.set_item("padding", s.padding)?;
        d.set_item("total", s.total())?;
        Ok(d)
    }

    /// The file's bytes.
    fn to_bytes<'py>(&self, py: Python<'py>) -> Bound<'py, PyBytes> {
        PyBytes::new(py, &self.file.to_bytes())
    }

    /// Writes the file (atomically).
    fn save(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        py.detach(|| self.file.save(&path))
            .map_err(|e| crate_error(Kind::File)(&e).into())
    }

    /// Meshlet `i` decoded at random access: (source vertex indices uint32 (k,), triangles
    /// uint8 (t, 3) over them, decoded positions float32 (k, 3)).
    #[allow(clippy::type_complexity)]
    fn decode<'py>(
        &self,
        py: Python<'py>,
        i: usize,
    ) -> PyResult<(
        Bound<'py, PyArray1<u32>>,
        Bound<'py, numpy::PyArray2<u8>>,
        Bound<'py, numpy::PyArray2<f32>>,
    )> {
        if i >= self.meshlets {
            return Err(fail(
                Kind::Compress,
                format!("meshlet {i} out of range ({} meshlets)", self.meshlets),
            )
            .into());
        }
        let d = self
            .file
            .format
            .decode(&self.file.encoded, i)
            .map_err(|e| crate_error(Kind::Compress)(&e))?;
        let t = d.triangles.len();
        let k = d.positions.len();
        Ok((
            PyArray1::from_vec(py, d.vertices),
            PyArray1::from_slice(py, d.triangles.as_flattened()).reshape([t, 3])?,
            PyArray1::from_slice(py, d.positions.as_flattened()).reshape([k, 3])?,
        ))
    }

    fn __len__(&self) -> usize {
        self.meshlets
    }

    fn __repr__(&self) -> String {
        format!(
            "Compressed({}, {} meshlets, {} bytes, tolerance {:e})",
            self.file.format.name(),
            self.meshlets,
            self.file.encoded.sizes.total(),
            self.file.tolerance
        )
    }
}

/// The codec named `name` (the command line's `--format` names).
fn codec(name: &str) -> Result<Codec> {
    Codec::ALL
        .into_iter()
        .find(|c| c.name() == name)
        .ok_or_else(|| {
            let names: Vec<String> = Codec::ALL.iter().map(|c| c.name()).collect();
            fail(
                Kind::Compress,
                format!("unknown format '{name}' (formats: {})", names.join(", ")),
            )
        })
}

/// Encodes `meshlets` in `format` with every position within `tolerance` (mesh units), or
/// `relative_tolerance` times the bounding-box diagonal, or else the paper's 14-bit default;
/// decodes every meshlet back and compares it with the mesh before returning.
#[pyfunction]
#[pyo3(signature = (mesh, meshlets, format = "meshopt", tolerance = None, relative_tolerance = None))]
pub fn compress(
    py: Python<'_>,
    mesh: &Bound<'_, PyMesh>,
    meshlets: &Bound<'_, PyMeshlets>,
    format: &str,
    tolerance: Option<f64>,
    relative_tolerance: Option<f64>,
) -> PyResult<PyCompressed> {
    let format = codec(format)?;
    let m = &mesh.get().mesh;
    let ml = meshlets.get().checked(m)?;
    let positive = |what: &str, t: f64| {
        if t > 0.0 && t.is_finite() {
            Ok(t)
        } else {
            Err(fail(
                Kind::Compress,
                format!("{what} must be a positive number, not {t}"),
            ))
        }
    };
    let tolerance = match (tolerance, relative_tolerance) {
        (Some(_), Some(_)) => {
            return Err(fail(
                Kind::Compress,
                "give tolerance or relative_tolerance, not both",
            )
            .into())
        }
        (Some(t), None) => positive("tolerance", t)?,
        (None, Some(r)) => positive("relative_tolerance", r)? * m.bounding_box_diagonal() as f64,
        (None, None) => meshletlab::compress::paper_tolerance(m),
    };
    let label = PathBuf::from(&mesh.get().name);
    let (file, max_error) = py.detach(|| -> Result<_> {
        let encoded = format
            .encode(m, ml, tolerance)
            .map_err(|e| fail(Kind::Compress, format!("{}: {e}", label.display())))?;
        let file = CompressedFile::new(m, format, tolerance, encoded);
        let max_error = file
            .check(m, &label)
            .map_err(|e| crate_error(Kind::Compress)(&e))?;
        Ok((file, max_error))
    })?;
    Ok(PyCompressed {
        meshlets: file.encoded.offsets.len(),
        file,
        max_error,
    })
}

/// One level of a LOD DAG: its meshlets and each one's error.
#[pyclass(frozen, name = "LodLevel", module = "meshletlab")]
pub struct PyLodLevel {
    meshlets: Py<PyMeshlets>,
    errors: Vec<f32>,
    parent_errors: Vec<f32>,
    groups: Vec<u32>,
}

#[pymethods]
impl PyLodLevel {
    /// The level's meshlets (level 0 covers the mesh; above it they index welded vertices of the
    /// mesh and cover its simplified surface).
    #[getter]
    fn meshlets(&self, py: Python<'_>) -> Py<PyMeshlets> {
        self.meshlets.clone_ref(py)
    }

    /// Each meshlet's simplification error (0 at level 0), float32.
    #[getter]
    fn errors<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f32>> {
        PyArray1::from_slice(py, &self.errors)
    }

    /// The error of the group each meshlet is simplified in (infinite for a root), float32.
    #[getter]
    fn parent_errors<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f32>> {
        PyArray1::from_slice(py, &self.parent_errors)
    }

    /// The group each meshlet is a child of (2^32 - 1 for a root), uint32.
    #[getter]
    fn groups<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<u32>> {
        PyArray1::from_slice(py, &self.groups)
    }

    fn __len__(&self) -> usize {
        self.errors.len()
    }
}

/// A cluster-LOD DAG (`meshletlab.lod.build`).
#[pyclass(frozen, name = "Lod", module = "meshletlab")]
pub struct PyLod {
    lod: Lod,
    levels: Vec<Py<PyLodLevel>>,
    source: (u32, u32, u64),
}

#[pymethods]
impl PyLod {
    /// The levels, level 0 (the mesh's meshlets) first.
    #[getter]
    fn levels(&self, py: Python<'_>) -> Vec<Py<PyLodLevel>> {
        self.levels.iter().map(|l| l.clone_ref(py)).collect()
    }

    /// Meshlets over all levels.
    #[getter]
    fn meshlet_count(&self) -> usize {
        self.lod.meshlet_count()
    }

    /// Meshlets with no parent.
    #[getter]
    fn roots(&self) -> usize {
        self.lod.roots()
    }

    /// Groups whose simplification kept too many triangles (carried up unchanged).
    #[getter]
    fn stuck_groups(&self) -> usize {
        self.lod.stuck_groups()
    }

    /// Writes the LOD file (`meshletlab lod-check` and `render --lod` read it).
    fn save(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        let file = LodFile {
            source_vertices: self.source.0,
            source_triangles: self.source.1,
            fingerprint: self.source.2,
            lod: self.lod.clone(),
        };
        py.detach(|| file.save(&path))
            .map_err(|e| crate_error(Kind::File)(&e).into())
    }

    fn __repr__(&self) -> String {
        format!(
            "Lod({} levels, {} meshlets, {} roots)",
            self.lod.levels.len(),
            self.lod.meshlet_count(),
            self.lod.roots()
        )
    }
}

/// Builds the cluster-LOD DAG of `mesh`: level 0 is `strategy`'s meshlets, each level above
/// groups about `group_size` meshlets, simplifies them to half and splits them again.
#[pyfunction]
#[pyo3(signature = (mesh, strategy = "meshopt", limits = None, group_size = 8, **options))]
pub fn lod_build(
    py: Python<'_>,
    mesh: &Bound<'_, PyMesh>,
    strategy: &str,
    limits: Option<&Bound<'_, PyAny>>,
    group_size: usize,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<PyLod> {
    let limits = self::limits(limits)?;
    let opts = crate::options::parse("lod.build", options)?;
    if group_size == 0 {
        return Err(fail(Kind::Option, "group_size must be at least 1").into());
    }
    let s = meshletlab::strategy::by_name(strategy, &opts)
        .map_err(|e| crate_error(Kind::Strategy)(&e))?;
    let m = &mesh.get().mesh;
    let cfg = meshletlab::lod::Config {
        group_size,
        ..Default::default()
    };
    let lod = py.detach(|| meshletlab::lod::build(m, s.as_ref(), limits, &cfg));
    let levels = lod
        .levels
        .iter()
        .enumerate()
        .map(|(i, l)| {
            let meshlets = Py::new(
                py,
                PyMeshlets {
                    meshlets: l.meshlets.clone(),
                    limits,
                    mesh: mesh.clone().unbind(),
                    source: format!("lod level {i} of {strategy}"),
                    build_ms: None,
                    clusters: None,
                },
            )?;
            Py::new(
                py,
                PyLodLevel {
                    meshlets,
                    errors: l.info.iter().map(|x| x.error).collect(),
                    parent_errors: l.info.iter().map(|x| x.parent_error).collect(),
                    groups: l.info.iter().map(|x| x.group).collect(),
                },
            )
        })
        .collect::<PyResult<Vec<_>>>()?;
    Ok(PyLod {
        source: (
            m.vertex_count() as u32,
            m.triangle_count() as u32,
            m.fingerprint(),
        ),
        lod,
        levels,
    })
}

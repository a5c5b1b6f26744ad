//! Where a GPU run reads its mesh: a host mesh uploaded, or an engine's buffers already on the
//! device ([`MeshSource`]). Every GPU strategy driver (`kmedoids_flat`, `kmedoids_parallel`,
//! `build`) places its input through it.

use super::{timed, DeviceMesh, Gpu, GpuError, Split};
use crate::mesh::Mesh;

/// Where a GPU run reads its mesh: uploaded from the host, or already on the device.
#[derive(Clone, Copy)]
pub enum MeshSource<'a> {
    /// A mesh on the host (its index buffer and positions are uploaded).
    Host(&'a Mesh),
    /// A mesh the caller holds on the device: nothing of it is read on the host.
    Device(DeviceMesh<'a>),
}

/// A [`MeshSource`] on the device ([`MeshSource::place`]).
pub(crate) struct Placed<'a> {
    /// The index buffer.
    pub indices: Split,
    /// The positions, three f32 per vertex.
    pub positions: Positions<'a>,
    /// Seconds spent uploading.
    pub upload: f64,
}

/// Positions uploaded by this run, or the caller's.
pub(crate) enum Positions<'a> {
    /// Uploaded from a host mesh.
    Owned(wgpu::Buffer),
    /// The caller's buffer.
    Borrowed(&'a wgpu::Buffer),
}

impl std::ops::Deref for Positions<'_> {
    type Target = wgpu::Buffer;
    fn deref(&self) -> &wgpu::Buffer {
        match self {
            Positions::Owned(b) => b,
            Positions::Borrowed(b) => b,
        }
    }
}

impl<'a> MeshSource<'a> {
    /// Triangles and vertices.
    pub fn counts(&self) -> (usize, usize) {
        match self {
            MeshSource::Host(m) => (m.triangle_count(), m.vertex_count()),
            MeshSource::Device(d) => (d.triangles, d.vertices),
        }
    }

    /// The mesh on the device: a host mesh's index buffer and positions uploaded, or the
    /// caller's buffers.
    pub(crate) fn place(self, gpu: &Gpu) -> Result<Placed<'a>, GpuError> {
        let (placed, upload) = timed(|| -> Result<_, GpuError> {
            Ok(match self {
                MeshSource::Host(m) => (
                    Split::upload(gpu, "indices", &m.indices)?,
                    Positions::Owned(gpu.upload("positions", &m.positions)),
                ),
                MeshSource::Device(d) => (d.split_indices(gpu)?, Positions::Borrowed(d.positions)),
            })
        });
        let (indices, positions) = placed?;
        Ok(Placed {
            indices,
            positions,
            upload,
        })
    }
}

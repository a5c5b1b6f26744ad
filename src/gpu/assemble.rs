//! Meshlets assembled on the device (`wgsl/assemble.wgsl`) from a clustering that is already
//! there: the GPU strategies end with this instead of reading their labels back, so the meshlets
//! can stay on the device for a renderer ([`DeviceMeshlets`]). The CPU reference is
//! [`crate::meshlet::assemble::assemble`]; the arrays are identical, byte for byte.
//!
//! Host traffic: one round trip after the counts (the meshlet and vertex totals, which size the
//! output, and the over-limit counter), none after the write unless the caller reads.

use super::scan::Scan;
use super::{binding_set, param_block, wgsl, Batch, Gpu, GpuError, Kernels, Split};
use crate::meshlet::{Limits, Meshlet, Meshlets};

param_block! {
    /// `struct Params` of `wgsl/assemble.wgsl`.
    pub struct Params {
        /// Triangles.
        t,
        /// Groups (clusters).
        g,
        /// Meshlet vertex limit.
        max_v,
        /// Meshlet triangle limit.
        max_t,
    }
}

binding_set! {
    /// The storage buffers of `wgsl/assemble.wgsl`, in binding order.
    pub struct Buffers {
        /// Index buffer, first part.
        idx_a: Read,
        /// Index buffer, second part.
        idx_b: Read,
        /// Group of each triangle.
        owner: Read,
        /// Order key of each triangle in its group.
        key: Read,
        /// Triangles per group, scanned into first slots.
        toff: ReadWrite,
        /// Per-group placement cursor.
        cursor: ReadWrite,
        /// Triangle ids by group.
        members: ReadWrite,
        /// Distinct vertices per group, scanned into first vertex slots.
        voff: ReadWrite,
        /// Non-empty flags, scanned into meshlet indices.
        mindex: ReadWrite,
        /// Out: four words per meshlet.
        meshlets: ReadWrite,
        /// Out: global vertex indices.
        vertices: ReadWrite,
        /// Out: local corners, four bytes to a word.
        triangles: ReadWrite,
        /// Over-limit counter.
        counters: ReadWrite,
    }
}

/// Meshlets in device buffers, in [`Meshlets`]' layout: `meshlets` holds a [`Meshlet`] (four u32)
/// per meshlet, `vertices` the global vertex indices, `triangles` the local corners as bytes,
/// little-endian, four to a word. Bind them as storage buffers; [`DeviceMeshlets::read`] copies
/// them to the host.
pub struct DeviceMeshlets {
    /// Meshlet records.
    pub meshlets: wgpu::Buffer,
    /// Global vertex indices.
    pub vertices: wgpu::Buffer,
    /// Local corners, bytes packed into u32 words.
    pub triangles: wgpu::Buffer,
    /// Meshlets.
    pub count: usize,
    /// Entries of `vertices`.
    pub vertex_count: usize,
    /// Triangles (a third of the corner bytes).
    pub triangle_count: usize,
}

impl DeviceMeshlets {
    /// The meshlets on the host (one round trip).
    pub fn read(&self, gpu: &Gpu) -> Result<Meshlets, GpuError> {
        let words = (3 * self.triangle_count).div_ceil(4);
        let (_, mut r) = Batch::new(gpu).run_read(&[
            (&self.meshlets, 0, 4 * self.count),
            (&self.vertices, 0, self.vertex_count),
            (&self.triangles, 0, words),
        ])?;
        let (raw_m, vertices, raw_t) = (r.remove(0), r.remove(0), r.remove(0));
        let meshlets = raw_m
            .chunks_exact(4)
            .map(|c| Meshlet {
                vertex_offset: c[0],
                triangle_offset: c[1],
                vertex_count: c[2],
                triangle_count: c[3],
            })
            .collect();
        let mut triangles: Vec<u8> = bytemuck::cast_slice(&raw_t).to_vec();
        triangles.truncate(3 * self.triangle_count);
        Ok(Meshlets {
            meshlets,
            vertices,
            triangles,
        })
    }
}

/// A clustering on the device: the group of each triangle and its order key in the group (ties
/// go to the lower triangle id).
pub struct Groups<'a> {
    /// Group per triangle (< `count`).
    pub owner: &'a wgpu::Buffer,
    /// Order key per triangle.
    pub key: &'a wgpu::Buffer,
    /// Groups.
    pub count: usize,
}

/// The assembly kernels.
pub struct Assembly {
    kernels: Kernels<Params>,
}

impl Assembly {
    /// Compiles the kernels.
    pub fn new(gpu: &Gpu) -> Self {
        Self {
            kernels: Kernels::new::<Buffers>(
                gpu,
                "assemble",
                wgsl!("assemble.wgsl"),
                &["count", "place", "sort_count", "write"],
            ),
        }
    }

    /// Assembles `groups` into meshlets on the device (`indices`: the mesh's index buffer, one
    /// owner and key per triangle). Returns them and the kernel time; a group over `limits` is
    /// refused ([`GpuError::Wrong`]: the strategies that call this never make one).
    pub fn run(
        &self,
        gpu: &Gpu,
        scan: &Scan,
        indices: &Split,
        groups: Groups<'_>,
        limits: Limits,
    ) -> Result<(DeviceMeshlets, f64), GpuError> {
        let Groups {
            owner,
            key,
            count: groups,
        } = groups;
        let t = indices.len / 3;
        let params = Params {
            t: t as u32,
            g: groups as u32,
            max_v: limits.max_vertices,
            max_t: limits.max_triangles,
        };
        let toff = gpu.zeros("group triangles", groups + 1);
        let cursor = gpu.zeros("group cursor", groups);
        let members = gpu.zeros("group members", t);
        let voff = gpu.zeros("group vertices", groups + 1);
        let mindex = gpu.zeros("meshlet index", groups + 1);
        let counters = gpu.zeros("assembly counters", 1);
        let triangles = gpu.zeros("meshlet triangles", (3 * t).div_ceil(4));
        let bind = |meshlets: &wgpu::Buffer, vertices: &wgpu::Buffer| {
            self.kernels.bind(
                gpu,
                &Buffers {
                    idx_a: &indices.a,
                    idx_b: &indices.b,
                    owner,
                    key,
                    toff: &toff,
                    cursor: &cursor,
                    members: &members,
                    voff: &voff,
                    mindex: &mindex,
                    meshlets,
                    vertices,
                    triangles: &triangles,
                    counters: &counters,
                },
            )
        };
        // The outputs are sized by the first batch's totals: placeholders bind until then.
        let (m0, v0) = (gpu.zeros("placeholder", 1), gpu.zeros("placeholder", 1));
        let first = bind(&m0, &v0);
        let (toff_scan, voff_scan, mindex_scan) = (
            scan.bind(gpu, &toff, groups + 1),
            scan.bind(gpu, &voff, groups + 1),
            scan.bind(gpu, &mindex, groups + 1),
        );
        let mut b = Batch::new(gpu);
        b.threads(&self.kernels, "count", &first, params, t);
        scan.record(&mut b, &toff_scan);
        b.threads(&self.kernels, "place", &first, params, t);
        b.groups(&self.kernels, "sort_count", &first, params, groups as u32);
        scan.record(&mut b, &voff_scan);
        scan.record(&mut b, &mindex_scan);
        let (mut kernel, r) =
            b.run_read(&[(&voff, groups, 1), (&mindex, groups, 1), (&counters, 0, 1)])?;
        let (vertex_count, count, over) = (r[0][0] as usize, r[1][0] as usize, r[2][0]);
        if over > 0 {
            return Err(GpuError::Wrong(format!(
                "{over} clusters exceed the meshlet limits {limits}"
            )));
        }
        let meshlets = gpu.zeros("meshlets", 4 * count);
        let vertices = gpu.zeros("meshlet vertices", vertex_count);
        let second = bind(&meshlets, &vertices);
        let mut b = Batch::new(gpu);
        b.threads(&self.kernels, "write", &second, params, t);
        kernel += b.run()?;
        Ok((
            DeviceMeshlets {
                meshlets,
                vertices,
                triangles,
                count,
                vertex_count,
                triangle_count: t,
            },
            kernel,
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate;
    use crate::strategy::kmedoids::{cluster, Mode};

    /// Members are ordered by (key, id) as on the CPU through both ranks of `sort_count`: the key
    /// histogram (every key of a group below 256) and the all-pairs count (some key above), in
    /// one run, with ties among the keys.
    #[test]
    fn small_and_large_keys_order_members_as_on_the_cpu() {
        let gpu = Gpu::new().unwrap_or_else(|e| panic!("{e}"));
        let mesh = generate::terrain(40, 2);
        for limits in [Limits::DEFAULT, Limits::new(8, 6).unwrap()] {
            let c = cluster(&mesh, limits, Mode::Parallel, &Default::default());
            let k = c.medoids.len();
            let keys: Vec<u32> = (0..mesh.triangle_count() as u32)
                .map(|t| {
                    let tie = (t.wrapping_mul(7919) >> 3) % 5;
                    if c.labels[t as usize].is_multiple_of(2) {
                        tie
                    } else {
                        1000 * tie + (t % 3) * 256
                    }
                })
                .collect();
            let cpu = crate::meshlet::assemble::assemble(&mesh, &c.labels, &keys, k, limits);
            let indices = Split::upload(&gpu, "indices", &mesh.indices).unwrap();
            let (owner, key) = (gpu.upload("owner", &c.labels), gpu.upload("key", &keys));
            let groups = Groups {
                owner: &owner,
                key: &key,
                count: k,
            };
            let (device, _) = Assembly::new(&gpu)
                .run(&gpu, &Scan::new(&gpu), &indices, groups, limits)
                .unwrap();
            assert_eq!(device.read(&gpu).unwrap(), cpu, "{limits}");
        }
    }
}

//! Meshlet bounding spheres on the GPU (`wgsl/bounds.wgsl`) and their f32 CPU mirror.
//!
//! Parity tolerance: the centre is min/max/add/halve, exact in IEEE f32, but a shader compiler may
//! reassociate, so centres may differ by two ulps of their largest coordinate ([`CENTRE_ULPS`]). The radius goes through a dot product that a shader compiler may fuse into FMAs
//! and a sqrt that WGSL only bounds as loosely as `1 / inverseSqrt` (lavapipe differed from the CPU
//! by about 18 ulps, 1.1e-6 relative): the check allows a relative 2^-16 (1.5e-5), which is also
//! the padding that keeps the sphere conservative on both sides. For a 1 m meshlet that is 15 um.

use super::assemble::DeviceMeshlets;
use super::{binding_set, param_block, wgsl, Batch, Gpu, GpuError, Kernels};
use crate::mesh::Mesh;
use crate::meshlet::{Cone, Meshlets};
use glam::Vec3;

param_block! {
    /// `struct Params` of `wgsl/bounds.wgsl`.
    pub struct Params {
        /// Meshlets.
        n,
    }
}

binding_set! {
    /// The storage buffers of `wgsl/bounds.wgsl`, in binding order.
    pub struct Buffers {
        /// The mesh's positions, three f32 per vertex.
        positions: Read,
        /// The meshlets.
        meshlets: Read,
        /// The meshlets' global vertex indices.
        vertices: Read,
        /// Out: centre and radius per meshlet.
        spheres: ReadWrite,
        /// The meshlets' local corners, four bytes to a word (`task_bounds` only).
        triangles: Read,
        /// Out: the split task layout, three vec4 per meshlet (`task_bounds` only).
        task: ReadWrite,
    }
}

/// Relative radius tolerance between GPU and CPU (and the conservative padding).
pub const RADIUS_TOLERANCE: f32 = 1.0 / 65_536.0;

/// Absolute padding and tolerance in units of the centre's largest coordinate: 2^-22, two f32
/// ulps. A shader compiler may measure the radius from the unrounded centre (NIR folds
/// `(p0 + h) - p0` into `h`; WGSL cannot forbid it), which is off by up to half an ulp of the
/// centre; the stress test at 1e6 found exactly that.
pub const CENTRE_ULPS: f32 = 1.0 / 4_194_304.0;

/// A sphere as (centre, radius).
pub type SphereF32 = ([f32; 3], f32);

/// The CPU mirror of the `sphere` kernel for meshlet `i`: (centre, radius).
pub fn sphere_f32(mesh: &Mesh, ml: &Meshlets, i: usize) -> ([f32; 3], f32) {
    let m = ml.meshlets[i];
    let verts = &ml.vertices[m.vertex_offset as usize..(m.vertex_offset + m.vertex_count) as usize];
    let pos = |v: u32| Vec3::from_array(mesh.positions[v as usize]);
    let p0 = pos(verts[0]);
    let (mut lo, mut hi) = (Vec3::ZERO, Vec3::ZERO);
    for &v in verts {
        let d = pos(v) - p0;
        lo = lo.min(d);
        hi = hi.max(d);
    }
    let c = p0 + (lo + hi) * 0.5;
    let cl = c - p0;
    let r2 = verts.iter().fold(0.0f32, |r2, &v| {
        let d = (pos(v) - p0) - cl;
        r2.max(d.x * d.x + d.y * d.y + d.z * d.z)
    });
    (
        c.to_array(),
        r2.sqrt() * (1.0 + RADIUS_TOLERANCE) + c.abs().max_element() * CENTRE_ULPS,
    )
}

/// Spheres of all meshlets on the GPU: (centre, radius) per meshlet, and the kernel time.
pub fn spheres(gpu: &Gpu, mesh: &Mesh, ml: &Meshlets) -> Result<(Vec<SphereF32>, f64), GpuError> {
    let positions = gpu.upload("positions", &mesh.positions);
    let meshlets = gpu.upload("meshlets", &ml.meshlets);
    let vertices = gpu.upload("meshlet vertices", &ml.vertices);
    let n = ml.len();
    let (out, time) = spheres_on_device(gpu, &positions, &meshlets, &vertices, n)?;
    let raw = gpu.read(&out, 0, 4 * n)?;
    let s = raw
        .chunks_exact(4)
        .map(|c| {
            let f = |x: u32| f32::from_bits(x);
            ([f(c[0]), f(c[1]), f(c[2])], f(c[3]))
        })
        .collect();
    Ok((s, time))
}

/// The `sphere` kernel over meshlets already on the device (`n` records in `meshlets`, global
/// indices in `vertices`, three f32 per vertex in `positions`): a buffer of four f32 per meshlet
/// (centre, radius), left on the device, and the kernel time.
pub fn spheres_on_device(
    gpu: &Gpu,
    positions: &wgpu::Buffer,
    meshlets: &wgpu::Buffer,
    vertices: &wgpu::Buffer,
    n: usize,
) -> Result<(wgpu::Buffer, f64), GpuError> {
    let k = kernels(gpu);
    let out = gpu.zeros("spheres", 4 * n);
    let unused = gpu.zeros("unused", 1);
    let bind = k.bind(
        gpu,
        &Buffers {
            positions,
            meshlets,
            vertices,
            spheres: &out,
            triangles: &unused,
            task: &gpu.zeros("unused", 4),
        },
    );
    let mut b = Batch::new(gpu);
    b.threads(&k, "sphere", &bind, Params { n: n as u32 }, n);
    let time = b.run()?;
    Ok((out, time))
}

fn kernels(gpu: &Gpu) -> Kernels<Params> {
    Kernels::new::<Buffers>(
        gpu,
        "bounds",
        wgsl!("bounds.wgsl"),
        &["sphere", "task_bounds"],
    )
}

/// Words per meshlet of the split task layout (three vec4: sphere, apex and cutoff, axis and
/// triangle count), as `meshlet::descriptor` packs it for the mesh-shader pass.
pub const TASK_WORDS: usize = 12;

/// The `task_bounds` kernel over meshlets on the device (`positions`: three f32 per vertex):
/// sphere, normal cone and triangle count per meshlet in the split task layout ([`TASK_WORDS`]
/// each), left on the device, and the kernel time. The sphere is the `sphere` kernel's; the cone
/// is conservative (see [`cones_from_task`] and `meshlet::bounds::check_cones`).
pub fn task_on_device(
    gpu: &Gpu,
    positions: &wgpu::Buffer,
    ml: &DeviceMeshlets,
) -> Result<(wgpu::Buffer, f64), GpuError> {
    let k = kernels(gpu);
    let n = ml.count;
    let out = gpu.zeros("task bounds", TASK_WORDS * n);
    let bind = k.bind(
        gpu,
        &Buffers {
            positions,
            meshlets: &ml.meshlets,
            vertices: &ml.vertices,
            spheres: &gpu.zeros("unused", 4),
            triangles: &ml.triangles,
            task: &out,
        },
    );
    let mut b = Batch::new(gpu);
    b.threads(&k, "task_bounds", &bind, Params { n: n as u32 }, n);
    let time = b.run()?;
    Ok((out, time))
}

/// Sphere and cone of every meshlet from split task words (read back from [`task_on_device`]).
pub fn cones_from_task(words: &[u32]) -> Vec<(SphereF32, Cone)> {
    let f = |x: u32| f32::from_bits(x);
    words
        .chunks_exact(TASK_WORDS)
        .map(|w| {
            (
                ([f(w[0]), f(w[1]), f(w[2])], f(w[3])),
                Cone {
                    apex: [f(w[4]), f(w[5]), f(w[6])],
                    cutoff: f(w[7]),
                    axis: [f(w[8]), f(w[9]), f(w[10])],
                },
            )
        })
        .collect()
}

/// Compares GPU spheres with the CPU mirror: `None` if centres are within [`CENTRE_ULPS`] and radii
/// within [`RADIUS_TOLERANCE`] relative plus [`CENTRE_ULPS`] of the centre, else the first
/// difference.
pub fn compare(mesh: &Mesh, ml: &Meshlets, gpu: &[([f32; 3], f32)]) -> Option<String> {
    (0..ml.len()).find_map(|i| {
        let (c, r) = sphere_f32(mesh, ml, i);
        let (gc, gr) = gpu[i];
        let scale = c.iter().fold(0.0f32, |m, x| m.max(x.abs()));
        let centre_ok = (0..3).all(|a| (gc[a] - c[a]).abs() <= scale * CENTRE_ULPS);
        let ok = centre_ok && (gr - r).abs() <= r * RADIUS_TOLERANCE + scale * CENTRE_ULPS;
        (!ok).then(|| format!("sphere {i}: GPU {gc:?} r {gr}, CPU {c:?} r {r}"))
    })
}

/// Vertices outside their meshlet's sphere, measured in f64 (0 for a conservative sphere set).
pub fn outside(mesh: &Mesh, ml: &Meshlets, spheres: &[([f32; 3], f32)]) -> usize {
    (0..ml.len())
        .map(|i| {
            let m = ml.meshlets[i];
            let (c, r) = spheres[i];
            ml.vertices[m.vertex_offset as usize..(m.vertex_offset + m.vertex_count) as usize]
                .iter()
                .filter(|&&v| {
                    let p = mesh.positions[v as usize];
                    let d2: f64 = (0..3).map(|a| (p[a] as f64 - c[a] as f64).powi(2)).sum();
                    d2.sqrt() > r as f64
                })
                .count()
        })
        .sum()
}

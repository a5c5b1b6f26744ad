//! Meshlets built on the GPU and drawn from the buffers the build left there, with no readback in
//! between, on a device the application owns (as an engine would hold it).
//!
//! `kmedoids-parallel` and `kmedoids-flat` build from the application's vertex and index buffers
//! (`gpu::build::build_on_device`: nothing of the mesh is read on the host), `bsphere-parallel`
//! from the host mesh (`gpu::build::build_resident`: its setup, the seed grid, runs on the
//! host); all three leave the
//! meshlet records, vertex lists, packed local triangles and culling bounds (sphere and normal
//! cone, the mesh-shader pass's split layout) in device buffers.
//! A vertex shader pulls each meshlet's corners from them (one instance per meshlet) and skips
//! meshlets whose sphere lies outside the view or whose cone faces away; a second pipeline draws
//! the mesh's plain index buffer. Both cull back faces. The depth images of the two draws must be
//! bit-identical: the meshlets cover the mesh exactly and neither test drops a visible triangle.
//! Exit 1 on any difference.
//!
//!     cargo run --release --example gpu_draw -- [MESH] [OUT.png]

use meshletlab::gpu::bounds::{cones_from_task, TASK_WORDS};
use meshletlab::gpu::build::{build_on_device, build_resident, ResidentBuild};
use meshletlab::gpu::{DeviceMesh, Gpu};
use meshletlab::mesh::{self, Mesh};
use meshletlab::meshlet::{Cone, Limits};
use meshletlab::strategy::Options;
use wgpu::util::DeviceExt;

/// Image side in pixels (rows of 4-byte texels stay a multiple of 256 bytes, as copies need).
const SIZE: u32 = 512;

const SHADER: &str = r#"
struct View { scale: vec4<f32>, offset: vec4<f32> }
@group(0) @binding(0) var<uniform> view: View;
@group(0) @binding(1) var<storage, read> positions: array<f32>;
@group(0) @binding(2) var<storage, read> meshlets: array<vec4<u32>>;
@group(0) @binding(3) var<storage, read> vertices: array<u32>;
@group(0) @binding(4) var<storage, read> triangles: array<u32>;
// Per meshlet: (sphere centre, radius), (cone apex, cutoff), (cone axis, triangle count).
@group(0) @binding(5) var<storage, read> task: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read> indices: array<u32>;

struct Out { @builtin(position) clip: vec4<f32>, @location(0) @interpolate(flat) id: u32 }

// Orthographic: x and y into [-1, 1] (the same scale on both), z into [0, 1]. Both pipelines
// project a vertex with this one function, so they rasterise identical triangles.
fn project(v: u32) -> vec4<f32> {
    let p = vec3<f32>(positions[3u * v], positions[3u * v + 1u], positions[3u * v + 2u]);
    return vec4<f32>(p * view.scale.xyz + view.offset.xyz, 1.0);
}

// A meshlet whose sphere is wholly outside the view in x or y, or whose every triangle faces away
// from the camera (its normal cone, for a view along +z: the axis within the cutoff of it).
fn skipped(m: u32) -> bool {
    let s = task[3u * m];
    let c = s.xyz * view.scale.xyz + view.offset.xyz;
    let r = s.w * abs(view.scale.x);
    let cone = task[3u * m + 2u];
    let cutoff = task[3u * m + 1u].w;
    return abs(c.x) - r > 1.0 || abs(c.y) - r > 1.0 || (cutoff < 1.0 && cone.z >= cutoff);
}

@vertex
fn meshlet_corner(@builtin(vertex_index) i: u32, @builtin(instance_index) m: u32) -> Out {
    let d = meshlets[m];
    var out: Out;
    out.id = m;
    // Corners past the meshlet's triangles, and culled meshlets, collapse to one point.
    if (i / 3u >= d.w || skipped(m)) {
        out.clip = vec4<f32>(2.0, 2.0, 2.0, 1.0);
        return out;
    }
    let b = d.y + i;
    let local = (triangles[b / 4u] >> (8u * (b % 4u))) & 0xffu;
    out.clip = project(vertices[d.x + local]);
    return out;
}

@vertex
fn index_corner(@builtin(vertex_index) i: u32) -> Out {
    var out: Out;
    out.id = i / 3u;
    out.clip = project(indices[i]);
    return out;
}

struct Targets { @location(0) depth: u32, @location(1) colour: vec4<f32> }

@fragment
fn shade(in: Out) -> Targets {
    var t: Targets;
    t.depth = bitcast<u32>(in.clip.z);
    let h = in.id * 2654435761u;
    t.colour = vec4<f32>(f32(h & 255u), f32((h >> 8u) & 255u), f32((h >> 16u) & 255u), 255.0) / 255.0;
    return t;
}
"#;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mesh = match args.first() {
        Some(path) => mesh::load(path.as_ref())?,
        None => mesh::generate::knot_tube(300, 16, 3),
    };
    let limits = Limits::DEFAULT;

    // The application's own device, requested with what the kernels need.
    let adapter = Gpu::default_adapter()?;
    let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        required_features: Gpu::wanted_features(&adapter),
        required_limits: Gpu::required_limits(&adapter.limits()),
        ..Default::default()
    }))?;
    let gpu = Gpu::from_device(device.clone(), queue.clone(), adapter.get_info())?;
    println!("device: {}", gpu.describe());

    // The mesh as the application holds it on the device.
    let positions = buffer(&device, "positions", bytemuck::cast_slice(mesh.positions()));
    let indices = buffer(&device, "indices", bytemuck::cast_slice(mesh.indices()));
    let view = View::fitting(&mesh, 1.6);
    let reference = draw(&device, &queue, &view, &positions, &indices, None);
    let covered = reference.depth.iter().filter(|&&d| d != CLEAR).count();
    if covered == 0 {
        return Err("the mesh covers no pixel of the view".into());
    }
    // The mesh as the build sees it: the application's buffers, nothing read on the host.
    let on_device = DeviceMesh {
        positions: &positions,
        vertices: mesh.vertex_count(),
        indices: &indices,
        triangles: mesh.triangle_count(),
    };
    let opts = Options::default();
    for name in ["kmedoids-parallel", "kmedoids-flat", "bsphere-parallel"] {
        let built = if name == "bsphere-parallel" {
            // Its setup (quantised positions and the seed grid) runs on the host, from `mesh`.
            build_resident(&gpu, name, &mesh, &positions, limits, &opts)?
        } else {
            build_on_device(&gpu, name, on_device, limits, &opts)?
        };
        let image = draw(&device, &queue, &view, &positions, &indices, Some(&built));
        let same = image.depth == reference.depth;
        // After the draw, for the report only: how many meshlets the shader skipped.
        let words = gpu.read(&built.task, 0, TASK_WORDS * built.meshlets.count)?;
        let skipped = cones_from_task(&words)
            .iter()
            .filter(|(s, c)| view.skips(*s, c))
            .count();
        println!(
            "{name}: {} triangles -> {} meshlets built in {:.1} ms, drawn from the device ({skipped} outside the view or facing away skipped): depth image {} ({covered} pixels covered)",
            mesh.triangle_count(),
            built.meshlets.count,
            built.seconds * 1e3,
            if same { "identical to the index-buffer draw" } else { "DIFFERENT" },
        );
        if !same {
            std::process::exit(1);
        }
        if let (Some(out), "bsphere-parallel") = (args.get(1), name) {
            write_png(out.as_ref(), &image.colour)?;
            println!("wrote {out}");
        }
    }
    Ok(())
}

/// Cleared depth value (1.0) as the depth image stores it.
const CLEAR: u32 = 0x3f80_0000;

/// A storage buffer holding `bytes`.
fn buffer(device: &wgpu::Device, label: &str, bytes: &[u8]) -> wgpu::Buffer {
    device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some(label),
        contents: bytes,
        usage: wgpu::BufferUsages::STORAGE,
    })
}

/// `struct View` of the shader.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct View {
    scale: [f32; 4],
    offset: [f32; 4],
}

impl View {
    /// Looks at the mesh's box along -z, zoomed by `zoom` (above 1 part of it leaves the view, so
    /// the sphere test has meshlets to skip).
    fn fitting(mesh: &Mesh, zoom: f32) -> Self {
        let (lo, hi) = mesh.bounding_box();
        let centre = (lo + hi) * 0.5;
        let s = zoom * 2.0 / (hi - lo).truncate().max_element().max(f32::MIN_POSITIVE);
        let sz = 0.9 / (hi.z - lo.z).max(f32::MIN_POSITIVE);
        Self {
            scale: [s, s, sz, 0.0],
            offset: [-centre.x * s, -centre.y * s, 0.05 - lo.z * sz, 0.0],
        }
    }
}

impl View {
    /// The shader's `skipped`: a sphere (centre, radius) wholly outside the view in x or y, or a
    /// cone that faces away from a view along +z.
    fn skips(&self, (c, r): ([f32; 3], f32), cone: &Cone) -> bool {
        let r = r * self.scale[0].abs();
        (0..2).any(|a| (c[a] * self.scale[a] + self.offset[a]).abs() - r > 1.0)
            || (cone.cutoff < 1.0 && cone.axis[2] >= cone.cutoff)
    }
}

/// What a draw left: depth bits and colour, row by row.
struct Image {
    depth: Vec<u32>,
    colour: Vec<u8>,
}

/// Draws the meshlets of `built` (one instance each) or, without it, the index buffer.
fn draw(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    view: &View,
    positions: &wgpu::Buffer,
    indices: &wgpu::Buffer,
    built: Option<&ResidentBuild>,
) -> Image {
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("draw"),
        source: wgpu::ShaderSource::Wgsl(SHADER.into()),
    });
    let target = |format, usage| {
        device.create_texture(&wgpu::TextureDescriptor {
            label: None,
            size: wgpu::Extent3d {
                width: SIZE,
                height: SIZE,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage,
            view_formats: &[],
        })
    };
    let copy = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC;
    let depth_bits = target(wgpu::TextureFormat::R32Uint, copy);
    let colour = target(wgpu::TextureFormat::Rgba8Unorm, copy);
    let depth = target(
        wgpu::TextureFormat::Depth32Float,
        wgpu::TextureUsages::RENDER_ATTACHMENT,
    );
    let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("draw"),
        layout: None,
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some(if built.is_some() {
                "meshlet_corner"
            } else {
                "index_corner"
            }),
            compilation_options: Default::default(),
            buffers: &[],
        },
        // The camera looks along +z with x and y kept, so a face turned to it winds clockwise.
        primitive: wgpu::PrimitiveState {
            front_face: wgpu::FrontFace::Cw,
            cull_mode: Some(wgpu::Face::Back),
            ..Default::default()
        },
        depth_stencil: Some(wgpu::DepthStencilState {
            format: wgpu::TextureFormat::Depth32Float,
            depth_write_enabled: Some(true),
            depth_compare: Some(wgpu::CompareFunction::Less),
            stencil: Default::default(),
            bias: Default::default(),
        }),
        multisample: Default::default(),
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some("shade"),
            compilation_options: Default::default(),
            targets: &[
                Some(wgpu::TextureFormat::R32Uint.into()),
                Some(wgpu::TextureFormat::Rgba8Unorm.into()),
            ],
        }),
        multiview_mask: None,
        cache: None,
    });
    let uniform = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("view"),
        contents: bytemuck::bytes_of(view),
        usage: wgpu::BufferUsages::UNIFORM,
    });
    // Each pipeline's layout holds the bindings its entry points read: 0-5 for the meshlets,
    // 0, 1 and 6 for the index buffer (the placeholders below are left out).
    let (m, v, t, s) = match built {
        Some(b) => (
            &b.meshlets.meshlets,
            &b.meshlets.vertices,
            &b.meshlets.triangles,
            &b.task,
        ),
        None => (indices, indices, indices, positions),
    };
    let entries = [&uniform, positions, m, v, t, s, indices];
    let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &pipeline.get_bind_group_layout(0),
        entries: &entries
            .iter()
            .enumerate()
            .filter(|(i, _)| {
                if built.is_some() {
                    *i <= 5
                } else {
                    matches!(i, 0 | 1 | 6)
                }
            })
            .map(|(i, b)| wgpu::BindGroupEntry {
                binding: i as u32,
                resource: b.as_entire_binding(),
            })
            .collect::<Vec<_>>(),
    });
    let mut enc = device.create_command_encoder(&Default::default());
    {
        let views = [
            depth_bits.create_view(&Default::default()),
            colour.create_view(&Default::default()),
        ];
        let clear = |view, r: f64| wgpu::RenderPassColorAttachment {
            view,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                load: wgpu::LoadOp::Clear(wgpu::Color {
                    r,
                    g: 0.0,
                    b: 0.0,
                    a: 1.0,
                }),
                store: wgpu::StoreOp::Store,
            },
        };
        let depth_view = depth.create_view(&Default::default());
        let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("draw"),
            color_attachments: &[
                Some(clear(&views[0], CLEAR as f64)),
                Some(clear(&views[1], 0.0)),
            ],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &depth_view,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(1.0),
                    store: wgpu::StoreOp::Discard,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &bind, &[]);
        match built {
            Some(b) => pass.draw(
                0..3 * Limits::DEFAULT.max_triangles(),
                0..b.meshlets.count as u32,
            ),
            None => pass.draw(0..indices.size() as u32 / 4, 0..1),
        }
    }
    let read = |tex: &wgpu::Texture, enc: &mut wgpu::CommandEncoder| {
        let buf = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("image"),
            size: (SIZE * SIZE * 4) as u64,
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        enc.copy_texture_to_buffer(
            tex.as_image_copy(),
            wgpu::TexelCopyBufferInfo {
                buffer: &buf,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(SIZE * 4),
                    rows_per_image: None,
                },
            },
            tex.size(),
        );
        buf
    };
    let (a, b) = (read(&depth_bits, &mut enc), read(&colour, &mut enc));
    queue.submit([enc.finish()]);
    let bytes = |buf: &wgpu::Buffer| {
        buf.slice(..)
            .map_async(wgpu::MapMode::Read, |r| r.expect("map"));
        device
            .poll(wgpu::PollType::wait_indefinitely())
            .expect("poll");
        let v = buf.slice(..).get_mapped_range().expect("mapped").to_vec();
        buf.unmap();
        v
    };
    Image {
        depth: bytemuck::cast_slice(&bytes(&a)).to_vec(),
        colour: bytes(&b),
    }
}

/// Writes an RGBA image of `SIZE` x `SIZE` as PNG.
fn write_png(path: &std::path::Path, rgba: &[u8]) -> Result<(), Box<dyn std::error::Error>> {
    let mut enc = png::Encoder::new(std::fs::File::create(path)?, SIZE, SIZE);
    enc.set_color(png::ColorType::Rgba);
    enc.set_depth(png::BitDepth::Eight);
    enc.write_header()?.write_image_data(rgba)?;
    Ok(())
}

//! Build meshlets from a mesh file (or, without one, a generated terrain), check them, write a
//! meshlet file and read it back.
//!
//!     cargo run --example build_meshlets -- [MESH] [OUT.mlt]
//!
//! Needs only the core: works with `--no-default-features`.

use meshletlab::mesh::{self, Mesh};
use meshletlab::meshlet::bounds::compute_bounds;
use meshletlab::meshlet::io::MeshletFile;
use meshletlab::meshlet::{validate, Limits, Metrics};
use meshletlab::strategy::{Kind, Options};
use std::path::PathBuf;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mesh: Mesh = match args.first() {
        Some(path) => mesh::load(path.as_ref())?,
        None => mesh::generate::terrain(64, 7),
    };
    // Without OUT the file is a scratch file, removed once it has been read back.
    let (out, scratch) = match args.get(1) {
        Some(p) => (PathBuf::from(p), false),
        None => (std::env::temp_dir().join("meshletlab-example.mlt"), true),
    };
    let limits = Limits::new(64, 126)?;
    let opts = Options::default();

    // Two strategies by type: meshoptimizer's builder and our k-medoids.
    for kind in [Kind::Meshopt, Kind::Kmedoids] {
        let meshlets = kind.strategy(&opts).build(&mesh, limits);
        validate(&mesh, &meshlets, limits)?;
        let bounds = compute_bounds(&mesh, &meshlets);
        let m = Metrics::compute(&mesh, &meshlets, limits, &bounds, None);
        let cullable = bounds.iter().filter(|b| b.cone.can_cull()).count();
        println!(
            "{:>8}: {} meshlets over {} triangles, {:.1} % triangle fill (primitive fill), {cullable} with a cullable normal cone",
            kind.name(),
            meshlets.len(),
            mesh.triangle_count(),
            100.0 * m.primitive_fill,
        );
        if kind == Kind::Meshopt {
            let file = MeshletFile {
                limits,
                source_vertices: mesh.vertex_count() as u32,
                source_triangles: mesh.triangle_count() as u32,
                fingerprint: mesh.fingerprint(),
                strategy: kind.name().to_string(),
                meshlets,
            };
            file.save(&out)?; // atomic: a temporary file renamed into place
            let back = MeshletFile::load(&out)?;
            back.check(&mesh, &out)?; // the file belongs to this mesh
            assert_eq!(back, file);
            println!("wrote {} and read it back", out.display());
            if scratch {
                std::fs::remove_file(&out)?;
            }
        }
    }
    Ok(())
}

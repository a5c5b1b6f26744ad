//! Build a cluster-LOD DAG (level 0 = meshlets, then groups simplified level by level), select
//! the cut a camera needs at a one-pixel error threshold, and check it is a valid cut (exactly one
//! meshlet on every path from the finest level to a root, so no crack and no overlap).
//!
//!     cargo run --example lod_cut -- [MESH]
//!
//! Needs only the core: works with `--no-default-features`.

use meshletlab::lod::{self, camera::Camera, select};
use meshletlab::mesh;
use meshletlab::meshlet::Limits;
use meshletlab::strategy::{Kind, Options};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mesh = match std::env::args().nth(1) {
        Some(path) => mesh::load(path.as_ref())?,
        None => mesh::generate::noisy_sphere(5, 0.3, 11),
    };
    let limits = Limits::new(64, 126)?;
    let strategy = Kind::Meshopt.strategy(&Options::default());
    let dag = lod::build(&mesh, strategy.as_ref(), limits, &lod::Config::default());
    for (n, level) in dag.levels.iter().enumerate() {
        println!(
            "level {n}: {:>6} meshlets, {:>8} triangles",
            level.meshlets.len(),
            lod::level_triangles(level)
        );
    }
    select::check_monotonic(&dag)?;

    // Cameras at growing distances along one direction, each framing the mesh less.
    let (lo, hi) = mesh.bounding_box();
    let centre = (lo + hi) * 0.5;
    let diagonal = (hi - lo).length();
    for distance in [1.0, 4.0, 16.0, 64.0] {
        let camera = Camera::looking_at(
            &mesh,
            centre + glam::Vec3::new(0.3, 0.4, 1.0).normalize() * diagonal * distance,
        );
        let view = select::View::new(
            camera.eye,
            lod::camera::HEIGHT as f32,
            lod::camera::FOV_Y.to_radians(),
            1.0,
        );
        let cut = select::select_cut(&dag, &view, 0);
        select::check_cut(&dag, &cut, 0)?;
        let (meshlets, triangles) =
            cut.iter()
                .zip(&dag.levels)
                .fold((0, 0), |(m, t), (sel, level)| {
                    let picked = sel.iter().enumerate().filter(|&(_, &s)| s);
                    picked.fold((m, t), |(m, t), (i, _)| {
                        (
                            m + 1,
                            t + level.meshlets.meshlets()[i].triangle_count as usize,
                        )
                    })
                });
        println!("camera at {distance:>4} diagonals: {meshlets:>6} meshlets, {triangles:>8} triangles in the cut");
    }
    Ok(())
}

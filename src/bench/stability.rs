//! Numerical stability under stress, shared by `tests/gpu_parity.rs` and `meshletlab bench
//! stability` (-> results/stability.md): one mesh translated, scaled, flattened into slivers,
//! with duplicated vertices and with a huge coordinate range; on each, the GPU kernels must agree
//! with their CPU references, bounds must stay conservative and nothing may be NaN or Inf.
//!
//! Where f32 loses precision: a coordinate near 1e6 has an ulp of 0.0625, so a bunny-sized meshlet
//! (a few mm) placed there loses most of its shape in the input already; the kernels do not lose
//! more, because every difference is taken relative to a vertex of the meshlet (exact for nearby
//! floats) and the radius is measured from the rounded centre and padded. The integer kernels
//! (adjacency, k-medoids) never look at coordinates, and k-medoids' seeding quantises centroids
//! relative to the bounding box, so they are unaffected by translation and scale.

use super::{create_dir, write_file, write_header, Common};
use crate::gpu::{self, Gpu, GpuError};
use crate::mesh::Mesh;
use crate::meshlet::bounds::{check_cones, compute_bounds};
use crate::meshlet::Limits;
use std::fmt::Write as _;

/// What to run: the arguments of `meshletlab bench stability`.
#[derive(clap::Args, Clone, Debug)]
pub struct Config {
    /// Base mesh (file stem in the folder).
    #[arg(long, default_value = "stanford_bunny", display_order = 1)]
    pub mesh: String,
    /// Mesh folder, output folder, smoke run (the first smoke mesh as the base), quiet.
    #[command(flatten)]
    pub common: Common,
    /// Meshlet limits.
    #[arg(short, long, default_value = "64/126", value_parser = clap::value_parser!(Limits))]
    pub limits: Limits,
}

/// The stressed variants of `base`: (name, mesh).
pub fn cases(base: &Mesh) -> Vec<(&'static str, Mesh)> {
    let map = |f: &dyn Fn([f32; 3]) -> [f32; 3]| Mesh {
        positions: base.positions.iter().map(|&p| f(p)).collect(),
        indices: base.indices.clone(),
    };
    let mut dup = base.clone();
    // Every vertex duplicated; the second half of the triangles uses the copies.
    let n = base.vertex_count() as u32;
    dup.positions.extend_from_slice(&base.positions);
    let half = base.indices.len() / 6 * 3;
    for i in &mut dup.indices[half..] {
        *i += n;
    }
    let mut huge = base.clone();
    // A second copy 1e9 away: f32 keeps ~64 units there, so that copy collapses into slivers and
    // degenerate triangles, and the whole mesh spans 10 orders of magnitude.
    huge.positions
        .extend(base.positions.iter().map(|p| [p[0] + 1e9, p[1], p[2]]));
    huge.indices.extend(base.indices.iter().map(|i| i + n));
    vec![
        ("as loaded", base.clone()),
        ("translated by 1e6", map(&|p| p.map(|x| x + 1e6))),
        ("scaled by 1e-6", map(&|p| p.map(|x| x * 1e-6))),
        ("scaled by 1e6", map(&|p| p.map(|x| x * 1e6))),
        (
            "flattened to slivers (z x 1e-7)",
            map(&|p| [p[0], p[1], p[2] * 1e-7]),
        ),
        ("duplicate vertices", dup),
        ("huge range (copy at 1e9)", huge),
    ]
}

/// What one stressed mesh showed.
#[derive(Clone, Debug)]
pub struct Report {
    /// Variant.
    pub name: &'static str,
    /// Triangles.
    pub triangles: usize,
    /// GPU/CPU differences (empty = all identical or within tolerance).
    pub mismatches: Vec<String>,
    /// Vertices outside their GPU sphere (f64 check).
    pub gpu_outside: usize,
    /// Vertices outside their CPU (Welzl) sphere.
    pub cpu_outside: usize,
    /// Front-facing triangles in meshlets the cone culled, over all test cameras.
    pub cone_violations: usize,
    /// (meshlet, camera) pairs culled by the cone (so the check had something to check).
    pub cone_culls: usize,
    /// NaN or Inf in any sphere or cone.
    pub non_finite: usize,
    /// Largest relative radius difference GPU vs CPU mirror.
    pub max_radius_rel: f64,
    /// Largest difference of a sphere-centre coordinate, GPU vs CPU mirror, in units in the last
    /// place (0: bit-identical; the parity check allows 2).
    pub max_centre_ulps: u32,
    /// Largest radius difference, GPU vs CPU mirror, in ulps of the sphere centre's largest
    /// coordinate (the parity check allows 2^-16 of the radius plus 2 of these).
    pub max_radius_centre_ulps: f64,
}

impl Report {
    /// Whether everything held.
    pub fn ok(&self) -> bool {
        self.mismatches.is_empty()
            && self.gpu_outside == 0
            && self.cpu_outside == 0
            && self.cone_violations == 0
            && self.non_finite == 0
    }
}

/// Checks one variant.
pub fn check(g: &Gpu, name: &'static str, mesh: &Mesh, limits: Limits) -> Result<Report, GpuError> {
    // One parity run: its meshlets and both sphere sets are reused below, not recomputed.
    let par = gpu::parity::run(g, mesh, limits)?;
    let mismatches: Vec<String> = par
        .checks
        .iter()
        .filter_map(|c| c.mismatch.as_ref().map(|m| format!("{}: {m}", c.name)))
        .collect();
    let (ml, gs) = (&par.meshlets, &par.gpu_spheres);
    let max_radius_rel = gs
        .iter()
        .zip(&par.cpu_spheres)
        .map(|(g, &(_, r))| {
            if r > 0.0 {
                ((g.1 - r).abs() / r) as f64
            } else {
                0.0
            }
        })
        .fold(0.0, f64::max);
    let ulps = |a: f32, b: f32| {
        let (a, b) = (a.to_bits() as i64, b.to_bits() as i64);
        // Same sign (both non-negative or both negative) compares bit patterns; else far apart.
        if (a < 1 << 31) == (b < 1 << 31) {
            (a - b).unsigned_abs().min(u32::MAX as u64) as u32
        } else {
            u32::MAX
        }
    };
    let max_radius_centre_ulps = gs
        .iter()
        .zip(&par.cpu_spheres)
        .map(|(g, c)| {
            let x = c.0.iter().fold(0f32, |m, v| m.max(v.abs()));
            let ulp = f32::from_bits(x.to_bits() + 1) - x;
            ((g.1 - c.1).abs() / ulp) as f64
        })
        .fold(0.0, f64::max);
    let max_centre_ulps = gs
        .iter()
        .zip(&par.cpu_spheres)
        .flat_map(|(g, c)| (0..3).map(move |k| ulps(g.0[k], c.0[k])))
        .max()
        .unwrap_or(0);
    // The CPU's own bounds (Welzl spheres, cones), as the renderer will use them.
    let bounds = compute_bounds(mesh, ml);
    let welzl: Vec<([f32; 3], f32)> = bounds
        .iter()
        .map(|b| (b.sphere.center, b.sphere.radius))
        .collect();
    let mut non_finite = gs
        .iter()
        .chain(&welzl)
        .filter(|(c, r)| !r.is_finite() || c.iter().any(|x| !x.is_finite()))
        .count();
    non_finite += bounds
        .iter()
        .filter(|b| {
            let c = &b.cone;
            !c.cutoff.is_finite() || c.apex.iter().chain(&c.axis).any(|x| !x.is_finite())
        })
        .count();
    let cones: Vec<_> = bounds.iter().map(|b| b.cone).collect();
    let (cone_culls, cone_violations) = check_cones(mesh, ml, &cones);
    Ok(Report {
        name,
        triangles: mesh.triangle_count(),
        mismatches,
        gpu_outside: gpu::bounds::outside(mesh, ml, gs),
        cpu_outside: gpu::bounds::outside(mesh, ml, &welzl),
        cone_violations,
        cone_culls,
        non_finite,
        max_radius_rel,
        max_centre_ulps,
        max_radius_centre_ulps,
    })
}

/// Runs every variant of `base` and writes results/stability.md into `out` (its header says so
/// when `smoke`: see [`super::write_header`]).
pub fn run(
    base_name: &str,
    base: &Mesh,
    limits: Limits,
    out: &std::path::Path,
    smoke: bool,
) -> anyhow::Result<Vec<Report>> {
    let g = Gpu::new()?;
    let mut reports = Vec::new();
    for (name, m) in cases(base) {
        reports.push(check(&g, name, &m, limits)?);
    }
    let mut md = String::new();
    write_header(
        &mut md,
        "Numerical stability under stress",
        &if smoke {
            format!("meshletlab bench stability --limits {limits}")
        } else {
            format!("meshletlab bench stability --mesh {base_name} --limits {limits}")
        },
        "",
        smoke.then_some(out),
    );
    writeln!(md, "GPU: {}.\n", g.describe())?;
    writeln!(md, "Base mesh: {base_name}, meshlet limits {}/{}. For each variant: every GPU kernel against its CPU reference, as `meshletlab parity` runs them (exactly: adjacency CSR and side flags; k-medoids medoids, labels, distances, iteration, split and skipped-update counts, objective and meshlets; the parallel grower; the LOD selection's drawn meshlets. Within tolerance: sphere centres within 2 ulps of their largest coordinate, radii within 2^-16 relative plus 2 ulps of the centre, whose use the radius columns show), spheres checked in f64 (every vertex inside), cones checked from 27 cameras around and inside the mesh (a culled meshlet must have no front-facing triangle; edge-on within 1e-6 does not count), and NaN/Inf counted.\n", limits.max_vertices, limits.max_triangles)?;
    writeln!(md, "| variant | triangles | GPU against CPU | max radius diff (rel) | max radius diff (ulps of the centre) | vertices outside GPU spheres | outside CPU spheres | cone culls checked | front faces culled | NaN/Inf |")?;
    writeln!(md, "|---|---:|---|---:|---:|---:|---:|---:|---:|---:|")?;
    for r in &reports {
        writeln!(
            md,
            "| {} | {} | {} | {:.2e} | {:.2} | {} | {} | {} | {} | {} |",
            r.name,
            r.triangles,
            if !r.mismatches.is_empty() {
                format!("NO: {}", r.mismatches.join("; "))
            } else {
                // Radii always differ a little: the GPU pads for WGSL's loose sqrt.
                format!(
                    "exact checks identical; sphere centres {}; radii within tolerance",
                    match r.max_centre_ulps {
                        0 => "bit-identical".to_string(),
                        n => format!("within {n} ulps"),
                    }
                )
            },
            r.max_radius_rel,
            r.max_radius_centre_ulps,
            r.gpu_outside,
            r.cpu_outside,
            r.cone_culls,
            r.cone_violations,
            r.non_finite
        )?;
    }
    writeln!(
        md,
        "\n## Where f32 loses precision, and what the code does\n"
    )?;
    writeln!(md, "- Positions are f32 on input. Near 1e6 their ulp is 0.0625 and near 1e9 it is 64, so detail below that is gone before any kernel runs (the 1e9 copy above collapses into slivers and degenerate triangles); the kernels must not lose more and must stay conservative.")?;
    writeln!(md, "- GPU spheres (`wgsl/bounds.wgsl`) take every difference relative to the meshlet's first vertex, where subtracting nearby floats is exact, round the centre once, then measure the radius and pad it by 2^-16 relative (WGSL's loose sqrt) plus two ulps of the centre's largest coordinate: this stress test found that the shader compiler folds `(p0 + h) - p0` back into `h`, measuring from the unrounded centre, which at 1e6 put thousands of vertices up to 0.03 outside before the padding. The CPU sphere (Welzl) works in f64 and rounds the radius up.")?;
    writeln!(md, "- Cones (CPU, `src/meshlet/bounds.rs`) are computed in f64 and widened by a safety margin so that they stay conservative after rounding to f32; a cutoff of 1 means the meshlet is never culled.")?;
    writeln!(md, "- The integer kernels (adjacency, k-medoids) never read coordinates except k-medoids' seeding, which quantises centroids relative to the bounding box, so they give the same result under translation and scale.")?;
    create_dir(out)?;
    write_file(out.join("stability.md"), md)?;
    Ok(reports)
}

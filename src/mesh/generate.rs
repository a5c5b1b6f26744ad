//! Procedural meshes for `meshletlab demo` and for tests: deterministic for a given seed.
//!
//! They stand in for real inputs of three kinds: a rough closed scan (noisy sphere), thin tubes like
//! 3D-printed or vessel meshes (a knotted tube with ridged "print layers"), and a height-field
//! terrain with a boundary. The stress set ([`stress_set`]) adds what scans never have and CAD
//! exports and print supports always do: fans of long thin triangles around hubs of valence
//! 100-400 ([`cad_part`]) and thin struts that touch only at shared vertices ([`strut_lattice`]),
//! beside a smaller open terrain.

use super::scene::{Instance, Scene};
use super::{subdivide, Mesh};
use glam::{Mat4, Quat, Vec3};

/// A named generated mesh.
pub struct Generated {
    /// Short name used in tables.
    pub name: &'static str,
    /// The mesh.
    pub mesh: Mesh,
}

/// The three demo meshes (each tens of thousands of triangles).
pub fn demo_set(seed: u64) -> Vec<Generated> {
    vec![
        Generated {
            name: "noisy-sphere",
            mesh: noisy_sphere(5, 0.15, seed),
        },
        Generated {
            name: "knot-tube",
            mesh: knot_tube(640, 40, seed),
        },
        Generated {
            name: "terrain",
            mesh: terrain(160, seed),
        },
    ]
}

/// The stress meshes every strategy is tested on beside the shared real meshes: two CAD-like
/// parts (caps of 128 and 400 segments), a strut lattice and an open terrain (a long boundary,
/// which no closed scan has), 3 000 to 13 000 triangles each.
pub fn stress_set(seed: u64) -> Vec<Generated> {
    vec![
        Generated {
            name: "cad-part-128",
            mesh: cad_part(128, seed),
        },
        Generated {
            name: "cad-part-400",
            mesh: cad_part(400, seed),
        },
        Generated {
            name: "strut-lattice",
            mesh: strut_lattice(5, 6, seed),
        },
        Generated {
            name: "terrain-80",
            mesh: terrain(80, seed),
        },
    ]
}

/// The names of [`stress_set`]'s meshes, in its order (what the benches load as `gen:NAME`).
pub const STRESS_NAMES: [&str; 4] = [
    "cad-part-128",
    "cad-part-400",
    "strut-lattice",
    "terrain-80",
];

/// Seed of the generated meshes a `gen:NAME` path names (so every bench and command sees the same
/// mesh under one name).
pub const NAMED_SEED: u64 = 1;

/// The names `gen:NAME` accepts: the stress set, then the demo set.
pub const NAMES: &[&str] = &[
    "cad-part-128",
    "cad-part-400",
    "strut-lattice",
    "terrain-80",
    "noisy-sphere",
    "knot-tube",
    "terrain",
];

/// The generated mesh called `name` (one of [`NAMES`], seeded with [`NAMED_SEED`]); `None` for an
/// unknown name. Only the one mesh is generated.
pub fn named(name: &str) -> Option<Mesh> {
    let s = NAMED_SEED;
    Some(match name {
        "cad-part-128" => cad_part(128, s),
        "cad-part-400" => cad_part(400, s),
        "strut-lattice" => strut_lattice(5, 6, s),
        "terrain-80" => terrain(80, s),
        "noisy-sphere" => noisy_sphere(5, 0.15, s),
        "knot-tube" => knot_tube(640, 40, s),
        "terrain" => terrain(160, s),
        _ => return None,
    })
}

/// The names `gen:NAME` accepts for scenes ([`named_scene`]); commands that draw one mesh get
/// the scene baked ([`Scene::flatten`]).
pub const SCENE_NAMES: &[&str] = &["scene-grid", "scene-small"];

/// The generated scene called `name` (one of [`SCENE_NAMES`]); `None` for any other name.
///
/// - `scene-grid`: a 4 x 4 x 4 grid of interpenetrating noisy spheres (5120 triangles each,
///   spaced at 0.7 of their extent, so from any view outside most of them are hidden), each
///   rotated, every fifth mirrored and every seventh stretched unevenly, beside a knotted tube
///   threaded through the grid: two meshes, 65 instances.
/// - `scene-small`: the same rules on a 2 x 2 x 2 grid of 1280-triangle spheres (tests).
pub fn named_scene(name: &str) -> Option<Scene> {
    let (n, levels) = match name {
        "scene-grid" => (4, 4),
        "scene-small" => (2, 3),
        _ => return None,
    };
    Some(sphere_grid(n, levels, NAMED_SEED))
}

/// `n`^3 noisy spheres (`levels` subdivisions) on a grid at 0.7 of their extent, plus one knotted
/// tube through them; see [`named_scene`].
pub fn sphere_grid(n: usize, levels: u32, seed: u64) -> Scene {
    let sphere = noisy_sphere(levels, 0.15, seed);
    let knot = knot_tube(80 * n, 12, seed);
    // The spheres' extent is about 2 (radius 1 +- the noise): spacing 0.7 of it.
    let spacing = 1.4;
    let mut instances = Vec::with_capacity(n * n * n + 1);
    for k in 0..n * n * n {
        let (x, y, z) = (k % n, (k / n) % n, k / (n * n));
        let h = splitmix64(seed ^ (k as u64 + 1));
        let angle = |s: u32| ((h >> s) & 0xffff) as f32 / 65536.0 * std::f32::consts::TAU;
        let rotation = Quat::from_euler(glam::EulerRot::XYZ, angle(0), angle(16), angle(32));
        let mut scale = Vec3::ONE;
        if k % 5 == 4 {
            scale.x = -1.0;
        }
        if k % 7 == 6 {
            scale *= Vec3::new(1.25, 0.8, 1.0);
        }
        let centre = (Vec3::new(x as f32, y as f32, z as f32) - (n as f32 - 1.0) / 2.0) * spacing;
        instances.push(Instance {
            mesh: 0,
            transform: Mat4::from_scale_rotation_translation(scale, rotation, centre),
        });
    }
    // The knot's extent is about 6 across: scaled to span the grid.
    let span = spacing * n as f32 / 6.0;
    instances.push(Instance {
        mesh: 1,
        transform: Mat4::from_scale(Vec3::splat(span)),
    });
    Scene {
        meshes: vec![sphere, knot],
        instances,
    }
}

/// Revolves `profile` ((radius, height) points, bottom to top) around the z axis in `segments`
/// steps. A point of radius 0 becomes one hub vertex whose triangles fan around it; the others
/// become rings joined by quads. Faces point away from the axis (counter-clockwise outside).
fn revolve(
    profile: &[(f32, f32)],
    segments: usize,
    positions: &mut Vec<[f32; 3]>,
    indices: &mut Vec<u32>,
) {
    let base = positions.len() as u32;
    // First vertex of each profile point's ring (one vertex for a hub).
    let mut starts = Vec::with_capacity(profile.len());
    for &(r, z) in profile {
        starts.push(positions.len() as u32 - base);
        if r == 0.0 {
            positions.push([0.0, 0.0, z]);
        } else {
            for j in 0..segments {
                let a = std::f32::consts::TAU * j as f32 / segments as f32;
                positions.push([r * a.cos(), r * a.sin(), z]);
            }
        }
    }
    let at = |i: usize, j: usize| {
        base + starts[i]
            + if profile[i].0 == 0.0 {
                0
            } else {
                (j % segments) as u32
            }
    };
    for i in 0..profile.len() - 1 {
        let (hub_low, hub_high) = (profile[i].0 == 0.0, profile[i + 1].0 == 0.0);
        for j in 0..segments {
            let (a, b, c, d) = (at(i, j), at(i, j + 1), at(i + 1, j + 1), at(i + 1, j));
            if !hub_low {
                indices.extend_from_slice(&[a, b, c]);
            }
            if !hub_high {
                indices.extend_from_slice(&[a, c, d]);
            }
        }
    }
}

/// A CAD-like part as a tessellator exports it: a closed cylinder of `segments` sides whose flat
/// caps are single fans (a hub of valence `segments` and `segments` long thin triangles), rounded
/// into the side by three-step fillets, with a narrower boss on top (its own fan cap). The side
/// quads are tall and narrow (height over width grows with `segments`): long thin triangles
/// everywhere. Sizes vary a little with `seed`.
pub fn cad_part(segments: usize, seed: u64) -> Mesh {
    let segments = segments.max(3);
    let jitter = |k: u64| 1.0 + 0.2 * ((splitmix64(seed ^ k) >> 11) as f32 / (1u64 << 53) as f32);
    let (r, h, f) = (1.0 * jitter(1), 2.5 * jitter(2), 0.15);
    let (rb, hb) = (0.45 * jitter(3), 0.6 * jitter(4));
    let fillet = |c: (f32, f32), from: f32| {
        (1..=3).map(move |k| {
            let a = from + std::f32::consts::FRAC_PI_2 * k as f32 / 4.0;
            (c.0 + f * a.cos(), c.1 + f * a.sin())
        })
    };
    let mut profile = vec![(0.0, 0.0), (r - f, 0.0)];
    // Bottom fillet: centre (r - f, f), from straight down to straight out.
    profile.extend(fillet((r - f, f), -std::f32::consts::FRAC_PI_2));
    profile.extend([(r, f), (r, h - f)]);
    // Top fillet: centre (r - f, h - f), from straight out to straight up.
    profile.extend(fillet((r - f, h - f), 0.0));
    // The shoulder up to the boss, its side, and its fan cap.
    profile.extend([(r - f, h), (rb, h), (rb, h + hb), (0.0, h + hb)]);
    let mut positions = Vec::new();
    let mut indices = Vec::new();
    revolve(&profile, segments, &mut positions, &mut indices);
    Mesh { positions, indices }
}

/// A lattice of thin struts along the edges of a `cells`^3 cubic grid, as a 3D-print support or
/// a lightweighting infill: each strut is a `sides`-sided prism as long as a cell and a tenth as
/// wide, closed at both ends by a fan around the grid node, and the struts meeting at a node
/// share its hub vertex, so the lattice is one piece connected only through vertices (no edge is
/// shared between struts). Node positions are jittered by `seed`.
pub fn strut_lattice(cells: usize, sides: usize, seed: u64) -> Mesh {
    let (cells, sides) = (cells.max(1), sides.max(3));
    let n = cells + 1;
    let node = |x: usize, y: usize, z: usize| -> Vec3 {
        let k = ((x * n + y) * n + z) as u64;
        let j = |a: u64| {
            0.08 * ((splitmix64(seed ^ (3 * k + a)) >> 11) as f32 / (1u64 << 53) as f32 - 0.5)
        };
        Vec3::new(x as f32 + j(0), y as f32 + j(1), z as f32 + j(2))
    };
    let mut positions: Vec<[f32; 3]> = (0..n * n * n)
        .map(|i| node(i / (n * n), i / n % n, i % n).to_array())
        .collect();
    let mut indices = Vec::new();
    let radius = 0.05;
    for i in 0..n * n * n {
        let (x, y, z) = (i / (n * n), i / n % n, i % n);
        for (dx, dy, dz) in [(1, 0, 0), (0, 1, 0), (0, 0, 1)] {
            let (x2, y2, z2) = (x + dx, y + dy, z + dz);
            if x2 >= n || y2 >= n || z2 >= n {
                continue;
            }
            let j = (x2 * n + y2) * n + z2;
            let (a, b) = (
                Vec3::from_array(positions[i]),
                Vec3::from_array(positions[j]),
            );
            let axis = (b - a).normalize();
            let u = axis.any_orthonormal_vector();
            let v = axis.cross(u);
            // Two rings a tenth of the strut's length in from each node.
            let ring = |p: Vec3, positions: &mut Vec<[f32; 3]>| {
                let first = positions.len() as u32;
                for s in 0..sides {
                    let t = std::f32::consts::TAU * s as f32 / sides as f32;
                    positions.push((p + radius * (t.cos() * u + t.sin() * v)).to_array());
                }
                first
            };
            let r0 = ring(a + 0.1 * (b - a), &mut positions);
            let r1 = ring(b - 0.1 * (b - a), &mut positions);
            for s in 0..sides as u32 {
                let t = (s + 1) % sides as u32;
                // Side quads (outward: u, v, axis is right-handed), then the two end fans.
                indices.extend_from_slice(&[r0 + s, r0 + t, r1 + t, r0 + s, r1 + t, r1 + s]);
                indices.extend_from_slice(&[i as u32, r0 + t, r0 + s]);
                indices.extend_from_slice(&[j as u32, r1 + s, r1 + t]);
            }
        }
    }
    Mesh { positions, indices }
}

/// SplitMix64: a tiny, well-mixed hash for seeded noise.
pub fn splitmix64(mut x: u64) -> u64 {
    x = x.wrapping_add(0x9e37_79b9_7f4a_7c15);
    x = (x ^ (x >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    x ^ (x >> 31)
}

fn lattice(ix: i32, iy: i32, iz: i32, seed: u64) -> f32 {
    let h = splitmix64(
        seed ^ (ix as u32 as u64) ^ ((iy as u32 as u64) << 21) ^ ((iz as u32 as u64) << 42),
    );
    (h >> 40) as f32 / (1u64 << 24) as f32 * 2.0 - 1.0
}

/// Smooth 3D value noise in [-1, 1].
pub fn value_noise(p: Vec3, seed: u64) -> f32 {
    let f = p.floor();
    let t = p - f;
    let s = t * t * (Vec3::splat(3.0) - 2.0 * t);
    let (x, y, z) = (f.x as i32, f.y as i32, f.z as i32);
    let mut acc = 0.0;
    for dz in 0..2 {
        for dy in 0..2 {
            for dx in 0..2 {
                let w = (if dx == 1 { s.x } else { 1.0 - s.x })
                    * (if dy == 1 { s.y } else { 1.0 - s.y })
                    * (if dz == 1 { s.z } else { 1.0 - s.z });
                acc += w * lattice(x + dx, y + dy, z + dz, seed);
            }
        }
    }
    acc
}

/// Fractal sum of `octaves` value-noise layers, roughly in [-1, 1].
pub fn fbm(p: Vec3, octaves: u32, seed: u64) -> f32 {
    let (mut sum, mut amp, mut freq, mut norm) = (0.0, 1.0, 1.0, 0.0);
    for o in 0..octaves {
        sum += amp * value_noise(p * freq, seed.wrapping_add(o as u64));
        norm += amp;
        amp *= 0.5;
        freq *= 2.0;
    }
    sum / norm
}

/// An icosphere subdivided `levels` times (20 * 4^levels triangles) with its radius displaced by
/// fractal noise of relative amplitude `roughness`.
pub fn noisy_sphere(levels: u32, roughness: f32, seed: u64) -> Mesh {
    let t = (1.0 + 5f32.sqrt()) / 2.0;
    let positions = vec![
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ];
    let indices = vec![
        0, 11, 5, 0, 5, 1, 0, 1, 7, 0, 7, 10, 0, 10, 11, 1, 5, 9, 5, 11, 4, 11, 10, 2, 10, 7, 6, 7,
        1, 8, 3, 9, 4, 3, 4, 2, 3, 2, 6, 3, 6, 8, 3, 8, 9, 4, 9, 5, 2, 4, 11, 6, 2, 10, 8, 6, 7, 9,
        8, 1,
    ];
    let ico = Mesh { positions, indices };
    let mut m = subdivide::subdivide(&ico, levels).expect("icosphere fits u32");
    for p in &mut m.positions {
        let d = Vec3::from_array(*p).normalize();
        let r = 1.0 + roughness * fbm(d * 3.0, 5, seed);
        *p = (d * r).to_array();
    }
    m
}

/// A (2,3) torus-knot tube: `segments` rings of `sides` vertices, closed into a torus-like surface,
/// with ridges along its length like the layers of a 3D print and a slow thickness wobble.
pub fn knot_tube(segments: usize, sides: usize, seed: u64) -> Mesh {
    let curve = |u: f32| {
        let (p, q) = (2.0, 3.0);
        let r = 2.0 + (q * u).cos();
        Vec3::new(r * (p * u).cos(), r * (p * u).sin(), -(q * u).sin())
    };
    let tau = std::f32::consts::TAU;
    let mut positions = Vec::with_capacity(segments * sides);
    for i in 0..segments {
        let u = tau * i as f32 / segments as f32;
        let c = curve(u);
        let tangent = (curve(u + 1e-3) - curve(u - 1e-3)).normalize();
        // The curve never runs parallel to z for long, so z gives a stable frame.
        let n = tangent.cross(Vec3::Z).normalize();
        let b = tangent.cross(n);
        let ridge = 0.02 * (u * segments as f32 * 0.5).sin();
        let wobble = 0.08 * value_noise(Vec3::new(u * 3.0, 0.0, 0.0), seed);
        for j in 0..sides {
            let v = tau * j as f32 / sides as f32;
            let r = 0.45 + ridge + wobble;
            positions.push((c + r * (v.cos() * n + v.sin() * b)).to_array());
        }
    }
    let mut indices = Vec::with_capacity(segments * sides * 6);
    for i in 0..segments {
        for j in 0..sides {
            let at = |i: usize, j: usize| ((i % segments) * sides + j % sides) as u32;
            let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
            indices.extend_from_slice(&[a, b, c, a, c, d]);
        }
    }
    Mesh { positions, indices }
}

/// An `n` x `n` height-field terrain over [-1, 1]^2 with fractal hills (an open surface).
pub fn terrain(n: usize, seed: u64) -> Mesh {
    let n = n.max(2);
    let mut positions = Vec::with_capacity(n * n);
    for y in 0..n {
        for x in 0..n {
            let (fx, fy) = (
                x as f32 / (n - 1) as f32 * 2.0 - 1.0,
                y as f32 / (n - 1) as f32 * 2.0 - 1.0,
            );
            let h = 0.35 * fbm(Vec3::new(fx * 2.5, fy * 2.5, 0.5), 6, seed);
            positions.push([fx, h, fy]);
        }
    }
    let mut indices = Vec::with_capacity((n - 1) * (n - 1) * 6);
    for y in 0..n - 1 {
        for x in 0..n - 1 {
            let at = |x: usize, y: usize| (y * n + x) as u32;
            let (a, b, c, d) = (at(x, y), at(x + 1, y), at(x + 1, y + 1), at(x, y + 1));
            // Counter-clockwise seen from above (+y).
            indices.extend_from_slice(&[a, c, b, a, d, c]);
        }
    }
    Mesh { positions, indices }
}

/// `n` seeded directions, uniform on the unit sphere (z uniform in [-1, 1], angle uniform).
pub fn random_directions(n: usize, seed: u64) -> Vec<Vec3> {
    let mut state = seed;
    let mut unit = || {
        state = splitmix64(state);
        (state >> 11) as f32 / (1u64 << 53) as f32
    };
    (0..n)
        .map(|_| {
            let z = 2.0 * unit() - 1.0;
            let a = std::f32::consts::TAU * unit();
            let s = (1.0 - z * z).max(0.0).sqrt();
            Vec3::new(s * a.cos(), z, s * a.sin())
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::MeshStats;

    #[test]
    fn generated_meshes_are_valid_and_deterministic() {
        for g in demo_set(7) {
            g.mesh.validate().unwrap();
            let again = demo_set(7).into_iter().find(|h| h.name == g.name).unwrap();
            assert_eq!(g.mesh, again.mesh, "{}", g.name);
            let s = MeshStats::of(&g.mesh);
            assert_eq!(s.components, 1, "{}", g.name);
            assert_eq!(s.non_manifold_edges, 0, "{}", g.name);
        }
        assert_eq!(MeshStats::of(&noisy_sphere(3, 0.1, 1)).boundary_edges, 0);
        assert_eq!(MeshStats::of(&knot_tube(50, 8, 1)).boundary_edges, 0);
        assert_eq!(MeshStats::of(&terrain(10, 1)).boundary_edges, 36);
    }

    /// Six times the enclosed volume (positive when every face points outward).
    fn volume6(m: &Mesh) -> f32 {
        (0..m.triangle_count())
            .map(|t| {
                let [a, b, c] = m.triangle(t).map(|v| m.position(v));
                a.dot(b.cross(c))
            })
            .sum()
    }

    #[test]
    fn stress_meshes_are_closed_outward_and_deterministic_but_the_terrain() {
        for g in stress_set(NAMED_SEED)
            .into_iter()
            .chain(demo_set(NAMED_SEED))
        {
            assert!(NAMES.contains(&g.name));
            assert_eq!(named(g.name).unwrap(), g.mesh, "{}", g.name);
        }
        assert_eq!(NAMES.len(), 7);
        let stress: Vec<&str> = stress_set(1).iter().map(|g| g.name).collect();
        assert_eq!(stress, STRESS_NAMES);
        assert!(named("no-such-mesh").is_none());
        for g in stress_set(5) {
            g.mesh.validate().unwrap();
            let again = stress_set(5)
                .into_iter()
                .find(|h| h.name == g.name)
                .unwrap();
            assert_eq!(g.mesh, again.mesh, "{}", g.name);
            let s = MeshStats::of(&g.mesh);
            assert_eq!(s.non_manifold_edges, 0, "{}", g.name);
            // The terrain is the one open stress mesh: its boundary is the grid's rim.
            if g.name == "terrain-80" {
                assert_eq!(s.boundary_edges, 4 * 79, "{}", g.name);
                continue;
            }
            assert_eq!(s.boundary_edges, 0, "{}", g.name);
            assert!(volume6(&g.mesh) > 0.0, "{} faces inward", g.name);
        }
        // The caps are fans: the hub has one triangle per segment.
        let m = cad_part(400, 1);
        let hub_triangles = m.indices.iter().filter(|&&v| v == 0).count();
        assert_eq!(hub_triangles, 400);
        // Struts are closed prisms whose fans share the grid nodes: a node inside the lattice
        // carries six struts' fans.
        let l = strut_lattice(2, 5, 1);
        let centre = (9 + 3 + 1) as u32; // node (1, 1, 1) of a 3^3 grid
        assert_eq!(l.indices.iter().filter(|&&v| v == centre).count(), 6 * 5);
        assert_eq!(l.triangle_count(), 3 * 2 * 9 * 4 * 5);
    }

    #[test]
    fn terrain_faces_up() {
        let m = terrain(4, 3);
        let [a, b, c] = m.triangle(0);
        let n = (m.position(b) - m.position(a)).cross(m.position(c) - m.position(a));
        assert!(n.y > 0.0);
    }
}

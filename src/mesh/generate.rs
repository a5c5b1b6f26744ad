//! Procedural meshes for `meshletlab demo` and for tests: deterministic for a given seed.
//!
//! They stand in for real inputs of three kinds: a rough closed scan (noisy sphere), thin tubes like
//! 3D-printed or vessel meshes (a knotted tube with ridged "print layers"), and a height-field
//! terrain with a boundary.

use super::{subdivide, Mesh};
use glam::Vec3;

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

    #[test]
    fn terrain_faces_up() {
        let m = terrain(4, 3);
        let [a, b, c] = m.triangle(0);
        let n = (m.position(b) - m.position(a)).cross(m.position(c) - m.position(a));
        assert!(n.y > 0.0);
    }
}

//! Per-meshlet culling bounds: a tight bounding sphere and a normal cone for backface culling.
//!
//! The sphere is the exact minimal enclosing sphere (Welzl's algorithm in f64, deterministic order);
//! its f32 radius is recomputed from the rounded f32 centre and rounded up, so every vertex is inside
//! the stored sphere. meshoptimizer uses an approximate sphere; ours is never larger.
//!
//! The cone follows meshoptimizer's construction (axis = centre of the minimal sphere around the unit
//! normals, apex pushed back behind every triangle plane), computed in f64 with margins so that the
//! stored f32 values stay conservative: if [`Cone::culls`] says a camera sees only back faces, every
//! non-degenerate triangle of the meshlet faces away from it. Zero-area triangles have no normal,
//! produce no fragments, and are ignored; they never produce NaN.

use super::Meshlets;
use crate::mesh::Mesh;
use glam::DVec3;
use rayon::prelude::*;

/// A bounding sphere.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct Sphere {
    /// Centre.
    pub center: [f32; 3],
    /// Radius (every point is within it).
    pub radius: f32,
}

/// A normal cone for backface culling of a whole meshlet.
///
/// Cull when `cutoff < 1 && dot(normalize(apex - camera), axis) >= cutoff`. A `cutoff` of 1 means
/// the normals spread over a half-space or more and the cone can never cull (the explicit `< 1` test
/// matters: a normalised dot product can round to 1.0 exactly).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct Cone {
    /// Apex: a point behind every triangle plane of the meshlet.
    pub apex: [f32; 3],
    /// Unit axis (the mean facing direction).
    pub axis: [f32; 3],
    /// sin of the normals' half-angle around `axis`, plus a safety margin; 1 = never culls.
    pub cutoff: f32,
}

impl Cone {
    /// A cone that never culls.
    pub const NEVER: Cone = Cone {
        apex: [0.0; 3],
        axis: [0.0, 0.0, 1.0],
        cutoff: 1.0,
    };

    /// Whether the cone can cull from some viewpoint at all.
    pub fn can_cull(&self) -> bool {
        self.cutoff < 1.0
    }

    /// The backface test as a shader evaluates it, in f32.
    pub fn culls(&self, camera: [f32; 3]) -> bool {
        if !self.can_cull() {
            return false;
        }
        let d = glam::Vec3::from_array(self.apex) - glam::Vec3::from_array(camera);
        let len = d.length();
        // At the apex itself the direction is undefined: do not cull.
        len > 0.0 && d.dot(glam::Vec3::from_array(self.axis)) >= self.cutoff * len
    }
}

/// Bounds of one meshlet.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct MeshletBounds {
    /// Bounding sphere of its vertices.
    pub sphere: Sphere,
    /// Normal cone of its triangles.
    pub cone: Cone,
}

/// Margin added to the cone cutoff: covers the f32 error of the shader's normalise-and-dot (about
/// 1e-7 relative) with two orders of magnitude to spare, and costs almost no culling.
const CUTOFF_MARGIN: f64 = 1e-5;

/// Bounds of every meshlet (in parallel; the result is independent of thread count).
pub fn compute_bounds(mesh: &Mesh, ml: &Meshlets) -> Vec<MeshletBounds> {
    (0..ml.len())
        .into_par_iter()
        .map(|i| meshlet_bounds(mesh, ml, i))
        .collect()
}

/// Bounds of meshlet `i`.
pub fn meshlet_bounds(mesh: &Mesh, ml: &Meshlets, i: usize) -> MeshletBounds {
    let pts: Vec<DVec3> = ml
        .meshlet_vertices(i)
        .iter()
        .map(|&v| dvec(mesh.positions[v as usize]))
        .collect();
    let sphere = bounding_sphere(&pts);
    let tris: Vec<[DVec3; 3]> = ml
        .global_triangles(i)
        .map(|t| t.map(|v| dvec(mesh.positions[v as usize])))
        .collect();
    let cone = normal_cone(&tris, sphere);
    MeshletBounds { sphere, cone }
}

#[inline]
fn dvec(p: [f32; 3]) -> DVec3 {
    DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64)
}

#[inline]
fn fvec(p: DVec3) -> [f32; 3] {
    [p.x as f32, p.y as f32, p.z as f32]
}

/// Smallest f32 >= x.
fn round_up(x: f64) -> f32 {
    let f = x as f32;
    if (f as f64) < x {
        f.next_up()
    } else {
        f
    }
}

/// The stored (f32) bounding sphere of a point set: minimal sphere in f64, centre rounded to f32,
/// radius re-measured from that centre and rounded up so containment holds exactly.
pub fn bounding_sphere(points: &[DVec3]) -> Sphere {
    if points.is_empty() {
        return Sphere::default();
    }
    let (c, _) = min_sphere(points);
    let center = fvec(c);
    let cd = dvec(center);
    let r = points
        .iter()
        .map(|p| (*p - cd).length())
        .fold(0.0, f64::max);
    Sphere {
        center,
        radius: round_up(r),
    }
}

/// Minimal enclosing sphere (centre, radius) by Welzl's move-to-front algorithm, in f64. Points are
/// visited in a fixed pseudo-random order, so the result is deterministic and expected linear time.
pub fn min_sphere(points: &[DVec3]) -> (DVec3, f64) {
    let mut pts = points.to_vec();
    // Deterministic shuffle (Fisher-Yates with a fixed-seed SplitMix64).
    let mut s = 0x5eed_u64;
    for i in (1..pts.len()).rev() {
        s = crate::mesh::generate::splitmix64(s);
        pts.swap(i, (s % (i as u64 + 1)) as usize);
    }
    let mut support = Vec::with_capacity(4);
    let (c, r2) = welzl(&mut pts, &mut support);
    (c, r2.max(0.0).sqrt())
}

/// Relative slack for "inside" tests: rounding must not make Welzl chase a point already inside.
const INSIDE_EPS: f64 = 1e-12;

fn welzl(pts: &mut [DVec3], support: &mut Vec<DVec3>) -> (DVec3, f64) {
    let (mut c, mut r2) = sphere_from_support(support);
    if support.len() == 4 {
        return (c, r2);
    }
    for i in 0..pts.len() {
        let p = pts[i];
        if (p - c).length_squared() > r2 * (1.0 + INSIDE_EPS) + 1e-300 {
            support.push(p);
            let (nc, nr2) = welzl(&mut pts[..i], support);
            support.pop();
            c = nc;
            r2 = nr2;
            // Move to front: points that forced growth are tried first next time.
            pts[..=i].rotate_right(1);
        }
    }
    (c, r2)
}

/// The smallest sphere with all support points on its surface (0 to 4 points). Degenerate
/// configurations (collinear, coplanar) fall back to the best sphere of a subset that contains all.
fn sphere_from_support(s: &[DVec3]) -> (DVec3, f64) {
    match s.len() {
        0 => (DVec3::ZERO, -1.0),
        1 => (s[0], 0.0),
        2 => {
            let c = (s[0] + s[1]) * 0.5;
            (c, (s[0] - c).length_squared())
        }
        3 => circumsphere3(s[0], s[1], s[2]).unwrap_or_else(|| widest_pair(s)),
        _ => circumsphere4(s).unwrap_or_else(|| {
            // Coplanar support: the best 3-subset sphere that holds the fourth point.
            let mut best: Option<(DVec3, f64)> = None;
            for skip in 0..4 {
                let sub: Vec<DVec3> = (0..4).filter(|&k| k != skip).map(|k| s[k]).collect();
                let (c, r2) =
                    circumsphere3(sub[0], sub[1], sub[2]).unwrap_or_else(|| widest_pair(&sub));
                let holds = (s[skip] - c).length_squared() <= r2 * (1.0 + 1e-9);
                if holds && best.is_none_or(|b| r2 < b.1) {
                    best = Some((c, r2));
                }
            }
            best.unwrap_or_else(|| widest_pair(s))
        }),
    }
}

fn widest_pair(s: &[DVec3]) -> (DVec3, f64) {
    let mut best = (s[0], 0.0);
    for i in 0..s.len() {
        for j in i + 1..s.len() {
            let c = (s[i] + s[j]) * 0.5;
            let r2 = (s[i] - c).length_squared();
            if r2 > best.1 {
                best = (c, r2);
            }
        }
    }
    best
}

fn circumsphere3(a: DVec3, b: DVec3, c: DVec3) -> Option<(DVec3, f64)> {
    let (ab, ac) = (b - a, c - a);
    let n = ab.cross(ac);
    let n2 = n.length_squared();
    if n2 <= 1e-24 * ab.length_squared() * ac.length_squared() || n2 == 0.0 {
        return None;
    }
    let off = (n.cross(ab) * ac.length_squared() + ac.cross(n) * ab.length_squared()) / (2.0 * n2);
    Some((a + off, off.length_squared()))
}

fn circumsphere4(s: &[DVec3]) -> Option<(DVec3, f64)> {
    let (a, b, c, d) = (s[0], s[1], s[2], s[3]);
    let (u, v, w) = (b - a, c - a, d - a);
    let det = u.dot(v.cross(w));
    let scale = u.length() * v.length() * w.length();
    if det.abs() <= 1e-12 * scale || det == 0.0 {
        return None;
    }
    let off = (v.cross(w) * u.length_squared()
        + w.cross(u) * v.length_squared()
        + u.cross(v) * w.length_squared())
        / (2.0 * det);
    Some((a + off, off.length_squared()))
}

/// Unit normal of a counter-clockwise triangle; `None` at zero area (no fragments: nothing to
/// cull or protect, so cones leave such a triangle out).
pub fn triangle_normal(t: &[DVec3; 3]) -> Option<DVec3> {
    let n = (t[1] - t[0]).cross(t[2] - t[0]);
    let len = n.length();
    (len > 0.0 && len.is_finite()).then(|| n / len)
}

/// The backface cone of unit `normals`: its axis as stored (rounded to f32) and its cutoff, or
/// `None` where no cone can cull (no normals, or normals over (almost) a half-space). The axis is
/// the centre of the normals' smallest enclosing sphere, which maximises the smallest dot product
/// with them. Shared by [`compute_bounds`] and the strategies that keep meshlets cullable.
pub fn cone_axis(normals: &[DVec3]) -> Option<(DVec3, f64)> {
    if normals.is_empty() {
        return None;
    }
    let (c, _) = min_sphere(normals);
    if c.length() < 1e-9 {
        return None;
    }
    let axis_d = dvec(fvec(c.normalize())); // test against the axis as stored
    let mindp = normals
        .iter()
        .map(|n| n.dot(axis_d))
        .fold(f64::INFINITY, f64::min);
    if mindp <= 1e-3 {
        // Normals spread over (almost) a half-space: no viewpoint sees only back faces reliably.
        return None;
    }
    let cutoff = (1.0 - mindp * mindp).max(0.0).sqrt() + CUTOFF_MARGIN;
    (cutoff < 1.0).then_some((axis_d, cutoff))
}

/// The normal cone of a triangle set, conservative after rounding to f32.
fn normal_cone(tris: &[[DVec3; 3]], sphere: Sphere) -> Cone {
    let mut normals = Vec::with_capacity(tris.len());
    let mut planes = Vec::with_capacity(tris.len());
    for t in tris {
        if let Some(n) = triangle_normal(t) {
            normals.push(n);
            planes.push((t[0], n));
        }
    }
    let Some((axis_d, cutoff)) = cone_axis(&normals) else {
        return Cone::NEVER;
    };
    let axis_f = fvec(axis_d);
    // Push the apex back from the sphere centre along -axis until it is behind every plane:
    // dot(p_i - apex, n_i) >= 0 for all i, i.e. t >= dot(center - p_i, n_i) / dot(axis, n_i).
    let center = dvec(sphere.center);
    let mut t = planes
        .iter()
        .map(|(p, n)| (center - *p).dot(*n) / n.dot(axis_d))
        .fold(0.0, f64::max);
    // Re-check with the rounded apex and grow t until rounding no longer breaks the guarantee.
    let scale = sphere.radius as f64 + center.abs().max_element();
    for _ in 0..64 {
        let apex = fvec(center - axis_d * t);
        let ad = dvec(apex);
        if planes.iter().all(|(p, n)| (*p - ad).dot(*n) >= 0.0)
            && apex.iter().all(|c| c.is_finite())
        {
            return Cone {
                apex,
                axis: axis_f,
                cutoff: cutoff as f32,
            };
        }
        t += scale * 1e-6 + t * 1e-6;
    }
    Cone::NEVER
}

/// Checks normal cones for conservativeness from 27 cameras on a grid around and inside the mesh's
/// box: `(culls, violations)`, the (meshlet, camera) pairs a cone culled ([`Cone::culls`], in f32
/// as a shader tests it) and, among their triangles, those facing the camera in f64. A triangle
/// seen edge-on within f32 resolution (|cos| < 1e-6) has no reliable facing, for a rasteriser
/// either, and does not count.
pub fn check_cones(mesh: &Mesh, ml: &Meshlets, cones: &[Cone]) -> (usize, usize) {
    let (lo, hi) = mesh.bounding_box();
    let (lo, hi) = (lo.as_dvec3(), hi.as_dvec3());
    let (mut culls, mut violations) = (0, 0);
    for k in 0..27u32 {
        let t = DVec3::new((k % 3) as f64, ((k / 3) % 3) as f64, (k / 9) as f64) / 2.0;
        let cam = (lo - (hi - lo) * 0.5) + (hi - lo) * 2.0 * t;
        let camf = cam.as_vec3().to_array();
        for (i, cone) in cones.iter().enumerate() {
            if !cone.culls(camf) {
                continue;
            }
            culls += 1;
            for tri in ml.global_triangles(i) {
                let p = tri.map(|v| dvec(mesh.positions[v as usize]));
                let n = (p[1] - p[0]).cross(p[2] - p[0]);
                // The camera as the cone saw it (f32).
                let v = p[0] - cam.as_vec3().as_dvec3();
                if n.dot(v) < -1e-6 * n.length() * v.length() {
                    violations += 1;
                }
            }
        }
    }
    (culls, violations)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn min_sphere_of_known_sets() {
        let pts = [
            DVec3::new(-1.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(0.0, 0.5, 0.0),
        ];
        let (c, r) = min_sphere(&pts);
        assert!((c - DVec3::ZERO).length() < 1e-12 && (r - 1.0).abs() < 1e-12);
        // Regular tetrahedron: circumsphere.
        let tet = [
            DVec3::new(1.0, 1.0, 1.0),
            DVec3::new(1.0, -1.0, -1.0),
            DVec3::new(-1.0, 1.0, -1.0),
            DVec3::new(-1.0, -1.0, 1.0),
        ];
        let (c, r) = min_sphere(&tet);
        assert!(c.length() < 1e-12 && (r - 3f64.sqrt()).abs() < 1e-12);
        // Many coplanar and duplicate points.
        let mut grid = Vec::new();
        for i in 0..10 {
            for j in 0..10 {
                grid.push(DVec3::new(i as f64, j as f64, 0.0));
                grid.push(DVec3::new(i as f64, j as f64, 0.0));
            }
        }
        let (c, r) = min_sphere(&grid);
        assert!((c - DVec3::new(4.5, 4.5, 0.0)).length() < 1e-9);
        assert!((r - (2.0 * 4.5f64 * 4.5).sqrt()).abs() < 1e-9);
    }

    #[test]
    fn cone_axis_needs_the_normals_inside_a_half_space() {
        // Normals 60 degrees apart around +z: a cone along +z, cutoff sin(60 deg) plus the margin.
        let (s, c) = (60f64.to_radians().sin(), 60f64.to_radians().cos());
        let tilted = [DVec3::new(s, 0.0, c), DVec3::new(-s, 0.0, c)];
        let (axis, cutoff) = cone_axis(&tilted).expect("a cone");
        assert!((axis - DVec3::Z).length() < 1e-6, "{axis}");
        // The widest normal's dot with the axis is cos 60; the cutoff sqrt(1 - cos^2) is sin 60.
        assert!((cutoff - s).abs() < 1e-4, "{cutoff}");
        // Opposite normals, normals over a whole half-space, and none: no cone.
        assert_eq!(cone_axis(&[DVec3::Z, -DVec3::Z]), None);
        assert_eq!(cone_axis(&[DVec3::X, DVec3::Y, -DVec3::X]), None);
        assert_eq!(cone_axis(&[]), None);
        // A zero-area triangle has no normal; a counter-clockwise one in the xy plane faces +z.
        assert_eq!(triangle_normal(&[DVec3::ZERO, DVec3::X, DVec3::X]), None);
        assert_eq!(
            triangle_normal(&[DVec3::ZERO, DVec3::X, DVec3::Y]),
            Some(DVec3::Z)
        );
    }

    #[test]
    fn cone_of_a_flat_patch_culls_from_behind_only() {
        let tris = [
            [DVec3::ZERO, DVec3::X, DVec3::Y],
            [DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y],
        ];
        let pts: Vec<DVec3> = tris.iter().flatten().copied().collect();
        let cone = normal_cone(&tris, bounding_sphere(&pts));
        assert!(cone.can_cull());
        assert!(cone.culls([0.5, 0.5, -3.0]));
        assert!(!cone.culls([0.5, 0.5, 3.0]));
        // Grazing view from within the plane: the patch is edge-on, not culled.
        assert!(!cone.culls([5.0, 0.5, 0.0]));
    }

    #[test]
    fn degenerate_triangles_give_no_nan() {
        let p = DVec3::new(1.0, 2.0, 3.0);
        let cone = normal_cone(
            &[[p, p, p], [p, p * 2.0, p * 3.0]],
            bounding_sphere(&[p, p * 2.0, p * 3.0]),
        );
        assert_eq!(cone, Cone::NEVER);
        let s = bounding_sphere(&[p]);
        assert_eq!(s.radius, 0.0);
    }
}

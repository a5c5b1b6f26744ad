//! Cluster LOD: the DAG checks, the crack test over random (view, threshold) pairs, streaming
//! prefixes, determinism across thread counts, welding, and the LOD file's round trip.

mod common;

use glam::Vec3;
use meshletlab::lod::flat::{self, Flat, Query};
use meshletlab::lod::{self, io::LodFile, select, Lod};
use meshletlab::mesh::{generate, Mesh};
use meshletlab::meshlet::Limits;
use std::collections::HashSet;

fn build(m: &Mesh) -> Lod {
    let s = meshletlab::strategy::by_name("meshopt", &Default::default()).unwrap();
    lod::build(m, s.as_ref(), Limits::DEFAULT, &Default::default())
}

/// What the crack test needs of the source (over welded vertices).
struct Shape {
    /// Vertices on the boundary (edges used once).
    boundary: HashSet<u32>,
    /// Every edge used twice, in opposite directions.
    closed: bool,
    /// Some edge used more than twice.
    non_manifold: bool,
}

fn source_shape(m: &Mesh, remap: &[u32]) -> Shape {
    let mut edges = std::collections::HashMap::<(u32, u32), (u32, u32)>::new();
    for t in 0..m.triangle_count() {
        let t = m.triangle(t).map(|v| remap[v as usize]);
        if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
            continue;
        }
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            let e = edges.entry((a.min(b), a.max(b))).or_insert((0, 0));
            e.0 += 1;
            e.1 += (a < b) as u32;
        }
    }
    Shape {
        closed: edges.values().all(|&(u, d)| u == 2 && d == 1),
        non_manifold: edges.values().any(|&(u, _)| u > 2),
        boundary: edges
            .iter()
            .filter(|(_, &(u, _))| u == 1)
            .flat_map(|(&(a, b), _)| [a, b])
            .collect(),
    }
}

/// Seeded random views: directions on the sphere, distances 0.5..64 radii (log-uniform), thresholds
/// 0.25..8 pixels.
fn views(m: &Mesh, n: usize, seed: u64) -> Vec<select::View> {
    let (lo, hi) = m.bounding_box();
    let (c, r) = ((lo + hi) * 0.5, (hi - lo).length() * 0.5);
    let mut s = seed;
    let mut unit = || {
        s = generate::splitmix64(s);
        (s >> 11) as f32 / (1u64 << 53) as f32
    };
    meshletlab::render::random_directions(n, seed ^ 0x5eed)
        .into_iter()
        .map(|dir| {
            let dist = 0.5 * 128f32.powf(unit());
            let px = 0.25 * 32f32.powf(unit());
            select::View::new(c + dir * r * dist, 720.0, 60f32.to_radians(), px)
        })
        .collect()
}

/// Counts over the cuts of one mesh.
#[derive(Default)]
struct Tally {
    /// Edges used more than twice: on a closed source only where two neighbouring groups
    /// simplified to the same triangle from both sides (a zero-area fin between them, watertight
    /// but not manifold).
    over: usize,
    /// Open edges off the source's boundary (allowed, and counted, on non-manifold sources only).
    open: usize,
}

/// One cut: exactly one meshlet per DAG path, and no crack: on a closed source every edge is used
/// as often in one direction as in the other (watertight); on an open manifold source every
/// once-used edge joins two source boundary vertices. Non-manifold sources are counted.
/// One mesh's DAG and what the crack test compares it with.
struct Subject<'a> {
    lod: &'a Lod,
    flat: &'a Flat,
    remap: &'a [u32],
    shape: &'a Shape,
}

fn check_view(s: &Subject, v: &select::View, finest: usize, name: &str, t: &mut Tally) {
    let Subject {
        lod,
        flat,
        remap,
        shape,
    } = *s;
    let sel = select::select(lod, v, finest);
    select::check_cut(lod, &sel, finest).unwrap_or_else(|e| panic!("{name}: {e}"));
    // The flattened selection the kernel and the task shader mirror picks the same meshlets.
    let q = Query {
        view: *v,
        finest,
        frustum: None,
        cone: false,
    };
    let flat_sel: Vec<u32> = flat::select(flat, &q);
    let per_level: Vec<u32> = (0..lod.levels.len())
        .rev()
        .flat_map(|l| {
            let start = flat.starts[l];
            sel[l]
                .iter()
                .enumerate()
                .filter(|(_, &s)| s)
                .map(move |(m, _)| start + m as u32)
        })
        .collect();
    assert_eq!(flat_sel, per_level, "{name}: flat selection differs");
    for (&(a, b), &(uses, forward)) in &select::cut_edges(lod, &sel, remap) {
        if uses == 1 && !(shape.boundary.contains(&a) && shape.boundary.contains(&b)) {
            assert!(
                shape.non_manifold,
                "{name}: crack: edge {a}-{b} is open but not on the source's boundary"
            );
            t.open += 1;
        }
        if shape.closed {
            assert_eq!(
                2 * forward,
                uses,
                "{name}: edge {a}-{b}: {forward} of {uses} uses one way"
            );
        }
        t.over += (uses > 2) as usize;
    }
}

fn dag_checks(name: &str, m: &Mesh, views_per_mesh: usize) {
    let lod = build(m);
    let remap = lod::weld(m);
    let shape = source_shape(m, &remap);
    let flat = Flat::new(m, &lod);
    let subject = Subject {
        lod: &lod,
        flat: &flat,
        remap: &remap,
        shape: &shape,
    };
    // Level 0 is the strategy's meshlets of the source: the validator checks them; the file's
    // check adds limits on every level and monotonic errors and bounds.
    let file = LodFile {
        source_vertices: m.vertex_count() as u32,
        source_triangles: m.triangle_count() as u32,
        fingerprint: m.fingerprint(),
        lod: lod.clone(),
    };
    file.check(m, std::path::Path::new(name)).unwrap();
    assert_eq!(lod.stuck_groups(), 0, "{name}: stuck groups");
    // Every level about halves the one below, and all levels stay within 2x the source.
    for w in lod.levels.windows(2) {
        let (a, b) = (lod::level_triangles(&w[0]), lod::level_triangles(&w[1]));
        assert!(
            b * 10 <= a * 7,
            "{name}: level of {a} triangles reduced only to {b}"
        );
    }
    assert!(
        lod.triangle_count() <= 2 * m.triangle_count(),
        "{name}: {} triangles in all levels",
        lod.triangle_count()
    );
    let vs = views(m, views_per_mesh, 7);
    let mut t = Tally::default();
    for v in &vs {
        check_view(&subject, v, 0, name, &mut t);
    }
    // Streaming: every prefix of levels, coarsest first, with the streamed rule.
    for finest in 1..lod.levels.len() {
        for v in vs.iter().step_by(50) {
            check_view(&subject, v, finest, name, &mut t);
        }
    }
    println!(
        "{name}: {} levels, {} roots, {:.3}x triangles; {} views: cuts exact; over all cuts: {} edges used > 2 times, {} open edges off the boundary{}",
        lod.levels.len(),
        lod.roots(),
        lod.triangle_count() as f64 / m.triangle_count() as f64,
        vs.len(),
        t.over,
        t.open,
        if shape.non_manifold { " (non-manifold source)" } else { "" }
    );
}

#[test]
fn dag_is_monotonic_and_every_cut_is_crack_free_on_every_shared_mesh() {
    for f in common::mesh_files() {
        let m = meshletlab::mesh::load(&f).unwrap();
        let name = f.file_name().unwrap().to_string_lossy().to_string();
        dag_checks(&name, &m, 1000);
    }
}

#[test]
fn generated_closed_open_and_unwelded_meshes() {
    let sphere = generate::noisy_sphere(5, 0.15, 3);
    dag_checks("noisy-sphere", &sphere, 1000);
    dag_checks("terrain", &generate::terrain(120, 2), 1000);
    dag_checks("knot", &generate::knot_tube(300, 24, 4), 1000);
    // Faceted: every triangle has its own three vertices. Welding makes it reduce like the welded
    // sphere, and the welded edges are still crack-free.
    let mut facets = Mesh::default();
    for t in 0..sphere.triangle_count() {
        for v in sphere.triangle(t) {
            facets.indices.push(facets.positions.len() as u32);
            facets.positions.push(sphere.positions[v as usize]);
        }
    }
    dag_checks("faceted-sphere", &facets, 1000);
    let (a, b) = (build(&sphere), build(&facets));
    assert_eq!(
        a.levels.len(),
        b.levels.len(),
        "faceted input reduces as the welded one"
    );
}

#[test]
fn output_is_identical_for_any_thread_count() {
    let m = common::load("stanford_bunny");
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap()
        .install(|| build(&m));
    let two = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap()
        .install(|| build(&m));
    assert!(one == two, "different DAGs for 1 and 2 threads");
}

#[test]
fn lod_file_round_trips_and_rejects_corruption() {
    let m = common::load("fandisk");
    let f = LodFile {
        source_vertices: m.vertex_count() as u32,
        source_triangles: m.triangle_count() as u32,
        fingerprint: m.fingerprint(),
        lod: build(&m),
    };
    let p = std::path::Path::new("fandisk.lod");
    let bytes = f.to_bytes();
    let back = LodFile::from_bytes(&bytes, p).unwrap();
    assert!(back == f);
    back.check(&m, p).unwrap();
    // Truncation anywhere, a trailing byte, another mesh: typed errors naming the file.
    for cut in [0, 7, 40, bytes.len() / 2, bytes.len() - 1] {
        let e = LodFile::from_bytes(&bytes[..cut], p).unwrap_err();
        assert!(e.to_string().starts_with("fandisk.lod: "), "{e}");
    }
    let mut long = bytes.clone();
    long.push(0);
    assert!(LodFile::from_bytes(&long, p).is_err());
    let other = common::load("stellarium_gaspra");
    assert!(back.check(&other, p).is_err());
    // A parent error below its child's: monotonicity fails the check.
    let mut bad = f.clone();
    let i = &mut bad.lod.levels[0].info[0];
    i.parent_error = -1.0;
    assert!(bad
        .check(&m, p)
        .unwrap_err()
        .to_string()
        .contains("parent error"));
}

#[test]
fn the_checks_catch_a_broken_cut() {
    let m = common::load("fandisk");
    let lod = build(&m);
    let remap = lod::weld(&m);
    // Far enough that coarse levels are drawn, near enough that several meshlets are.
    let (lo, hi) = m.bounding_box();
    let (c, r) = ((lo + hi) * 0.5, (hi - lo).length() * 0.5);
    let v = &select::View::new(c + Vec3::new(0.6, 0.0, 0.8) * r * 6.0, 720.0, 1.0, 1.0);
    let sel = select::select(&lod, v, 0);
    assert!(
        !sel[0].iter().any(|&b| b),
        "level 0 is not drawn from 6 radii"
    );
    select::check_cut(&lod, &sel, 0).unwrap();
    let (l, k) = sel
        .iter()
        .enumerate()
        .find_map(|(l, s)| s.iter().position(|&b| b).map(|k| (l, k)))
        .unwrap();
    // One meshlet dropped: a hole (paths selecting nothing) and open edges on a closed source.
    let mut hole = sel.clone();
    hole[l][k] = false;
    assert!(select::check_cut(&lod, &hole, 0).is_err());
    let open = select::cut_edges(&lod, &hole, &remap)
        .values()
        .filter(|&&(u, _)| u == 1)
        .count();
    assert!(open > 0, "dropping a meshlet must open edges");
    // A meshlet drawn with one of its parents: some path selects two.
    let mut twice = sel.clone();
    twice[0][0] = true;
    assert!(select::check_cut(&lod, &twice, 0).is_err());
}

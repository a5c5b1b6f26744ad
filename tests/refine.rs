//! `+refine` on the shared real meshes: every refined output validates, never has more meshlets or
//! more meshlets in pieces than its input, and does not depend on the thread count; at the default
//! effort it beats meshoptimizer's count on the bunny at no worse radius and cullability, as
//! `partition` does, and k-medoids reaches the fills the refinement aims at.

mod common;

use meshletlab::mesh;
use meshletlab::meshlet::{
    bounds, metrics::is_edge_connected, validate, Limits, Meshlets, Metrics,
};
use meshletlab::strategy::{self, refine, Options};

fn pieces(ml: &Meshlets) -> usize {
    (0..ml.len())
        .filter(|&i| !is_edge_connected(ml.meshlet_triangles(i)))
        .count()
}

/// A refined output validates and has no more meshlets, nor more meshlets in pieces, than its input.
fn check_refined(
    m: &meshletlab::mesh::Mesh,
    input: &Meshlets,
    out: &Meshlets,
    limits: Limits,
    what: &str,
) {
    validate(m, out, limits).unwrap_or_else(|e| panic!("{what}: {e}"));
    assert!(
        out.len() <= input.len(),
        "{what}: {} -> {}",
        input.len(),
        out.len()
    );
    assert!(
        pieces(out) <= pieces(input),
        "{what}: more meshlets in pieces"
    );
}

fn metrics(m: &meshletlab::mesh::Mesh, ml: &Meshlets, limits: Limits) -> Metrics {
    Metrics::compute(m, ml, limits, &bounds::compute_bounds(m, ml), None)
}

/// Meshes below this many triangles have every strategy's output refined at every count preset;
/// the four larger ones (270 k to 870 k triangles) only these inputs, at the default preset:
/// meshoptimizer's (the count comparison's subject), the paper's greedy (loose, vertex-bound) and
/// nvidia's (the worst input: the most dissolving), so that CI stays short. The other count
/// presets are refined on the six smaller meshes, from every strategy (meshoptimizer's at full
/// effort): on the large meshes they would run the same moves at another limit, which a size does
/// not change.
const EVERY_STRATEGY_BELOW: usize = 100_000;
const LARGE_MESH_INPUTS: &[&str] = &["meshopt", "greedy", "nvidia"];

/// Below this many triangles meshopt's and k-medoids' outputs get the full effort (the default
/// `+refine`) and the thread-count check; elsewhere the fast effort runs the same boundary moves
/// and dissolving in one round, without rebuilds and with a smaller search.
fn full_effort(name: &str, triangles: usize) -> bool {
    (name == "meshopt" && triangles < EVERY_STRATEGY_BELOW)
        || (name == "kmedoids" && triangles < 25_000)
}

/// Strategy outputs on the shared meshes whose stem `pick` selects (which must be `meshes` of
/// them, all small or all large) refined: each validates, never has more meshlets or more meshlets
/// in pieces than its input, and (at full effort) does not depend on the thread count.
fn refine_every_output(small: bool, pick: impl Fn(&str) -> bool, meshes: usize) {
    let mut opts = Options::default();
    opts.kmedoids.paper.budget = std::time::Duration::from_millis(500);
    let (one, many) = (common::pool(1), common::pool(common::MANY_THREADS));
    let (mut checked, mut picked) = (0, 0);
    let presets: &[Limits] = if small {
        &Limits::COUNT_PRESETS
    } else {
        &[Limits::DEFAULT]
    };
    for f in common::mesh_files() {
        if !pick(&meshletlab::bench::build::mesh_name(&f)) {
            continue;
        }
        let m = mesh::load(&f).unwrap();
        assert_eq!(
            m.triangle_count() < EVERY_STRATEGY_BELOW,
            small,
            "{}",
            f.display()
        );
        picked += 1;
        for &limits in presets {
            for name in strategy::NAMES
                .iter()
                .filter(|n| !strategy::SLOW.contains(n))
                // Already packed by the same boundary moves and chains: refining it again is no
                // new input for `+refine`, and would cost a minute of every test run.
                .filter(|n| **n != "partition")
                .filter(|n| small || LARGE_MESH_INPUTS.contains(n))
            {
                let input = strategy::by_name(name, &opts).unwrap().build(&m, limits);
                let full = full_effort(name, m.triangle_count());
                let effort = if full {
                    refine::Effort::Full
                } else {
                    refine::Effort::Fast
                };
                let config = refine::Config::new(effort);
                let out = many.install(|| refine::refine(&m, &input, limits, config));
                let what = format!("{} {name}+refine {effort:?} {limits}", f.display());
                check_refined(&m, &input, &out, limits, &what);
                if full {
                    // Determinism: the same on one thread as on many (the input too).
                    let again = one.install(|| {
                        let input = strategy::by_name(name, &opts).unwrap().build(&m, limits);
                        refine::refine(&m, &input, limits, config)
                    });
                    assert_eq!(out, again, "{what}: differs on one thread");
                }
                checked += 1;
            }
        }
    }
    // A missing mesh must not pass silently.
    assert_eq!(picked, meshes, "shared meshes picked");
    let per_mesh = if small {
        3 * (strategy::NAMES.len() - strategy::SLOW.len() - 1)
    } else {
        LARGE_MESH_INPUTS.len()
    };
    assert_eq!(checked, meshes * per_mesh, "refined outputs checked");
}

/// The bunny is the largest of the six small meshes, as long to refine as the other five together:
/// it has its own test, so that the test threads share the work.
const BUNNY: &str = "stanford_bunny";

/// [`refine_every_output`] on the bunny.
#[test]
fn every_refined_output_validates_on_the_bunny() {
    refine_every_output(true, |stem| stem == BUNNY, 1);
}

/// [`refine_every_output`] on the five other shared meshes below 100 k triangles.
#[test]
fn every_refined_output_validates_on_the_other_small_meshes() {
    refine_every_output(
        true,
        |stem| stem != BUNNY && !LARGE_MESHES.contains(&stem),
        5,
    );
}

/// The shared meshes above 100 k triangles.
const LARGE_MESHES: &[&str] = &[
    "igea",
    "openfoam_motorbike",
    "pycortex_S1_pia_lh",
    "stanford_dragon_vrip",
];

/// The dragon holds about half of the large meshes' triangles: it has its own test, so that the
/// test threads share the work.
const DRAGON: &str = "stanford_dragon_vrip";

/// [`refine_every_output`] on the dragon.
#[test]
fn refined_outputs_validate_on_the_dragon() {
    refine_every_output(false, |stem| stem == DRAGON, 1);
}

/// [`refine_every_output`] on the three other shared meshes above 100 k triangles.
#[test]
fn refined_outputs_validate_on_the_other_large_meshes() {
    refine_every_output(
        false,
        |stem| stem != DRAGON && LARGE_MESHES.contains(&stem),
        3,
    );
}

/// Annealing never leaves the input worse: `+refine-max` of meshoptimizer's meshlets on the small
/// meshes at every count preset validates and has at most as many meshlets (its first, hot anneal
/// can end with a meshlet over a limit, which must be driven out or undone, not split).
#[test]
fn refine_max_never_adds_meshlets() {
    let opts = Options::default();
    for f in common::mesh_files() {
        let m = mesh::load(&f).unwrap();
        if m.triangle_count() >= 20_000 {
            continue;
        }
        for limits in Limits::COUNT_PRESETS {
            let input = strategy::by_name("meshopt", &opts)
                .unwrap()
                .build(&m, limits);
            let out = refine::refine(&m, &input, limits, refine::Config::new(refine::Effort::Max));
            let what = format!("{} meshopt+refine-max {limits}", f.display());
            check_refined(&m, &input, &out, limits, &what);
        }
    }
}

/// The bunny, meshoptimizer's meshlets of it at 64/126, and the fewest meshlets any
/// meshoptimizer builder makes there.
fn bunny_and_meshopt() -> (mesh::Mesh, Meshlets, usize) {
    let m = common::load("stanford_bunny");
    let opts = Options::default();
    let peer = |n: &str| {
        strategy::by_name(n, &opts)
            .unwrap()
            .build(&m, Limits::DEFAULT)
    };
    let best_peer = ["meshopt", "meshopt-scan", "meshopt-spatial"]
        .iter()
        .map(|n| peer(n).len())
        .min()
        .unwrap();
    let input = peer("meshopt");
    (m, input, best_peer)
}

/// Meshlets whose normal cone cannot cull. Cullability by count: the share of cullable meshlets
/// drops by a hair when the same few non-cullable meshlets sit among fewer meshlets, which is no
/// loss to a renderer.
fn non_cullable(x: &Metrics) -> f64 {
    ((1.0 - x.cone_cullable) * x.meshlets as f64).round()
}

/// The count goal on the bunny: fewer meshlets than every meshoptimizer builder, with
/// mean radius and number of meshlets that cannot be cone-culled no worse than `meshopt`'s.
fn assert_beats_meshoptimizer(ours: &Metrics, base: &Metrics, best_peer: usize) {
    assert!(
        ours.meshlets < best_peer,
        "{} vs {best_peer}",
        ours.meshlets
    );
    assert!(ours.mean_radius_rel <= base.mean_radius_rel, "{ours:?}");
    assert!(
        non_cullable(ours) <= non_cullable(base),
        "{ours:?} vs {base:?}"
    );
}

/// `+refine` on the bunny at 64/126 meets the goal at the default effort (its per-victim anneal).
#[test]
fn refinement_beats_meshoptimizer_on_the_bunny() {
    let (m, input, best_peer) = bunny_and_meshopt();
    let limits = Limits::DEFAULT;
    let base = metrics(&m, &input, limits);
    let s = strategy::by_name("meshopt+refine", &Options::default()).unwrap();
    let ml = s.build(&m, limits);
    validate(&m, &ml, limits).unwrap();
    let ours = metrics(&m, &ml, limits);
    assert_beats_meshoptimizer(&ours, &base, best_peer);
    // meshoptimizer leaves some meshlets in pieces; the refinement never adds one.
    let in_pieces = |x: &Metrics| ((1.0 - x.connected) * x.meshlets as f64).round();
    assert!(in_pieces(&ours) <= in_pieces(&base), "{ours:?} vs {base:?}");
}

/// `partition` on the bunny at 64/126 meets the goal too. The cone step (7) is what brings the
/// last non-cullable meshlet level: without it the partition keeps three where meshoptimizer has
/// two.
#[test]
fn partition_beats_meshoptimizer_on_the_bunny() {
    use meshletlab::strategy::refine::partition::{partition_with_stats, Config};
    let (m, input, best_peer) = bunny_and_meshopt();
    let limits = Limits::DEFAULT;
    let base = metrics(&m, &input, limits);
    let (ml, stats) = partition_with_stats(&m, &input, limits, Config::default());
    check_refined(&m, &input, &ml, limits, "partition");
    let ours = metrics(&m, &ml, limits);
    assert_beats_meshoptimizer(&ours, &base, best_peer);
    assert!(stats.cones_fixed > 0, "{stats:?}");
    // The same partition without the cone step: one more non-cullable meshlet per cell fixed.
    let without = Config {
        cone_repair: false,
        ..Config::default()
    };
    let (plain, _) = partition_with_stats(&m, &input, limits, without);
    assert_eq!(plain.len(), ml.len());
    // The step's moves keep every cell in one piece.
    assert!(pieces(&ml) <= pieces(&plain));
    assert_eq!(
        non_cullable(&metrics(&m, &plain, limits)),
        non_cullable(&ours) + stats.cones_fixed as f64
    );
}

/// k-medoids keeps its small radii and, refined at the default effort, fills its meshlets: vertex
/// fill >= 0.95 and primitive fill >= 0.74 on the bunny, with fewer meshlets than k-medoids alone
/// (which fills them nearly as well since its seeds are taken deepest first: one meshlet more).
#[test]
fn refined_kmedoids_fills_its_meshlets() {
    let m = common::load("stanford_bunny");
    let opts = Options::default();
    let limits = Limits::DEFAULT;
    let plain = metrics(
        &m,
        &strategy::by_name("kmedoids", &opts)
            .unwrap()
            .build(&m, limits),
        limits,
    );
    let ml = strategy::by_name("kmedoids+refine", &opts)
        .unwrap()
        .build(&m, limits);
    validate(&m, &ml, limits).unwrap();
    let r = metrics(&m, &ml, limits);
    assert!(r.vertex_fill >= 0.95 && r.primitive_fill >= 0.74, "{r:?}");
    let meshopt = metrics(
        &m,
        &strategy::by_name("meshopt", &opts)
            .unwrap()
            .build(&m, limits),
        limits,
    );
    assert!(r.mean_radius_rel <= meshopt.mean_radius_rel, "{r:?}");
    assert!(r.meshlets < plain.meshlets);
}

/// `bench build` on one small mesh writes the refined rows and the per-preset comparison, and the
/// refined counts in it never exceed meshoptimizer's.
#[test]
fn bench_build_writes_the_per_preset_comparison() {
    use meshletlab::bench::build;
    let dir = common::scratch("bench-build");
    let meshes = dir.join("meshes");
    std::fs::create_dir_all(&meshes).unwrap();
    let src = common::meshes_dir().join("fandisk.ply.zst");
    std::os::unix::fs::symlink(&src, meshes.join("fandisk.ply.zst")).unwrap();
    let mut options = Options::default();
    options.kmedoids.paper.budget = std::time::Duration::from_millis(500);
    let cfg = build::Config {
        meshes,
        runs: 1,
        out: dir.join("out"),
        limits: Limits::DEFAULT,
        strategies: Vec::new(),
        options,
        quiet: true,
        refined: true,
        refine_max: false,
        stress: false,
    };
    let rows = build::run(&cfg).unwrap();
    for limits in Limits::COUNT_PRESETS {
        let count = |n: &str| {
            rows.iter()
                .find(|r| r.eval.limits == limits && r.eval.strategy == n)
                .unwrap_or_else(|| panic!("no {n} row at {limits}"))
                .eval
                .metrics
                .meshlets
        };
        assert!(count("meshopt+refine") <= count("meshopt"), "{limits}");
        assert!(count("partition") <= count("meshopt"), "{limits}");
        assert!(count("meshopt-scan") >= limits.min_meshlets(rows[0].triangles));
    }
    assert!(rows.iter().any(|r| r.eval.strategy == "kmedoids+refine"));
    assert!(!rows
        .iter()
        .any(|r| r.eval.strategy.ends_with("+refine-max")));
    let md = std::fs::read_to_string(dir.join("out/strategies.md")).unwrap();
    for h in [
        "### 64/126",
        "### 64/84",
        "### 128/128",
        "hard bound",
        "meshopt+refine",
        "`partition` against every meshoptimizer builder",
    ] {
        assert!(md.contains(h), "strategies.md lacks {h}");
    }
    let csv = std::fs::read_to_string(dir.join("out/build.csv")).unwrap();
    assert!(csv.contains(",meshopt+refine,64/84,"));
}

//! The physical limit of each GPU kernel (background: `docs/gpu-clustering.md`), for `bench gpu`: the bytes a kernel
//! must read and write, the floor this machine's measured bandwidth puts under its time, and its
//! time over that floor; the same floor at an H100's bandwidth, as a projection.
//!
//! "Must move" counts every array a kernel touches once, as 32-bit words: the least traffic its
//! job allows, with no cache reuse and no atomics' extra cost. A kernel far above its floor is
//! bound by something else (dispatch count, latency of dependent loads, SIMD divergence), which is
//! what the ratio tells.

use super::table::{
    Align::{Left, Right},
    Style, Table,
};
use crate::gpu::{copy::Bandwidth, Profile};
use rayon::prelude::*;

/// An H100 SXM's HBM3 bandwidth (NVIDIA's data sheet), for the projection column.
pub const H100_BYTES_PER_S: f64 = 3.35e12;

/// Sizes the byte counts are functions of.
#[derive(Clone, Copy, Debug)]
pub struct Sizes {
    /// Triangles.
    pub t: u64,
    /// Vertices.
    pub v: u64,
    /// Dual-graph items (edge-adjacent pairs, both ways).
    pub e: u64,
    /// Share of the triangles whose cluster an `update` call recomputes (1 when every cluster
    /// is; the flat method's cache skips unchanged clusters, so there it is the share of updates
    /// run, taken as a share of triangles).
    pub update_share: f64,
}

/// What a kernel must move in one call, as a formula and in bytes; `None` for kernels whose size
/// the profile does not give (prefix sums over arrays of several lengths, per-cluster
/// bookkeeping), all of which are a few percent of the time.
pub fn bytes_per_call(kernel: &str, s: &Sizes) -> Option<(&'static str, f64)> {
    let (t, v, e) = (s.t as f64, s.v as f64, s.e as f64);
    let w = 4.0;
    Some(match kernel {
        // Adjacency.
        "vt_count" => (
            "indices 3T, counts 2V (read, write)",
            w * (3.0 * t + 2.0 * v),
        ),
        "vt_scatter" => (
            "indices 3T, offsets V, cursors 2V, items 3T",
            w * (6.0 * t + 3.0 * v),
        ),
        "vt_sort" => ("offsets V, items 6T (read, write)", w * (6.0 * t + v)),
        "dual_count" => (
            "indices 3T, offsets V, items 3T, degenerate T, out 5T",
            w * (12.0 * t + v),
        ),
        "dual_fill" => ("offsets T, gathered 3T, rows E", w * (4.0 * t + e)),
        // Flat k-medoids; `push` per assignment (all its BFS levels together).
        "clear" => ("labels, distances 2T", w * 2.0 * t),
        "push" => (
            "dual offsets T, rows E, labels and distances 4T (read, write)",
            w * (5.0 * t + e),
        ),
        "mem_count" => ("labels T", w * t),
        "mem_scatter" => ("labels T, members T", w * 2.0 * t),
        "update" => (
            "share x (members T, labels T, dual offsets T, rows E)",
            s.update_share * w * (3.0 * t + e),
        ),
        "stats" => ("members T, indices 3T, distances T", w * 5.0 * t),
        "remember" | "dirty_mark" => ("labels T, per-triangle medoid T", w * 2.0 * t),
        "dist_partial" => ("distances T", w * t),
        _ => return None,
    })
}

/// Calls of `kernel` in `p`: `push` runs a dispatch per BFS level, so its calls are the
/// assignments (one `clear` each); every other kernel is one dispatch per call.
fn calls(kernel: &str, p: &Profile) -> u64 {
    let n = |k: &str| p.per_kernel.get(k).map_or(0, |e| e.0);
    match kernel {
        "push" => n("clear"),
        _ => n(kernel),
    }
}

/// One kernel of one profiled run.
pub struct Row {
    /// Which run (`kmedoids-flat`).
    pub run: &'static str,
    /// Entry point.
    pub kernel: &'static str,
    /// The must-move formula.
    pub formula: &'static str,
    /// Calls in the run.
    pub calls: u64,
    /// Bytes moved in the run at the floor.
    pub bytes: f64,
    /// Measured kernel time, seconds.
    pub seconds: f64,
    /// Bytes per second the floor is taken at (the copy kernel's).
    pub bandwidth: f64,
}

impl Row {
    /// The floor at this machine's measured bandwidth, seconds.
    pub fn floor(&self) -> f64 {
        self.bytes / self.bandwidth
    }
}

/// The rows of one profiled run, largest measured time first; kernels without a formula left out.
pub fn rows(run: &'static str, p: &Profile, s: &Sizes, copy: &Bandwidth) -> Vec<Row> {
    let mut out: Vec<Row> = p
        .per_kernel
        .iter()
        .filter_map(|(&kernel, &(_, seconds))| {
            let (formula, per_call) = bytes_per_call(kernel, s)?;
            let calls = calls(kernel, p);
            Some(Row {
                run,
                kernel,
                formula,
                calls,
                bytes: per_call * calls as f64,
                seconds,
                bandwidth: copy.per_second(),
            })
        })
        .collect();
    out.sort_by(|a, b| b.seconds.total_cmp(&a.seconds).then(a.kernel.cmp(b.kernel)));
    out
}

/// The table: markdown for gpu.md, CSV with more digits.
pub fn table<'a>() -> Table<'a, Row> {
    let ms = |x: f64| format!("{:.2}", x * 1e3);
    Table::new(Style::Compact)
        .col("run", Left, |r: &Row| r.run.to_string())
        .md("kernel", Left, |r| format!("`{}`", r.kernel))
        .csv_only("kernel", |r| r.kernel.to_string())
        .col("must move per call (words)", Left, |r| {
            r.formula.to_string()
        })
        .col("calls", Right, |r| r.calls.to_string())
        .split(
            "MB moved",
            Right,
            |r| format!("{:.1}", r.bytes / 1e6),
            "bytes",
            |r| format!("{:.0}", r.bytes),
        )
        .split(
            "measured ms",
            Right,
            move |r| ms(r.seconds),
            "measured_s",
            |r| format!("{:.6}", r.seconds),
        )
        .split(
            "floor ms (copy kernel)",
            Right,
            move |r| ms(r.floor()),
            "floor_s",
            |r| format!("{:.6}", r.floor()),
        )
        .split(
            "measured / floor",
            Right,
            |r| format!("{:.1}x", r.seconds / r.floor().max(f64::MIN_POSITIVE)),
            "measured_over_floor",
            |r| format!("{:.3}", r.seconds / r.floor().max(f64::MIN_POSITIVE)),
        )
        .split(
            "H100 floor µs (projection)",
            Right,
            |r| format!("{:.1}", r.bytes / H100_BYTES_PER_S * 1e6),
            "h100_floor_s_projection",
            |r| format!("{:.9}", r.bytes / H100_BYTES_PER_S),
        )
}

/// Host memory bandwidth: `bytes` copied with `copy_from_slice` on one thread, and in one chunk
/// per rayon thread at once; the median of `runs` each, as read-plus-written bytes per second.
pub fn memcpy(bytes: usize, runs: usize) -> (f64, f64) {
    let src: Vec<u8> = (0..bytes)
        .map(|i| (i as u32).wrapping_mul(2654435761) as u8)
        .collect();
    let mut dst = vec![0u8; bytes];
    // Touch the destination once so page faults stay out of the timing.
    dst.copy_from_slice(&src);
    let chunk = bytes.div_ceil(rayon::current_num_threads().max(1)).max(1);
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let time = |f: &mut dyn FnMut()| {
        let t = std::time::Instant::now();
        f();
        t.elapsed().as_secs_f64()
    };
    let one = median(
        (0..runs.max(1))
            .map(|_| time(&mut || dst.copy_from_slice(std::hint::black_box(&src))))
            .collect(),
    );
    let all = median(
        (0..runs.max(1))
            .map(|_| {
                time(&mut || {
                    dst.par_chunks_mut(chunk)
                        .zip(src.par_chunks(chunk))
                        .for_each(|(d, s)| d.copy_from_slice(std::hint::black_box(s)))
                })
            })
            .collect(),
    );
    assert_eq!(dst, src, "memcpy probe copied wrongly");
    let rate = |s: f64| 2.0 * bytes as f64 / s.max(f64::MIN_POSITIVE);
    (rate(one), rate(all))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn formulas_scale_with_the_mesh_and_the_update_share() {
        let s = Sizes {
            t: 1000,
            v: 500,
            e: 3000,
            update_share: 1.0,
        };
        // dual_fill: offsets T, gathered 3T, rows E.
        assert_eq!(
            bytes_per_call("dual_fill", &s).unwrap().1,
            4.0 * (4000.0 + 3000.0)
        );
        let half = Sizes {
            update_share: 0.5,
            ..s
        };
        let full = bytes_per_call("update", &s).unwrap().1;
        assert_eq!(bytes_per_call("update", &half).unwrap().1 * 2.0, full);
        assert!(bytes_per_call("scan_blocks", &s).is_none());
    }

    #[test]
    fn push_counts_one_call_per_assignment() {
        let mut p = Profile::default();
        p.per_kernel.insert("push", (40, 0.4));
        p.per_kernel.insert("clear", (2, 0.01));
        let copy = Bandwidth {
            bytes: 1_000_000,
            seconds: 1e-3,
        };
        let s = Sizes {
            t: 100,
            v: 60,
            e: 300,
            update_share: 1.0,
        };
        let r = rows("flat", &p, &s, &copy);
        let push = r.iter().find(|r| r.kernel == "push").unwrap();
        assert_eq!(push.calls, 2);
        assert_eq!(push.bytes, 2.0 * 4.0 * (500.0 + 300.0));
        // 1 GB/s: the floor is bytes / 1e9.
        assert!((push.floor() - push.bytes / 1e9).abs() < 1e-15);
        // Largest measured time first.
        assert_eq!(r[0].kernel, "push");
    }

    #[test]
    fn memcpy_probe_reports_a_rate() {
        let (one, all) = memcpy(1 << 20, 3);
        assert!(one > 0.0 && all > 0.0 && one.is_finite() && all.is_finite());
    }
}

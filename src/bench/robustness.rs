//! `meshletlab bench robustness`: the mutation fuzzer ([`crate::fuzz`]) at scale, written to
//! results/robustness.md and robustness.csv: cases per format and mutation, their outcomes, the
//! typed-error kinds each format gave, the heaviest and slowest case, and every defect found.

use super::{create_dir, write_file, write_header};
use crate::fuzz::harness::{self, Report, Verdict};
use crate::fuzz::{memory_bound, Mutation, Target, HANG_SECONDS};
use anyhow::{Context, Result};
use std::fmt::Write as _;
use std::path::PathBuf;

/// What to run: the arguments of `meshletlab bench robustness` (it reads no meshes, so it takes
/// the output half of [`super::Common`] only).
#[derive(clap::Args, Clone, Debug)]
pub struct Config {
    /// Output folder.
    #[arg(long, default_value = "results")]
    pub out: PathBuf,
    /// A smoke run ([`super::SMOKE_HELP`] is its help).
    #[arg(long, help = super::SMOKE_HELP)]
    pub smoke: bool,
    /// Number of cases (at least 1).
    #[arg(long, default_value_t = 1_000_000, value_parser = clap::value_parser!(u64).range(1..))]
    pub cases: u64,
    /// Run seed (case k of seed s is always the same file).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Worker processes (default: one per core).
    #[arg(long, value_parser = clap::builder::RangedU64ValueParser::<usize>::new().range(1..))]
    pub workers: Option<usize>,
    /// Write case K's file to -o instead of running (to reproduce a reported case).
    #[arg(long, value_name = "K")]
    pub dump: Option<u64>,
    /// Folder for --dump.
    #[arg(short, long, default_value = ".")]
    pub output: PathBuf,
    /// No progress bar: the command's global `--quiet`, not an argument of the bench.
    #[arg(skip)]
    pub quiet: bool,
}

impl Config {
    /// Number of cases: 2,000 in a smoke run.
    pub fn cases(&self) -> u64 {
        if self.smoke {
            2000
        } else {
            self.cases
        }
    }

    /// Worker processes (default: rayon's thread count).
    pub fn workers(&self) -> usize {
        self.workers.unwrap_or_else(rayon::current_num_threads)
    }
}

/// Runs the cases and writes robustness.md and robustness.csv.
pub fn run(cfg: &Config) -> Result<Report> {
    if cfg.smoke {
        // Refuses results/ as --out, like every smoke run.
        super::smoke::prepare(&cfg.out)?;
    }
    let exe = std::env::current_exe().context("cannot find the meshletlab binary")?;
    let pb = super::progress::bar(cfg.quiet, cfg.cases());
    pb.set_message("cases");
    let progress = {
        let pb = pb.clone();
        Box::new(move |n: u64| {
            if n.is_multiple_of(1000) {
                pb.set_position(n)
            }
        })
    };
    let scratch = std::env::temp_dir().join(format!("meshletlab-fuzz-{}", std::process::id()));
    let report = harness::run(&harness::Config {
        exe,
        seed: cfg.seed,
        cases: cfg.cases(),
        workers: cfg.workers(),
        scratch: scratch.clone(),
        selftest: None,
        stall: harness::STALL,
        progress: Some(progress),
    })?;
    pb.finish_and_clear();
    let _ = std::fs::remove_dir_all(&scratch);
    create_dir(&cfg.out)?;
    write_file(cfg.out.join("robustness.md"), markdown(cfg, &report)?)?;
    write_file(cfg.out.join("robustness.csv"), csv(&report))?;
    Ok(report)
}

fn csv(r: &Report) -> String {
    let mut s = String::from("format,mutation,cases,valid,error,panic,hang,over_limit,crash\n");
    for ((t, m), c) in &r.cells {
        s += &format!("{},{},{}", t.name(), m.name(), c.total());
        for v in c.by_verdict {
            s += &format!(",{v}");
        }
        s.push('\n');
    }
    s
}

fn markdown(cfg: &Config, r: &Report) -> Result<String> {
    let mut md = String::new();
    let t = r.totals();
    write_header(
        &mut md,
        "Robustness: a mutation fuzzer over every reader",
        &format!(
            "meshletlab bench robustness --cases {} --seed {}",
            cfg.cases(),
            r.seed
        ),
        "",
        cfg.smoke.then_some(cfg.out.as_path()),
    );
    writeln!(
        md,
        "{}; {} worker processes, {:.0} s ({:.0} cases/s).\n",
        if cfg!(debug_assertions) {
            "Built with overflow checks and debug assertions: an overflow is a counted panic"
        } else {
            "**Built without overflow checks: an arithmetic overflow would wrap unseen; use `make bench-robustness` (profile fuzz)**"
        },
        cfg.workers(),
        r.seconds,
        r.cases as f64 / r.seconds.max(1e-9)
    )?;
    writeln!(
        md,
        "**{} cases: {} loaded as valid meshes, {} gave a typed error naming the file, {} panics, {} hangs, {} allocations over the bound, {} other crashes.**\n",
        r.cases,
        t.get(Verdict::Valid),
        t.get(Verdict::Error),
        t.get(Verdict::Panic),
        t.get(Verdict::Hang),
        t.get(Verdict::OverLimit),
        t.get(Verdict::Crash)
    )?;
    writeln!(
        md,
        "Each case is a seed file (small valid files of every format, `src/fuzz/corpus.rs`) with one mutation (`src/fuzz/mutate.rs`), run in a child process. \
         A panic is caught and counted; a case longer than {HANG_SECONDS} s, or a worker silent for {} s, is a hang; \
         while a case runs the worker's allocator refuses live heap beyond 64 MiB + 256 × the input's bytes (for `.zst`, the larger of compressed and decompressed size), \
         so an allocation a header asks for aborts the worker and counts as over the limit. \
         The heaviest case peaked at {:.1} MiB on {} input bytes ({:.1} % of its bound of {:.1} MiB); the slowest took {:.1} ms (case {}).\n",
        harness::STALL.as_secs(),
        r.max_peak.0 as f64 / (1 << 20) as f64,
        r.max_peak.1,
        100.0 * r.max_bound_use,
        memory_bound(r.max_peak.1 as usize) as f64 / (1 << 20) as f64,
        r.slowest.1 as f64 / 1e3,
        r.slowest.0,
    )?;
    writeln!(md, "## Cases per format and mutation\n")?;
    writeln!(
        md,
        "Cell: cases (valid / typed error). Defects, if any, are listed below. `-`: the mutation does not apply to the format.\n"
    )?;
    let mut head = String::from("| mutation |");
    let mut rule = String::from("|---|");
    for tg in Target::ALL {
        head += &format!(" {} |", tg.name());
        rule += "---:|";
    }
    writeln!(md, "{head}\n{rule}")?;
    for m in Mutation::ALL {
        let mut row = format!("| {} |", m.name());
        for tg in Target::ALL {
            row += &match r.cells.get(&(tg, m)) {
                Some(c) => format!(
                    " {} ({} / {}) |",
                    c.total(),
                    c.get(Verdict::Valid),
                    c.get(Verdict::Error)
                ),
                None => " - |".into(),
            };
        }
        writeln!(md, "{row}")?;
    }
    let mut row = String::from("| **all** |");
    for tg in Target::ALL {
        let (n, d) = r
            .cells
            .iter()
            .filter(|((t, _), _)| *t == tg)
            .fold((0, 0), |(n, d), (_, c)| (n + c.total(), d + c.defects()));
        row += &format!(" **{n}** ({d} defects) |");
    }
    writeln!(md, "{row}\n")?;
    writeln!(md, "## Typed errors per format\n")?;
    writeln!(md, "| format | error kinds (count) |\n|---|---|")?;
    for tg in Target::ALL {
        let mut kinds: Vec<(&String, &u64)> = r
            .error_kinds
            .iter()
            .filter(|((t, _), _)| *t == tg)
            .map(|((_, k), n)| (k, n))
            .collect();
        kinds.sort_by(|a, b| b.1.cmp(a.1).then(a.0.cmp(b.0)));
        let list: Vec<String> = kinds.iter().map(|(k, n)| format!("{k} ({n})")).collect();
        writeln!(md, "| {} | {} |", tg.name(), list.join(", "))?;
    }
    writeln!(md, "\n## Defects\n")?;
    if r.failures.is_empty() {
        writeln!(md, "None.")?;
    } else {
        writeln!(
            md,
            "Reproduce one with `meshletlab bench robustness --seed {} --dump K -o DIR`.\n\n| case | format | mutation | verdict | message |\n|---|---|---|---|---|",
            r.seed
        )?;
        for f in &r.failures {
            writeln!(
                md,
                "| {} | {} | {} | {} | {} |",
                f.case,
                f.target.name(),
                f.mutation.name(),
                f.verdict.name(),
                f.message.replace('|', "\\|")
            )?;
        }
    }
    Ok(md)
}

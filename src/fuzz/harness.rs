//! Running cases in child processes and collecting the report.
//!
//! The parent splits the case range among workers (`meshletlab fuzz-worker`, one per core), each a
//! single-threaded child in a scratch directory (a glTF naming an external buffer can only reach
//! files there). A worker prints one line per case, `k target mutation outcome peak input micros
//! kind`, flushed, so the parent always knows the case in flight. When a worker dies (an allocation
//! over the bound aborts it) or prints nothing for [`Config::stall`], the parent records the case in
//! flight as over the limit, crashed or hung, kills the worker and starts a new one after that case.

use super::corpus::Corpus;
use super::{alloc, case, input_size, memory_bound, read, Mutation, Outcome, Target, HANG_SECONDS};
use serde::Serialize;
use std::collections::BTreeMap;
use std::io::{BufRead, BufReader, Write};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

/// Default for [`Config::stall`]: a worker that prints nothing for this long is killed and its case
/// counted as a hang (ten times [`HANG_SECONDS`]).
pub const STALL: Duration = Duration::from_secs(20);

/// How a case ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize)]
pub enum Verdict {
    /// Loaded a valid mesh.
    Valid,
    /// A typed error naming the file.
    Error,
    /// A panic (a defect).
    Panic,
    /// Ran past [`HANG_SECONDS`] or stalled the worker (a defect).
    Hang,
    /// Asked for more heap than [`memory_bound`] (a defect).
    OverLimit,
    /// The worker died otherwise, or an error did not name the file (a defect).
    Crash,
}

impl Verdict {
    const NAMES: [&'static str; 6] = ["valid", "error", "panic", "hang", "over-limit", "crash"];
    fn code(self) -> usize {
        self as usize
    }
    fn from_code(c: usize) -> Option<Self> {
        [
            Self::Valid,
            Self::Error,
            Self::Panic,
            Self::Hang,
            Self::OverLimit,
            Self::Crash,
        ]
        .get(c)
        .copied()
    }
    /// Short name.
    pub fn name(self) -> &'static str {
        Self::NAMES[self.code()]
    }
    /// Whether it is a defect.
    pub fn is_defect(self) -> bool {
        self > Verdict::Error
    }
}

/// Outcome counts of one (target, mutation) cell.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct Counts {
    /// Per [`Verdict`] code.
    pub by_verdict: [u64; 6],
}

impl Counts {
    /// Cases in the cell.
    pub fn total(&self) -> u64 {
        self.by_verdict.iter().sum()
    }
    /// Count of one verdict.
    pub fn get(&self, v: Verdict) -> u64 {
        self.by_verdict[v.code()]
    }
    /// Cases that are defects.
    pub fn defects(&self) -> u64 {
        self.by_verdict[2..].iter().sum()
    }
}

/// A defective case, with what is needed to reproduce it.
#[derive(Clone, Debug, Serialize)]
pub struct Failure {
    /// Case index (`meshletlab bench robustness --seed S --dump K -o FILE` writes its file).
    pub case: u64,
    /// Format.
    pub target: Target,
    /// Mutation.
    pub mutation: Mutation,
    /// Verdict.
    pub verdict: Verdict,
    /// Panic message, error text or exit status.
    pub message: String,
}

/// A fuzz run's results.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Report {
    /// Run seed.
    pub seed: u64,
    /// Cases run.
    pub cases: u64,
    /// Outcomes per (target, mutation).
    pub cells: BTreeMap<(Target, Mutation), Counts>,
    /// Typed-error kinds per target.
    pub error_kinds: BTreeMap<(Target, String), u64>,
    /// The first 100 defective cases.
    pub failures: Vec<Failure>,
    /// Highest peak heap of a case over its bound (0..1 when within it).
    pub max_bound_use: f64,
    /// Highest peak heap of a case, bytes, and that case's input size.
    pub max_peak: (u64, u64),
    /// Slowest case: (index, microseconds).
    pub slowest: (u64, u64),
    /// Wall-clock seconds.
    pub seconds: f64,
    /// Worker processes started (more than the worker count means some were restarted).
    pub processes: u64,
}

impl Report {
    /// Totals per verdict over all cells.
    pub fn totals(&self) -> Counts {
        let mut t = Counts::default();
        for c in self.cells.values() {
            for (a, b) in t.by_verdict.iter_mut().zip(c.by_verdict) {
                *a += b;
            }
        }
        t
    }

    fn record(&mut self, f: Failure) {
        if self.failures.len() < 100 {
            self.failures.push(f);
        }
    }

    fn merge(&mut self, o: Report) {
        self.cases += o.cases;
        for (k, c) in o.cells {
            let e = self.cells.entry(k).or_default();
            for (a, b) in e.by_verdict.iter_mut().zip(c.by_verdict) {
                *a += b;
            }
        }
        for (k, n) in o.error_kinds {
            *self.error_kinds.entry(k).or_default() += n;
        }
        for f in o.failures {
            self.record(f);
        }
        if o.max_bound_use > self.max_bound_use {
            self.max_bound_use = o.max_bound_use;
            self.max_peak = o.max_peak;
        }
        if o.slowest.1 > self.slowest.1 {
            self.slowest = o.slowest;
        }
        self.processes += o.processes;
    }
}

/// Deliberate defects for the harness's own test: a reader that panics, loops, or over-allocates.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum SelfTest {
    /// Case 1 panics.
    Panic,
    /// Case 1 never returns.
    Hang,
    /// Case 1 asks for 1 MiB more than its bound (an amount the system would grant).
    Alloc,
}

/// What to run.
pub struct Config {
    /// The `meshletlab` binary (its hidden `fuzz-worker` command runs the cases).
    pub exe: PathBuf,
    /// Run seed.
    pub seed: u64,
    /// Number of cases.
    pub cases: u64,
    /// Worker processes (one per core is right: each is single-threaded).
    pub workers: usize,
    /// Scratch directory (the workers' working directory).
    pub scratch: PathBuf,
    /// Harness self-test instead of the readers.
    pub selftest: Option<SelfTest>,
    /// A worker silent for this long is killed and its case counted as a hang.
    pub stall: Duration,
    /// Called with the number of cases finished so far.
    pub progress: Option<Box<dyn Fn(u64) + Send + Sync>>,
}

/// Runs `cfg.cases` cases in worker processes and collects the report.
pub fn run(cfg: &Config) -> std::io::Result<Report> {
    std::fs::create_dir_all(&cfg.scratch)?;
    let t0 = Instant::now();
    let w = cfg.workers.max(1) as u64;
    let done = std::sync::atomic::AtomicU64::new(0);
    let reports: Vec<std::io::Result<Report>> = std::thread::scope(|s| {
        let handles: Vec<_> = (0..w)
            .map(|i| {
                let (from, to) = (cfg.cases * i / w, cfg.cases * (i + 1) / w);
                let done = &done;
                s.spawn(move || drive(cfg, from, to, done))
            })
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().expect("fuzz driver thread"))
            .collect()
    });
    let mut report = Report {
        seed: cfg.seed,
        ..Default::default()
    };
    for r in reports {
        report.merge(r?);
    }
    report.seconds = t0.elapsed().as_secs_f64();
    Ok(report)
}

/// One worker slot: cases `from..to`, restarting the child after a case that kills it.
fn drive(
    cfg: &Config,
    from: u64,
    to: u64,
    done: &std::sync::atomic::AtomicU64,
) -> std::io::Result<Report> {
    let mut rep = Report::default();
    let corpus = Corpus::new();
    let mut next = from;
    while next < to {
        let mut cmd = Command::new(&cfg.exe);
        cmd.arg("fuzz-worker")
            .args(["--seed", &cfg.seed.to_string()])
            .args(["--from", &next.to_string(), "--to", &to.to_string()])
            .current_dir(&cfg.scratch)
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped());
        if let Some(t) = cfg.selftest {
            use clap::ValueEnum as _;
            cmd.args([
                "--selftest",
                t.to_possible_value().expect("named").get_name(),
            ]);
        }
        let mut child = cmd.spawn()?;
        rep.processes += 1;
        let stdout = child.stdout.take().expect("piped");
        let mut stderr = child.stderr.take().expect("piped");
        let (tx, rx) = mpsc::channel::<String>();
        let reader = std::thread::spawn(move || {
            for line in BufReader::new(stdout).lines() {
                let Ok(line) = line else { break };
                if tx.send(line).is_err() {
                    break;
                }
            }
        });
        let err_reader = std::thread::spawn(move || {
            let mut s = String::new();
            let _ = std::io::Read::read_to_string(&mut stderr, &mut s);
            s
        });
        let mut stalled = false;
        loop {
            match rx.recv_timeout(cfg.stall) {
                Ok(line) => {
                    if let Some(k) = take_line(&line, &mut rep) {
                        next = k + 1;
                        done.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                        if let Some(p) = &cfg.progress {
                            p(done.load(std::sync::atomic::Ordering::Relaxed));
                        }
                    }
                }
                Err(mpsc::RecvTimeoutError::Timeout) => {
                    stalled = true;
                    let _ = child.kill();
                    break;
                }
                Err(mpsc::RecvTimeoutError::Disconnected) => break,
            }
        }
        let status = child.wait()?;
        let _ = reader.join();
        // A line that arrived as the stall fired still counts: the hang is the case after it.
        for line in rx.try_iter() {
            if let Some(k) = take_line(&line, &mut rep) {
                next = k + 1;
                done.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            }
        }
        let stderr = err_reader.join().unwrap_or_default();
        if next >= to {
            if !status.success() && !stalled {
                // Every case answered, then the worker failed: not a case's defect, the harness's.
                return Err(std::io::Error::other(format!(
                    "fuzz worker for cases {from}..{to} exited with {status} after its last case: {}",
                    stderr.trim()
                )));
            }
            break;
        }
        // The case in flight killed or stalled the worker.
        let c = case(&corpus, cfg.seed, next);
        let verdict = if stalled {
            Verdict::Hang
        } else if stderr.contains("memory allocation of") {
            Verdict::OverLimit
        } else {
            Verdict::Crash
        };
        let message = if stalled {
            format!("no answer for {:.0} s", cfg.stall.as_secs_f64())
        } else {
            format!("worker exited with {status}: {}", stderr.trim())
        };
        tally(&mut rep, next, c.target, c.mutation, verdict, None);
        rep.record(Failure {
            case: next,
            target: c.target,
            mutation: c.mutation,
            verdict,
            message,
        });
        done.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        next += 1;
    }
    Ok(rep)
}

fn tally(rep: &mut Report, _case: u64, t: Target, m: Mutation, v: Verdict, kind: Option<&str>) {
    rep.cases += 1;
    rep.cells.entry((t, m)).or_default().by_verdict[v.code()] += 1;
    if let Some(k) = kind {
        *rep.error_kinds.entry((t, k.to_string())).or_default() += 1;
    }
}

/// Parses one worker line into the report; returns the case index.
fn take_line(line: &str, rep: &mut Report) -> Option<u64> {
    let mut f = line.splitn(8, ' ');
    let k: u64 = f.next()?.parse().ok()?;
    let t = Target::ALL.get(f.next()?.parse::<usize>().ok()?).copied()?;
    let m = Mutation::ALL
        .get(f.next()?.parse::<usize>().ok()?)
        .copied()?;
    let v = Verdict::from_code(f.next()?.parse().ok()?)?;
    let peak: u64 = f.next()?.parse().ok()?;
    let input: u64 = f.next()?.parse().ok()?;
    let micros: u64 = f.next()?.parse().ok()?;
    let rest = f.next().unwrap_or("");
    tally(rep, k, t, m, v, (v == Verdict::Error).then_some(rest));
    if v.is_defect() {
        rep.record(Failure {
            case: k,
            target: t,
            mutation: m,
            verdict: v,
            message: rest.to_string(),
        });
    }
    let used = peak as f64 / memory_bound(input as usize) as f64;
    if used > rep.max_bound_use {
        rep.max_bound_use = used;
        rep.max_peak = (peak, input);
    }
    if micros > rep.slowest.1 {
        rep.slowest = (k, micros);
    }
    Some(k)
}

/// The worker: runs cases `from..to` in this process and prints one line each. Needs
/// [`alloc::LimitAlloc`] installed as the global allocator (the `meshletlab` binary has it).
pub fn worker(seed: u64, from: u64, to: u64, selftest: Option<SelfTest>) -> std::io::Result<()> {
    let corpus = Corpus::new();
    let last_panic = std::sync::Arc::new(std::sync::Mutex::new(String::new()));
    {
        let slot = last_panic.clone();
        std::panic::set_hook(Box::new(move |info| {
            let msg = match info.location() {
                Some(l) => format!("{info} at {}:{}", l.file(), l.line()),
                None => info.to_string(),
            };
            if let Ok(mut s) = slot.lock() {
                *s = msg.replace('\n', " ");
            }
        }));
    }
    let out = std::io::stdout();
    for k in from..to {
        let c = case(&corpus, seed, k);
        let input = input_size(&c);
        let t0 = Instant::now();
        alloc::arm(memory_bound(input));
        let r = std::panic::catch_unwind(|| match (selftest, k) {
            (Some(SelfTest::Panic), 1) => panic!("self-test panic"),
            (Some(SelfTest::Hang), 1) => loop {
                std::thread::sleep(Duration::from_secs(1));
            },
            (Some(SelfTest::Alloc), 1) => {
                // Just past the bound: the system would grant it, only LimitAlloc refuses.
                std::hint::black_box(Vec::<u8>::with_capacity(memory_bound(input) + (1 << 20)));
                Ok(Outcome::Valid)
            }
            _ => read(&c, &corpus),
        });
        let peak = alloc::disarm();
        let micros = t0.elapsed().as_micros() as u64;
        let (verdict, text) = match r {
            Ok(Ok(Outcome::Valid)) => (Verdict::Valid, String::new()),
            Ok(Ok(Outcome::Error(kind))) => (Verdict::Error, kind.to_string()),
            Ok(Err(unnamed)) => (Verdict::Crash, unnamed.replace('\n', " ")),
            Err(_) => (
                Verdict::Panic,
                last_panic.lock().map(|s| s.clone()).unwrap_or_default(),
            ),
        };
        let verdict = if micros as f64 > HANG_SECONDS * 1e6 && !verdict.is_defect() {
            Verdict::Hang
        } else {
            verdict
        };
        let mut o = out.lock();
        writeln!(
            o,
            "{k} {} {} {} {peak} {input} {micros} {text}",
            Target::ALL
                .iter()
                .position(|&t| t == c.target)
                .expect("listed"),
            Mutation::ALL
                .iter()
                .position(|&m| m == c.mutation)
                .expect("listed"),
            verdict.code(),
        )?;
        o.flush()?;
    }
    Ok(())
}

/// Writes case `k`'s file into `dir` under its reader-facing name; returns the path.
pub fn dump(seed: u64, k: u64, dir: &Path) -> std::io::Result<PathBuf> {
    let c = case(&Corpus::new(), seed, k);
    let p = dir.join(format!(
        "case-{k}.{}",
        c.file_name.trim_start_matches("case.")
    ));
    crate::atomic::write(&p, &c.bytes)?;
    Ok(p)
}

//! The mutation fuzzer (`meshletlab::fuzz`) in the test suite: a few thousand seeded cases over every
//! reader, each a valid mesh or a typed error naming the file; and the harness's own detectors
//! (panic, hang, allocation over the bound) shown to fire.

mod common;

use meshletlab::fuzz::harness::{self, Config, SelfTest, Verdict};
use meshletlab::fuzz::{Mutation, Target};
use std::path::PathBuf;
use std::time::Duration;

fn config(
    scratch: &common::Scratch,
    cases: u64,
    selftest: Option<SelfTest>,
    stall: Duration,
) -> Config {
    Config {
        exe: PathBuf::from(env!("CARGO_BIN_EXE_meshletlab")),
        seed: 1,
        cases,
        workers: 2,
        scratch: scratch.to_path_buf(),
        selftest,
        stall,
        progress: None,
    }
}

#[test]
fn seeded_cases_load_or_fail_with_a_typed_error() {
    // The test binary is built with overflow checks, so arithmetic overflow shows as a panic.
    let dir = common::scratch("fuzz");
    let r = harness::run(&config(&dir, 20000, None, harness::STALL)).unwrap();
    let t = r.totals();
    assert_eq!(r.cases, 20000);
    assert_eq!(t.defects(), 0, "defects: {:#?}", r.failures);
    for tg in Target::ALL {
        for m in Mutation::ALL.into_iter().filter(|m| m.applies(tg)) {
            let n = r.cells.get(&(tg, m)).map_or(0, |c| c.total());
            assert!(n > 0, "{} x {}: no case ran", tg.name(), m.name());
        }
        let (valid, errors) = r
            .cells
            .iter()
            .filter(|((t, _), _)| *t == tg)
            .fold((0, 0), |(v, e), (_, c)| {
                (v + c.get(Verdict::Valid), e + c.get(Verdict::Error))
            });
        // Mutations must both break files and leave some loadable: a fuzzer whose cases all fail
        // at the first byte tests nothing past it.
        assert!(
            valid > 0 && errors > 0,
            "{}: {valid} valid, {errors} errors",
            tg.name()
        );
    }
}

#[test]
fn the_harness_catches_panics_hangs_and_allocations_over_the_bound() {
    for (st, want) in [
        (SelfTest::Panic, Verdict::Panic),
        (SelfTest::Alloc, Verdict::OverLimit),
        (SelfTest::Hang, Verdict::Hang),
    ] {
        let dir = common::scratch(&format!("selftest-{want:?}"));
        let mut cfg = config(&dir, 4, Some(st), Duration::from_secs(3));
        cfg.workers = 1;
        let r = harness::run(&cfg).unwrap();
        assert_eq!(r.cases, 4, "{st:?}");
        let f: Vec<_> = r.failures.iter().map(|f| (f.case, f.verdict)).collect();
        assert_eq!(f, vec![(1, want)], "{st:?}: {:#?}", r.failures);
        // The cases after the bad one still ran (a killed worker is replaced).
        assert_eq!(r.totals().defects(), 1);
    }
}

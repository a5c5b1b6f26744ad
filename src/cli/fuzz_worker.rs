//! `meshletlab fuzz-worker` (hidden): the child process of `bench robustness` (see
//! `meshletlab::fuzz::harness`).

use crate::fuzz::harness::{self, SelfTest};
use anyhow::{bail, Result};
use clap::Args;

/// Arguments of `fuzz-worker`.
#[derive(Args, Debug)]
pub struct FuzzWorkerArgs {
    /// Run seed.
    #[arg(long)]
    seed: u64,
    /// First case.
    #[arg(long)]
    from: u64,
    /// One past the last case.
    #[arg(long)]
    to: u64,
    /// Deliberate defect at case 1 (the harness's own test).
    #[arg(long, value_enum)]
    selftest: Option<SelfTest>,
}

pub(super) fn run(a: FuzzWorkerArgs) -> Result<()> {
    // Without the counting allocator the memory bound would go unchecked: refuse to run.
    if !crate::fuzz::alloc::installed() {
        bail!("fuzz-worker needs meshletlab's LimitAlloc as the global allocator");
    }
    harness::worker(a.seed, a.from, a.to, a.selftest)?;
    Ok(())
}

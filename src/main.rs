//! The `meshletlab` binary: see `meshletlab --help`.

use std::process::ExitCode;

/// Passes through to the system allocator; `meshletlab fuzz-worker` arms it to cap each fuzz case's
/// heap (one relaxed atomic load per call otherwise).
#[global_allocator]
static ALLOC: meshletlab::fuzz::alloc::LimitAlloc = meshletlab::fuzz::alloc::LimitAlloc;

fn main() -> ExitCode {
    match meshletlab::cli::run(std::env::args_os()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            // One line: the whole cause chain, colon-separated.
            let msg = format!("{e:#}").replace('\n', " ");
            eprintln!("error: {msg}");
            ExitCode::FAILURE
        }
    }
}

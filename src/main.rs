//! The `meshletlab` binary: see `meshletlab --help`.

use std::process::ExitCode;

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

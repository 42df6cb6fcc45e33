//! The `mint` command line. Each subcommand is a thin layer over a library
//! crate: parse and check arguments, run with progress bars, print a summary
//! (or `--json`), and turn any error into one line on stderr and a non-zero
//! exit code. No output file is left behind on error or Ctrl-C: writers go
//! through temporary files that are renamed only on success.
//!
//! `cli` holds the parser (the subcommand list and its help) and the
//! dispatch; `cmd` has one module per subcommand. What several commands
//! share: `jobs` (argument groups and option builders), `summary` (the
//! resampling, grid-job and check reports), `preview` (the `--preview`
//! pictures), `contour_report` (the contour commands' summary and status
//! file), `paths` (output checks), `progress` (bars and Ctrl-C), `units`
//! (sizes), `alloc` (the counting allocator) and `out` (where summaries
//! and warnings go: the terminal, or an embedding such as the Python
//! package, through [`embed::run_embedded`]).

pub mod alloc;
mod cli;
mod cmd;
mod contour_report;
pub mod embed;
mod jobs;
pub mod out;
mod paths;
mod preview;
pub mod progress;
mod summary;
pub mod units;

use std::process::ExitCode;

#[global_allocator]
static GLOBAL: alloc::CountingAllocator = alloc::CountingAllocator;

/// Runs the command line and returns the process exit code.
pub fn main() -> ExitCode {
    ExitCode::from(embed::exit_status(std::env::args_os().collect()))
}

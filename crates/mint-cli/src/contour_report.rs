//! What `mint slice`, `contours` and `optimize` report: a one-paragraph
//! summary on stderr (or `--json`) and the `--stats` status file (the run's
//! `mint_contour::run::RunStats`: time, counts, every parameter used and the
//! method's own counters, plus the peak heap), and the write options of the
//! commands that write a mesh.

use crate::alloc;
use crate::units::human_bytes;
use anyhow::{Context, Result};
use mint_contour::run::RunStats;
use mint_io::WriteOptions;
use std::path::{Path, PathBuf};

/// The status JSON: the run's stats plus the peak heap.
pub(crate) fn status(s: &RunStats) -> Result<serde_json::Value> {
    let mut v = serde_json::to_value(s)?;
    v["peak_heap_bytes"] = alloc::peak_heap().into();
    Ok(v)
}

/// Writes the status file atomically (temporary name, then rename).
pub(crate) fn write_stats(path: &Path, v: &serde_json::Value) -> Result<()> {
    let tmp = path.with_extension("json.mint-tmp");
    std::fs::write(&tmp, serde_json::to_string_pretty(v)? + "\n").with_context(|| format!("{}: writing the status file", tmp.display()))?;
    std::fs::rename(&tmp, path).with_context(|| format!("{}: renaming the status file", path.display()))?;
    Ok(())
}

/// Prints and records a finished run.
pub(crate) fn report(s: &RunStats, stats: &Option<PathBuf>, quiet: bool, json: bool, line: String) -> Result<()> {
    let v = status(s)?;
    if let Some(p) = stats {
        write_stats(p, &v)?;
    }
    if json {
        crate::out::json(&v)?;
    } else if !quiet {
        eprintln!("{line}");
        eprintln!("  time {:.3}s, peak heap {}", s.seconds, human_bytes(alloc::peak_heap()));
    }
    Ok(())
}

pub(crate) fn write_options(ascii: bool, double: bool) -> WriteOptions {
    WriteOptions { ascii, double, ..Default::default() }
}

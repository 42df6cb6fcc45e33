//! `mint convert`: from one mesh format to another (PLY, OBJ, STL, OFF…),
//! streaming, with a progress bar and Ctrl-C. Calls
//! `mint_io::convert_cancellable`.

use crate::jobs::{QuietArg};
use crate::progress::Bars;
use crate::units::human_bytes;
use anyhow::{Context, Result};
use clap::Args;
use mint_io::WriteOptions;
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct ConvertArgs {
    /// Input mesh.
    pub input: PathBuf,
    /// Output mesh; the format follows the extension.
    pub output: PathBuf,
    /// Write ASCII instead of binary (PLY/STL).
    #[arg(long)]
    pub ascii: bool,
    /// Write vertex coordinates as f64 (PLY).
    #[arg(long)]
    pub double: bool,
    /// Directory for temporary spill files [default: the system temp dir].
    #[arg(long)]
    pub tmp: Option<PathBuf>,
    #[command(flatten)]
    pub quiet: QuietArg,
}

pub(crate) fn cmd_convert(a: ConvertArgs) -> Result<()> {
    crate::paths::check_output(&a.output, &[&a.input])?;
    let bars = Bars::new(a.quiet.quiet);
    use mint_pipeline::{Phase, Progress};
    bars.start(Phase::named("convert"), 0);
    let read = mint_io::ReadOptions { spill_dir: a.tmp.clone(), ..Default::default() };
    let write = WriteOptions { ascii: a.ascii, double: a.double, ..Default::default() };
    let mut last = 0u64;
    let summary = mint_io::convert_cancellable(&a.input, &a.output, read, write, &mut |done, _total| {
        bars.advance(done.saturating_sub(last));
        last = last.max(done);
        !crate::progress::interrupted()
    })
    .with_context(|| format!("converting {} to {}", a.input.display(), a.output.display()))?;
    bars.finish();
    if !a.quiet.quiet {
        eprintln!(
            "converted {} ({:?}) -> {} ({:?}): {} vertices, {} triangles, {}, coordinates {}",
            a.input.display(),
            summary.input_format,
            a.output.display(),
            summary.output_format,
            summary.vertices_written,
            summary.triangles,
            human_bytes(summary.bytes_written),
            summary.precision
        );
    }
    Ok(())
}

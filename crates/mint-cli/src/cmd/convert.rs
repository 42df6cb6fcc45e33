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
    /// Input mesh; several files (tiles), a directory of them or @LIST are
    /// joined into one mesh (each file's vertices kept, its faces offset).
    #[arg(required = true, num_args = 1.., value_name = "IN")]
    pub inputs: Vec<PathBuf>,
    /// Output mesh; the format follows the extension.
    #[arg(value_name = "OUT")]
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
    /// Drop per-vertex colour [default: kept where the output format holds
    /// it: PLY, OBJ, glTF; a warning says when it cannot].
    #[arg(long)]
    pub no_color: bool,
    #[command(flatten)]
    pub quiet: QuietArg,
}

pub(crate) fn cmd_convert(a: ConvertArgs) -> Result<()> {
    let files = crate::jobs::surface_files(&a.inputs)?;
    crate::paths::check_output(&a.output, &files.iter().map(|p| p.as_path()).collect::<Vec<_>>())?;
    if files.len() > 1 {
        let format = mint_io::Format::from_path(&a.output)?;
        // Joining tiles keeps geometry only (for now).
        let write = WriteOptions { ascii: a.ascii, double: a.double, spill_dir: a.tmp.clone(), colours: false };
        let (v, f) = mint_io::concatenate(&files, &a.output, format, write, &crate::progress::interrupted)?;
        if !a.quiet.quiet {
            eprintln!("joined {} files -> {} ({format:?}): {v} vertices, {f} triangles", files.len(), a.output.display());
        }
        return Ok(());
    }
    let input = &files[0];
    let bars = Bars::new(a.quiet.quiet);
    use mint_pipeline::{Phase, Progress};
    bars.start(Phase::named("convert"), 0);
    let read = mint_io::ReadOptions { spill_dir: a.tmp.clone(), ..Default::default() };
    let write = WriteOptions { ascii: a.ascii, double: a.double, colours: !a.no_color, ..Default::default() };
    let mut last = 0u64;
    let summary = mint_io::convert_cancellable(input, &a.output, read, write, &mut |done, _total| {
        bars.advance(done.saturating_sub(last));
        last = last.max(done);
        !crate::progress::interrupted()
    })
    .with_context(|| format!("converting {} to {}", input.display(), a.output.display()))?;
    bars.finish();
    if summary.colour_kept == Some(false) {
        crate::out::warn(&format!(
            "{}: {} cannot hold per-vertex colour; the input's colours were dropped (PLY, OBJ and glTF keep them)",
            a.output.display(),
            summary.output_format
        ));
    }
    if !a.quiet.quiet {
        eprintln!(
            "converted {} ({:?}) -> {} ({:?}): {} vertices, {} triangles, {}, coordinates {}",
            input.display(),
            summary.input_format,
            a.output.display(),
            summary.output_format,
            summary.vertices_written,
            summary.triangles,
            human_bytes(summary.bytes_written),
            summary.precision
        );
        if summary.colour_kept == Some(true) {
            eprintln!("  per-vertex colour kept");
        }
    }
    Ok(())
}

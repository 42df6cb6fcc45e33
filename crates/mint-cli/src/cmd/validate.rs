//! `mint validate`: streams every triangle of a file with its positions
//! resolved, which checks indices and coordinates, and reports the read
//! speed. Reads through `mint_io::MeshReader`.

use crate::jobs::{QuietArg, JsonArg};
use crate::progress::Bars;
use anyhow::{bail, Result};
use clap::Args;
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct ValidateArgs {
    /// Mesh file.
    pub file: PathBuf,
    /// Directory for temporary spill files (ASCII input) [default: the system temp dir].
    #[arg(long)]
    pub tmp: Option<PathBuf>,
    #[command(flatten)]
    pub quiet: QuietArg,
    #[command(flatten)]
    pub json: JsonArg,
}

pub(crate) fn cmd_validate(a: ValidateArgs) -> Result<()> {
    use mint_pipeline::{Phase, Progress};
    let t = std::time::Instant::now();
    let mut reader = mint_io::MeshReader::open(&a.file, mint_io::ReadOptions { spill_dir: a.tmp.clone(), ..Default::default() })?;
    let bars = Bars::new(a.quiet.quiet || a.json.json);
    bars.start(Phase::named("validate"), reader.info().face_count.unwrap_or(0));
    let mut chunk = mint_io::TriangleChunk::default();
    let mut triangles = 0u64;
    // A checksum over positions keeps the read from being optimized away and
    // lets two runs be compared.
    let mut checksum = 0.0f64;
    while reader.next_chunk(&mut chunk)? {
        triangles += chunk.positions.len() as u64;
        for t in &chunk.positions {
            checksum += t[0][0] + t[1][1] + t[2][2];
        }
        bars.advance(chunk.positions.len() as u64);
        if crate::progress::interrupted() {
            bail!("interrupted");
        }
    }
    bars.finish();
    for w in reader.warnings() {
        crate::out::warn(&w);
    }
    let secs = t.elapsed().as_secs_f64();
    let bytes = std::fs::metadata(&a.file).map(|m| m.len()).unwrap_or(0);
    let tps = triangles as f64 / secs.max(1e-9);
    let mbs = bytes as f64 / 1e6 / secs.max(1e-9);
    if a.json.json {
        let v = serde_json::json!({
            "file": a.file.display().to_string(), "vertices": reader.vertex_count(), "triangles": triangles,
            "seconds": secs, "triangles_per_second": tps, "mb_per_second": mbs, "checksum": checksum,
        });
        crate::out::json(&v)?;
    } else {
        println!(
            "{}: ok, {} vertices, {} triangles in {:.3}s ({:.1} M triangles/s, {:.0} MB/s)",
            a.file.display(),
            reader.vertex_count(),
            triangles,
            secs,
            tps / 1e6,
            mbs
        );
    }
    Ok(())
}

//! `mint distance`: the Metro-style surface distance between two meshes,
//! both directions (mean, RMS, max). Calls
//! `mint_mesh::try_symmetric_distance` on the meshes read into memory.

use crate::jobs::{load_mesh, JsonArg};
use anyhow::{Context, Result};
use clap::Args;
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct DistanceArgs {
    /// The mesh sampled first (A → B, then B → A).
    pub a: PathBuf,
    /// The other mesh.
    pub b: PathBuf,
    /// Area-uniform samples per direction.
    #[arg(long, default_value_t = 1_000_000)]
    pub samples: usize,
    /// Seed of the sample positions.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    #[command(flatten)]
    pub json: JsonArg,
}

pub(crate) fn cmd_distance(a: DistanceArgs) -> Result<()> {
    let ma = load_mesh(&a.a)?;
    let mb = load_mesh(&a.b)?;
    let (ab, ba) = mint_mesh::try_symmetric_distance((&ma.0, &ma.1), (&mb.0, &mb.1), a.samples, a.seed)
        .with_context(|| format!("distance between {} and {}", a.a.display(), a.b.display()))?;
    if a.json.json {
        let v = serde_json::json!({ "a": a.a.display().to_string(), "b": a.b.display().to_string(), "a_to_b": ab, "b_to_a": ba });
        crate::out::json(&v)?;
    } else {
        for (name, r) in [(format!("{} -> {}", a.a.display(), a.b.display()), &ab), (format!("{} -> {}", a.b.display(), a.a.display()), &ba)] {
            println!("{name} ({} samples)", r.samples);
            println!("  mean {:.6e} ({:.3e} of diagonal)", r.mean, r.mean_rel);
            println!("  rms  {:.6e} ({:.3e} of diagonal)", r.rms, r.rms_rel);
            println!("  max  {:.6e} ({:.3e} of diagonal) at {:?}", r.max, r.max_rel, r.max_point);
        }
    }
    Ok(())
}

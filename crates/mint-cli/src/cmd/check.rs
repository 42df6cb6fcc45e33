//! `mint check`: judges a mesh of any size (counts, components, boundary and
//! non-manifold edges, orientation, degenerate and duplicate faces, genus,
//! volume) and gives one verdict, watertight or not. Calls
//! `mint_check::check_file` (and `mint_mesh::self_intersections` for
//! `--self-intersections`).

use crate::jobs::{JsonArg, MemArg, QuietArg};
use crate::progress::Bars;
use crate::summary::print_check;
use crate::units::human_bytes;
use anyhow::Result;
use clap::Args;
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct CheckArgs {
    /// Mesh file; several files (tiles), a directory of them or @LIST are
    /// checked as one surface (welding joins their seams).
    #[arg(required = true, num_args = 1.., value_name = "FILE")]
    pub files: Vec<PathBuf>,
    #[command(flatten)]
    pub json: JsonArg,
    /// Exit with code 3 when the mesh is not watertight (for scripts).
    #[arg(long)]
    pub strict: bool,
    /// Also count the pairs of faces that intersect (exact predicates;
    /// faces sharing a vertex or an edge count only if they overlap beyond
    /// it), with a few examples. In memory: about 100 bytes per face.
    #[arg(long)]
    pub self_intersections: bool,
    /// Judge the indices as written. By default vertices at identical
    /// positions are merged first, as MeshLab and trimesh do on import: STL
    /// stores each triangle's corners separately and OBJ splits vertices at
    /// texture seams, which would otherwise read as boundaries everywhere.
    #[arg(long)]
    pub no_weld: bool,
    /// The check keeps a few bytes per vertex in memory and sends each
    /// face's corners to buckets that spill to disk past --mem, so a mesh of
    /// any size can be checked (--self-intersections is in memory, though).
    #[command(flatten)]
    pub mem: MemArg,
    /// Directory for spill files [default: the system temp dir].
    #[arg(long)]
    pub tmp: Option<PathBuf>,
    /// Worker threads [default: all cores]. The report is the same for any value.
    #[arg(long, default_value_t = 0, hide_default_value = true)]
    pub threads: usize,
    #[command(flatten)]
    pub quiet: QuietArg,
}

pub(crate) fn cmd_check(a: CheckArgs) -> Result<()> {
    let threads = if a.threads == 0 { std::thread::available_parallelism().map_or(1, |n| n.get()) } else { a.threads };
    let opts = mint_check::CheckOptions { mem_bytes: a.mem.bytes(), weld: !a.no_weld, tmp_dir: a.tmp.clone(), threads, list_boundary: 0 };
    let files = crate::jobs::surface_files(&a.files)?;
    let name = mint_pipeline::spec::files_name(&files);
    let (r, stats) = mint_check::check_files(&files, &opts, &Bars::new(a.quiet.quiet || a.json.json))?;
    let sx = if a.self_intersections {
        let (mut positions, mut faces) = crate::jobs::load_meshes(&files)?;
        if !a.no_weld {
            mint_mesh::weld(&mut positions, &mut faces);
        }
        Some(mint_mesh::self_intersections(&positions, &faces, 5))
    } else {
        None
    };
    if !a.json.json && !a.quiet.quiet && stats.bytes_spilled > 0 {
        eprintln!("  ({} of positions and corners spilled to disk to stay within --mem)", human_bytes(stats.bytes_spilled));
    }
    if a.json.json {
        let mut v = serde_json::to_value(&r)?;
        v["file"] = name.clone().into();
        if files.len() > 1 {
            v["files"] = files.len().into();
        }
        v["spilled_bytes"] = stats.bytes_spilled.into();
        if let Some(x) = &sx {
            v["self_intersections"] = serde_json::to_value(x)?;
        }
        crate::out::json(&v)?;
    } else {
        print_check(&name, &r);
        if let Some(x) = &sx {
            let ex: Vec<String> = x.examples.iter().map(|[i, j]| format!("{i}-{j}")).collect();
            println!(
                "  self-intersections {} pairs of faces{}",
                x.pairs,
                if ex.is_empty() { String::new() } else { format!(" (e.g. faces {})", ex.join(", ")) }
            );
        }
    }
    if a.strict && !r.watertight {
        std::process::exit(3);
    }
    Ok(())
}

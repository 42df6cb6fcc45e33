//! Summaries that several commands print: the resampling's (`resample`,
//! `stage run`, `slurm`), the grid jobs' (`bool`, `csg`), each with a
//! warning when the output is empty, and the check report (`check`, `demo`).

use crate::alloc;
use crate::jobs::ReportArgs;
use crate::units::human_bytes;
use anyhow::Result;

/// Prints a resampling summary: JSON on stdout, or lines on stderr.
pub(crate) fn print_resample_summary(summary: &mint_pipeline::ResampleSummary, json: bool, quiet: bool, mem: u64) -> Result<()> {
    print_removed(&summary.removed_dead);
    let peak_heap = alloc::peak_heap();
    let peak_rss = alloc::peak_rss();
    let warnings = summary_warnings(summary);
    print_warnings(&warnings);
    if json {
        let mut v = serde_json::to_value(summary)?;
        v["warnings"] = warnings.into();
        v["mem_budget_bytes"] = mem.into();
        v["peak_heap_bytes"] = peak_heap.into();
        v["peak_rss_bytes"] = peak_rss.into();
        crate::out::json(&v)?;
    } else if !quiet {
        let s = summary;
        eprintln!("resampled {} -> {}", s.input, s.output);
        eprintln!(
            "  input        {}{} vertices, {} faces{}",
            match (s.input_files, s.input_tiles) {
                (f, t) if t > 0 => format!("{f} file{} holding {t} tiles, ", if f == 1 { "" } else { "s" }),
                (f, _) if f > 1 => format!("{f} files, "),
                _ => String::new(),
            },
            s.input_vertices,
            s.input_faces,
            if s.orientation_inverted {
                " (inside-out: signs reversed)"
            } else if s.orientation_from == "faces" {
                " (open: orientation from its faces)"
            } else {
                ""
            }
        );
        eprintln!(
            "  grid         {}x{}x{} cells of {:.6} (slabs along {}: {}, {} threads)",
            s.grid_cells[0], s.grid_cells[1], s.grid_cells[2], s.cell_size, s.slab_axis, s.slabs, s.threads
        );
        eprintln!(
            "  intercepts   {} found, {} removed, {} kept ({} of shards)",
            s.intercepts_found,
            s.intercepts_removed,
            s.intercepts_kept,
            human_bytes(s.shard_bytes)
        );
        eprintln!("  output       {} vertices, {} faces, coordinates {}", s.output_vertices, s.output_faces, s.output_precision);
        if !s.deref.is_empty() {
            let spilled = if s.deref_spilled_bytes > 0 { format!(" ({} spilled to disk)", human_bytes(s.deref_spilled_bytes)) } else { String::new() };
            eprintln!("  faces        dereferenced by {}{spilled}", s.deref);
        }
        if s.sign_rule == "orient" {
            eprintln!("  signs        orient; non-canonical cells {} (left open)", s.non_canonical_cells);
        } else {
            eprintln!(
                "  signs        {} ({} of {} lines winding-valid, {} odd); {} lines through holes, {} vertices synthesized, {} overlapping edges merged",
                s.sign_rule, s.census_winding_valid, s.census_lines, s.census_odd, s.inconsistent_lines, s.synthesized_vertices, s.merged_edges
            );
            eprintln!(
                "  holes        {} closed, {} left open ({} cells); the output's boundary: {} edges in {} loops",
                s.holes_closed, s.holes_left_open, s.open_cells, s.output_boundary_edges, s.output_boundary_loops
            );
        }
        eprintln!(
            "  time         {:.2}s (bounds {:.2}s, discretize {:.2}s, reconstruct {:.2}s, write {:.2}s)",
            s.seconds_total, s.seconds_bounds, s.seconds_discretize, s.seconds_reconstruct, s.seconds_write
        );
        if s.distributed {
            eprintln!("  memory       per task: see each task's line (mint stage run) or its log");
        } else {
            eprintln!(
                "  memory       peak heap {}, peak RSS {}, budget {}",
                human_bytes(peak_heap),
                peak_rss.map(human_bytes).unwrap_or_else(|| "?".into()),
                human_bytes(mem)
            );
        }
    }
    if let Some(dir) = &summary.work_dir {
        if !json && !quiet && summary.distributed {
            eprintln!("  work dir     {dir} (remove it when you no longer need its results)");
        } else if !json && !quiet {
            eprintln!("  work dir     {dir} ({} tasks run, {} found done); remove it when you no longer need to resume", summary.tasks_run, summary.tasks_resumed);
        }
    }
    Ok(())
}

/// Warnings about a run that succeeded: an empty output, and why.
pub(crate) fn summary_warnings(s: &mint_pipeline::ResampleSummary) -> Vec<String> {
    summary_warnings_with(s, "--signs union")
}

/// [`summary_warnings`], naming `close` as the way to close an open input
/// into a solid (`decimate` has no `--signs`: it names `mint resample`).
pub(crate) fn summary_warnings_with(s: &mint_pipeline::ResampleSummary, close: &str) -> Vec<String> {
    let mut w = s.input_warnings.clone();
    if s.input_coloured_files > 0 && !s.colour && !s.no_colour {
        w.push(format!(
            "{}: {} of the input files have per-vertex colour, which {} cannot hold: the output is geometry only (write .ply, .obj, .gltf or .glb to keep it)",
            s.input, s.input_coloured_files, s.output
        ));
    }
    if s.sign_rule == "sheet" && s.census_odd * 3 > s.census_lines {
        w.push(format!(
            "{}: the input is open ({} of {} grid lines cross it an odd number of times): resampled as an open sheet with its faces' orientation, enclosing no volume, its boundary within about two cells of the input's (the rim's last cells are dropped whole); {close} closes it into a solid",
            s.input, s.census_odd, s.census_lines
        ));
    }
    if let Some(why) = s.empty_reason() {
        w.push(format!("{}: the output is empty: {why}", s.output));
    }
    w
}

/// Says which leftovers of killed runs were removed (also with --quiet and --json).
pub(crate) fn print_removed(removed: &[String]) {
    for r in removed {
        eprintln!("mint: removed {r}, left by a run that was killed");
    }
}

/// Prints the warnings on stderr, one line each (also with --quiet and --json).
fn print_warnings(warnings: &[String]) {
    for w in warnings {
        crate::out::warn(w);
    }
}

pub(crate) fn report(g: &ReportArgs, s: &mint_pipeline::ResampleSummary) -> Result<()> {
    print_removed(&s.removed_dead);
    let warnings = summary_warnings(s);
    print_warnings(&warnings);
    if g.json() {
        let mut v = serde_json::to_value(s)?;
        v["warnings"] = warnings.into();
        v["peak_heap_bytes"] = alloc::peak_heap().into();
        v["peak_rss_bytes"] = alloc::peak_rss().into();
        crate::out::json(&v)?;
    } else if !g.quiet() {
        eprintln!("{} -> {}", s.input, s.output);
        eprintln!("  grid         {}x{}x{} cells of {:.6} ({} slabs)", s.grid_cells[0], s.grid_cells[1], s.grid_cells[2], s.cell_size, s.slabs);
        eprintln!("  input        {} mesh faces; operand signs: {}", s.input_faces, s.sign_rule);
        eprintln!("  output       {} vertices, {} faces, coordinates {}", s.output_vertices, s.output_faces, s.output_precision);
        eprintln!("  time         {:.2}s; peak heap {}", s.seconds_total, human_bytes(alloc::peak_heap()));
    }
    Ok(())
}

pub(crate) fn print_check(name: &str, r: &mint_mesh::CheckReport) {
    println!("{name}: {}", if r.watertight { "watertight (closed, 2-manifold, consistently oriented)" } else { "NOT watertight" });
    println!("  vertices {} ({} unreferenced), faces {}", r.vertices, r.unreferenced_vertices, r.faces);
    if r.welded_vertices > 0 {
        println!("  welded {} vertices at identical positions into earlier ones (--no-weld judges the indices as written)", r.welded_vertices);
    }
    if let (Some(lo), Some(hi)) = (r.bbox_min, r.bbox_max) {
        println!("  bbox [{:.6}, {:.6}, {:.6}] .. [{:.6}, {:.6}, {:.6}]", lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]);
    }
    println!("  components {} ({} closed), genus of closed ones {:?} (total {})", r.components, r.closed_components, r.genera, r.genus_total);
    println!("  edges {}, boundary edges {} in {} loops ({} on non-simple boundaries)", r.edges, r.boundary_edges, r.boundary_loops, r.non_simple_boundary_edges);
    println!("  non-manifold edges {}, non-manifold vertices {}", r.non_manifold_edges, r.non_manifold_vertices);
    println!("  inconsistently oriented edges {}", r.inconsistently_oriented_edges);
    println!("  degenerate faces {} ({} with a repeated index), duplicate faces {}", r.degenerate_faces, r.collapsed_faces, r.duplicate_faces);
    println!("  Euler characteristic {}, signed volume {:.9}, area {:.9}", r.euler_characteristic, r.signed_volume, r.surface_area);
}

/// The decimate and simplify summaries' line on the output's distance to
/// its reference.
pub(crate) fn surface_error_line(e: &Option<mint_decimate::SurfaceError>) -> String {
    let Some(e) = e else { return "  distance     not measured (--error-samples 0)".to_string() };
    format!(
        "  distance     to the {}: mean {:.2e}, max {:.2e} of its diagonal ({:.3e} and {:.3e}; 2 x {} samples, {:.2} s)",
        e.reference, e.mean_rel, e.max_rel, e.mean, e.max, e.samples, e.seconds
    )
}

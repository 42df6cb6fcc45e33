//! `csg`: booleans and CSG trees of meshes and analytic primitives, computed
//! on intersection lists (Rocchini et al. 2001, §3.3), out of core.
//!
//! Every operand is a *solid on the grid*: something that yields, plane by
//! plane, the signed intercepts of its surface with the grid lines. A mesh
//! does so through the same streaming discretization and shard store as
//! `resample` (one store per mesh operand); a [`Primitive`] computes its
//! intercepts exactly, plane by plane, on demand. Reconstruction does not care
//! which: each slab gathers every operand's planes and hands them to
//! `mint_core::robust::reconstruct_slab_solids`, which decides each
//! operand's node states, combines them with the expression, and puts one
//! vertex on every edge where the result changes — at the operand crossing
//! that changes it. No mesh-mesh intersection is ever computed and the
//! output is closed by construction. The same slab planner, ordered writer,
//! progress hook and summary as `resample` are used, so `--mem`, `--threads`
//! and `--slab` behave the same and the output bytes do not depend on them.

use crate::progress::{Phase, Progress};
use crate::resample::{bounds, check_cancel, discretize_all, plan_slabs, reconstruct_ordered, Done, PipelineError, ResampleOptions, ResampleSummary, BYTES_PER_RECORD_IN_SLAB};
use crate::output::OrderedOutput;
use crate::scene::{Operand, Scene};
use mint_core::grid::Grid;
use mint_core::primitives::Primitive;
use mint_core::robust::{census_plane, reconstruct_slab_solids, BoolOp, Expr};
use mint_core::signs::{LineCensus, RepairStats, SignRule};
use mint_core::{FilterStats, Intercept};
use mint_io::{Format, MeshReader, ReadOptions};
use mint_store::ShardStore;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The bounding box of an expression (`None`: unbounded).
fn expr_bounds(e: &Expr, leaf: &[([f64; 3], [f64; 3])]) -> ([f64; 3], [f64; 3]) {
    match e {
        Expr::Operand(i) => leaf[*i],
        Expr::Op(op, c) => {
            let bs: Vec<_> = c.iter().map(|x| expr_bounds(x, leaf)).collect();
            match op {
                BoolOp::Union => bs.iter().fold(([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]), |(l, h), (bl, bh)| {
                    ([0, 1, 2].map(|d| l[d].min(bl[d])), [0, 1, 2].map(|d| h[d].max(bh[d])))
                }),
                BoolOp::Intersection => bs.iter().fold(([f64::NEG_INFINITY; 3], [f64::INFINITY; 3]), |(l, h), (bl, bh)| {
                    ([0, 1, 2].map(|d| l[d].max(bl[d])), [0, 1, 2].map(|d| h[d].min(bh[d])))
                }),
                BoolOp::Difference => bs[0],
            }
        }
    }
}

enum Source {
    Store { store: ShardStore, invert: bool, rule: SignRule },
    Primitive(Primitive),
}

/// Evaluates `scene` on the grid `opts.size` into `output`.
pub fn csg(scene: &Scene, scene_name: &str, output: &Path, opts: &ResampleOptions, progress: &dyn Progress) -> Result<ResampleSummary, PipelineError> {
    let t_start = Instant::now();
    let threads = if opts.threads == 0 { std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1) } else { opts.threads };
    let tmp_root = match &opts.tmp_dir {
        Some(d) => d.clone(),
        None => output.parent().filter(|p| !p.as_os_str().is_empty()).map(Path::to_path_buf).unwrap_or_else(|| PathBuf::from(".")),
    };
    let out_format = Format::from_path(output)?;
    let mut summary = ResampleSummary { input: scene_name.to_string(), output: output.display().to_string(), threads, ..Default::default() };

    // 1. Bounds of every operand, then of the expression.
    let t = Instant::now();
    let mut readers: Vec<Option<MeshReader>> = Vec::new();
    let mut leaf_bounds = Vec::new();
    for op in &scene.operands {
        match op {
            Operand::Primitive(p) => {
                leaf_bounds.push(p.bounds());
                readers.push(None);
            }
            Operand::Mesh { path, transform } => {
                let r = MeshReader::open(path, ReadOptions { chunk_triangles: 64 * 1024, spill_dir: Some(tmp_root.clone()), resolve_positions: false })?;
                leaf_bounds.push(bounds(&r, path, threads, progress, Some(transform))?);
                summary.input_vertices += r.vertex_count() as u64;
                readers.push(Some(r));
            }
        }
    }
    let (elo, ehi) = expr_bounds(&scene.expr, &leaf_bounds);
    if (0..3).any(|d| !(elo[d].is_finite() && ehi[d].is_finite())) {
        return Err(PipelineError::Unbounded { path: PathBuf::from(scene_name) });
    }
    if (0..3).any(|d| elo[d] > ehi[d]) {
        return Err(PipelineError::Empty { path: PathBuf::from(scene_name) });
    }
    // The grid holds every bounded operand whole (so that every line starts
    // and ends outside each of them), not only the result's box.
    let mut lo = elo;
    let mut hi = ehi;
    for (l, h) in &leaf_bounds {
        for d in 0..3 {
            if l[d].is_finite() && h[d].is_finite() {
                lo[d] = lo[d].min(l[d]);
                hi[d] = hi[d].max(h[d]);
            }
        }
    }
    let grid = Grid::around(lo, hi, opts.size, opts.grid_offset, opts.axis).map_err(|source| PipelineError::Grid { path: PathBuf::from(scene_name), source })?;
    summary.seconds_bounds = t.elapsed().as_secs_f64();
    summary.grid_cells = grid.dims;
    summary.cell_size = grid.cell;
    summary.grid_origin = grid.origin;
    summary.slab_axis = ['x', 'y', 'z'][grid.slab_axis];

    // 2. Discretize the mesh operands, each into its own store.
    let t = Instant::now();
    let [_, _, ns] = grid.local_dims();
    let mut sources = Vec::new();
    for (op, reader) in scene.operands.iter().zip(readers) {
        match (op, reader) {
            (Operand::Mesh { path, transform }, Some(mut r)) => {
                let mut store = ShardStore::create(&tmp_root, ns + 1)?;
                let (faces, volume) = discretize_all(&mut r, &grid, &mut store, threads, progress, Some(transform))?;
                if faces == 0 {
                    return Err(PipelineError::Empty { path: path.clone() });
                }
                store.finish_writing()?;
                summary.input_faces += faces;
                summary.intercepts_found += store.plane_counts().iter().sum::<u64>();
                summary.shard_bytes += store.bytes_written();
                sources.push(Source::Store { store, invert: volume < 0.0, rule: SignRule::Auto });
            }
            (Operand::Primitive(p), _) => sources.push(Source::Primitive(*p)),
            _ => unreachable!(),
        }
        check_cancel(progress)?;
    }
    summary.seconds_discretize = t.elapsed().as_secs_f64();

    // 3. Plan slabs on the mesh operands' counts; resolve each mesh's signs.
    let mut counts = vec![0u64; ns as usize + 1];
    for s in &sources {
        if let Source::Store { store, .. } = s {
            for (c, x) in counts.iter_mut().zip(store.plane_counts()) {
                *c += x;
            }
        }
    }
    let slab_budget = opts.mem_bytes.saturating_sub(48 << 20) / (threads as u64 + 2);
    let slabs = plan_slabs(&counts, ns, opts.slab_layers, slab_budget);
    summary.slabs = slabs.len() as u64;
    summary.planned_slab_bytes = slabs.iter().map(|&(a, b)| counts[a as usize..=b as usize].iter().sum::<u64>() * BYTES_PER_RECORD_IN_SLAB).max().unwrap_or(0);
    let t = Instant::now();
    let mut rule_names = Vec::new();
    for s in &mut sources {
        match s {
            Source::Store { store, invert, rule } => {
                let mut census = LineCensus::default();
                for &(k0, k1) in &slabs {
                    for mut p in store.read_planes(k0, k1 - 1, false)? {
                        if *invert {
                            p.iter_mut().for_each(|r| r.signed_value = -r.signed_value);
                        }
                        census += census_plane(&mut p);
                    }
                }
                *rule = match opts.signs {
                    SignRule::Auto | SignRule::Orient => census.resolve(),
                    r => r,
                };
                rule_names.push(format!("{:?}", rule).to_lowercase());
            }
            Source::Primitive(_) => rule_names.push("exact".into()),
        }
    }
    summary.sign_rule = rule_names.join(",");
    summary.seconds_census = t.elapsed().as_secs_f64();

    // 4. Reconstruct slab by slab, in order.
    let t = Instant::now();
    let rules: Vec<SignRule> = sources.iter().map(|s| match s {
        Source::Store { rule, .. } => *rule,
        Source::Primitive(_) => SignRule::Union,
    }).collect();
    let compute = |k0: u32, k1: u32| -> Result<Done, PipelineError> {
        let mut operands: Vec<Vec<Vec<Intercept>>> = Vec::with_capacity(sources.len());
        for s in &sources {
            operands.push(match s {
                Source::Store { store, invert, .. } => {
                    let mut planes = store.read_planes(k0, k1, true)?;
                    if *invert {
                        planes.iter_mut().flatten().for_each(|r| r.signed_value = -r.signed_value);
                    }
                    planes
                }
                Source::Primitive(p) => (k0..=k1).map(|k| p.plane_intercepts(&grid, k, k < k1)).collect(),
            });
        }
        let (res, rep) = reconstruct_slab_solids(&grid, k0, operands, &rules, &scene.expr, None);
        Ok((res, FilterStats::default(), rep))
    };
    let mut out = OrderedOutput::create(output, out_format, opts.write.clone(), &tmp_root)?;
    let mut repair = RepairStats::default();
    progress.start(Phase::Reconstruct, ns as u64);
    reconstruct_ordered(&slabs, threads, &compute, progress, &mut |res, _f, rep, layers| {
        repair += rep;
        out.push(&res)?;
        summary.active_cells += res.stats.active_cells;
        progress.advance(layers);
        Ok(())
    })?;
    progress.finish();
    drop(sources);
    summary.record_reconstruction(&repair, &out, t);
    check_cancel(progress)?;

    // 5. Faces after vertices; rename into place.
    summary.finish_output(out, progress, t_start)?;
    Ok(summary)
}

/// `A op B` for two mesh files (`mint bool`).
pub fn boolean(op: BoolOp, a: &Path, b: &Path, output: &Path, opts: &ResampleOptions, progress: &dyn Progress) -> Result<ResampleSummary, PipelineError> {
    let scene = Scene {
        expr: Expr::Op(op, vec![Expr::Operand(0), Expr::Operand(1)]),
        operands: vec![
            Operand::Mesh { path: a.to_path_buf(), transform: Default::default() },
            Operand::Mesh { path: b.to_path_buf(), transform: Default::default() },
        ],
    };
    let name = format!("{} {:?} {}", a.display(), op, b.display());
    csg(&scene, &name, output, opts, progress)
}

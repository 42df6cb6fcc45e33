//! Resampling held in memory: discretize a triangle soup, reconstruct it as
//! one slab, and push the mesh into a sink. This is the whole pipeline in
//! one place, for tests, fuzzing and small inputs; the out-of-core engine
//! (mint-pipeline) runs the same steps per shard and per slab, and its
//! output is the same mesh.
//!
//! - [`resample_in_core`]: the paper's strict rule ([`crate::reconstruct`]);
//! - [`resample_in_core_with`]: under a sign rule; the robust rules use
//!   [`crate::robust`] and close every hole;
//! - [`resample_in_core_holes`]: the same with the whole hole protocol of
//!   `--max-hole` (reconstruct, group the hole cells, reconstruct again
//!   with the large holes open).

use crate::cells::SlabResult;
use crate::colour::{colour_vertices, crossing_colour, sort_coloured, Rgba, Tinted};
use crate::expr::Expr;
use crate::grid::Grid;
use crate::holes::{open_cells, HoleStats};
use crate::intercept::{filter_plane, Intercept};
use crate::reconstruct::reconstruct_slab;
use crate::robust::{census_plane, reconstruct_slab_robust, reconstruct_slab_solids};
use crate::signs::{LineCensus, RepairStats, SignRule};
use crate::sink::{MeshSink, SinkError};

/// The raw intercepts of `triangles` (world coordinates), per plane.
pub fn discretize_in_core<I>(grid: &Grid, triangles: I) -> Vec<Vec<Intercept>>
where
    I: IntoIterator<Item = [[f64; 3]; 3]>,
{
    let [_, nb, ns] = grid.local_dims();
    let mut planes: Vec<Vec<Intercept>> = vec![Vec::new(); ns as usize + 1];
    for t in triangles {
        let local = t.map(|p| grid.to_local(p));
        crate::discretize::discretize_triangle(&local, |c| {
            let r = c.intercept(nb);
            planes[r.plane as usize].push(r);
        });
    }
    planes
}

/// Resamples a triangle soup by the strict rule: discretize, filter,
/// reconstruct as one slab, and push the result into `sink`.
pub fn resample_in_core<I>(grid: &Grid, triangles: I, sink: &mut dyn MeshSink) -> Result<SlabResult, SinkError>
where
    I: IntoIterator<Item = [[f64; 3]; 3]>,
{
    let mut planes = discretize_in_core(grid, triangles);
    for p in &mut planes {
        filter_plane(p);
    }
    let result = reconstruct_slab(grid, 0, &planes, usize::MAX);
    emit(&result, None, sink)?;
    Ok(result)
}

/// [`resample_in_core`] under a sign rule: `Orient` is the strict path;
/// `Union`, `Parity` and `Auto` (resolved by a census of all planes) use the
/// robust state-first reconstruction, which closes every hole. Returns the
/// result, the repair counters and the rule that ran.
pub fn resample_in_core_with<I>(grid: &Grid, triangles: I, rule: SignRule, sink: &mut dyn MeshSink) -> Result<(SlabResult, RepairStats, SignRule), SinkError>
where
    I: IntoIterator<Item = [[f64; 3]; 3]>,
{
    resample_in_core_holes(grid, triangles, rule, None, sink).map(|(r, s, rule, _)| (r, s, rule))
}

/// The whole hole protocol in core, as the staged engine runs it across
/// slabs (its `reconstruct` and `reopen` stages): reconstruct once, closing
/// every hole and collecting the hole-capping cells; group them and, with
/// `max_hole`, choose the cells to leave open ([`open_cells`]); if any,
/// reconstruct again with those cells open. Returns what
/// [`resample_in_core_with`] returns and the hole statistics. `Orient` has
/// no holes to close (its non-canonical cells stay empty).
pub fn resample_in_core_holes<I>(
    grid: &Grid,
    triangles: I,
    rule: SignRule,
    max_hole: Option<u32>,
    sink: &mut dyn MeshSink,
) -> Result<(SlabResult, RepairStats, SignRule, HoleStats), SinkError>
where
    I: IntoIterator<Item = [[f64; 3]; 3]>,
{
    if rule == SignRule::Orient {
        let r = resample_in_core(grid, triangles, sink)?;
        return Ok((r, Default::default(), SignRule::Orient, Default::default()));
    }
    let planes = discretize_in_core(grid, triangles);
    let (result, repair, rule, holes) = reconstruct_in_core(grid, planes, rule, max_hole);
    emit(&result, None, sink)?;
    Ok((result, repair, rule, holes))
}

/// The raw intercepts of coloured triangles (world coordinates, corner
/// colours), per plane, each with the colour of its crossing
/// ([`crossing_colour`]).
pub fn discretize_in_core_coloured<I>(grid: &Grid, triangles: I) -> Vec<Vec<Tinted>>
where
    I: IntoIterator<Item = ([[f64; 3]; 3], [Rgba; 3])>,
{
    let [_, nb, ns] = grid.local_dims();
    let mut planes: Vec<Vec<Tinted>> = vec![Vec::new(); ns as usize + 1];
    for (t, colours) in triangles {
        let local = t.map(|p| grid.to_local(p));
        crate::discretize::discretize_triangle(&local, |c| {
            let r = c.intercept(nb);
            planes[r.plane as usize].push((r, crossing_colour(&local, &colours, &c)));
        });
    }
    planes
}

/// [`resample_in_core_holes`] for coloured triangles: the same mesh, each
/// vertex pushed with its colour ([`colour_vertices`]). Returns the same,
/// and the vertex colours.
pub fn resample_in_core_coloured<I>(
    grid: &Grid,
    triangles: I,
    rule: SignRule,
    max_hole: Option<u32>,
    sink: &mut dyn MeshSink,
) -> Result<(SlabResult, RepairStats, SignRule, HoleStats, Vec<Rgba>), SinkError>
where
    I: IntoIterator<Item = ([[f64; 3]; 3], [Rgba; 3])>,
{
    let mut tinted = discretize_in_core_coloured(grid, triangles);
    let planes: Vec<Vec<Intercept>> = tinted.iter().map(|p| p.iter().map(|t| t.0).collect()).collect();
    let (result, repair, rule, holes) = if rule == SignRule::Orient {
        let mut planes = planes;
        for p in &mut planes {
            filter_plane(p);
        }
        (reconstruct_slab(grid, 0, &planes, usize::MAX), Default::default(), SignRule::Orient, Default::default())
    } else {
        reconstruct_in_core(grid, planes, rule, max_hole)
    };
    for p in &mut tinted {
        sort_coloured(p);
    }
    let owned = tinted.len().saturating_sub(1);
    let colours = colour_vertices(grid, 0, &result.vertices, &tinted[..owned]);
    emit(&result, Some(&colours), sink)?;
    Ok((result, repair, rule, holes, colours))
}

/// The robust reconstruction of raw planes with the hole protocol.
fn reconstruct_in_core(grid: &Grid, mut planes: Vec<Vec<Intercept>>, rule: SignRule, max_hole: Option<u32>) -> (SlabResult, RepairStats, SignRule, HoleStats) {
    let rule = if rule == SignRule::Auto {
        let mut census = LineCensus::default();
        for p in &mut planes {
            census += census_plane(p);
        }
        census.resolve()
    } else {
        rule
    };
    let Some(k) = max_hole else {
        let (result, repair) = reconstruct_slab_robust(grid, 0, planes, rule);
        return (result, repair, rule, Default::default());
    };
    let (mut result, mut repair) = reconstruct_slab_robust(grid, 0, planes.clone(), rule);
    let mut cells = result.hole_cells.clone();
    let (open, holes) = open_cells(&mut cells, grid.local_dims(), effective_max_hole(rule, k));
    if !open.is_empty() {
        (result, repair) = reconstruct_slab_solids(grid, 0, vec![planes], &[rule], &Expr::Operand(0), Some(&open), &[]);
    }
    (result, repair, rule, holes)
}

/// The `--max-hole` that applies under `rule`: every hole cell of a sheet
/// (its back and its rim) stays open, whatever the asked size.
pub fn effective_max_hole(rule: SignRule, max_hole: u32) -> u32 {
    if rule == SignRule::Sheet {
        0
    } else {
        max_hole
    }
}

/// Sends a result's vertices (with their colours, if any) and faces to `sink`.
fn emit(result: &SlabResult, colours: Option<&[Rgba]>, sink: &mut dyn MeshSink) -> Result<(), SinkError> {
    match colours {
        Some(c) => {
            for (v, c) in result.vertices.iter().zip(c) {
                sink.vertex_rgba(*v, *c)?;
            }
        }
        None => {
            for v in &result.vertices {
                sink.vertex(*v)?;
            }
        }
    }
    for f in &result.faces {
        sink.face(*f)?;
    }
    Ok(())
}

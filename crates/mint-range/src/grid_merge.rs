//! Grid-based merge (`mint zipper --method grid`): registered scans become
//! one closed mesh through the Marching Intersections grid, after Rocchini,
//! Cignoni, Montani and Scopigno, "The Marching Intersections algorithm for
//! merging range images" (2000), with the signed-distance voting of
//! Curless and Levoy, "A volumetric method for building complex models from
//! range images" (SIGGRAPH 1996), restricted to the grid's lines.
//!
//! Why not just resample the scans together: a single view is an open
//! surface, so the parity or winding of its crossings along a line says
//! nothing about the far side of the object; a line that enters through
//! one scan and leaves through a part no scan saw would stay "inside" to
//! the edge of the grid. Each crossing is therefore trusted only near
//! itself:
//! 1. **Discretize** every posed scan on one grid (mint-core's exact
//!    [`discretize_triangle`]): each crossing is a cell edge, a position
//!    along the line, a sign (entering or leaving, from the triangle's
//!    orientation: scan triangles face the scanner), and a weight — the
//!    triangle's confidence (lowered near the scan's boundary) times
//!    |cos| of the angle between the line and the triangle's normal
//!    (grazing crossings are placed badly).
//! 2. **Vote** at the grid nodes: a crossing at `t` gives every node `x`
//!    of its line within the band `D` the signed distance
//!    `±(x − t)·|cos|` (positive behind the surface, i.e. inside), with
//!    its weight times a tent `1 − |x − t|/D`; a node's value is the
//!    weighted mean over the crossings of its three lines, and its state
//!    is "inside" when the value is positive. This is Curless and Levoy's
//!    cumulative signed distance, sampled only on the grid lines.
//! 3. **Fill** the nodes no crossing reached (the interior of the object,
//!    the empty space around it, and unseen regions) by multi-source
//!    breadth-first search from the voted nodes: each takes the majority
//!    state of its already-decided 6-neighbours (ties: outside). Nodes on
//!    the grid's border are outside. Unseen holes are thus closed where
//!    the states around them meet.
//!    Then outside regions sealed from the grid's border become inside (a
//!    scanner cannot see a sealed void) and inside specks smaller than
//!    [`GridMergeOptions::min_part`] of the largest part become outside.
//! 4. **Intercepts**: every cell edge whose two end states differ gets
//!    exactly one intercept with the matching sign, at the
//!    confidence-weighted mean of the crossings of all scans on that edge
//!    with that sign (the merge of the MI paper); with none, at the zero
//!    of the linear interpolation of the two end values; at the midpoint
//!    when an end was not voted or the two values do not straddle zero
//!    (states that came from the fill or the clean-up).
//! 5. **Reconstruct** with the resampler's state-first reconstruction
//!    ([`mint_core::robust`], winding rule): the intercepts agree with the
//!    states by construction, so every cell is canonical and the output is
//!    a closed, oriented 2-manifold.
//!
//! Memory: two `f32` and one byte per grid node, and during the clean-up
//! a `u32` region label per node and a search stack (up to 8 bytes per
//! node): at most about 21 bytes per node; plus the crossings (a few per
//! cell the surface passes through, per scan seeing it), plus one scan at
//! a time from the [`ScanSource`]. The whole grid is held at once, bounded
//! by [`GridMergeOptions::max_nodes`].

use crate::error::RangeError;
use crate::geom::Rigid;
use crate::source::ScanSource;
use mint_core::progress::{NoProgress, Progress};
use mint_core::signs::SignRule;
use mint_core::{discretize_triangle, Crossing, Grid, GridSize, Intercept, MARGIN};
use serde::Serialize;
use glam::DVec3;

/// Options of [`grid_merge`]; every field has a documented default.
#[derive(Debug, Clone, PartialEq)]
pub struct GridMergeOptions {
    /// The grid: about this many cells over the scans' bounding box, or
    /// this cell size. Default `Cells(1_000_000)`.
    pub size: GridSize,
    /// Half-width D of a crossing's vote along its line, world units.
    /// Default `None`: the larger of 1.5 cells and 3 sampling distances
    /// (registration error and noise must fall inside it).
    pub band: Option<f64>,
    /// Most grid nodes allowed (memory peaks at about 21 bytes per node).
    /// Default 100 million (about 2 GB at the peak).
    pub max_nodes: u64,
    /// Inside regions (6-connected nodes) smaller than this fraction of the
    /// largest one are made outside: specks from stray samples. Default
    /// 0.001; 0 keeps everything.
    pub min_part: f64,
}

impl Default for GridMergeOptions {
    fn default() -> Self {
        GridMergeOptions { size: GridSize::Cells(1_000_000), band: None, max_nodes: 100_000_000, min_part: 0.001 }
    }
}

/// What [`grid_merge`] did.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct GridMergeReport {
    pub scans: usize,
    /// Cells along x, y, z, and the cell size.
    pub dims: [u32; 3],
    pub cell: f64,
    /// The band D used, world units.
    pub band: f64,
    /// Crossings of the scans with the grid lines.
    pub crossings: u64,
    /// Nodes that got a vote, and nodes filled from their neighbours.
    pub voted_nodes: u64,
    pub filled_nodes: u64,
    /// Output vertices placed at a weighted mean of crossings, of which on
    /// an edge crossed by more than one scan (merged); by interpolating
    /// the votes; at an edge midpoint.
    pub vertices_from_crossings: u64,
    pub vertices_merged: u64,
    pub vertices_interpolated: u64,
    pub vertices_midpoint: u64,
    /// Regions of outside nodes sealed from the grid's border that were
    /// made inside, and small inside regions made outside
    /// ([`GridMergeOptions::min_part`]).
    pub voids_filled: u64,
    pub specks_removed: u64,
    pub vertices: usize,
    pub faces: usize,
}

/// One crossing kept for vertex placement: the cell edge (lower node ×
/// 3 + family), its value along the line, sign, weight and scan.
#[derive(Debug, Clone, Copy)]
struct EdgeCrossing {
    edge: u64,
    value: f64,
    entering: bool,
    weight: f64,
    scan: u32,
}

/// The node lattice in the grid's local frame (a, b, s).
struct Lattice {
    /// Nodes along a, b, s.
    n: [u64; 3],
}

impl Lattice {
    #[inline]
    fn index(&self, p: [u64; 3]) -> u64 {
        (p[2] * self.n[1] + p[1]) * self.n[0] + p[0]
    }
    #[inline]
    fn coords(&self, i: u64) -> [u64; 3] {
        [i % self.n[0], (i / self.n[0]) % self.n[1], i / (self.n[0] * self.n[1])]
    }
    fn len(&self) -> u64 {
        self.n[0] * self.n[1] * self.n[2]
    }
    /// The node of line `(family, u, v)` at position `x` along it.
    #[inline]
    fn on_line(family: usize, u: u64, v: u64, x: u64) -> [u64; 3] {
        let mut p = [0; 3];
        p[family] = x;
        p[(family + 1) % 3] = u;
        p[(family + 2) % 3] = v;
        p
    }
}

/// Regions of equal state, 6-connected, in node order: `(region of each
/// node, (state, size, touches the border) of each region)`.
fn regions(state: &[u8], lat: &Lattice, neighbours: &dyn Fn(u64) -> [u64; 6]) -> (Vec<u32>, Vec<(u8, u64, bool)>) {
    const NONE: u32 = u32::MAX;
    let n = state.len();
    let mut region = vec![NONE; n];
    let mut regions: Vec<(u8, u64, bool)> = Vec::new();
    let mut stack = Vec::new();
    for seed in 0..n {
        if region[seed] != NONE {
            continue;
        }
        let id = regions.len() as u32;
        let st = state[seed];
        let (mut size, mut border) = (0u64, false);
        region[seed] = id;
        stack.push(seed as u64);
        while let Some(i) = stack.pop() {
            size += 1;
            let p = lat.coords(i);
            border |= (0..3).any(|k| p[k] == 0 || p[k] == lat.n[k] - 1);
            for j in neighbours(i) {
                if j != u64::MAX && region[j as usize] == NONE && state[j as usize] == st {
                    region[j as usize] = id;
                    stack.push(j);
                }
            }
        }
        regions.push((st, size, border));
    }
    (region, regions)
}

/// The clean-up of the node states. First every region of outside nodes
/// that does not reach the grid's border becomes inside (a range scanner
/// cannot see a sealed void, so such a region comes from noise or a
/// missed back side). Then, on the new regions, every inside region with
/// fewer than `min_part` times the nodes of the largest becomes outside
/// (it then joins an outside region that reaches the border, so no new
/// void appears). Returns how many regions of each kind were changed. The
/// result depends on the states only.
fn clean_states(state: &mut [u8], lat: &Lattice, neighbours: &dyn Fn(u64) -> [u64; 6], min_part: f64) -> (u64, u64) {
    let (region, list) = regions(state, lat, neighbours);
    let void: Vec<bool> = list.iter().map(|&(st, _, border)| st == 0 && !border).collect();
    let voids = void.iter().filter(|&&v| v).count() as u64;
    for (i, s) in state.iter_mut().enumerate() {
        if void[region[i] as usize] {
            *s = 1;
        }
    }
    drop(region);
    let (region, list) = regions(state, lat, neighbours);
    let largest_inside = list.iter().filter(|r| r.0 == 1).map(|r| r.1).max().unwrap_or(0);
    let speck: Vec<bool> = list.iter().map(|&(st, size, _)| st == 1 && (size as f64) < min_part * largest_inside as f64).collect();
    let specks = speck.iter().filter(|&&v| v).count() as u64;
    for (i, s) in state.iter_mut().enumerate() {
        if speck[region[i] as usize] {
            *s = 0;
        }
    }
    (voids, specks)
}

/// Merges the scans at their poses into one closed mesh on a grid (see the
/// module docs). Returns world `(positions, faces, report)`.
pub fn grid_merge<S: ScanSource + ?Sized>(scans: &S, poses: &[Rigid], opts: &GridMergeOptions) -> Result<crate::Merged<GridMergeReport>, RangeError> {
    grid_merge_with(scans, poses, opts, &NoProgress)
}

/// [`grid_merge`], reporting each scan visited ([`crate::phases::GRID_MERGE`]: the
/// bounding-box pass, then the voting pass) and stopping with
/// [`RangeError::Cancelled`] between scans when asked.
pub fn grid_merge_with<S: ScanSource + ?Sized>(scans: &S, poses: &[Rigid], opts: &GridMergeOptions, progress: &dyn Progress) -> Result<crate::Merged<GridMergeReport>, RangeError> {
    if scans.is_empty() {
        return Err(RangeError::option("scans", "nothing to merge"));
    }
    if scans.len() != poses.len() {
        return Err(RangeError::option("poses", format!("{} poses for {} scans", poses.len(), scans.len())));
    }
    // 1. The grid around every posed scan vertex in use.
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    progress.start(crate::phases::GRID_MERGE, 2 * poses.len() as u64);
    let step = || crate::error::advance(progress);
    for (i, pose) in poses.iter().enumerate() {
        step()?;
        let s = scans.scan(i)?;
        for f in &s.faces {
            for &v in f {
                let p = pose.apply(s.positions[v as usize]);
                for k in 0..3 {
                    lo[k] = lo[k].min(p[k]);
                    hi[k] = hi[k].max(p[k]);
                }
            }
        }
    }
    if lo[0] > hi[0] {
        return Err(RangeError::option("scans", "no scan has a triangle"));
    }
    let grid = Grid::around(lo, hi, opts.size, [0.0; 3], None)?;
    let dims = grid.local_dims();
    let lat = Lattice { n: dims.map(|d| d as u64 + 1) };
    if lat.len() > opts.max_nodes {
        return Err(RangeError::option("size", format!("{} grid nodes exceed the limit of {} (up to about 21 bytes each); use fewer cells", lat.len(), opts.max_nodes)));
    }
    let s_max = scans.max_sampling();
    let band_world = opts.band.unwrap_or((1.5 * grid.cell).max(3.0 * s_max));
    if !(band_world.is_finite() && band_world > 0.0) {
        return Err(RangeError::option("band", format!("{band_world} is not a positive number")));
    }
    let band = band_world / grid.cell;
    let mut report = GridMergeReport { scans: scans.len(), dims: grid.dims, cell: grid.cell, band: band_world, ..Default::default() };

    // 2. Discretize and vote.
    let nodes = lat.len() as usize;
    let mut sum_w = vec![0f32; nodes];
    let mut sum_wd = vec![0f32; nodes];
    let mut kept: Vec<EdgeCrossing> = Vec::new();
    for (si, pose) in poses.iter().enumerate() {
        step()?;
        let s = scans.scan(si)?;
        for (fi, f) in s.faces.iter().enumerate() {
            let conf = s.face_confidence[fi];
            if conf <= 0.0 {
                continue;
            }
            let local = f.map(|v| grid.to_local(pose.apply(s.positions[v as usize])));
            let [a, b, c] = local.map(DVec3::from);
            let n = (b - a).cross(c - a).normalize_or_zero();
            discretize_triangle(&local, |c: Crossing| {
                let fam = c.family as usize;
                let cos = n[fam].abs();
                let w = conf * cos;
                if w <= 0.0 {
                    return;
                }
                report.crossings += 1;
                let (u, v) = (c.u as u64, c.v as u64);
                let lower = lat.index(Lattice::on_line(fam, u, v, c.cell as u64));
                kept.push(EdgeCrossing { edge: lower * 3 + fam as u64, value: c.value, entering: c.entering, weight: w, scan: si as u32 });
                let sign = if c.entering { 1.0 } else { -1.0 };
                let x0 = (c.value - band).ceil().max(0.0) as u64;
                let x1 = ((c.value + band).floor() as u64).min(lat.n[fam] - 1);
                for x in x0..=x1 {
                    let off = x as f64 - c.value;
                    let tent = 1.0 - off.abs() / band;
                    if tent <= 0.0 {
                        continue;
                    }
                    let i = lat.index(Lattice::on_line(fam, u, v, x)) as usize;
                    sum_w[i] += (w * tent) as f32;
                    sum_wd[i] += (w * tent * sign * off * cos) as f32;
                }
            });
        }
    }

    progress.finish();

    // 3. States: voted nodes by the sign of their mean, the border
    // outside, the rest filled breadth-first.
    const UNKNOWN: u8 = 2;
    let mut state = vec![UNKNOWN; nodes];
    for i in 0..nodes {
        if sum_w[i] > 0.0 {
            state[i] = (sum_wd[i] > 0.0) as u8;
            report.voted_nodes += 1;
        }
    }
    for i in 0..lat.len() {
        let p = lat.coords(i);
        if (0..3).any(|k| p[k] == 0 || p[k] == lat.n[k] - 1) {
            state[i as usize] = 0;
        }
    }
    let neighbours = |i: u64| {
        let p = lat.coords(i);
        let mut out = [u64::MAX; 6];
        for k in 0..3 {
            if p[k] > 0 {
                let mut q = p;
                q[k] -= 1;
                out[2 * k] = lat.index(q);
            }
            if p[k] + 1 < lat.n[k] {
                let mut q = p;
                q[k] += 1;
                out[2 * k + 1] = lat.index(q);
            }
        }
        out
    };
    let mut frontier: Vec<u64> = (0..lat.len()).filter(|&i| state[i as usize] != UNKNOWN && neighbours(i).iter().any(|&j| j != u64::MAX && state[j as usize] == UNKNOWN)).collect();
    while !frontier.is_empty() {
        let mut next: Vec<u64> = frontier.iter().flat_map(|&i| neighbours(i)).filter(|&j| j != u64::MAX && state[j as usize] == UNKNOWN).collect();
        next.sort_unstable();
        next.dedup();
        let votes: Vec<u8> = next
            .iter()
            .map(|&j| {
                let (mut inside, mut outside) = (0, 0);
                for k in neighbours(j) {
                    match state.get(k as usize) {
                        Some(1) => inside += 1,
                        Some(0) => outside += 1,
                        _ => {}
                    }
                }
                (inside > outside) as u8
            })
            .collect();
        for (&j, &s) in next.iter().zip(&votes) {
            state[j as usize] = s;
        }
        report.filled_nodes += next.len() as u64;
        frontier = next;
    }

    // Clean-up of the states: sealed voids and specks.
    let (voids, specks) = clean_states(&mut state, &lat, &neighbours, opts.min_part);
    report.voids_filled = voids;
    report.specks_removed = specks;

    // 4. One intercept per edge with a state change.
    kept.sort_by(|a, b| a.edge.cmp(&b.edge).then(a.scan.cmp(&b.scan)).then(a.value.total_cmp(&b.value)));
    let mut planes: Vec<Vec<Intercept>> = vec![Vec::new(); dims[2] as usize + 1];
    let value_at = |i: u64| -> Option<f64> { (sum_w[i as usize] > 0.0).then(|| sum_wd[i as usize] as f64 / sum_w[i as usize] as f64) };
    for i in 0..lat.len() {
        let p = lat.coords(i);
        for fam in 0..3 {
            if p[fam] + 1 >= lat.n[fam] {
                continue;
            }
            let mut q = p;
            q[fam] += 1;
            let j = lat.index(q);
            let (s0, s1) = (state[i as usize], state[j as usize]);
            if s0 == s1 {
                continue;
            }
            let entering = s1 == 1;
            let edge = i * 3 + fam as u64;
            let start = kept.partition_point(|c| c.edge < edge);
            let matching = kept[start..].iter().take_while(|c| c.edge == edge).filter(|c| c.entering == entering);
            let (mut w, mut wv, mut first_scan, mut several) = (0.0, 0.0, None, false);
            for c in matching {
                w += c.weight;
                wv += c.weight * c.value;
                match first_scan {
                    None => first_scan = Some(c.scan),
                    Some(s) if s != c.scan => several = true,
                    _ => {}
                }
            }
            let x = p[fam] as f64;
            let interpolated = match (value_at(i), value_at(j)) {
                (Some(f0), Some(f1)) if (f0 > 0.0) != (f1 > 0.0) => Some(x + f0 / (f0 - f1)),
                _ => None,
            };
            let value = if w > 0.0 {
                report.vertices_from_crossings += 1;
                report.vertices_merged += several as u64;
                wv / w
            } else if let Some(v) = interpolated {
                report.vertices_interpolated += 1;
                v
            } else {
                report.vertices_midpoint += 1;
                x + 0.5
            };
            let value = value.clamp(x + MARGIN, x + 1.0 - MARGIN);
            let c = Crossing { family: fam as u8, u: p[(fam + 1) % 3] as i64, v: p[(fam + 2) % 3] as i64, cell: p[fam] as i64, value, entering };
            let r = c.intercept(dims[1]);
            planes[r.plane as usize].push(r);
        }
    }
    drop(kept);
    drop(sum_w);
    drop(sum_wd);

    // 5. Reconstruct.
    let (result, _) = mint_core::robust::reconstruct_slab_robust(&grid, 0, planes, SignRule::Union);
    report.vertices = result.vertices.len();
    report.faces = result.faces.len();
    Ok((result.vertices, result.faces, report))
}

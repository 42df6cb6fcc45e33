//! [`simplify`]: in-core decimation of a triangle mesh to a face target by
//! quadric edge collapse in f64 ([`crate::qem`]: each kept vertex moves to
//! where the error of the planes it gathers is least), followed by a
//! judgement of the result with [`crate::check`]: a closed, 2-manifold,
//! consistently oriented input must give one too. The collapses keep the
//! link condition and refuse faces that turn over, so a defect is rare; if
//! one appears anyway, the target is relaxed step by step towards the input
//! size until the result is clean, and the report says so. A mesh worse
//! than the input is never handed over silently.
//!
//! Memory: the input, the collapse's tables (per vertex a quadric of 88
//! bytes, 288 with colour, a position, a face list and an edge list; per
//! face 12 bytes; per edge its ends, 8 bytes, its id in both ends' lists
//! and a heap entry of 28 bytes), and the result.
//!
//! [`simplify_coloured`] does the same for a mesh with a colour per vertex,
//! by colour-aware quadrics ([`crate::qem::collapse_coloured`]).

use crate::check::{try_check, CheckReport};
use crate::error::MeshError;

/// Options of [`simplify`].
#[derive(Debug, Clone)]
pub struct SimplifyOptions {
    /// The number of faces to reach (at most; a closed surface needs at
    /// least 4).
    pub target_faces: u64,
    /// Stop early once the geometric error would exceed this fraction of the
    /// mesh's extent. Default 1.0: the face target decides.
    pub max_error: f32,
    /// The planes the quadrics gather: the faces' own (a mesh simplified
    /// itself, the default) or lifted onto the surface through the
    /// vertices (a resampled intermediate, [`crate::qem::Planes`]).
    pub planes: crate::qem::Planes,
}

impl Default for SimplifyOptions {
    fn default() -> Self {
        SimplifyOptions { target_faces: 1000, max_error: 1.0, planes: crate::qem::Planes::Faces }
    }
}

/// What [`simplify`] did.
#[derive(Debug, Clone, serde::Serialize)]
pub struct SimplifyReport {
    pub input_faces: u64,
    pub output_faces: u64,
    pub output_vertices: u64,
    /// The simplifier's own error estimate, relative to the mesh extent.
    pub error: f32,
    /// Pairs of faces on the same three vertices with opposite orientations
    /// (a handle or a thin part collapsed flat), removed together.
    pub folded_pairs_removed: u64,
    /// The input was closed, 2-manifold and consistently oriented.
    pub input_watertight: bool,
    /// So is the output.
    pub output_watertight: bool,
    /// Times the target was relaxed because a result was less clean than the input.
    pub relaxed: u32,
}

/// Simplifies `positions`/`faces` to about `o.target_faces` faces; returns
/// the new mesh (unreferenced vertices removed, order kept) and a report.
pub fn simplify(positions: &[[f64; 3]], faces: &[[u32; 3]], o: &SimplifyOptions) -> Result<(Vec<[f64; 3]>, Vec<[u32; 3]>, SimplifyReport), MeshError> {
    simplify_with(positions, faces, o, &|| false)
}

/// [`simplify`] with a `stop` hook (Ctrl-C), asked while collapsing: when
/// it says true, [`MeshError::Cancelled`].
pub fn simplify_with(
    positions: &[[f64; 3]],
    faces: &[[u32; 3]],
    o: &SimplifyOptions,
    stop: &(dyn Fn() -> bool + Sync),
) -> Result<(Vec<[f64; 3]>, Vec<[u32; 3]>, SimplifyReport), MeshError> {
    simplify_impl(positions, faces, None, o, stop).map(|(p, f, _, r)| (p, f, r))
}

/// [`simplify_with`] for a mesh with a colour per vertex, by colour-aware
/// quadrics ([`crate::qem::collapse_coloured`]; `colour_weight`: the
/// distance, as a fraction of the extent, that a full-range colour
/// difference costs as much as). Returns the colours of the output's
/// vertices too.
#[allow(clippy::type_complexity)]
pub fn simplify_coloured(
    positions: &[[f64; 3]],
    faces: &[[u32; 3]],
    colours: &[[u8; 4]],
    colour_weight: f64,
    o: &SimplifyOptions,
    stop: &(dyn Fn() -> bool + Sync),
) -> Result<(Vec<[f64; 3]>, Vec<[u32; 3]>, Vec<[u8; 4]>, SimplifyReport), MeshError> {
    simplify_impl(positions, faces, Some((colours, colour_weight)), o, stop).map(|(p, f, c, r)| (p, f, c.unwrap_or_default(), r))
}

#[allow(clippy::type_complexity)]
fn simplify_impl(
    positions: &[[f64; 3]],
    faces: &[[u32; 3]],
    colours: Option<(&[[u8; 4]], f64)>,
    o: &SimplifyOptions,
    stop: &(dyn Fn() -> bool + Sync),
) -> Result<(Vec<[f64; 3]>, Vec<[u32; 3]>, Option<Vec<[u8; 4]>>, SimplifyReport), MeshError> {
    let trace = std::env::var_os("MINT_QEM_TRACE").is_some();
    let t = std::time::Instant::now();
    let before = try_check(positions, faces)?;
    let input_watertight = before.watertight;
    if trace {
        eprintln!("qem: input checked at {:.2}s", t.elapsed().as_secs_f64());
    }
    let mut target = o.target_faces.min(faces.len() as u64);
    let mut relaxed = 0;
    loop {
        let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
        let blocks = crate::qem::blocks_for(faces.len());
        let (moved, out, moved_colours, collapse) = match colours {
            Some((c, w)) => {
                let (p, f, c, st) = crate::qem::collapse_coloured(positions, faces, o.planes, c, w, target, o.max_error as f64, blocks, threads, stop);
                (p, f, Some(c), st)
            }
            None => {
                let (p, f, st) = crate::qem::collapse_in_blocks(positions, faces, o.planes, target, o.max_error as f64, blocks, threads, stop);
                (p, f, None, st)
            }
        };
        if collapse.stopped {
            return Err(MeshError::Cancelled);
        }
        if trace {
            eprintln!("qem: {collapse:?} at {:.2}s", t.elapsed().as_secs_f64());
        }
        let error = if collapse.extent > 0.0 { (collapse.max_error / collapse.extent) as f32 } else { 0.0 };
        let mut out: Vec<u32> = out.iter().flatten().copied().collect();
        let positions = &moved[..];
        let mut removed = 0;
        if input_watertight {
            removed = drop_folded_pairs(&mut out);
        }
        let (p, f, kept) = compact(positions, &out);
        let out_colours = moved_colours.map(|c| kept.iter().map(|&v| c[v as usize]).collect::<Vec<[u8; 4]>>());
        let after: CheckReport = try_check(&p, &f)?;
        if trace {
            eprintln!("qem: checked at {:.2}s", t.elapsed().as_secs_f64());
        }
        let clean = !input_watertight || after.watertight;
        if clean || target >= faces.len() as u64 {
            let report = SimplifyReport {
                input_faces: faces.len() as u64,
                output_faces: f.len() as u64,
                output_vertices: p.len() as u64,
                error,
                folded_pairs_removed: removed,
                input_watertight,
                output_watertight: after.watertight,
                relaxed,
            };
            return Ok((p, f, out_colours, report));
        }
        // Less clean than the input: another collapse sequence. First
        // targets within ±1.5% of the asked one (the defect usually comes
        // from one late collapse), then ever fewer collapses.
        relaxed += 1;
        let asked = o.target_faces.min(faces.len() as u64) as f64;
        target = match relaxed {
            r @ 1..=6 => {
                let step = [0.995, 1.005, 0.99, 1.01, 0.985, 1.015][r as usize - 1];
                ((asked * step).round() as u64).max(4)
            }
            _ => target + target / 8 + 1,
        }
        .min(faces.len() as u64);
    }
}

/// Removes pairs of faces on the same three vertices with opposite
/// orientations: the flat remains of a handle or thin part the collapses
/// squeezed shut. Each such pair is its own closed two-sided sheet; the rest
/// of the surface does not use it, so removing both keeps the rest closed.
/// Returns the pairs removed.
fn drop_folded_pairs(indices: &mut Vec<u32>) -> u64 {
    let n = indices.len() / 3;
    let key = |f: usize| {
        let mut t = [indices[3 * f], indices[3 * f + 1], indices[3 * f + 2]];
        t.sort_unstable();
        t
    };
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_unstable_by_key(|&f| (key(f), f));
    let mut drop = vec![false; n];
    let mut pairs = 0;
    let mut i = 0;
    while i < n {
        let mut j = i + 1;
        while j < n && key(order[j]) == key(order[i]) {
            j += 1;
        }
        // Exactly two faces on these vertices, of opposite orientation.
        if j - i == 2 {
            let (a, b) = (order[i], order[i + 1]);
            let ta = [indices[3 * a], indices[3 * a + 1], indices[3 * a + 2]];
            let tb = [indices[3 * b], indices[3 * b + 1], indices[3 * b + 2]];
            let same = (0..3).any(|r| [tb[r], tb[(r + 1) % 3], tb[(r + 2) % 3]] == ta);
            if !same {
                drop[a] = true;
                drop[b] = true;
                pairs += 1;
            }
        }
        i = j;
    }
    if pairs > 0 {
        let kept: Vec<u32> = (0..n).filter(|&f| !drop[f]).flat_map(|f| [indices[3 * f], indices[3 * f + 1], indices[3 * f + 2]]).collect();
        *indices = kept;
    }
    pairs
}

/// The faces of `indices` with only their vertices, renumbered in order;
/// and the old id of each new vertex.
fn compact(positions: &[[f64; 3]], indices: &[u32]) -> (Vec<[f64; 3]>, Vec<[u32; 3]>, Vec<u32>) {
    let mut map = vec![u32::MAX; positions.len()];
    let mut p = Vec::new();
    let mut kept = Vec::new();
    let f = indices
        .chunks_exact(3)
        .map(|t| {
            [0, 1, 2].map(|k| {
                let v = t[k] as usize;
                if map[v] == u32::MAX {
                    map[v] = p.len() as u32;
                    p.push(positions[v]);
                    kept.push(v as u32);
                }
                map[v]
            })
        })
        .collect();
    (p, f, kept)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sphere(n: u32) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
        // A UV sphere with poles: n rings, 2n segments.
        let seg = 2 * n;
        let mut p = vec![[0.0, 0.0, 1.0]];
        for i in 1..n {
            let t = std::f64::consts::PI * i as f64 / n as f64;
            for j in 0..seg {
                let u = 2.0 * std::f64::consts::PI * j as f64 / seg as f64;
                p.push([t.sin() * u.cos(), t.sin() * u.sin(), t.cos()]);
            }
        }
        p.push([0.0, 0.0, -1.0]);
        let south = p.len() as u32 - 1;
        let ring = |i: u32, j: u32| 1 + (i - 1) * seg + j % seg;
        let mut f = Vec::new();
        for j in 0..seg {
            f.push([0, ring(1, j), ring(1, j + 1)]);
            f.push([south, ring(n - 1, j + 1), ring(n - 1, j)]);
        }
        for i in 1..n - 1 {
            for j in 0..seg {
                f.push([ring(i, j), ring(i + 1, j), ring(i + 1, j + 1)]);
                f.push([ring(i, j), ring(i + 1, j + 1), ring(i, j + 1)]);
            }
        }
        (p, f)
    }

    #[test]
    fn a_sphere_simplifies_to_its_target_and_stays_closed() {
        let (p, f) = sphere(60);
        assert!(try_check(&p, &f).unwrap().watertight);
        for target in [5000u64, 1000, 200] {
            let (q, g, r) = simplify(&p, &f, &SimplifyOptions { target_faces: target, ..Default::default() }).unwrap();
            assert!(r.output_watertight, "{target}: {r:?}");
            assert!(g.len() as u64 <= target && g.len() as f64 >= 0.98 * target as f64, "{target}: {} faces", g.len());
            assert_eq!(q.len() as u64, r.output_vertices);
        }
    }
}

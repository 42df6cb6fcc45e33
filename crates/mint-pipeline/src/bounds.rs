//! The bounds pass: a range of vertices (after a transform) to their box,
//! read from the map by the worker pool, checking on the way that every
//! vertex is finite, so that workers resolving indices later need not
//! check again.

use crate::error::PipelineError;
use crate::progress::Progress;
use mint_core::primitives::Transform;
use mint_io::VertexPositions;
use std::path::Path;

/// The bounding box of vertices `range` (after `xf`), read from the map in
/// parallel; `None` for an empty range. Also the check that every vertex is
/// finite, so that workers resolving indices later need not check again.
pub(crate) fn bounds(
    positions: &VertexPositions,
    range: (u64, u64),
    path: &Path,
    threads: usize,
    progress: &dyn Progress,
    xf: Option<&Transform>,
) -> Result<Option<([f64; 3], [f64; 3])>, PipelineError> {
    let (first, end) = range;
    let n = end - first;
    progress.start(crate::progress::BOUNDS, n);
    // Blocks of 2^20 vertices; each worker keeps its own box (min and max
    // do not depend on which worker saw which block).
    const BLOCK: u64 = 1 << 20;
    let boxes = mint_core::pool::collect(
        threads,
        n.div_ceil(BLOCK),
        |_| ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]),
        |(lo, hi), k| {
            let (a, b) = (first + k * BLOCK, first + ((k + 1) * BLOCK).min(n));
            let mut grow = |p: [f64; 3]| {
                for d in 0..3 {
                    lo[d] = lo[d].min(p[d]);
                    hi[d] = hi[d].max(p[d]);
                }
            };
            match xf {
                // The common case: a tight loop in mint-io.
                None => match positions.bounds(a as u32, b as u32) {
                    Ok(Some((l, h))) => {
                        grow(l);
                        grow(h);
                    }
                    Ok(None) => {}
                    Err((i, p)) => return Err(PipelineError::NonFinite { path: path.to_path_buf(), index: i as u64, x: p[0], y: p[1], z: p[2] }),
                },
                Some(t) => {
                    for i in a..b {
                        let p = positions.get(i as u32);
                        if !(p[0].is_finite() && p[1].is_finite() && p[2].is_finite()) {
                            return Err(PipelineError::NonFinite { path: path.to_path_buf(), index: i, x: p[0], y: p[1], z: p[2] });
                        }
                        let p = t.apply_point(p);
                        if !(p[0].is_finite() && p[1].is_finite() && p[2].is_finite()) {
                            return Err(PipelineError::TransformOverflow { path: path.to_path_buf(), index: i, x: p[0], y: p[1], z: p[2] });
                        }
                        grow(p);
                    }
                }
            }
            progress.advance(b - a);
            Ok(())
        },
        |b| b,
    )?;
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for (l, h) in boxes {
        for d in 0..3 {
            lo[d] = lo[d].min(l[d]);
            hi[d] = hi[d].max(h[d]);
        }
    }
    progress.finish();
    Ok((n > 0).then_some((lo, hi)))
}

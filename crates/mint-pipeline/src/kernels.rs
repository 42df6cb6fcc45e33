//! The per-triangle kernels of the discretize passes: a triangle to local
//! grid coordinates (the slab axis a constant), its crossings with grid
//! lines and its signed volume, in a scalar and an AVX2 compilation that
//! give the same bits.

use crate::progress::Progress;
use mint_core::grid::Grid;
use mint_core::primitives::Transform;
use mint_core::{discretize_triangle, Intercept};
use mint_io::{TriangleRecords, TriangleVisitor};

/// One chunk of the direct path: each triangle to local coordinates (the
/// slab axis `S` a constant, so that the permutation costs nothing; `S = 3`:
/// any axis, with a transform), its volume, its crossings.
///
/// On x86-64 CPUs with AVX2 the same code runs compiled for them (chosen at
/// run time): the VEX encoding's three-operand forms save the register
/// copies that dominate the per-triangle work. The arithmetic is the same
/// IEEE operations in the same order (Rust never fuses a multiply and an
/// add on its own), so the output bytes do not depend on the CPU;
/// `MINT_NO_AVX2=1` in the environment forces the baseline compilation, so
/// that a test can compare the two.
#[inline(never)]
pub(crate) fn visit_chunk<const S: usize>(job: &ChunkJob, recs: &mut Vec<Intercept>, volume: &mut f64) -> Result<bool, mint_io::Error> {
    visit_chunk_marked::<S, false>(job, recs, volume, &mut Vec::new())
}

/// [`visit_chunk`] that also notes, with `MARK`, each triangle that crossed
/// a line: `(record, index of its first record in recs)`, in order (for
/// the colours of a coloured file). The records and volume are the same.
#[inline(never)]
pub(crate) fn visit_chunk_marked<const S: usize, const MARK: bool>(job: &ChunkJob, recs: &mut Vec<Intercept>, volume: &mut f64, marks: &mut Vec<(u64, u32)>) -> Result<bool, mint_io::Error> {
    #[cfg(target_arch = "x86_64")]
    if mint_io::use_avx2() {
        #[target_feature(enable = "avx2")]
        unsafe fn with_avx2<const S: usize, const MARK: bool>(job: &ChunkJob, recs: &mut Vec<Intercept>, volume: &mut f64, marks: &mut Vec<(u64, u32)>) -> Result<bool, mint_io::Error> {
            visit_chunk_body::<S, true, MARK>(job, recs, volume, marks)
        }
        // SAFETY: the CPU has AVX2 (checked by `use_avx2`).
        return unsafe { with_avx2::<S, MARK>(job, recs, volume, marks) };
    }
    visit_chunk_body::<S, false, MARK>(job, recs, volume, marks)
}

/// What one call of [`visit_chunk`] works on: records `a .. b`.
pub(crate) struct ChunkJob<'a> {
    pub(crate) records: &'a TriangleRecords,
    pub(crate) a: u64,
    pub(crate) b: u64,
    pub(crate) local: &'a LocalMap,
    pub(crate) xf: Option<&'a Transform>,
    pub(crate) nb: u32,
    pub(crate) progress: &'a dyn Progress,
}

/// [`visit_chunk`]'s work, inlined into each of its two compilations
/// (`AVX`: the AVX2 one, which takes [`triangle_avx`] for the common case).
#[inline(always)]
fn visit_chunk_body<const S: usize, const AVX: bool, const MARK: bool>(job: &ChunkJob, recs: &mut Vec<Intercept>, volume: &mut f64, marks: &mut Vec<(u64, u32)>) -> Result<bool, mint_io::Error> {
    let ChunkJob { records, a, b, local, xf, nb, progress } = *job;
    // One visitor for the whole chunk (one running volume sum, so the same
    // bits), walked in steps so that a cancellation is seen within a step
    // even when every corner is a page fault.
    const STEP: u64 = 4096;
    let mut visitor = Chunk::<S, AVX, MARK> { local, xf, nb, recs, volume: 0.0, k: a, marks };
    let mut at = a;
    while at < b {
        if at > a && progress.cancelled() {
            return Ok(false);
        }
        let to = (at + STEP).min(b);
        records.visit(at, to, &mut visitor)?;
        at = to;
    }
    *volume = visitor.volume;
    Ok(true)
}

/// What [`visit_chunk`] does with each triangle.
struct Chunk<'a, const S: usize, const AVX: bool, const MARK: bool> {
    local: &'a LocalMap,
    xf: Option<&'a Transform>,
    nb: u32,
    recs: &'a mut Vec<Intercept>,
    volume: f64,
    /// With `MARK`: the record being visited, and the marks.
    k: u64,
    marks: &'a mut Vec<(u64, u32)>,
}

impl<const S: usize, const AVX: bool, const MARK: bool> Chunk<'_, S, AVX, MARK> {
    /// Notes record `k` when it added records from `before` on.
    #[inline(always)]
    fn mark(&mut self, before: usize) {
        if MARK {
            if self.recs.len() != before {
                self.marks.push((self.k, before as u32));
            }
            self.k += 1;
        }
    }
}

impl<const S: usize, const AVX: bool, const MARK: bool> TriangleVisitor for Chunk<'_, S, AVX, MARK> {
    #[inline(always)]
    fn triangle(&mut self, p: &[[f64; 3]; 3]) {
        let before = self.recs.len();
        #[cfg(target_arch = "x86_64")]
        if AVX && S < 3 {
            // SAFETY: `AVX` is true only in `visit_chunk`'s AVX2
            // compilation, entered after checking that the CPU has AVX2.
            unsafe { triangle_avx::<S>(p, self.local, self.nb, self.recs, &mut self.volume) };
            self.mark(before);
            return;
        }
        triangle::<S>(p, self.local, self.xf, self.nb, self.recs, &mut self.volume);
        self.mark(before);
    }

    #[inline(always)]
    fn triangle_f32le(&mut self, raw: &[[u8; 16]; 3]) {
        #[cfg(target_arch = "x86_64")]
        if AVX && S < 3 {
            let before = self.recs.len();
            // SAFETY: as in `triangle`.
            unsafe { triangle_avx_f32::<S>(raw, self.local, self.nb, self.recs, &mut self.volume) };
            self.mark(before);
            return;
        }
        self.triangle(&mint_io::f32le_corners(raw))
    }
}

/// [`triangle`] for a slab axis `S` of 0, 1 or 2 (no transform), on AVX
/// vectors of one vertex each: the same IEEE operations lane by lane, in
/// the same order, so the same local coordinates and volume bits. The
/// vectors only decide the common case, a triangle whose bounding box
/// holds no line of two families; any other goes to the scalar
/// [`discretize_triangle`] with the same local coordinates. (The vector
/// ceiling may give -0.0 where the scalar one gives 0.0; both compare the
/// same.)
///
/// # Safety
/// The CPU must have AVX2, and the caller must be compiled for it.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn triangle_avx<const S: usize>(p: &[[f64; 3]; 3], local: &LocalMap, nb: u32, recs: &mut Vec<Intercept>, v: &mut f64) {
    use std::arch::x86_64::*;
    // Local axes (a, b, s) = ((s + 1) % 3, (s + 2) % 3, s), as in `triangle`;
    // the fourth lane is 0 throughout.
    let world = |q: &[f64; 3]| match S {
        0 => _mm256_setr_pd(q[1], q[2], q[0], 0.0),
        1 => _mm256_setr_pd(q[2], q[0], q[1], 0.0),
        _ => _mm256_setr_pd(q[0], q[1], q[2], 0.0),
    };
    triangle_avx_local(world(&p[0]), world(&p[1]), world(&p[2]), local, nb, recs, v)
}

/// [`triangle_avx`] for corners given as packed little-endian f32 windows
/// (`TriangleVisitor::triangle_f32le`): each corner is one 16-byte load
/// and one conversion to f64 (exact, so the same values), its lanes put in
/// local axis order with the fourth set to 0, as `triangle_avx` has them.
///
/// # Safety
/// As [`triangle_avx`].
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn triangle_avx_f32<const S: usize>(raw: &[[u8; 16]; 3], local: &LocalMap, nb: u32, recs: &mut Vec<Intercept>, v: &mut f64) {
    use std::arch::x86_64::*;
    // (x, y, z, w) -> (y, z, x, w), (z, x, y, w) or (x, y, z, w).
    const YZX: i32 = 0b11_00_10_01;
    const ZXY: i32 = 0b11_01_00_10;
    let zero = _mm256_setzero_pd();
    let world = |r: &[u8; 16]| {
        let q = _mm256_cvtps_pd(_mm_loadu_ps(r.as_ptr() as *const f32));
        let q = match S {
            0 => _mm256_permute4x64_pd::<YZX>(q),
            1 => _mm256_permute4x64_pd::<ZXY>(q),
            _ => q,
        };
        _mm256_blend_pd::<0b1000>(q, zero)
    };
    triangle_avx_local(world(&raw[0]), world(&raw[1]), world(&raw[2]), local, nb, recs, v)
}

/// The rest of [`triangle_avx`]: corners in local axis order (fourth lane
/// 0) to local coordinates, the volume, the reject, the crossings.
///
/// # Safety
/// As [`triangle_avx`].
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn triangle_avx_local(
    p0: std::arch::x86_64::__m256d,
    p1: std::arch::x86_64::__m256d,
    p2: std::arch::x86_64::__m256d,
    local: &LocalMap,
    nb: u32,
    recs: &mut Vec<Intercept>,
    v: &mut f64,
) {
    use std::arch::x86_64::*;
    let o = local.origin;
    let origin = _mm256_setr_pd(o[0], o[1], o[2], 0.0);
    let inv = _mm256_set1_pd(local.inv);
    let map = |q: __m256d| _mm256_mul_pd(_mm256_sub_pd(q, origin), inv);
    let (a, b, c) = (map(p0), map(p1), map(p2));
    // signed_volume6: a0 (b1 c2 - b2 c1) - a1 (b0 c2 - b2 c0) + a2 (b0 c1 - b1 c0),
    // lanes (b1, b0, b0) (c2, c2, c1) - (b2, b2, b1) (c1, c0, c0).
    const B1B0B0: i32 = 0b11_00_00_01;
    const B2B2B1: i32 = 0b11_01_10_10;
    let m = _mm256_sub_pd(
        _mm256_mul_pd(_mm256_permute4x64_pd::<B1B0B0>(b), _mm256_permute4x64_pd::<B2B2B1>(c)),
        _mm256_mul_pd(_mm256_permute4x64_pd::<B2B2B1>(b), _mm256_permute4x64_pd::<B1B0B0>(c)),
    );
    let mut t = [0.0f64; 4];
    _mm256_storeu_pd(t.as_mut_ptr(), _mm256_mul_pd(a, m));
    *v += t[0] - t[1] + t[2];
    // discretize_triangle's fast reject: a family is possible when its two
    // axes each hold an integer in [ceil(lo), hi).
    let lo = _mm256_min_pd(_mm256_min_pd(a, b), c);
    let hi = _mm256_max_pd(_mm256_max_pd(a, b), c);
    let first = _mm256_round_pd::<{ _MM_FROUND_TO_POS_INF | _MM_FROUND_NO_EXC }>(lo);
    let has = _mm256_movemask_pd(_mm256_cmp_pd::<_CMP_LT_OQ>(first, hi)) & 7;
    if has & (has - 1) == 0 {
        return;
    }
    let mut l = [[0.0f64; 4]; 3];
    _mm256_storeu_pd(l[0].as_mut_ptr(), a);
    _mm256_storeu_pd(l[1].as_mut_ptr(), b);
    _mm256_storeu_pd(l[2].as_mut_ptr(), c);
    crossings_of(&l.map(|q| [q[0], q[1], q[2]]), nb, recs);
}

/// The crossings of one triangle (local coordinates) into `recs`, out of
/// line, so that the caller's loop stays small. (Holding the triangles
/// that are not rejected and finding their crossings in batches, to save
/// the mispredicted branch, measured no faster.)
#[inline(never)]
fn crossings_of(l: &[[f64; 3]; 3], nb: u32, recs: &mut Vec<Intercept>) {
    discretize_triangle(l, |x| recs.push(x.intercept(nb)));
}

/// Resolved triangles `tris` (each chunk's, in face order): local
/// coordinates, volume and crossings, exactly as the direct path computes
/// them triangle by triangle (so the same bits).
pub(crate) fn discretize_slice(tris: &[[[f64; 3]; 3]], axis: usize, local: &LocalMap, xf: Option<&Transform>, nb: u32, recs: &mut Vec<Intercept>, volume: &mut f64) {
    #[inline(never)]
    fn run<const S: usize>(tris: &[[[f64; 3]; 3]], local: &LocalMap, xf: Option<&Transform>, nb: u32, recs: &mut Vec<Intercept>, volume: &mut f64) {
        for p in tris {
            triangle::<S>(p, local, xf, nb, recs, volume);
        }
    }
    match (axis, xf) {
        (0, None) => run::<0>(tris, local, None, nb, recs, volume),
        (1, None) => run::<1>(tris, local, None, nb, recs, volume),
        (_, None) => run::<2>(tris, local, None, nb, recs, volume),
        (_, Some(t)) => run::<3>(tris, local, Some(t), nb, recs, volume),
    }
}

/// One triangle: local coordinates, volume, crossings.
#[inline(always)]
fn triangle<const S: usize>(p: &[[f64; 3]; 3], local: &LocalMap, xf: Option<&Transform>, nb: u32, recs: &mut Vec<Intercept>, v: &mut f64) {
    let (o, inv) = (local.origin, local.inv);
    let map = |q: [f64; 3]| -> [f64; 3] {
        match S {
            // Local axes (a, b, s) = ((s + 1) % 3, (s + 2) % 3, s).
            0 => [(q[1] - o[0]) * inv, (q[2] - o[1]) * inv, (q[0] - o[2]) * inv],
            1 => [(q[2] - o[0]) * inv, (q[0] - o[1]) * inv, (q[1] - o[2]) * inv],
            2 => [(q[0] - o[0]) * inv, (q[1] - o[1]) * inv, (q[2] - o[2]) * inv],
            _ => local.map(xf.map_or(q, |t| t.apply_point(q))),
        }
    };
    let l = [map(p[0]), map(p[1]), map(p[2])];
    *v += signed_volume6(&l);
    discretize_triangle(&l, |x| recs.push(x.intercept(nb)));
}

/// [`Grid::to_local`] with its axes and scale taken out of the loop (the
/// same arithmetic, so the same bits).
pub(crate) struct LocalMap {
    ax: [usize; 3],
    origin: [f64; 3],
    inv: f64,
}

impl LocalMap {
    pub(crate) fn new(grid: &Grid) -> LocalMap {
        let ax = grid.local_axes();
        LocalMap { ax, origin: ax.map(|a| grid.origin[a]), inv: 1.0 / grid.cell }
    }

    #[inline(always)]
    pub(crate) fn map(&self, p: [f64; 3]) -> [f64; 3] {
        [(p[self.ax[0]] - self.origin[0]) * self.inv, (p[self.ax[1]] - self.origin[1]) * self.inv, (p[self.ax[2]] - self.origin[2]) * self.inv]
    }
}

/// Six times the signed volume of the tetrahedron (origin, a, b, c).
#[inline]
pub(crate) fn signed_volume6(t: &[[f64; 3]; 3]) -> f64 {
    let [a, b, c] = t;
    a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) + a[2] * (b[0] * c[1] - b[1] * c[0])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Crossings and volume of one triangle on slab axis `S`: scalar and
    /// AVX2 from f64 corners, then scalar from the f32-rounded corners and
    /// AVX2 from their raw windows.
    #[cfg(target_arch = "x86_64")]
    fn all_four<const S: usize>(p: &[[f64; 3]; 3], pf: &[[f64; 3]; 3], raw: &[[u8; 16]; 3], map: &LocalMap) -> [(Vec<Intercept>, f64); 4] {
        let mut out: [(Vec<Intercept>, f64); 4] = Default::default();
        let [a, b, c, d] = &mut out;
        triangle::<S>(p, map, None, 64, &mut a.0, &mut a.1);
        triangle::<S>(pf, map, None, 64, &mut c.0, &mut c.1);
        // SAFETY: the caller checked that the CPU has AVX2.
        unsafe {
            triangle_avx::<S>(p, map, 64, &mut b.0, &mut b.1);
            triangle_avx_f32::<S>(raw, map, 64, &mut d.0, &mut d.1);
        }
        out
    }

    /// The AVX2 triangle gives the scalar one's crossings and volume bits
    /// on every slab axis, for triangles made to sit on and beside grid
    /// lines and planes (integers, integers plus or minus an ulp, halves),
    /// degenerate ones, negative coordinates and a grid with an offset
    /// origin and an inexact scale.
    #[test]
    #[cfg(target_arch = "x86_64")]
    fn the_avx2_triangle_equals_the_scalar_one_bit_for_bit() {
        // Also the raw f32 windows' entry (`triangle_avx_f32`).
        if !std::arch::is_x86_feature_detected!("avx2") {
            eprintln!("this CPU has no AVX2: the AVX2 path never runs here, nothing to compare");
            return;
        }
        let mut seed = 0x9E37_79B9_7F4A_7C15u64;
        let mut next = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            seed
        };
        let maps = [LocalMap { ax: [0, 1, 2], origin: [0.0; 3], inv: 1.0 }, LocalMap { ax: [0, 1, 2], origin: [-3.25, 0.1, 7.0], inv: 1.0 / 0.3 }];
        let mut rejected = 0;
        for round in 0..100_000u32 {
            let map = &maps[(round & 1) as usize];
            let mut coord = || {
                let r = next();
                let base = (r % 17) as f64 - 8.0;
                let x = match (r >> 8) % 6 {
                    0 => base,
                    // One ulp away from the integer (either side).
                    1 if base == 0.0 => f64::from_bits(1),
                    2 if base == 0.0 => -f64::from_bits(1),
                    1 => f64::from_bits(base.to_bits() + 1),
                    2 => f64::from_bits(base.to_bits() - 1),
                    3 => base + 0.5,
                    4 => base + (r >> 16) as f64 / (1u64 << 48) as f64,
                    _ => base + ((r >> 16) % 8) as f64 * 0.125,
                };
                // Back to the raw coordinates this map sends to `x` (not
                // exactly, which is the point: the two paths must agree
                // whatever the rounding).
                x / map.inv + map.origin[0]
            };
            let mut p = [[0.0; 3]; 3];
            for q in p.iter_mut() {
                *q = [coord(), coord(), coord()];
            }
            if round % 7 == 0 {
                p[2] = p[(round as usize / 7) % 2]; // a repeated corner
            }
            // The same corners rounded to f32 and given as raw 16-byte
            // windows, whose last 4 bytes (the next record in a file) are
            // anything, NaN and infinity included.
            let mut raw = [[0u8; 16]; 3];
            let mut pf = [[0.0f64; 3]; 3];
            for k in 0..3 {
                for d in 0..3 {
                    let c = p[k][d] as f32;
                    raw[k][4 * d..4 * d + 4].copy_from_slice(&c.to_le_bytes());
                    pf[k][d] = c as f64;
                }
                let junk = [f32::NAN, f32::INFINITY, f32::from_bits(1), f32::from_bits(next() as u32)][(next() % 4) as usize];
                raw[k][12..].copy_from_slice(&junk.to_le_bytes());
            }
            for s in 0..3 {
                let [want, got, want_f32, got_f32] = match s {
                    0 => all_four::<0>(&p, &pf, &raw, map),
                    1 => all_four::<1>(&p, &pf, &raw, map),
                    _ => all_four::<2>(&p, &pf, &raw, map),
                };
                assert_eq!(got.0, want.0, "crossings of {p:?} on axis {s}");
                assert_eq!(got.1.to_bits(), want.1.to_bits(), "volume of {p:?} on axis {s}");
                assert_eq!(got_f32.0, want_f32.0, "crossings of the f32 windows of {pf:?} on axis {s}");
                assert_eq!(got_f32.1.to_bits(), want_f32.1.to_bits(), "volume of the f32 windows of {pf:?} on axis {s}");
                rejected += want.0.is_empty() as u32;
            }
        }
        // Both kinds of triangle were met.
        assert!(rejected > 1000 && rejected < 3 * 100_000 - 1000, "{rejected}");
    }
}

//! Voxel volumes on the grid: where an iso-surface crosses grid lines
//! (Rocchini et al. 2001, §3.2: MI converts "volumetric schemes" by the
//! crossings alone). A volume is a field sampled at voxel centres; the grid's
//! nodes take the field's value there (trilinear between voxel centres), a
//! node is *inside* when its value is at least the iso value, and each grid
//! edge whose two nodes disagree holds one crossing, where the linear
//! interpolation of its two node values meets the iso value. These are the
//! same [`Intercept`] records the mesh discretization produces, so the rest
//! of the engine (shards, slabs, the robust reconstruction's consistent
//! rules for ambiguous cells) is the one it runs for meshes: the output is a
//! closed, oriented 2-manifold by the same argument.
//!
//! Contract:
//! - **Placement.** The grid's axes run along the volume's index axes (a
//!   signed permutation, [`Placement`]), its slab axis along the volume's
//!   slice axis (index `k`, the slowest in every format), so a slab of grid
//!   planes reads a contiguous range of slices and a volume larger than
//!   memory streams. Oblique volumes are placed in their own index frame
//!   and mapped to the world when written (mint-pipeline).
//! - **Domain.** The field is defined over the voxels' extent, half a voxel
//!   beyond the outer centres (nearest value there); beyond it every node is
//!   outside, so the border of the volume closes the surface. A crossing
//!   between a node inside the domain and one outside sits on the domain's
//!   border.
//! - **Ties.** A value equal to the iso value is inside; NaN is outside,
//!   and a crossing next to a NaN node sits halfway along its edge.
//! - At the volume's own resolution (a grid of cell 1 in index units whose
//!   nodes are the voxel centres) node values are the samples themselves, and
//!   the crossings are marching cubes' vertices exactly.
//! - Labels ([`Field::Label`]): the field is 1 on voxels of the label and 0
//!   elsewhere, iso 1/2: two labels that touch cross each shared edge at the
//!   same point, so their surfaces share their boundary without gaps.
//!
//! Crossing values are kept [`MARGIN`] inside their cell, as everywhere.

use crate::intercept::{Intercept, FAMILY_A, FAMILY_B, FAMILY_S};
use crate::MARGIN;

/// Which surface of the volume: an iso value, or the boundary of a label.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Field {
    /// Voxels with a value `>= iso` are inside.
    Iso(f32),
    /// Voxels whose value equals the label are inside (the field is their
    /// indicator, iso 1/2).
    Label(f32),
}

impl Field {
    /// The iso value of the sampled field.
    #[inline]
    pub fn iso(&self) -> f32 {
        match *self {
            Field::Iso(v) => v,
            Field::Label(_) => 0.5,
        }
    }
    /// A voxel's value as the field sees it.
    #[inline]
    pub fn value(&self, v: f32) -> f32 {
        match *self {
            Field::Iso(_) => v,
            Field::Label(l) => (v == l) as u8 as f32,
        }
    }
}

/// How the grid's nodes sit on the volume: along local grid axis `d`
/// (a, b, s), node `n` is at index `start[d] + step[d] · n` of volume
/// axis `axis[d]` (0 = x, the fastest in memory; 1 = y; 2 = z, the
/// slices). `axis[2]` is always 2.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Placement {
    pub axis: [usize; 3],
    pub start: [f64; 3],
    pub step: [f64; 3],
    /// The volume's size in voxels (x, y, z).
    pub dims: [u64; 3],
    /// Node counts of the grid along a, b, s (cells + 1).
    pub nodes: [u32; 3],
}

impl Placement {
    /// The volume index of node `n` along local axis `d`.
    #[inline]
    pub fn index(&self, d: usize, n: u32) -> f64 {
        self.start[d] + self.step[d] * n as f64
    }

    /// The interval of node coordinates along local axis `d` where the
    /// field is defined (the voxels' extent).
    pub fn domain(&self, d: usize) -> (f64, f64) {
        let n = self.dims[self.axis[d]] as f64;
        let (x, y) = ((-0.5 - self.start[d]) / self.step[d], (n - 0.5 - self.start[d]) / self.step[d]);
        (x.min(y), x.max(y))
    }

    /// Where plane `k` reads the volume: slice `z0`, and the weight `w` of
    /// slice `z0 + 1` (0 when the plane lies on slice `z0`); `None` when
    /// the plane is outside the domain.
    pub fn slices_of_plane(&self, k: u32) -> Option<(u64, f32)> {
        let (z, nz) = (self.index(2, k), self.dims[2]);
        if !(z >= -0.5 && z <= nz as f64 - 0.5) {
            return None;
        }
        // (floor of a value clamped to the last centre: w > 0 only below it.)
        let z = z.clamp(0.0, (nz - 1) as f64);
        let z0 = z.floor() as u64;
        let w = (z - z0 as f64) as f32;
        Some((z0, if w > 0.0 { w } else { 0.0 }))
    }

    /// The slices that planes `k0 ..= k1` read: `[first, end)` (empty
    /// when every plane is outside the domain). Planes map monotonically
    /// to slices, and one outside the domain reads nothing, so the ends,
    /// clamped to the outer centres, bound the rest.
    pub fn slice_range(&self, k0: u32, k1: u32) -> (u64, u64) {
        let (z0, z1) = (self.index(2, k0), self.index(2, k1));
        let (a, b) = (z0.min(z1), z0.max(z1));
        let nz = self.dims[2];
        if b < -0.5 || a > nz as f64 - 0.5 {
            return (0, 0);
        }
        let top = (nz - 1) as f64;
        let (lo, hi) = (a.clamp(0.0, top), b.clamp(0.0, top));
        (lo.floor() as u64, (hi.ceil() as u64 + 1).min(nz))
    }

    /// True when every node sits on a voxel centre or outside the domain
    /// (steps of ±1 from an integer start): node values are samples.
    pub fn on_voxels(&self) -> bool {
        (0..2).all(|d| self.step[d].abs() == 1.0 && self.start[d].fract() == 0.0)
    }
}

/// Per in-plane node coordinate: the voxel index and weight of the next one
/// along that axis (bilinear), or `None` outside the domain.
fn axis_taps(p: &Placement, d: usize) -> Vec<Option<(u32, f32)>> {
    let n = p.dims[p.axis[d]];
    (0..p.nodes[d])
        .map(|i| {
            let x = p.index(d, i);
            if !(x >= -0.5 && x <= n as f64 - 0.5) {
                return None;
            }
            let x = x.clamp(0.0, (n - 1) as f64);
            let x0 = x.floor() as u64;
            let w = (x - x0 as f64) as f32;
            Some((x0 as u32, if w > 0.0 { w } else { 0.0 }))
        })
        .collect()
}

/// The node values of one grid plane, from the volume slices it reads.
/// Nodes are stored `j * na1 + i` (local a fastest); a node outside the
/// domain holds `-inf`.
pub struct PlaneSampler {
    p: Placement,
    taps: [Vec<Option<(u32, f32)>>; 2],
}

impl PlaneSampler {
    pub fn new(p: Placement) -> PlaneSampler {
        PlaneSampler { taps: [axis_taps(&p, 0), axis_taps(&p, 1)], p }
    }

    pub fn placement(&self) -> &Placement {
        &self.p
    }

    /// Fills `out` with plane `k`'s node values from `lower` (slice `z0`)
    /// and `upper` (slice `z0 + 1`, weight `w`; ignored when `w == 0`),
    /// each `nx · ny` samples, x fastest. `inside` is `None` when the plane
    /// is outside the domain (then `lower`/`upper` are not read).
    pub fn sample(&self, field: Field, at: Option<(&[f32], &[f32], f32)>, out: &mut Vec<f32>) {
        let [na1, nb1, _] = self.p.nodes.map(|n| n as usize);
        out.clear();
        out.resize(na1 * nb1, f32::NEG_INFINITY);
        self.sample_rows(field, at, 0, out);
    }

    /// Rows `first ..` of [`Self::sample`]'s plane into `out` (whole rows
    /// of `na1` nodes, as many as it holds), so that bands of one plane can
    /// be sampled in parallel.
    pub fn sample_rows(&self, field: Field, at: Option<(&[f32], &[f32], f32)>, first: usize, out: &mut [f32]) {
        let na1 = self.p.nodes[0] as usize;
        // Nodes with no samples (beyond the volume) are outside.
        const OUT: f32 = f32::NEG_INFINITY;
        let Some((lower, upper, w)) = at else {
            out.fill(OUT);
            return;
        };
        let nx = self.p.dims[0] as usize;
        // Offsets in a slice of one step along local a and b.
        let stride = |d: usize| if self.p.axis[d] == 0 { 1 } else { nx };
        let (sa, sb) = (stride(0), stride(1));
        let value = |s: &[f32], at: usize, wa: f32, wb: f32| -> f32 {
            let v00 = field.value(s[at]);
            if wa == 0.0 && wb == 0.0 {
                return v00;
            }
            let v10 = if wa > 0.0 { field.value(s[at + sa]) } else { v00 };
            let v01 = if wb > 0.0 { field.value(s[at + sb]) } else { v00 };
            let v11 = if wa > 0.0 && wb > 0.0 { field.value(s[at + sa + sb]) } else if wa > 0.0 { v10 } else { v01 };
            let x0 = v00 + wa * (v10 - v00);
            let x1 = v01 + wa * (v11 - v01);
            x0 + wb * (x1 - x0)
        };
        // Own resolution: a run of samples is a run of nodes (`first ..
        // first + count` along a, from sample `x0`).
        let run = (self.p.on_voxels() && w == 0.0 && matches!(field, Field::Iso(_)) && sa == 1)
            .then(|| {
                let first = self.taps[0].iter().position(|t| t.is_some())?;
                let count = self.taps[0][first..].iter().take_while(|t| t.is_some()).count();
                Some((first, count, self.taps[0][first]?.0 as usize))
            })
            .flatten();
        let rows = out.len() / na1;
        out[rows * na1..].fill(OUT);
        for (r, tb) in self.taps[1][first..first + rows].iter().enumerate() {
            let row = &mut out[r * na1..(r + 1) * na1];
            let Some((b0, wb)) = *tb else {
                row.fill(OUT);
                continue;
            };
            if let Some((first, count, x0)) = run {
                let base = b0 as usize * sb;
                row[..first].fill(OUT);
                row[first + count..].fill(OUT);
                if self.p.step[0] > 0.0 {
                    row[first..first + count].copy_from_slice(&lower[base + x0..base + x0 + count]);
                } else {
                    for (n, v) in row[first..first + count].iter_mut().enumerate() {
                        *v = lower[base + x0 - n];
                    }
                }
                continue;
            }
            for (i, ta) in self.taps[0].iter().enumerate() {
                let Some((a0, wa)) = *ta else {
                    row[i] = OUT;
                    continue;
                };
                let at = a0 as usize * sa + b0 as usize * sb;
                let v0 = value(lower, at, wa, wb);
                row[i] = if w > 0.0 { v0 + w * (value(upper, at, wa, wb) - v0) } else { v0 };
            }
        }
    }
}

/// Where along an edge from node `n` (value `f0`) to node `n + 1` (value
/// `f1`) the field crosses `iso`, in node units from `n`: on the domain's
/// border `(lo, hi)` when one end is outside it, halfway when one value is
/// not finite, else by linear interpolation.
#[inline]
fn crossing(n: u32, f0: f32, f1: f32, iso: f32, (lo, hi): (f64, f64)) -> f64 {
    let x = n as f64;
    let t = if x < lo {
        lo - x
    } else if x + 1.0 > hi {
        hi - x
    } else if f0.is_finite() && f1.is_finite() {
        (iso as f64 - f0 as f64) / (f1 as f64 - f0 as f64)
    } else {
        0.5
    };
    x + t.clamp(MARGIN, 1.0 - MARGIN)
}

/// The inside bits of one node plane, a row of `words` u64 per line of
/// nodes along b (bit `i % 64` of word `i / 64` is node `i` along a).
fn inside_bits(nodes: &[f32], na1: usize, nb1: usize, iso: f32, out: &mut Vec<u64>) {
    out.clear();
    out.resize(na1.div_ceil(64) * nb1, 0);
    inside_rows(nodes, na1, iso, out);
}

/// [`inside_bits`] of whole rows of nodes into `out` (`na1.div_ceil(64)`
/// words per row), for bands of a plane in parallel.
pub fn inside_rows(nodes: &[f32], na1: usize, iso: f32, out: &mut [u64]) {
    let words = na1.div_ceil(64);
    for (row, bits) in nodes.chunks_exact(na1).zip(out.chunks_exact_mut(words)) {
        let mut chunks = row.chunks_exact(64);
        for (chunk, w) in (&mut chunks).zip(bits.iter_mut()) {
            *w = inside_word(chunk.try_into().expect("64 values"), iso);
        }
        if let Some(w) = bits.get_mut(row.len() / 64) {
            *w = inside_scalar(chunks.remainder(), iso);
        }
    }
}

/// Bit `b` set where `chunk[b] >= iso` (false for NaN), for up to 64 values.
fn inside_scalar(chunk: &[f32], iso: f32) -> u64 {
    let mut x = 0u64;
    for (b, &v) in chunk.iter().enumerate() {
        x |= ((v >= iso) as u64) << b;
    }
    x
}

/// [`inside_scalar`] of 64 values, four at a time with SSE compares and
/// sign masks where the target has them (every x86-64 does): the loop of
/// shifts above does not vectorise, and this is a tenth of a volume's
/// work. `cmpge` is an ordered compare, false for NaN, as `>=` is.
#[inline]
fn inside_word(chunk: &[f32; 64], iso: f32) -> u64 {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_mm_cmpge_ps, _mm_movemask_ps, _mm_set1_ps, _mm_setr_ps};
        // SAFETY: SSE is in every x86-64 target's baseline, and these
        // intrinsics touch only their arguments (no memory).
        unsafe {
            let t = _mm_set1_ps(iso);
            let mut x = 0u64;
            for (q, c) in chunk.chunks_exact(4).enumerate() {
                let v = _mm_setr_ps(c[0], c[1], c[2], c[3]);
                x |= (_mm_movemask_ps(_mm_cmpge_ps(v, t)) as u64 & 0xf) << (4 * q);
            }
            x
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    inside_scalar(chunk, iso)
}

/// Calls `f(i)` for every set bit `i` of `bits` below `n`, in order.
#[inline]
fn each_bit(bits: &[u64], n: usize, mut f: impl FnMut(usize)) {
    for (w, &x) in bits.iter().enumerate() {
        let mut x = x;
        if (w + 1) * 64 > n {
            let keep = n - w * 64;
            if keep < 64 {
                x &= (1u64 << keep) - 1;
            }
        }
        while x != 0 {
            f(w * 64 + x.trailing_zeros() as usize);
            x &= x - 1;
        }
    }
}

/// The crossings of plane `k`: families A and B within the plane, from its
/// node values `nodes` (see [`PlaneSampler::sample`]), and with `next`
/// (plane `k + 1`'s node values) family S between the two. Appends them to
/// `out`, by family, line and position. The edges that change state are
/// found on bit planes of the nodes' inside states, 64 nodes a word.
pub fn plane_crossings(p: &Placement, field: Field, k: u32, nodes: &[f32], next: Option<&[f32]>, out: &mut Vec<Intercept>) {
    let [na1, nb1, _] = p.nodes.map(|n| n as usize);
    let iso = field.iso();
    let (mut cur, mut nxt) = (Vec::new(), Vec::new());
    inside_bits(nodes, na1, nb1, iso, &mut cur);
    let next = next.map(|n| {
        inside_bits(n, na1, nb1, iso, &mut nxt);
        (n, &nxt[..])
    });
    band_crossings(p, field, k, 0..nb1, (nodes, &cur), next, out);
}

/// Rows per band of a plane `na1` nodes wide: about 64K nodes, so that a
/// band's crossings ([`band_capacity`]) stay a few MiB at any width. It
/// depends on the grid alone, so the order of records does too.
pub fn band_rows(na1: usize) -> usize {
    (65536 / na1.max(1)).max(1)
}

/// The most crossings rows `rows` of a plane `na1` wide can hold: one per
/// A, B and S edge.
pub fn band_capacity(na1: usize, rows: usize) -> usize {
    3 * na1 * rows
}

/// [`plane_crossings`] of rows `rows` only (A edges along those rows, B
/// edges from each of them to the next row, S edges from their nodes), from
/// the whole plane's node values and inside bits ([`inside_rows`]) and the
/// next plane's: bands of one plane can be found in parallel and written in
/// band order, so that a plane's crossings need not be held at once.
pub fn band_crossings(
    p: &Placement,
    field: Field,
    k: u32,
    rows: std::ops::Range<usize>,
    (nodes, cur): (&[f32], &[u64]),
    next: Option<(&[f32], &[u64])>,
    out: &mut Vec<Intercept>,
) {
    let [na1, nb1, _] = p.nodes.map(|n| n as usize);
    let iso = field.iso();
    let (da, db, ds) = (p.domain(0), p.domain(1), p.domain(2));
    let words = na1.div_ceil(64);
    let mut diff = vec![0u64; words];
    // A: node i against node i + 1 of the same row.
    for j in rows.clone() {
        let bits = &cur[j * words..(j + 1) * words];
        for w in 0..words {
            let carry = if w + 1 < words { bits[w + 1] << 63 } else { 0 };
            diff[w] = bits[w] ^ ((bits[w] >> 1) | carry);
        }
        let row = &nodes[j * na1..(j + 1) * na1];
        each_bit(&diff, na1 - 1, |i| {
            let (f0, f1) = (row[i], row[i + 1]);
            out.push(Intercept::new(k, FAMILY_A, j as u32, crossing(i as u32, f0, f1, iso, da), f1 >= iso));
        });
    }
    // B: row j against row j + 1.
    for j in rows.start..rows.end.min(nb1.saturating_sub(1)) {
        let (b0, b1) = (&cur[j * words..(j + 1) * words], &cur[(j + 1) * words..(j + 2) * words]);
        for w in 0..words {
            diff[w] = b0[w] ^ b1[w];
        }
        let (r0, r1) = (&nodes[j * na1..(j + 1) * na1], &nodes[(j + 1) * na1..(j + 2) * na1]);
        each_bit(&diff, na1, |i| {
            let (f0, f1) = (r0[i], r1[i]);
            out.push(Intercept::new(k, FAMILY_B, i as u32, crossing(j as u32, f0, f1, iso, db), f1 >= iso));
        });
    }
    let Some((next, nxt)) = next else { return };
    // S: this plane against the next, node by node.
    for j in rows {
        for w in 0..words {
            diff[w] = cur[j * words + w] ^ nxt[j * words + w];
        }
        each_bit(&diff, na1, |i| {
            let at = j * na1 + i;
            let (f0, f1) = (nodes[at], next[at]);
            out.push(Intercept::new(k, FAMILY_S, (i * nb1 + j) as u32, crossing(k, f0, f1, iso, ds), f1 >= iso));
        });
    }
}

/// The crossings of every plane of a volume held in memory (`samples`:
/// `dims[0] · dims[1] · dims[2]` values, x fastest), per plane: for tests,
/// fuzzing and small volumes. The engine streams the same per slab.
pub fn volume_planes(p: &Placement, field: Field, samples: &[f32]) -> Vec<Vec<Intercept>> {
    let slice = (p.dims[0] * p.dims[1]) as usize;
    let sampler = PlaneSampler::new(*p);
    let ns1 = p.nodes[2];
    let nodes_of = |k: u32, out: &mut Vec<f32>| {
        let at = p.slices_of_plane(k).map(|(z0, w)| {
            let lo = &samples[z0 as usize * slice..(z0 as usize + 1) * slice];
            let hi = if w > 0.0 { &samples[(z0 as usize + 1) * slice..(z0 as usize + 2) * slice] } else { lo };
            (lo, hi, w)
        });
        sampler.sample(field, at, out);
    };
    let (mut cur, mut next) = (Vec::new(), Vec::new());
    nodes_of(0, &mut cur);
    let mut planes = Vec::with_capacity(ns1 as usize);
    for k in 0..ns1 {
        let mut out = Vec::new();
        if k + 1 < ns1 {
            nodes_of(k + 1, &mut next);
            plane_crossings(p, field, k, &cur, Some(&next), &mut out);
            std::mem::swap(&mut cur, &mut next);
        } else {
            plane_crossings(p, field, k, &cur, None, &mut out);
        }
        planes.push(out);
    }
    planes
}

/// `--open-border`: which of the domain's six border planes a vertex lies
/// on, as bits (bit `2d` the low side of axis `d`, bit `2d + 1` the high
/// side), for a domain `[lo, hi]` per axis in the vertices' frame. A
/// crossing between a node inside the domain and one outside sits on the
/// border (see [`crossing`]), moved at most [`MARGIN`] cells, hence the
/// tolerance of two margins.
pub fn border_mask(v: [f64; 3], domain: [(f64, f64); 3], cell: f64) -> u8 {
    let tol = 2.0 * MARGIN * cell;
    let mut m = 0u8;
    for d in 0..3 {
        let (lo, hi) = domain[d];
        m |= (((v[d] - lo).abs() <= tol) as u8) << (2 * d);
        m |= (((v[d] - hi).abs() <= tol) as u8) << (2 * d + 1);
    }
    m
}

/// `--open-border`: a face belongs to the cap that closes the surface on
/// the volume's border when its three vertices lie on the border (each
/// [`border_mask`] non-zero; not necessarily one plane: where two border
/// planes meet, the cap turns the corner with faces across it). Such a face
/// lies in a cell between the outermost nodes and the padding beyond, and
/// only closes the surface there; leaving those faces out opens the surface
/// exactly where it meets the border, its boundary on the border.
#[inline]
pub fn on_border(masks: [u8; 3]) -> bool {
    masks[0] != 0 && masks[1] != 0 && masks[2] != 0
}

/// `--open-border`: where the cap meets the rest of the surface at a
/// vertex only (the faces left around a border vertex fall into more than
/// one fan: a "bowtie"), that vertex is split, one copy per fan, so that
/// the open surface is a 2-manifold with boundary.
///
/// `incident` holds, for every kept face and each of its vertices `v` on
/// the border, `(v, a, b)` with `a < b` the face's two other vertices.
/// Faces around `v` are in one fan when they are linked through shared
/// edges `v`–`w`. Returns, for the faces that must use a copy of their
/// vertex, `(v, a, b, k)`: copy `k` (1-based; fan 0 keeps `v`), fans
/// ordered by their smallest `(a, b)`; sorted by `v`, then `k`.
pub fn fan_splits(mut incident: Vec<(u32, u32, u32)>) -> Vec<(u32, u32, u32, u32)> {
    incident.sort_unstable();
    incident.dedup();
    let mut out = Vec::new();
    let mut i = 0;
    while i < incident.len() {
        let v = incident[i].0;
        let mut j = i;
        while j < incident.len() && incident[j].0 == v {
            j += 1;
        }
        let group = &incident[i..j];
        if group.len() > 1 {
            // Union-find over the group's faces, linked by shared neighbours.
            let mut parent: Vec<usize> = (0..group.len()).collect();
            fn root(p: &mut [usize], mut x: usize) -> usize {
                while p[x] != x {
                    p[x] = p[p[x]];
                    x = p[x];
                }
                x
            }
            let mut by_neighbour: Vec<(u32, usize)> = group.iter().enumerate().flat_map(|(n, &(_, a, b))| [(a, n), (b, n)]).collect();
            by_neighbour.sort_unstable();
            for w in by_neighbour.windows(2) {
                if w[0].0 == w[1].0 {
                    let (x, y) = (root(&mut parent, w[0].1), root(&mut parent, w[1].1));
                    parent[x.max(y)] = x.min(y);
                }
            }
            // Fans in order of their smallest face (the group is sorted, so
            // a fan's first face in group order is its smallest).
            let mut fan_of_root: Vec<(usize, u32)> = Vec::new();
            for n in 0..group.len() {
                let r = root(&mut parent, n);
                let k = match fan_of_root.iter().find(|e| e.0 == r) {
                    Some(e) => e.1,
                    None => {
                        let k = fan_of_root.len() as u32;
                        fan_of_root.push((r, k));
                        k
                    }
                };
                if k > 0 {
                    out.push((v, group[n].1, group[n].2, k));
                }
            }
        }
        i = j;
    }
    out.sort_unstable_by_key(|&(v, a, b, k)| (v, k, a, b));
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::{Grid, GridSize};
    use crate::robust::reconstruct_slab_robust;
    use crate::signs::SignRule;

    /// The own-resolution grid of a volume: nodes on the voxel centres, one
    /// padding node beyond each side.
    fn own_grid(dims: [u64; 3]) -> (Grid, Placement) {
        let hi = dims.map(|n| (n - 1) as f64);
        let g = Grid::around([0.0; 3], hi, GridSize::CellSize(1.0), [0.0; 3], Some(2)).unwrap();
        let [na, nb, ns] = g.local_dims();
        let p = Placement { axis: [0, 1, 2], start: [g.origin[0], g.origin[1], g.origin[2]], step: [1.0; 3], dims, nodes: [na + 1, nb + 1, ns + 1] };
        (g, p)
    }

    fn mesh(dims: [u64; 3], field: Field, samples: &[f32]) -> crate::cells::SlabResult {
        let (g, p) = own_grid(dims);
        reconstruct_slab_robust(&g, 0, volume_planes(&p, field, samples), SignRule::Union).0
    }

    /// Vertices, edges, faces, boundary edges and non-manifold edges.
    fn counts(r: &crate::cells::SlabResult) -> (usize, usize, usize, usize, usize) {
        let mut e = std::collections::HashMap::new();
        let mut directed = std::collections::HashSet::new();
        for f in &r.faces {
            for k in 0..3 {
                let (a, b) = (f[k], f[(k + 1) % 3]);
                *e.entry((a.min(b), a.max(b))).or_insert(0) += 1;
                assert!(directed.insert((a, b)), "edge {a}-{b} used twice in one direction: not oriented");
            }
        }
        let boundary = e.values().filter(|&&c| c == 1).count();
        let nonmanifold = e.values().filter(|&&c| c > 2).count();
        (r.vertices.len(), e.len(), r.faces.len(), boundary, nonmanifold)
    }

    #[test]
    fn one_voxel_above_iso_is_an_octahedron() {
        let mut s = vec![0.0f32; 27];
        s[13] = 1.0;
        let r = mesh([3, 3, 3], Field::Iso(0.5), &s);
        assert_eq!(counts(&r), (6, 12, 8, 0, 0));
        // Each vertex halfway between the centre voxel (1, 1, 1) and a neighbour.
        let mut v: Vec<[f64; 3]> = r.vertices.clone();
        v.sort_by(|a, b| a.partial_cmp(b).unwrap());
        let want = [[0.5, 1.0, 1.0], [1.0, 0.5, 1.0], [1.0, 1.0, 0.5], [1.0, 1.0, 1.5], [1.0, 1.5, 1.0], [1.5, 1.0, 1.0]];
        assert_eq!(v, want);
    }

    #[test]
    fn a_lone_voxel_at_the_border_closes_on_the_border() {
        // A 1x1x1 volume above iso: the grid around a single centre puts
        // nodes on the domain's border (inside, nearest value) with
        // padding beyond, so the surface is closed on the domain's border,
        // half a voxel from the centre (within the crossing margin).
        let r = mesh([1, 1, 1], Field::Iso(0.5), &[1.0]);
        let (_, _, f, b, n) = counts(&r);
        assert!(f > 0);
        assert_eq!((b, n), (0, 0), "closed and 2-manifold");
        for p in &r.vertices {
            let far = p.iter().map(|x| x.abs()).fold(0.0, f64::max);
            assert!((far - 0.5).abs() < 1e-3, "{p:?}");
        }
    }

    #[test]
    fn open_border_leaves_out_exactly_the_cap_on_the_border() {
        // A 5x4x6 volume whose layers z = 2..=3 are inside: a slab cut by
        // the x and y borders. Closed, it is a box; with the cap left out,
        // two sheets (its top and bottom) remain, each open on the border.
        let dims = [5u64, 4, 6];
        let s: Vec<f32> = (0..120).map(|i| ((2..=3).contains(&(i / 20)) as u8) as f32).collect();
        let r = mesh(dims, Field::Iso(0.5), &s);
        assert_eq!(counts(&r).3, 0, "closed before");
        let domain: [(f64, f64); 3] = std::array::from_fn(|d| (-0.5, dims[d] as f64 - 0.5));
        let masks: Vec<u8> = r.vertices.iter().map(|&v| border_mask(v, domain, 1.0)).collect();
        let kept: Vec<[u32; 3]> = r.faces.iter().copied().filter(|f| !on_border(f.map(|v| masks[v as usize]))).collect();
        assert!(kept.len() < r.faces.len());
        // Every face left has a vertex off the border, and lies
        // in the slab's top or bottom half-voxel band (z within 0.5 of 1.5 or 3.5).
        for f in &kept {
            for &v in f {
                let z = r.vertices[v as usize][2];
                assert!((z - 1.5).abs() <= 0.5 + 1e-9 || (z - 3.5).abs() <= 0.5 + 1e-9, "{z}");
            }
        }
        // The boundary edges are those the cap shared, on the border.
        let open = crate::cells::SlabResult { vertices: r.vertices.clone(), faces: kept, ..Default::default() };
        let (_, _, _, b, n) = counts(&open);
        assert_eq!(n, 0);
        assert!(b > 0);
        // The border of a 5x4 sheet crossed by one line per node at the
        // border: 2 sheets x 2 x (5 + 4) edges.
        assert_eq!(b, 2 * 2 * (5 + 4), "boundary edges");
        // Nothing inside the border changes: no face at all is left out of
        // a surface that does not reach it.
        let mut t = vec![0.0f32; 27];
        t[13] = 1.0;
        let r = mesh([3, 3, 3], Field::Iso(0.5), &t);
        let domain = [(-0.5, 2.5); 3];
        assert!(r.faces.iter().all(|f| !on_border(f.map(|v| border_mask(r.vertices[v as usize], domain, 1.0)))));
    }

    #[test]
    fn the_ambiguous_checkerboard_is_two_manifold() {
        // 2x2x2 voxels alternating: every face of the middle cell ambiguous.
        let s: Vec<f32> = (0..8).map(|i| ((i & 1) ^ (i >> 1 & 1) ^ (i >> 2 & 1)) as f32).collect();
        for field in [Field::Iso(0.5), Field::Iso(0.5 + 1e-3)] {
            let r = mesh([2, 2, 2], field, &s);
            let (_, _, f, b, n) = counts(&r);
            assert!(f > 0);
            assert_eq!((b, n), (0, 0), "closed and 2-manifold");
        }
    }

    #[test]
    fn a_full_volume_is_its_box() {
        // Every voxel inside: the surface is the domain's border, a box
        // of 4x3x2 voxels, closed; its vertices on the border planes.
        let dims = [4, 3, 2];
        let s = vec![7.0f32; 24];
        let r = mesh(dims, Field::Iso(7.0), &s);
        let (_, _, f, b, n) = counts(&r);
        assert!(f > 0);
        assert_eq!((b, n), (0, 0));
        for p in &r.vertices {
            let on = (0..3).any(|d| (p[d] + 0.5).abs() < 1e-9 || (p[d] - (dims[d] as f64 - 0.5)).abs() < 1e-9);
            assert!(on, "{p:?} is not on the border");
        }
        // Nothing inside: nothing out.
        assert!(mesh(dims, Field::Iso(7.5), &s).faces.is_empty());
    }

    #[test]
    fn touching_labels_share_their_boundary() {
        // Two labels side by side in a 4x2x2 volume: their surfaces meet
        // on the plane x = 1.5 with the same vertices there.
        let s: Vec<f32> = (0..16).map(|i| if i % 4 < 2 { 1.0 } else { 2.0 }).collect();
        let a = mesh([4, 2, 2], Field::Label(1.0), &s);
        let b = mesh([4, 2, 2], Field::Label(2.0), &s);
        let on = |r: &crate::cells::SlabResult| {
            let mut v: Vec<[f64; 3]> = r.vertices.iter().copied().filter(|p| (p[0] - 1.5).abs() < 1e-12).collect();
            v.sort_by(|x, y| x.partial_cmp(y).unwrap());
            v
        };
        assert!(!on(&a).is_empty());
        assert_eq!(on(&a), on(&b));
        assert_eq!(counts(&a).3, 0);
        assert_eq!(counts(&b).3, 0);
    }

    #[test]
    fn own_resolution_crossings_interpolate_linearly() {
        // Along x: 0, 10, 20, 30; iso 12 crosses between voxels 1 and 2 at 1.2.
        let s = [0.0f32, 10.0, 20.0, 30.0];
        let (_, p) = own_grid([4, 1, 1]);
        let planes = volume_planes(&p, Field::Iso(12.0), &s);
        let a: Vec<f64> = planes.iter().flatten().filter(|r| r.family() == FAMILY_A).map(|r| r.value()).collect();
        // Node 0 is padding at index -1: the crossing at 1.2 is at node 2.2.
        assert!(a.iter().any(|&v| (v - 2.2).abs() < 1e-6), "{a:?}");
    }

    #[test]
    fn slice_ranges_cover_every_plane_between_their_ends() {
        let (_, p) = own_grid([3, 3, 5]);
        // Plane 0 is the padding before slice 0; planes 1..=5 are slices 0..=4.
        assert_eq!(p.slice_range(0, 0), (0, 0));
        assert_eq!(p.slice_range(0, 3), (0, 3));
        assert_eq!(p.slice_range(2, 6), (1, 5));
        assert_eq!(p.slice_range(6, 6), (0, 0));
        for k0 in 0..7 {
            for k1 in k0..7 {
                let (a, b) = p.slice_range(k0, k1);
                for k in k0..=k1 {
                    if let Some((z, w)) = p.slices_of_plane(k) {
                        assert!(z >= a && z + (w > 0.0) as u64 + 1 <= b, "plane {k} in {k0}..={k1}: slice {z} not in {a}..{b}");
                    }
                }
            }
        }
    }

    #[test]
    fn a_coarser_grid_samples_trilinearly() {
        // A linear ramp along z sampled on planes between slices.
        let dims = [2u64, 2, 5];
        let s: Vec<f32> = (0..20).map(|i| (i / 4) as f32).collect();
        let p = Placement { axis: [0, 1, 2], start: [-1.0, -1.0, -0.25], step: [1.0, 1.0, 0.5], dims, nodes: [4, 4, 10] };
        let sampler = PlaneSampler::new(p);
        let mut out = Vec::new();
        let (z0, w) = p.slices_of_plane(3).unwrap();
        assert_eq!((z0, w), (1, 0.25));
        sampler.sample(Field::Iso(0.0), Some((&s[4..8], &s[8..12], w)), &mut out);
        assert_eq!(out[5], 1.25);
        assert_eq!(out[0], f32::NEG_INFINITY);
    }

    proptest::proptest! {
        /// The inside bits, 64 at a time by SSE where it runs, are the bits
        /// of `v >= iso` node by node, for rows of any length and values
        /// at, around and beyond the iso value, NaN and infinities.
        #[test]
        fn inside_bits_are_the_compares_node_by_node(na1 in 1usize..200, rows in 1usize..4, picks in proptest::collection::vec(0usize..9, 800), iso in proptest::sample::select(vec![0.0f32, -0.0, 1.5, f32::INFINITY, f32::NEG_INFINITY])) {
            let pool = [iso, -iso, f32::NAN, f32::INFINITY, f32::NEG_INFINITY, 1.5, 1.5f32.next_up(), 1.5f32.next_down(), 0.0];
            let nodes: Vec<f32> = (0..na1 * rows).map(|i| pool[picks[i % picks.len()]]).collect();
            let words = na1.div_ceil(64);
            let mut got = vec![!0u64; words * rows];
            inside_rows(&nodes, na1, iso, &mut got);
            for r in 0..rows {
                for i in 0..words * 64 {
                    let want = i < na1 && nodes[r * na1 + i] >= iso;
                    proptest::prop_assert_eq!(got[r * words + i / 64] >> (i % 64) & 1 == 1, want, "row {} node {}", r, i);
                }
            }
        }
    }

    proptest::proptest! {
        /// Bands of any height, sampled and crossed apart, give the whole
        /// plane's node values and crossings, in band order.
        #[test]
        fn bands_give_the_planes_crossings(dims in proptest::array::uniform3(1u64..7), seed in 0u64..1000, rows in 1usize..9, step in 0.5f64..2.0) {
            let n = (dims[0] * dims[1] * dims[2]) as usize;
            let mut x = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
            let s: Vec<f32> = (0..n).map(|_| { x ^= x << 13; x ^= x >> 7; x ^= x << 17; (x % 5) as f32 }).collect();
            let nodes = dims.map(|d| ((d as f64 + 1.0) / step).ceil() as u32 + 2);
            let p = Placement { axis: [0, 1, 2], start: [-1.0, -1.0, -1.0], step: [step, step, step], dims, nodes };
            let field = Field::Iso(2.0);
            let sampler = PlaneSampler::new(p);
            let slice = (dims[0] * dims[1]) as usize;
            let [na1, nb1, ns1] = p.nodes.map(|n| n as usize);
            let words = na1.div_ceil(64);
            let at = |k: u32| p.slices_of_plane(k).map(|(z, w)| {
                let lo = &s[z as usize * slice..(z as usize + 1) * slice];
                (lo, if w > 0.0 { &s[(z as usize + 1) * slice..(z as usize + 2) * slice] } else { lo }, w)
            });
            let whole = volume_planes(&p, field, &s);
            for k in 0..ns1 as u32 {
                let mut planes = [Vec::new(), Vec::new()];
                let mut bits = [vec![0u64; words * nb1], vec![0u64; words * nb1]];
                for (d, plane) in planes.iter_mut().enumerate() {
                    let q = (k as usize + d).min(ns1 - 1) as u32;
                    let mut want = Vec::new();
                    sampler.sample(field, at(q), &mut want);
                    plane.resize(na1 * nb1, 0.0);
                    for (b, chunk) in plane.chunks_mut(rows * na1).enumerate() {
                        sampler.sample_rows(field, at(q), b * rows, chunk);
                    }
                    proptest::prop_assert_eq!(&*plane, &want[..]);
                    for (v, w) in plane.chunks(rows * na1).zip(bits[d].chunks_mut(rows * words)) {
                        inside_rows(v, na1, 2.0, w);
                    }
                }
                let next = (k as usize + 1 < ns1).then(|| (&planes[1][..], &bits[1][..]));
                let mut got = Vec::new();
                for b in (0..nb1).step_by(rows) {
                    band_crossings(&p, field, k, b..(b + rows).min(nb1), (&planes[0], &bits[0]), next, &mut got);
                }
                let mut want = whole[k as usize].clone();
                proptest::prop_assert!(got.len() <= band_capacity(na1, nb1));
                if rows >= nb1 {
                    proptest::prop_assert_eq!(&got, &want);
                }
                got.sort_by(|a, b| a.sort_key().cmp(&b.sort_key()));
                want.sort_by(|a, b| a.sort_key().cmp(&b.sort_key()));
                proptest::prop_assert_eq!(got, want);
            }
        }
    }
}

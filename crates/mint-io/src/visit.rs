//! Direct, parallel access to the triangles of files whose face records all
//! have one size: binary PLY with one face element (every record must be a
//! triangle; checked) and binary STL. A [`TriangleRecords`] is a cheap,
//! thread-safe handle on the memory map; [`TriangleRecords::visit`] walks
//! any range of records and hands each triangle's three positions to a
//! closure, with no chunk buffers, channels or reader thread in between. The
//! common layout (little-endian `uchar 3` + three 32-bit indices, f32 or
//! f64 positions) has its own monomorphized loop; the rest read through the
//! generic scalar readers.
//!
//! Every index is range-checked and every position checked finite, as the
//! streaming reader does, with the same kind of located error (the
//! finiteness check can be waived by a caller that has checked every
//! position already: [`TriangleRecords::set_positions_known_finite`]).

use crate::error::{Error, ErrorKind};
use crate::mapped::Mapped;
use crate::positions::{check_finite, not_finite, PosKind, Positions, Reject, Scalar};
use std::path::PathBuf;
use std::sync::Arc;

/// What [`TriangleRecords::visit`] calls for every triangle. A trait rather
/// than a closure so that an `#[inline(always)]` implementation is inlined
/// into the visitor's loops (no call, no store-and-reload of the corners).
pub trait TriangleVisitor {
    /// One triangle: the positions of its three corners, in order.
    fn triangle(&mut self, p: &[[f64; 3]; 3]);

    /// The same, for positions stored as packed little-endian f32 triples
    /// whose finiteness the caller vouched for
    /// ([`TriangleRecords::set_positions_known_finite`]): the first 12
    /// bytes of `raw[k]` are corner `k`'s `x y z`, the last 4 whatever
    /// follows it in the file. A visitor can load each corner as one
    /// vector; the default converts and calls
    /// [`TriangleVisitor::triangle`], which gets the same values.
    #[inline(always)]
    fn triangle_f32le(&mut self, raw: &[[u8; 16]; 3]) {
        self.triangle(&f32le_corners(raw));
    }
}

/// The corner positions of [`TriangleVisitor::triangle_f32le`]'s windows,
/// as [`TriangleVisitor::triangle`] receives them.
#[inline(always)]
pub fn f32le_corners(raw: &[[u8; 16]; 3]) -> [[f64; 3]; 3] {
    let f = |r: &[u8; 16], o: usize| f32::from_le_bytes([r[o], r[o + 1], r[o + 2], r[o + 3]]) as f64;
    raw.each_ref().map(|r| [f(r, 0), f(r, 4), f(r, 8)])
}

impl<F: FnMut(&[[f64; 3]; 3])> TriangleVisitor for F {
    #[inline(always)]
    fn triangle(&mut self, p: &[[f64; 3]; 3]) {
        self(p)
    }
}

/// Where a file's fixed-size face records are (see `FaceStream::fixed_faces`).
#[derive(Debug, Clone)]
pub(crate) enum FixedFaces {
    /// A PLY face element: `count` records of `stride` bytes from `start`,
    /// each `pre` bytes of scalars, the list count (`cty`), three indices
    /// (`ity`), then more scalars.
    Ply { map: Arc<Mapped>, element: String, start: usize, stride: usize, pre: usize, cty: Scalar, ity: Scalar, be: bool, count: u64 },
    /// Binary STL: facet `k` is vertices `3k, 3k + 1, 3k + 2`.
    Soup { count: u64 },
    /// A glTF index accessor read in place: triangle `k` is elements
    /// `3k .. 3k + 3`, element `e` an unsigned `ity` (u8, u16 or u32, little
    /// endian) at `start + e * stride`; with no accessor (`ity` None),
    /// vertices `3k, 3k + 1, 3k + 2`. `element` names it in errors.
    Indexed { map: Arc<Mapped>, element: String, start: usize, stride: usize, ity: Option<Scalar>, count: u64 },
}

/// True when the hot loops may run their AVX2 compilations (decided once;
/// `MINT_NO_AVX2` in the environment says no, so that a test can compare).
#[cfg(target_arch = "x86_64")]
pub fn use_avx2() -> bool {
    static USE: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    *USE.get_or_init(|| std::arch::is_x86_feature_detected!("avx2") && std::env::var_os("MINT_NO_AVX2").is_none())
}


/// A thread-safe handle on a file's face records; see the module docs.
#[derive(Debug, Clone)]
pub struct TriangleRecords {
    path: PathBuf,
    positions: Positions,
    faces: FixedFaces,
    prefetch: bool,
    finite_known: bool,
}

impl TriangleRecords {
    pub(crate) fn new(path: PathBuf, positions: Positions, faces: FixedFaces) -> TriangleRecords {
        TriangleRecords { path, positions, faces, prefetch: true, finite_known: false }
    }

    /// Tells [`TriangleRecords::visit`] that every position is already known
    /// to be finite (the caller checked them all, for instance with
    /// `VertexPositions::bounds`), so that the common layout's loop skips
    /// its per-triangle check: a tenth of the visit when nothing else is
    /// done per triangle. Indices are still checked. Should a position be
    /// NaN or infinite after all, visitors receive it.
    pub fn set_positions_known_finite(&mut self, known: bool) {
        self.finite_known = known;
    }

    /// Whether [`TriangleRecords::visit`] prefetches the corners of the
    /// triangles ahead (on by default). Prefetching is what keeps a mesh
    /// whose vertices are in no spatial order from waiting on memory for
    /// every corner; on a mesh in good order the hardware prefetcher
    /// already has the corners, and the look-ahead's loads and prefetch
    /// instructions are a fifth of the visit's cost. Turn it off when a
    /// sample of the faces shows good locality. The triangles visited are
    /// the same either way.
    pub fn set_prefetch(&mut self, on: bool) {
        self.prefetch = on;
    }

    /// Number of face records (each a triangle).
    pub fn len(&self) -> u64 {
        match &self.faces {
            FixedFaces::Ply { count, .. } | FixedFaces::Soup { count } | FixedFaces::Indexed { count, .. } => *count,
        }
    }

    /// True when there are no records.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    fn reject(&self, r: Reject, record: u64, element: &str, byte: Option<u64>) -> Error {
        let e = match r {
            Reject::Index(v) => {
                Error::new(ErrorKind::Index, &self.path, format!("vertex index {v} is out of range (the file has {} vertices)", self.positions.count()))
            }
            Reject::NotFinite(v) => not_finite(&self.path, v, &self.positions),
        };
        let e = e.at_element(element).at_record(record);
        match byte {
            Some(b) => e.at_byte(b),
            None => e,
        }
    }

    /// Calls `f` with the three corner positions of every record in
    /// `first .. end` (clamped to the records), in order. Fails on the first
    /// record that is not a triangle, has an index out of range, or uses a
    /// non-finite position, naming it.
    #[inline(always)]
    pub fn visit<V: TriangleVisitor>(&self, first: u64, end: u64, visitor: &mut V) -> Result<(), Error> {
        let end = end.min(self.len());
        if first >= end {
            return Ok(());
        }
        match &self.faces {
            FixedFaces::Soup { .. } => {
                for k in first..end {
                    let v = (3 * k) as u32;
                    let t = [v, v + 1, v + 2];
                    let p = [self.positions.get(t[0]), self.positions.get(t[1]), self.positions.get(t[2])];
                    check_finite(&p, &t).map_err(|r| self.reject(r, k, "facet", Some(84 + 50 * k)))?;
                    visitor.triangle(&p);
                }
                Ok(())
            }
            FixedFaces::Indexed { element, .. } => self.indexed(first, end, |k, t| {
                let p = [self.positions.get(t[0]), self.positions.get(t[1]), self.positions.get(t[2])];
                check_finite(&p, &t).map_err(|r| self.reject(r, k, element, None))?;
                visitor.triangle(&p);
                Ok(())
            }),
            FixedFaces::Ply { map, element, start, stride, pre, cty, ity, be, .. } => {
                let data = map.bytes();
                let fast = !*be && *stride == 13 && *pre == 0 && *cty == Scalar::U8 && matches!(ity, Scalar::U32 | Scalar::I32);
                // Vouched-for packed f32 positions go to the visitor as raw
                // 16-byte windows (`TriangleVisitor::triangle_f32le`).
                let windows = if self.finite_known { self.positions.packed_f32_windows() } else { None };
                let raw = windows.is_some();
                let windows = windows.unwrap_or(&[]);
                match (fast, self.positions.kind(), self.prefetch, raw) {
                    (true, PosKind::F32Le, true, true) => self.fast::<false, true, true>(data, *start, first, end, element, windows, visitor),
                    (true, PosKind::F32Le, false, true) => self.fast::<false, false, true>(data, *start, first, end, element, windows, visitor),
                    (true, PosKind::F32Le, true, false) => self.fast::<false, true, false>(data, *start, first, end, element, windows, visitor),
                    (true, PosKind::F32Le, false, false) => self.fast::<false, false, false>(data, *start, first, end, element, windows, visitor),
                    (true, PosKind::F64Le, true, _) => self.fast::<true, true, false>(data, *start, first, end, element, windows, visitor),
                    (true, PosKind::F64Le, false, _) => self.fast::<true, false, false>(data, *start, first, end, element, windows, visitor),
                    _ => {
                        let nv = self.positions.count() as i64;
                        for k in first..end {
                            let at = start + k as usize * stride;
                            let rec = &data[at..at + stride];
                            let n = cty.read_i64(&rec[*pre..], *be);
                            if n != 3 {
                                return Err(self.not_triangle(n, k, element, at));
                            }
                            let mut t = [0u32; 3];
                            for (c, slot) in t.iter_mut().enumerate() {
                                let v = ity.read_i64(&rec[pre + cty.size() + c * ity.size()..], *be);
                                if v < 0 || v >= nv {
                                    return Err(self.reject(Reject::Index(v), k, element, Some(at as u64)));
                                }
                                *slot = v as u32;
                            }
                            let p = [self.positions.get(t[0]), self.positions.get(t[1]), self.positions.get(t[2])];
                            check_finite(&p, &t).map_err(|r| self.reject(r, k, element, Some(at as u64)))?;
                            visitor.triangle(&p);
                        }
                        Ok(())
                    }
                }
            }
        }
    }

    /// Asks the kernel to start reading records `first .. end` (clamped)
    /// from disk now, without waiting for them: a hint, given some way
    /// ahead of the records being visited, so that a file larger than the
    /// page cache streams in while the CPU works instead of in each
    /// worker's page faults. Costs a page-cache lookup when the records
    /// are already in memory.
    pub fn read_ahead(&self, first: u64, end: u64) {
        let end = end.min(self.len());
        if first >= end {
            return;
        }
        match &self.faces {
            FixedFaces::Ply { map, start, stride, .. } => map.advise_willneed(start + first as usize * stride, (end - first) as usize * stride),
            FixedFaces::Indexed { map, start, stride, ity: Some(_), .. } => map.advise_willneed(start + 3 * first as usize * stride, 3 * (end - first) as usize * stride),
            FixedFaces::Indexed { ity: None, .. } => {
                let (base, _) = self.positions.byte_range();
                let stride = self.positions.stride();
                self.positions.mapped().advise_willneed(base + 3 * first as usize * stride, 3 * (end - first) as usize * stride);
            }
            FixedFaces::Soup { .. } => {
                // A facet record holds its three corners: the positions'.
                let (base, _) = self.positions.byte_range();
                let stride = self.positions.stride();
                self.positions.mapped().advise_willneed(base + first as usize * stride, (end - first) as usize * stride);
            }
        }
    }

    /// The triangles `first .. end` (clamped by the callers) of an
    /// [`FixedFaces::Indexed`] layout, indices checked against the vertex
    /// count, to `f` until it fails.
    fn indexed(&self, first: u64, end: u64, mut f: impl FnMut(u64, [u32; 3]) -> Result<(), Error>) -> Result<(), Error> {
        let FixedFaces::Indexed { map, element, start, stride, ity, .. } = &self.faces else { unreachable!() };
        let nv = self.positions.count() as u64;
        let Some(ity) = ity else {
            for k in first..end {
                let v = (3 * k) as u32;
                f(k, [v, v + 1, v + 2])?;
            }
            return Ok(());
        };
        let data = map.bytes();
        let size = ity.size();
        for k in first..end {
            let mut t = [0u32; 3];
            for (c, slot) in t.iter_mut().enumerate() {
                let e = 3 * k as usize + c;
                let at = start + e * stride;
                let b = &data[at..at + size];
                let v = match size {
                    1 => b[0] as u64,
                    2 => u16::from_le_bytes([b[0], b[1]]) as u64,
                    _ => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as u64,
                };
                if v >= nv {
                    return Err(Error::new(ErrorKind::Index, &self.path, format!("{element}: index {v} (element {e}) is out of range ({nv} positions)")).at_record(k));
                }
                *slot = v as u32;
            }
            f(k, t)?;
        }
        Ok(())
    }

    /// Calls `f(k, [a, b, c])` with the vertex indices of every record `k`
    /// in `first .. end` (clamped), in order, without touching positions.
    /// Checks what [`TriangleRecords::visit`] checks except finiteness
    /// (positions are not read): every record is a triangle and every index
    /// is in range.
    pub fn visit_indices(&self, first: u64, end: u64, mut f: impl FnMut(u64, [u32; 3])) -> Result<(), Error> {
        let end = end.min(self.len());
        if first >= end {
            return Ok(());
        }
        match &self.faces {
            FixedFaces::Soup { .. } => {
                for k in first..end {
                    let v = (3 * k) as u32;
                    f(k, [v, v + 1, v + 2]);
                }
                Ok(())
            }
            FixedFaces::Indexed { .. } => self.indexed(first, end, |k, t| {
                f(k, t);
                Ok(())
            }),
            FixedFaces::Ply { map, element, start, stride, pre, cty, ity, be, .. } => {
                let data = map.bytes();
                let nv = self.positions.count() as i64;
                if !*be && *stride == 13 && *pre == 0 && *cty == Scalar::U8 && matches!(ity, Scalar::U32 | Scalar::I32) {
                    let bytes = &data[start + first as usize * 13..start + end as usize * 13];
                    for (i, r) in bytes.chunks_exact(13).enumerate() {
                        let k = first + i as u64;
                        let t = common_indices(r);
                        if r[0] != 3 || t.iter().any(|&v| v as i64 >= nv) {
                            return Err(self.bad_record(data, k, element, start + k as usize * 13));
                        }
                        f(k, t);
                    }
                    return Ok(());
                }
                for k in first..end {
                    let at = start + k as usize * stride;
                    match self.indices_at(&data[at..at + stride], *pre, *cty, *ity, *be) {
                        Some(t) => f(k, t),
                        None => return Err(self.bad_record(data, k, element, at)),
                    }
                }
                Ok(())
            }
        }
    }

    /// The three indices of a generic PLY face record, or `None` when it is
    /// not a triangle or an index is out of range.
    fn indices_at(&self, rec: &[u8], pre: usize, cty: Scalar, ity: Scalar, be: bool) -> Option<[u32; 3]> {
        if cty.read_i64(&rec[pre..], be) != 3 {
            return None;
        }
        let nv = self.positions.count() as i64;
        let mut t = [0u32; 3];
        for (c, slot) in t.iter_mut().enumerate() {
            let v = ity.read_i64(&rec[pre + cty.size() + c * ity.size()..], be);
            if v < 0 || v >= nv {
                return None;
            }
            *slot = v as u32;
        }
        Some(t)
    }

    /// The error for PLY face record `k` at byte `at`, which
    /// [`TriangleRecords::visit_indices`] found not a triangle or out of
    /// range: the same located error [`TriangleRecords::visit`] gives.
    fn bad_record(&self, data: &[u8], k: u64, element: &str, at: usize) -> Error {
        let FixedFaces::Ply { stride, pre, cty, ity, be, .. } = &self.faces else { unreachable!() };
        let rec = &data[at..at + stride];
        let n = cty.read_i64(&rec[*pre..], *be);
        if n != 3 {
            return self.not_triangle(n, k, element, at);
        }
        let nv = self.positions.count() as i64;
        let bad = (0..3)
            .map(|c| ity.read_i64(&rec[pre + cty.size() + c * ity.size()..], *be))
            .find(|&v| v < 0 || v >= nv)
            .unwrap_or(-1);
        self.reject(Reject::Index(bad), k, element, Some(at as u64))
    }

    fn not_triangle(&self, n: i64, record: u64, element: &str, at: usize) -> Error {
        Error::unsupported(&self.path, format!("a face with {n} corners: a file read in parts must hold only triangles (run it as one part, --parts 1)"))
            .at_element(element)
            .at_record(record)
            .at_byte(at as u64)
    }

    /// The common layout: `uchar 3`, three little-endian 32-bit indices.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn fast<const F64: bool, const PREFETCH: bool, const RAW: bool>(
        &self,
        data: &[u8],
        start: usize,
        first: u64,
        end: u64,
        element: &str,
        windows: &[u8],
        visitor: &mut impl TriangleVisitor,
    ) -> Result<(), Error> {
        let nv = self.positions.count();
        let finite_known = self.finite_known;
        // `RAW`: `windows` (from `packed_f32_windows`) holds 16 readable
        // bytes from every vertex's record.
        assert!(!RAW || windows.len() >= nv as usize * 12 + 4);
        let bytes = &data[start + first as usize * 13..start + end as usize * 13];
        // Prefetch the corners of the triangle this many records ahead: in
        // a mesh whose vertices are in no spatial order each corner is a
        // cache (and TLB) miss, and this keeps many of them in flight.
        // (Written in the loop, not as a closure: a closure is compiled on
        // its own, without the target features of a caller that
        // `visit_chunk` compiles for AVX2, and was not inlined there.)
        // The look-ahead reaches past `end` (to the file's last record), so
        // that a caller walking a range in steps does not start each step
        // with a full memory latency per corner.
        const AHEAD: usize = 32;
        let reach = &data[start + first as usize * 13..start + (end + AHEAD as u64).min(self.len()) as usize * 13];
        for (i, r) in bytes.chunks_exact(13).enumerate() {
            if PREFETCH {
                if let Some(r) = reach.get((i + AHEAD) * 13..(i + AHEAD) * 13 + 13) {
                    for c in 0..3 {
                        self.positions.prefetch(u32::from_le_bytes([r[1 + 4 * c], r[2 + 4 * c], r[3 + 4 * c], r[4 + 4 * c]]));
                    }
                }
            }
            let r: &[u8; 13] = r.try_into().unwrap();
            let k = first + i as u64;
            if r[0] != 3 {
                return Err(self.not_triangle(r[0] as i64, k, element, start + k as usize * 13));
            }
            let t = common_indices(r);
            if t[0] >= nv || t[1] >= nv || t[2] >= nv {
                let bad = t.iter().copied().find(|&v| v >= nv).unwrap();
                // An i32 index read as u32: report it as the file wrote it.
                let v = bad as i32 as i64;
                let v = if v < 0 { v } else { bad as i64 };
                return Err(self.reject(Reject::Index(v), k, element, Some((start + k as usize * 13) as u64)));
            }
            if RAW {
                // SAFETY: every index is below `nv` (checked above), and
                // `windows` holds `12 * nv + 4` bytes (asserted above), so
                // the 16 bytes from `12 * v` are inside it.
                let w = |v: u32| unsafe { std::ptr::read_unaligned(windows.as_ptr().add(v as usize * 12) as *const [u8; 16]) };
                visitor.triangle_f32le(&[w(t[0]), w(t[1]), w(t[2])]);
                continue;
            }
            // Positions stored as f64 (`F64`) or f32, little-endian.
            let pos = &self.positions;
            let p = if F64 { [pos.get_f64le(t[0]), pos.get_f64le(t[1]), pos.get_f64le(t[2])] } else { [pos.get_f32le(t[0]), pos.get_f32le(t[1]), pos.get_f32le(t[2])] };
            if !finite_known {
                check_finite(&p, &t).map_err(|r| self.reject(r, k, element, Some((start + k as usize * 13) as u64)))?;
            }
            visitor.triangle(&p);
        }
        Ok(())
    }
}

/// The three indices of a record in the common layout (`uchar 3`, then
/// three little-endian 32-bit indices; 13 bytes).
#[inline(always)]
fn common_indices(r: &[u8]) -> [u32; 3] {
    let w = |i: usize| u32::from_le_bytes([r[i], r[i + 1], r[i + 2], r[i + 3]]);
    [w(1), w(5), w(9)]
}

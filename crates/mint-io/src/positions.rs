//! Vertex positions fetched by index from a memory map, and the emitter that
//! turns vertex-index triples into checked triangles.
//!
//! [`Positions`] describes where vertex `i` lives in a [`Mapped`] file: a
//! base offset, a record stride, the offsets and [`Scalar`] types of x, y
//! and z, and the byte order. It covers a binary PLY vertex section read in
//! place, a spill file of little-endian `f64` triples, and binary STL facets
//! (three vertices per 50-byte record, via `group`). [`Emit`] appends
//! triangles to a chunk: it range-checks the indices, resolves positions and
//! rejects NaN/infinite coordinates, without allocating per triangle and
//! without building an [`Error`](crate::Error) unless something is wrong
//! (callers add the file position to a [`Reject`]).

use std::path::Path;
use std::sync::Arc;

use crate::error::{Error, ErrorKind};
use crate::mapped::Mapped;

/// A PLY scalar type (also used for the fixed layouts of STL and spills).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    /// Parses a PLY type name, including the `int8`..`float64` aliases.
    pub(crate) fn parse(name: &str) -> Option<Scalar> {
        Some(match name {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    #[inline]
    pub(crate) fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    pub(crate) fn is_float(self) -> bool {
        matches!(self, Scalar::F32 | Scalar::F64)
    }

    /// Reads a value as f64 from the first `size()` bytes of `b`.
    #[inline]
    pub(crate) fn read_f64(self, b: &[u8], be: bool) -> f64 {
        macro_rules! rd {
            ($t:ty, $n:expr) => {{
                let a: [u8; $n] = b[..$n].try_into().unwrap();
                (if be { <$t>::from_be_bytes(a) } else { <$t>::from_le_bytes(a) }) as f64
            }};
        }
        match self {
            Scalar::I8 => b[0] as i8 as f64,
            Scalar::U8 => b[0] as f64,
            Scalar::I16 => rd!(i16, 2),
            Scalar::U16 => rd!(u16, 2),
            Scalar::I32 => rd!(i32, 4),
            Scalar::U32 => rd!(u32, 4),
            Scalar::F32 => rd!(f32, 4),
            Scalar::F64 => rd!(f64, 8),
        }
    }

    /// Reads an integer value from the first `size()` bytes of `b`; float
    /// types are truncated (callers reject float index types up front).
    #[inline]
    pub(crate) fn read_i64(self, b: &[u8], be: bool) -> i64 {
        macro_rules! rd {
            ($t:ty, $n:expr) => {{
                let a: [u8; $n] = b[..$n].try_into().unwrap();
                (if be { <$t>::from_be_bytes(a) } else { <$t>::from_le_bytes(a) }) as i64
            }};
        }
        match self {
            Scalar::I8 => b[0] as i8 as i64,
            Scalar::U8 => b[0] as i64,
            Scalar::I16 => rd!(i16, 2),
            Scalar::U16 => rd!(u16, 2),
            Scalar::I32 => rd!(i32, 4),
            Scalar::U32 => rd!(u32, 4),
            Scalar::F32 => self.read_f64(b, be) as i64,
            Scalar::F64 => self.read_f64(b, be) as i64,
        }
    }
}

/// Which specialised fetch applies.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum PosKind {
    /// x, y, z are little-endian f32, one vertex per record.
    F32Le,
    /// x, y, z are little-endian f64, one vertex per record.
    F64Le,
    /// Anything else (other types, big-endian, grouped records).
    Other,
}

/// Where vertex `i` lives: record `base + (i / group) * stride + (i % group)
/// * inner`, coordinates at `off[k]` within it.
#[derive(Debug, Clone)]
pub(crate) struct Positions {
    map: Arc<Mapped>,
    count: u32,
    base: usize,
    stride: usize,
    group: usize,
    inner: usize,
    off: [usize; 3],
    ty: [Scalar; 3],
    be: bool,
    kind: PosKind,
}

/// The layout arguments of [`Positions::new`].
#[derive(Debug, Clone, Copy)]
pub(crate) struct Layout {
    pub(crate) base: usize,
    pub(crate) stride: usize,
    /// Vertices per record (1, or 3 for STL facets).
    pub(crate) group: usize,
    /// Distance between the vertices of one record.
    pub(crate) inner: usize,
    pub(crate) off: [usize; 3],
    pub(crate) ty: [Scalar; 3],
    pub(crate) be: bool,
}

impl Positions {
    /// Positions of `count` vertices in `map` laid out as `layout`.
    ///
    /// Panics if the layout does not fit in the map: callers check the file
    /// size first and report truncation as an error. The check here is what
    /// makes the unchecked reads in the fetch functions sound.
    pub(crate) fn new(map: Arc<Mapped>, count: u32, l: Layout) -> Positions {
        let len = map.bytes().len();
        assert!(l.group >= 1 && l.stride >= 1);
        for k in 0..3 {
            assert!(l.off[k] + l.ty[k].size() <= if l.group == 1 { l.stride } else { l.inner });
        }
        if count > 0 {
            let last = count as usize - 1;
            let rec = l.base + (last / l.group) * l.stride + (last % l.group) * l.inner;
            let end = (0..3).map(|k| rec + l.off[k] + l.ty[k].size()).max().unwrap();
            assert!(end <= len, "vertex layout past the end of the map ({end} > {len})");
        }
        let contiguous = l.group == 1 && !l.be;
        let kind = if contiguous && l.ty == [Scalar::F32; 3] {
            PosKind::F32Le
        } else if contiguous && l.ty == [Scalar::F64; 3] {
            PosKind::F64Le
        } else {
            PosKind::Other
        };
        Positions { map, count, base: l.base, stride: l.stride, group: l.group, inner: l.inner, off: l.off, ty: l.ty, be: l.be, kind }
    }

    /// A spill file of little-endian f64 triples.
    pub(crate) fn spilled(map: Arc<Mapped>, count: u32) -> Positions {
        Positions::new(
            map,
            count,
            Layout { base: 0, stride: 24, group: 1, inner: 0, off: [0, 8, 16], ty: [Scalar::F64; 3], be: false },
        )
    }

    /// No vertices.
    pub(crate) fn empty() -> Positions {
        Positions::spilled(Arc::new(Mapped::empty()), 0)
    }

    #[inline]
    pub(crate) fn count(&self) -> u32 {
        self.count
    }

    pub(crate) fn kind(&self) -> PosKind {
        self.kind
    }

    /// Bytes from one record to the next (a record holds `group` vertices).
    pub(crate) fn stride(&self) -> usize {
        self.stride
    }

    /// The byte range the positions occupy in the map, for madvise.
    pub(crate) fn byte_range(&self) -> (usize, usize) {
        let recs = (self.count as usize).div_ceil(self.group);
        (self.base, recs * self.stride)
    }

    /// True when every coordinate type converts to `f32` without loss
    /// (`f32` and the 8- and 16-bit integers), so a copy may be kept as f32.
    pub(crate) fn exact_in_f32(&self) -> bool {
        self.ty.iter().all(|t| matches!(t, Scalar::F32 | Scalar::I8 | Scalar::U8 | Scalar::I16 | Scalar::U16))
    }

    /// The bytes of vertices `first .. end` when they are packed
    /// little-endian f32 triples (`x y z`, 12 bytes a vertex, nothing
    /// between: what most binary PLY scans and every mint output hold);
    /// `None` for any other layout. The range must be within `count`.
    pub(crate) fn packed_f32(&self, first: u32, end: u32) -> Option<&[u8]> {
        if self.kind != PosKind::F32Le || self.stride != 12 || self.off != [0, 4, 8] || first > end || end > self.count {
            return None;
        }
        Some(&self.map.bytes()[self.base + first as usize * 12..self.base + end as usize * 12])
    }

    /// The map from vertex 0's record on, when the positions are packed
    /// little-endian f32 triples and at least 4 more bytes follow the last
    /// one in the map: then the 16 bytes at `12 * i` hold vertex `i`'s
    /// `x y z` and 4 bytes of whatever follows, for every `i < count`, and
    /// can be read as one vector. `None` otherwise.
    pub(crate) fn packed_f32_windows(&self) -> Option<&[u8]> {
        let all = self.packed_f32(0, self.count)?;
        let bytes = self.map.bytes();
        (self.base + all.len() + 4 <= bytes.len()).then(|| &bytes[self.base..self.base + all.len() + 4])
    }

    pub(crate) fn mapped(&self) -> &Mapped {
        &self.map
    }

    /// Vertex `i`. Panics if `i >= count()`.
    #[inline(always)]
    pub(crate) fn get(&self, i: u32) -> [f64; 3] {
        assert!(i < self.count, "vertex index {i} out of range (vertex count {})", self.count);
        match self.kind {
            PosKind::F32Le => self.get_f32le(i),
            PosKind::F64Le => self.get_f64le(i),
            PosKind::Other => self.get_other(i),
        }
    }

    /// Vertex `i` of an [`PosKind::F32Le`] layout; `i < count` is the
    /// caller's duty (checked in debug builds).
    #[inline(always)]
    pub(crate) fn get_f32le(&self, i: u32) -> [f64; 3] {
        debug_assert!(i < self.count && self.kind == PosKind::F32Le);
        let rec = self.base + i as usize * self.stride;
        let b = self.map.bytes();
        let at = |o: usize| {
            // SAFETY: `new` asserted that the record of the last vertex,
            // plus each coordinate's offset and size, lies inside the map,
            // and records of smaller indices lie before it; callers pass
            // only range-checked indices (`i < count`).
            let v = unsafe { std::ptr::read_unaligned(b.as_ptr().add(rec + o) as *const [u8; 4]) };
            f32::from_le_bytes(v) as f64
        };
        // Three reads, not `off.map(..)`: the map went through the stack,
        // and its narrow stores read back wide stalled the callers
        // (measured in `check`'s geometry).
        [at(self.off[0]), at(self.off[1]), at(self.off[2])]
    }

    /// Asks the CPU to start loading vertex `i`'s record into the cache
    /// (a hint; out-of-range indices are ignored). Used ahead of random
    /// gathers, so that meshes whose vertices are in no spatial order do
    /// not pay one full memory latency per corner.
    #[inline(always)]
    pub(crate) fn prefetch(&self, i: u32) {
        if i < self.count {
            // Ungrouped records (every PLY) skip the division: three per
            // triangle showed in the profile of a shuffled mesh.
            let rec = if self.group == 1 { i as usize } else { i as usize / self.group };
            let at = self.base + rec * self.stride;
            #[cfg(target_arch = "x86_64")]
            // SAFETY: `at` lies inside the map (the record of vertex
            // `i < count`, as `new` checked); a prefetch reads nothing and
            // cannot fault.
            unsafe {
                std::arch::x86_64::_mm_prefetch(self.map.bytes().as_ptr().add(at) as *const i8, std::arch::x86_64::_MM_HINT_T0);
            }
            #[cfg(not(target_arch = "x86_64"))]
            let _ = at;
        }
    }

    /// Vertex `i` of an [`PosKind::F64Le`] layout; `i < count` is the
    /// caller's duty (checked in debug builds).
    #[inline(always)]
    pub(crate) fn get_f64le(&self, i: u32) -> [f64; 3] {
        debug_assert!(i < self.count && self.kind == PosKind::F64Le);
        let rec = self.base + i as usize * self.stride;
        let b = self.map.bytes();
        let at = |o: usize| {
            // SAFETY: as in `get_f32le`.
            let v = unsafe { std::ptr::read_unaligned(b.as_ptr().add(rec + o) as *const [u8; 8]) };
            f64::from_le_bytes(v)
        };
        [at(self.off[0]), at(self.off[1]), at(self.off[2])]
    }

    /// Vertex `i` of any layout (bounds-checked slices).
    #[inline]
    pub(crate) fn get_other(&self, i: u32) -> [f64; 3] {
        let i = i as usize;
        let rec = self.base + (i / self.group) * self.stride + (i % self.group) * self.inner;
        let b = self.map.bytes();
        let mut p = [0.0; 3];
        for k in 0..3 {
            p[k] = self.ty[k].read_f64(&b[rec + self.off[k]..], self.be);
        }
        p
    }
}

/// Why a triangle was refused; the caller adds where it came from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Reject {
    /// A vertex index outside `0..count` (as read, before any conversion).
    Index(i64),
    /// Vertex `.0` has a NaN or infinite coordinate.
    NotFinite(u32),
}

/// Appends checked triangles to a chunk's vectors, up to `max`.
pub(crate) struct Emit<'a> {
    pub(crate) indices: &'a mut Vec<[u32; 3]>,
    pub(crate) positions: &'a mut Vec<[[f64; 3]; 3]>,
    pub(crate) max: usize,
    pub(crate) resolve: bool,
    pub(crate) pos: &'a Positions,
}

impl Emit<'_> {
    /// True when the chunk has room for another triangle.
    #[inline(always)]
    pub(crate) fn room(&self) -> bool {
        self.indices.len() < self.max
    }

    /// Triangles in the chunk so far.
    #[inline]
    pub(crate) fn len(&self) -> usize {
        self.indices.len()
    }

    /// Appends a triangle whose indices are known to be `< count`.
    #[inline(always)]
    pub(crate) fn tri_checked(&mut self, t: [u32; 3]) -> Result<(), Reject> {
        self.indices.push(t);
        if self.resolve {
            let p = [self.pos.get(t[0]), self.pos.get(t[1]), self.pos.get(t[2])];
            check_finite(&p, &t)?;
            self.positions.push(p);
        }
        Ok(())
    }
}

/// Checks nine coordinates at once: the sum of finite f32-range values is
/// finite, and a NaN or infinity anywhere makes it non-finite; only when the
/// sum is not finite (or could have overflowed, with huge f64 values) are
/// the coordinates examined one by one.
#[inline(always)]
pub(crate) fn check_finite(p: &[[f64; 3]; 3], t: &[u32; 3]) -> Result<(), Reject> {
    let s = (p[0][0] + p[0][1] + p[0][2]) + (p[1][0] + p[1][1] + p[1][2]) + (p[2][0] + p[2][1] + p[2][2]);
    if s.is_finite() {
        return Ok(());
    }
    for (k, q) in p.iter().enumerate() {
        if !q.iter().all(|c| c.is_finite()) {
            return Err(Reject::NotFinite(t[k]));
        }
    }
    Ok(())
}

/// The error for a referenced vertex with a NaN or infinite coordinate.
pub(crate) fn not_finite(path: &Path, v: u32, pos: &Positions) -> Error {
    let p = pos.get(v);
    Error::new(
        ErrorKind::Value,
        path,
        format!("vertex {v} used by this face has a non-finite coordinate ({}, {}, {})", p[0], p[1], p[2]),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scalar_reads_both_endians() {
        assert_eq!(Scalar::I16.read_i64(&[0xff, 0xfe], false), -257);
        assert_eq!(Scalar::I16.read_i64(&[0xfe, 0xff], true), -257);
        assert_eq!(Scalar::F32.read_f64(&1.5f32.to_be_bytes(), true), 1.5);
        assert_eq!(Scalar::U8.read_i64(&[200], true), 200);
        assert_eq!(Scalar::parse("float64"), Some(Scalar::F64));
        assert_eq!(Scalar::parse("int64"), None);
    }

    #[test]
    fn finite_check_tolerates_huge_sums() {
        let big = [[f64::MAX; 3]; 3];
        assert_eq!(check_finite(&big, &[0, 1, 2]), Ok(()));
        let mut p = [[0.0; 3]; 3];
        p[2][1] = f64::NAN;
        assert_eq!(check_finite(&p, &[4, 5, 6]), Err(Reject::NotFinite(6)));
    }
}

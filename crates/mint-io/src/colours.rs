//! Colour fetched by index, as [`crate::positions`] fetches positions:
//! - [`VertexColours`], per vertex: from a binary PLY's vertex records in
//!   place, or from a spill of RGBA bytes written while a text file was read;
//! - [`FaceColours`], per face (PLY `face` elements with `red green blue
//!   [alpha]`): a spill of RGBA bytes per *triangle*, in the order the reader
//!   delivers triangles (a polygon of n corners gives n − 2), written by one
//!   pass over the faces when the file is opened.
//!
//! Colours come back as 8-bit RGBA whatever the file holds: `uchar` as is,
//! `ushort` by its high byte, `float`/`double` from `[0, 1]` (clamped,
//! rounded; NaN gives 0). Alpha is 255 when the file has none. The engine
//! carries them through resampling (`mint_core::colour`).

use std::sync::Arc;

use crate::mapped::Mapped;
use crate::positions::Scalar;

/// Where vertex `i`'s colour lives; cheap to clone, shareable by threads.
#[derive(Debug, Clone)]
pub struct VertexColours {
    map: Arc<Mapped>,
    count: u32,
    base: usize,
    stride: usize,
    /// Offsets of red, green, blue and alpha in a record (alpha unused
    /// when `alpha` is false).
    off: [usize; 4],
    ty: [Scalar; 4],
    alpha: bool,
    be: bool,
}

impl VertexColours {
    /// Colours of `count` vertices in records of `stride` bytes from `base`.
    /// Panics if the last record does not fit in the map (callers check
    /// the file size first, as for positions).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn new(map: Arc<Mapped>, count: u32, base: usize, stride: usize, off: [usize; 4], ty: [Scalar; 4], alpha: bool, be: bool) -> VertexColours {
        if count > 0 {
            let rec = base + (count as usize - 1) * stride;
            let k = if alpha { 4 } else { 3 };
            let end = (0..k).map(|c| rec + off[c] + ty[c].size()).max().unwrap_or(0);
            assert!(end <= map.bytes().len(), "colour layout past the end of the map ({end} > {})", map.bytes().len());
        }
        VertexColours { map, count, base, stride, off, ty, alpha, be }
    }

    /// A spill of RGBA bytes, four per vertex.
    pub(crate) fn spilled(map: Arc<Mapped>, count: u32) -> VertexColours {
        VertexColours::new(map, count, 0, 4, [0, 1, 2, 3], [Scalar::U8; 4], true, false)
    }

    /// Number of vertices.
    pub fn count(&self) -> u32 {
        self.count
    }

    /// Vertex `i`'s colour as RGBA bytes. Panics if `i >= count()`.
    #[inline]
    pub fn get(&self, i: u32) -> [u8; 4] {
        assert!(i < self.count, "vertex index {i} out of range (vertex count {})", self.count);
        let rec = self.base + i as usize * self.stride;
        let b = self.map.bytes();
        let mut c = [255u8; 4];
        for k in 0..if self.alpha { 4 } else { 3 } {
            c[k] = to_u8(self.ty[k], &b[rec + self.off[k]..], self.be);
        }
        c
    }
}

/// Per-triangle colour, by the triangle's place in the file's stream of
/// triangles; cheap to clone, shareable by threads.
#[derive(Debug, Clone)]
pub struct FaceColours {
    map: Arc<Mapped>,
    count: u64,
}

impl FaceColours {
    /// A spill of RGBA bytes, four per triangle.
    pub(crate) fn spilled(map: Arc<Mapped>) -> FaceColours {
        let count = map.bytes().len() as u64 / 4;
        FaceColours { map, count }
    }

    /// Number of triangles.
    pub fn count(&self) -> u64 {
        self.count
    }

    /// Triangle `t`'s colour as RGBA bytes (white past `count()`: a
    /// second face element, which has no colour pass).
    #[inline]
    pub fn get(&self, t: u64) -> [u8; 4] {
        let at = t as usize * 4;
        self.map.bytes().get(at..at + 4).map_or([255; 4], |b| b.try_into().unwrap())
    }
}

/// One colour channel as a byte (see the module docs).
pub(crate) fn to_u8(ty: Scalar, b: &[u8], be: bool) -> u8 {
    match ty {
        Scalar::U8 => b[0],
        Scalar::U16 => (ty.read_i64(b, be) >> 8) as u8,
        _ => unit_to_u8(ty.read_f64(b, be)),
    }
}

/// A channel in `[0, 1]` as a byte: clamped, rounded; NaN gives 0.
pub(crate) fn unit_to_u8(v: f64) -> u8 {
    if v.is_nan() {
        0
    } else {
        (v.clamp(0.0, 1.0) * 255.0).round() as u8
    }
}

/// The colour types a PLY file may use (others are refused by name).
pub(crate) fn colour_scalar(ty: Scalar) -> bool {
    matches!(ty, Scalar::U8 | Scalar::U16 | Scalar::F32 | Scalar::F64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn channels_become_bytes() {
        assert_eq!(to_u8(Scalar::U8, &[200], false), 200);
        assert_eq!(to_u8(Scalar::U16, &0xABCDu16.to_le_bytes(), false), 0xAB);
        assert_eq!(to_u8(Scalar::U16, &0xABCDu16.to_be_bytes(), true), 0xAB);
        assert_eq!(to_u8(Scalar::F32, &0.5f32.to_le_bytes(), false), 128);
        assert_eq!(to_u8(Scalar::F64, &2.0f64.to_le_bytes(), false), 255);
        assert_eq!(to_u8(Scalar::F64, &(-1.0f64).to_le_bytes(), false), 0);
        assert_eq!(unit_to_u8(f64::NAN), 0);
    }
}

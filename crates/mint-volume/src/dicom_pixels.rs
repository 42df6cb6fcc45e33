//! Encapsulated (compressed) DICOM pixel data, one frame: the transfer
//! syntaxes mint decodes ([`Codec::of`]) and the decoding of a frame's
//! fragments into the samples an uncompressed file would hold
//! ([`decode_frame`]: little-endian, `BitsAllocated` wide, row-major).
//!
//! - RLE Lossless (1.2.840.10008.1.2.5), PS3.5 Annex G: a 64-byte header
//!   (segment count, 15 offsets), then one PackBits segment per byte of a
//!   sample, the most significant byte's first. Decoded here.
//! - JPEG Baseline (1.2.840.10008.1.2.4.50, 8 bits) and JPEG Lossless,
//!   Non-Hierarchical, Process 14 (1.2.840.10008.1.2.4.57) and its
//!   First-Order Prediction form (1.2.840.10008.1.2.4.70, the usual
//!   lossless CT export), 2 to 16 bits: decoded by `jpeg-decoder`, one
//!   grey component only.
//!
//! Others (JPEG Extended 12-bit, JPEG-LS, JPEG 2000, HTJ2K, deflate) have no
//! decoder here; `crate::dicom` names them in one line with a conversion
//! command. Every size is checked against the header (Rows, Columns,
//! BitsAllocated) before anything is allocated from it: a damaged or
//! crafted fragment is a one-line error, never a panic or a large buffer.

/// A compressed transfer syntax mint decodes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Codec {
    /// RLE Lossless.
    Rle,
    /// JPEG Baseline (Process 1), 8 bits.
    JpegBaseline,
    /// JPEG Lossless (Process 14, any predictor, or selection value 1).
    JpegLossless,
}

impl Codec {
    /// The codec of the transfer syntax `uid`, if mint decodes it.
    pub(crate) fn of(uid: &str) -> Option<Codec> {
        Some(match uid {
            "1.2.840.10008.1.2.5" => Codec::Rle,
            "1.2.840.10008.1.2.4.50" => Codec::JpegBaseline,
            "1.2.840.10008.1.2.4.57" | "1.2.840.10008.1.2.4.70" => Codec::JpegLossless,
            _ => return None,
        })
    }
}

/// The frame's geometry, from the header.
#[derive(Debug, Clone, Copy)]
pub(crate) struct FrameShape {
    pub(crate) rows: u64,
    pub(crate) cols: u64,
    pub(crate) bits_allocated: u32,
}

/// Decodes one frame held in `fragments` into `out` (cleared first):
/// `rows · cols` samples of `bits_allocated / 8` little-endian bytes. The
/// error says what is wrong, without the file (the caller adds it).
pub(crate) fn decode_frame(codec: Codec, fragments: &[Vec<u8>], shape: FrameShape, out: &mut Vec<u8>) -> Result<(), String> {
    out.clear();
    match codec {
        Codec::Rle => {
            if fragments.len() != 1 {
                return Err(format!("an RLE frame is one fragment, this one has {}", fragments.len()));
            }
            rle(&fragments[0], shape, out)
        }
        Codec::JpegBaseline | Codec::JpegLossless => {
            let bytes: Vec<u8>;
            let data: &[u8] = if fragments.len() == 1 {
                &fragments[0]
            } else {
                bytes = fragments.concat();
                &bytes
            };
            jpeg(data, shape, out)
        }
    }
}

/// RLE Lossless (PS3.5 G.3 and G.5).
fn rle(frag: &[u8], shape: FrameShape, out: &mut Vec<u8>) -> Result<(), String> {
    let bpp = (shape.bits_allocated / 8) as usize;
    let n = (shape.rows * shape.cols) as usize;
    if frag.len() < 64 {
        return Err(format!("the RLE header needs 64 bytes, the fragment holds {}", frag.len()));
    }
    let word = |i: usize| u32::from_le_bytes([frag[4 * i], frag[4 * i + 1], frag[4 * i + 2], frag[4 * i + 3]]) as usize;
    let segments = word(0);
    if segments != bpp {
        return Err(format!("{segments} RLE segments where one grey sample of {} bits needs {bpp}", shape.bits_allocated));
    }
    out.resize(n * bpp, 0);
    for s in 0..segments {
        let start = word(1 + s);
        let end = if s + 1 < segments { word(2 + s) } else { frag.len() };
        if start < 64 || start > end || end > frag.len() {
            return Err(format!("RLE segment {s} at bytes {start}..{end} of a fragment of {}", frag.len()));
        }
        // Segment s holds byte s of each sample, most significant first.
        let lane = bpp - 1 - s;
        let got = packbits(&frag[start..end], n, |i, b| out[i * bpp + lane] = b);
        if got != n {
            return Err(format!("RLE segment {s} decodes to {got} bytes, the frame's {} x {} samples need {n}", shape.cols, shape.rows));
        }
    }
    Ok(())
}

/// PackBits: calls `put(i, byte)` for the first `n` decoded bytes and
/// returns how many there were (a run past `n` is cut at `n`; the pad
/// byte an even-length segment may carry is ignored).
fn packbits(mut src: &[u8], n: usize, mut put: impl FnMut(usize, u8)) -> usize {
    let mut i = 0;
    while i < n {
        let Some((&h, rest)) = src.split_first() else { break };
        src = rest;
        let h = h as i8;
        if h >= 0 {
            let k = (h as usize + 1).min(src.len());
            for &b in &src[..k] {
                if i < n {
                    put(i, b);
                    i += 1;
                }
            }
            src = &src[k..];
        } else if h != -128 {
            let Some((&b, rest)) = src.split_first() else { break };
            src = rest;
            for _ in 0..(1 - h as isize) as usize {
                if i < n {
                    put(i, b);
                    i += 1;
                }
            }
        }
    }
    i
}

/// JPEG (baseline or lossless) through jpeg-decoder.
fn jpeg(data: &[u8], shape: FrameShape, out: &mut Vec<u8>) -> Result<(), String> {
    let mut d = jpeg_decoder::Decoder::new(data);
    d.read_info().map_err(|e| format!("JPEG: {e}"))?;
    let info = d.info().ok_or("JPEG: no frame header")?;
    if (info.width as u64, info.height as u64) != (shape.cols, shape.rows) {
        return Err(format!("the JPEG frame is {} x {}, the header's Columns x Rows {} x {}", info.width, info.height, shape.cols, shape.rows));
    }
    let wide = match info.pixel_format {
        jpeg_decoder::PixelFormat::L8 => false,
        jpeg_decoder::PixelFormat::L16 => true,
        other => return Err(format!("the JPEG frame holds {other:?} pixels; mint reads one grey sample per pixel")),
    };
    if wide && shape.bits_allocated < 16 {
        return Err(format!("the JPEG frame holds 16-bit samples, BitsAllocated is {}", shape.bits_allocated));
    }
    // The decoder's buffers are bounded by the checked frame size.
    d.set_max_decoding_buffer_size((shape.rows * shape.cols * 2).max(1 << 16) as usize);
    let px = d.decode().map_err(|e| format!("JPEG: {e}"))?;
    let n = (shape.rows * shape.cols) as usize;
    let bpp = (shape.bits_allocated / 8) as usize;
    if px.len() != n * if wide { 2 } else { 1 } {
        return Err(format!("the JPEG frame decodes to {} bytes, not {} x {} samples", px.len(), shape.cols, shape.rows));
    }
    out.resize(n * bpp, 0);
    if wide {
        for (o, c) in out.chunks_exact_mut(bpp).zip(px.chunks_exact(2)) {
            o[..2].copy_from_slice(&u16::from_ne_bytes([c[0], c[1]]).to_le_bytes());
        }
    } else {
        for (o, &b) in out.chunks_exact_mut(bpp).zip(&px) {
            o[0] = b;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn packbits_runs_literals_and_noops() {
        // A literal of 3, a run of 4, a no-op, a literal of 1, then a pad byte.
        let src = [2u8, 10, 11, 12, 0xFD, 7, 0x80, 0, 9, 0];
        let mut got = vec![0u8; 8];
        assert_eq!(packbits(&src, 8, |i, b| got[i] = b), 8);
        assert_eq!(got, [10, 11, 12, 7, 7, 7, 7, 9]);
        // Short input stops early; a run past n is cut.
        assert_eq!(packbits(&[0xFD], 8, |_, _| ()), 0);
        assert_eq!(packbits(&[0x81, 5], 3, |_, _| ()), 3);
    }

    #[test]
    fn rle_frames_of_two_byte_samples() {
        // A 2 x 2 frame of 16-bit samples 0x0102, 0x0304, 0x0506, 0x0708:
        // segment 0 the high bytes, segment 1 the low bytes.
        let mut f = vec![0u8; 64];
        f[..4].copy_from_slice(&2u32.to_le_bytes());
        f[4..8].copy_from_slice(&64u32.to_le_bytes());
        f[8..12].copy_from_slice(&69u32.to_le_bytes());
        f.extend([3, 1, 3, 5, 7]);
        f.extend([3, 2, 4, 6, 8]);
        let shape = FrameShape { rows: 2, cols: 2, bits_allocated: 16 };
        let mut out = Vec::new();
        decode_frame(Codec::Rle, &[f.clone()], shape, &mut out).unwrap();
        assert_eq!(out, [2, 1, 4, 3, 6, 5, 8, 7]);
        // Damage: one line each, never a panic.
        let mut short = f.clone();
        short.truncate(70);
        assert!(decode_frame(Codec::Rle, &[short], shape, &mut out).unwrap_err().contains("segment 1 decodes to"));
        let mut bad = f.clone();
        bad[8..12].copy_from_slice(&9999u32.to_le_bytes());
        assert!(decode_frame(Codec::Rle, &[bad], shape, &mut out).unwrap_err().contains("segment 0"));
        let mut three = f.clone();
        three[..4].copy_from_slice(&3u32.to_le_bytes());
        assert!(decode_frame(Codec::Rle, &[three], shape, &mut out).unwrap_err().contains("3 RLE segments"));
        assert!(decode_frame(Codec::Rle, &[f[..10].to_vec()], shape, &mut out).unwrap_err().contains("64 bytes"));
        for cut in 0..f.len() {
            let mut g = f.clone();
            g[cut] ^= 0xA5;
            let _ = decode_frame(Codec::Rle, &[g], shape, &mut out);
        }
    }

    #[test]
    fn jpeg_damage_is_an_error() {
        let shape = FrameShape { rows: 4, cols: 4, bits_allocated: 16 };
        let mut out = Vec::new();
        assert!(decode_frame(Codec::JpegLossless, &[vec![0xFF, 0xD8, 0xFF]], shape, &mut out).unwrap_err().starts_with("JPEG"));
        assert!(decode_frame(Codec::JpegLossless, &[vec![]], shape, &mut out).is_err());
    }
}

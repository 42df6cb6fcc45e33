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
//!   grey component only. The markers are walked first: one frame header
//!   of the named process, one scan, and for lossless no restart interval
//!   and no point transform (which jpeg-decoder 0.3 gets wrong silently).
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
    /// JPEG Lossless (Process 14); `first_order`: the syntax of selection
    /// value 1 only (.70), else any predictor (.57).
    JpegLossless { first_order: bool },
}

impl Codec {
    /// The codec of the transfer syntax `uid`, if mint decodes it.
    pub(crate) fn of(uid: &str) -> Option<Codec> {
        Some(match uid {
            "1.2.840.10008.1.2.5" => Codec::Rle,
            "1.2.840.10008.1.2.4.50" => Codec::JpegBaseline,
            "1.2.840.10008.1.2.4.57" => Codec::JpegLossless { first_order: false },
            "1.2.840.10008.1.2.4.70" => Codec::JpegLossless { first_order: true },
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
    let have: u64 = fragments.iter().map(|f| f.len() as u64).sum();
    if have < min_bytes(codec, shape) {
        return Err(format!("{have} bytes cannot hold a frame of {} x {} samples", shape.cols, shape.rows));
    }
    match codec {
        Codec::Rle => {
            if fragments.len() != 1 {
                return Err(format!("an RLE frame is one fragment, this one has {}", fragments.len()));
            }
            rle(&fragments[0], shape, out)
        }
        Codec::JpegBaseline | Codec::JpegLossless { .. } => {
            let bytes: Vec<u8>;
            let data: &[u8] = if fragments.len() == 1 {
                &fragments[0]
            } else {
                bytes = fragments.concat();
                &bytes
            };
            jpeg(data, codec, shape, out)
        }
    }
}

/// The fewest bytes of pixel data a valid frame of `shape` takes in
/// `codec` (RLE: a 64-byte header and at most 128 bytes from every 2 of a
/// segment; JPEG Lossless: at least a bit a sample; Baseline: at least 2
/// bits an 8 x 8 block): a frame claimed larger than its data can be is
/// refused before anything is sized by it.
pub(crate) fn min_bytes(codec: Codec, shape: FrameShape) -> u64 {
    let n = shape.rows * shape.cols;
    match codec {
        Codec::Rle => 64 + (shape.bits_allocated as u64 / 8) * 2 * n.div_ceil(128),
        Codec::JpegLossless { .. } => n / 8,
        Codec::JpegBaseline => n / 256,
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

/// Checks the markers of a JPEG frame before the decoder runs: one frame
/// header of the process the transfer syntax names (SOF0/SOF1 baseline,
/// SOF3 lossless), one scan, and for lossless no point transform and no
/// restart interval (jpeg-decoder 0.3 reconstructs those wrongly, without
/// an error), and the first-order predictor where the syntax says so. One
/// scan also bounds the decoder's work: each scan decodes the whole frame.
fn jpeg_markers(d: &[u8], codec: Codec) -> Result<(), String> {
    if d.len() < 4 || d[0] != 0xFF || d[1] != 0xD8 {
        return Err("the JPEG data does not start with SOI (FF D8)".into());
    }
    let (mut pos, mut frames, mut scans) = (2usize, 0u32, 0u32);
    loop {
        // A marker: FF (fill FFs allowed), then its code.
        if pos >= d.len() || d[pos] != 0xFF {
            return Err(format!("JPEG: no marker at byte {pos}"));
        }
        while pos < d.len() && d[pos] == 0xFF {
            pos += 1;
        }
        let Some(&m) = d.get(pos) else { return Err("the JPEG data ends early (no EOI)".into()) };
        pos += 1;
        if m == 0xD9 {
            break;
        }
        if (0xD0..=0xD7).contains(&m) || m == 0x01 {
            continue;
        }
        if pos + 2 > d.len() {
            return Err("the JPEG data ends early".into());
        }
        let len = u16::from_be_bytes([d[pos], d[pos + 1]]) as usize;
        if len < 2 || pos + len > d.len() {
            return Err(format!("JPEG: marker FF{m:02X} at byte {} claims {len} bytes", pos - 2));
        }
        let seg = &d[pos + 2..pos + len];
        pos += len;
        match m {
            0xC0..=0xCF if !matches!(m, 0xC4 | 0xC8 | 0xCC) => {
                frames += 1;
                let ok = match codec {
                    Codec::JpegBaseline => matches!(m, 0xC0 | 0xC1),
                    Codec::JpegLossless { .. } => m == 0xC3,
                    Codec::Rle => false,
                };
                if !ok {
                    return Err(format!("the JPEG frame is coded by process SOF{} where the transfer syntax names {}", m - 0xC0, if codec == Codec::JpegBaseline { "baseline (SOF0)" } else { "lossless (SOF3)" }));
                }
            }
            0xDD if matches!(codec, Codec::JpegLossless { .. }) => {
                if seg.len() >= 2 && u16::from_be_bytes([seg[0], seg[1]]) != 0 {
                    return Err("JPEG Lossless with restart intervals (DRI): not decoded by mint; convert with `dcmdjpeg`".into());
                }
            }
            0xDA => {
                scans += 1;
                if scans > 1 {
                    return Err("the JPEG frame has more than one scan; mint reads single-scan grey images".into());
                }
                if let Codec::JpegLossless { first_order } = codec {
                    // Ns, Ns component specs, then Ss (the predictor), Se, Ah|Al.
                    let ns = *seg.first().unwrap_or(&0) as usize;
                    let (Some(&ss), Some(&ahal)) = (seg.get(1 + 2 * ns), seg.get(3 + 2 * ns)) else { return Err("JPEG: a scan header cut short".into()) };
                    if ahal & 0x0F != 0 {
                        return Err(format!("JPEG Lossless with a point transform of {}: not decoded by mint; convert with `dcmdjpeg`", ahal & 0x0F));
                    }
                    if first_order && ss != 1 {
                        return Err(format!("the JPEG scan uses predictor {ss} where the transfer syntax names the first-order predictor (1)"));
                    }
                }
                // The entropy-coded data: up to the next marker that is not
                // a stuffed FF 00 or a restart marker.
                while pos + 1 < d.len() && !(d[pos] == 0xFF && d[pos + 1] != 0x00 && !(0xD0..=0xD7).contains(&d[pos + 1])) {
                    pos += 1;
                }
                if pos + 1 >= d.len() {
                    return Err("the JPEG data ends early (no EOI)".into());
                }
            }
            _ => {}
        }
    }
    if frames != 1 || scans != 1 {
        return Err(format!("the JPEG data has {frames} frame headers and {scans} scans; mint reads one of each"));
    }
    Ok(())
}

/// jpeg-decoder's error as one line (a short stream named as such).
fn jpeg_error(e: jpeg_decoder::Error) -> String {
    match e {
        jpeg_decoder::Error::Io(e) if e.kind() == std::io::ErrorKind::UnexpectedEof => "the JPEG data ends early".into(),
        e => format!("JPEG: {e}"),
    }
}

/// JPEG (baseline or lossless) through jpeg-decoder.
fn jpeg(data: &[u8], codec: Codec, shape: FrameShape, out: &mut Vec<u8>) -> Result<(), String> {
    jpeg_markers(data, codec)?;
    let mut d = jpeg_decoder::Decoder::new(data);
    d.read_info().map_err(jpeg_error)?;
    let info = d.info().ok_or("JPEG: no frame header")?;
    if (info.width as u64, info.height as u64) != (shape.cols, shape.rows) {
        return Err(format!("the JPEG frame is {} x {}, the header's Columns x Rows {} x {}", info.width, info.height, shape.cols, shape.rows));
    }
    let wide = match info.pixel_format {
        jpeg_decoder::PixelFormat::L8 => false,
        jpeg_decoder::PixelFormat::L16 => true,
        other => return Err(format!("the JPEG frame holds {other:?} pixels; mint reads one grey sample per pixel")),
    };
    // The decoder's buffers are bounded by the checked frame size.
    d.set_max_decoding_buffer_size((shape.rows * shape.cols * 2).max(1 << 16) as usize);
    let px = d.decode().map_err(jpeg_error)?;
    let n = (shape.rows * shape.cols) as usize;
    let bpp = (shape.bits_allocated / 8) as usize;
    // Lossless of 2 to 7 bits comes out as 16-bit words although the info
    // says L8 (jpeg-decoder 0.3 writes words for any precision but 8).
    let words = wide || (matches!(codec, Codec::JpegLossless { .. }) && px.len() == 2 * n);
    if px.len() != n * if words { 2 } else { 1 } {
        return Err(format!("the JPEG frame decodes to {} bytes, not {} x {} samples", px.len(), shape.cols, shape.rows));
    }
    out.resize(n * bpp, 0);
    for (i, o) in out.chunks_exact_mut(bpp).enumerate() {
        let v = if words { u16::from_ne_bytes([px[2 * i], px[2 * i + 1]]) } else { px[i] as u16 };
        if bpp == 1 && v > 255 {
            return Err(format!("the JPEG frame holds samples above 255 (more than 8 bits), BitsAllocated is {}", shape.bits_allocated));
        }
        o[..2.min(bpp)].copy_from_slice(&v.to_le_bytes()[..2.min(bpp)]);
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
        assert!(decode_frame(Codec::Rle, &[f[..10].to_vec()], shape, &mut out).unwrap_err().contains("cannot hold a frame"));
        assert!(rle(&f[..10], shape, &mut out).unwrap_err().contains("64 bytes"));
        for cut in 0..f.len() {
            let mut g = f.clone();
            g[cut] ^= 0xA5;
            let _ = decode_frame(Codec::Rle, &[g], shape, &mut out);
        }
    }

    /// The JPEG stream of a committed file (Process 14, predictor 6, 512 x 512).
    fn p14() -> Vec<u8> {
        let b = std::fs::read(std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/data/dicom-compressed/jpeg-lossless-p14/1-01.dcm")).unwrap();
        let soi = (0..b.len() - 3).find(|&i| b[i..i + 4] == [0xFF, 0xD8, 0xFF, 0xC3] || (b[i..i + 3] == [0xFF, 0xD8, 0xFF] && b[i + 3] != 0xD8)).unwrap();
        let eoi = (soi..b.len() - 1).rev().find(|&i| b[i..i + 2] == [0xFF, 0xD9]).unwrap();
        b[soi..eoi + 2].to_vec()
    }

    #[test]
    fn jpeg_markers_are_checked_before_decoding() {
        let shape = FrameShape { rows: 512, cols: 512, bits_allocated: 16 };
        let any = Codec::JpegLossless { first_order: false };
        let j = p14();
        let mut out = Vec::new();
        decode_frame(any, &[j.clone()], shape, &mut out).unwrap();
        assert_eq!(out.len(), 512 * 512 * 2);
        // Fragments split anywhere decode the same.
        let mut again = Vec::new();
        decode_frame(any, &[j[..1000].to_vec(), j[1000..].to_vec()], shape, &mut again).unwrap();
        assert!(again == out);
        // The first-order syntax (.70) refuses predictor 6; a baseline syntax refuses SOF3.
        let e = decode_frame(Codec::JpegLossless { first_order: true }, &[j.clone()], shape, &mut out).unwrap_err();
        assert!(e.contains("predictor 6"), "{e}");
        let e = decode_frame(Codec::JpegBaseline, &[j.clone()], shape, &mut out).unwrap_err();
        assert!(e.contains("SOF3"), "{e}");
        // A restart interval, a second scan, a truncated stream, a frame of another size.
        let dri = [&j[..2], &[0xFF, 0xDD, 0x00, 0x04, 0x00, 0x10][..], &j[2..]].concat();
        assert!(decode_frame(any, &[dri], shape, &mut out).unwrap_err().contains("restart"));
        let sos = (0..j.len() - 1).find(|&i| j[i..i + 2] == [0xFF, 0xDA]).unwrap();
        let two = [&j[..j.len() - 2], &j[sos..]].concat();
        assert!(decode_frame(any, &[two], shape, &mut out).unwrap_err().contains("more than one scan"));
        let e = decode_frame(any, &[j[..j.len() / 2].to_vec()], shape, &mut out).unwrap_err();
        assert!(e.contains("ends early"), "{e}");
        let small = FrameShape { rows: 256, cols: 512, bits_allocated: 16 };
        assert!(decode_frame(any, &[j.clone()], small, &mut out).unwrap_err().contains("512 x 512"));
        // A frame claimed far larger than its data: refused before decoding.
        let huge = FrameShape { rows: 65535, cols: 65535, bits_allocated: 16 };
        assert!(decode_frame(any, &[j.clone()], huge, &mut out).unwrap_err().contains("cannot hold a frame"));
        // Tiny or empty data, and bytes flipped anywhere: an error or a frame, never a panic.
        let tiny = FrameShape { rows: 4, cols: 4, bits_allocated: 16 };
        assert!(decode_frame(any, &[vec![0xFF, 0xD8, 0xFF]], tiny, &mut out).unwrap_err().contains("SOI"));
        assert!(decode_frame(any, &[vec![]], tiny, &mut out).is_err());
        for k in (0..j.len()).step_by(j.len() / 97) {
            let mut g = j.clone();
            g[k] ^= 0xFF;
            let _ = decode_frame(any, &[g], shape, &mut out);
        }
    }
}

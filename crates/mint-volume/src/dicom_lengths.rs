//! DICOM files as bytes, before any parser sees them: their layout
//! ([`layout`]: preamble, bare meta group, or a bare data set) and a walk
//! of their element headers that checks every declared length against
//! what holds it ([`check_lengths`]). dicom-parser zero-fills a buffer of
//! each value's claimed length before reading it, so a damaged or crafted
//! length (4 GB in a 500 KB file) would cost minutes and gigabytes before
//! the read fails; every DICOM reader of mint (RT structure sets in
//! mint-contour, image series here) runs this walk first, so that every
//! allocation is bounded by the file's size.

/// How a DICOM file is laid out, from its first bytes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Layout {
    /// A 128-byte preamble, then `DICM` and the file meta group.
    Preamble,
    /// `DICM` and the file meta group at the start (no preamble).
    Meta,
    /// A bare data set, no meta group: little endian, explicit VR or not.
    Bare {
        /// The two bytes after the first tag are VR letters.
        explicit: bool,
    },
}

/// The DICOM layout of a file starting with `head` (give at least its
/// first 132 bytes), or `None` if it is not DICOM. A bare data set is
/// recognised by a first tag in group 0008 (no text file starts with the
/// bytes `08 00`).
pub fn layout(head: &[u8]) -> Option<Layout> {
    if head.len() >= 132 && &head[128..132] == b"DICM" {
        Some(Layout::Preamble)
    } else if head.starts_with(b"DICM") {
        Some(Layout::Meta)
    } else if head.len() >= 8 && head[0] == 0x08 && head[1] == 0x00 {
        Some(Layout::Bare { explicit: head[4].is_ascii_uppercase() && head[5].is_ascii_uppercase() })
    } else {
        None
    }
}

const UNDEFINED: u32 = 0xFFFF_FFFF;

/// Explicit VRs whose length takes 4 bytes (after 2 reserved ones).
fn long_vr(vr: &[u8]) -> bool {
    matches!(vr, b"OB" | b"OD" | b"OF" | b"OL" | b"OV" | b"OW" | b"SQ" | b"SV" | b"UC" | b"UN" | b"UR" | b"UT" | b"UV")
}

fn u16_at(b: &[u8], i: usize) -> u16 {
    u16::from_le_bytes([b[i], b[i + 1]])
}

fn u32_at(b: &[u8], i: usize) -> u32 {
    u32::from_le_bytes([b[i], b[i + 1], b[i + 2], b[i + 3]])
}

/// Walks the element headers of a little-endian file and checks that every
/// defined length fits in what encloses it (the file, or a defined-length
/// sequence or item), without interpreting values. Sequences are entered:
/// in explicit VR by their VR `SQ`, in implicit VR when the value starts
/// with an item tag. Walks Explicit VR Big Endian data sets too. Stops,
/// content, for Deflated data sets (their
/// readers refuse them); the fragments of encapsulated pixel data are walked
/// as items that must fit in the file. The message names the element and the byte.
pub fn check_lengths(b: &[u8], lay: Layout) -> Result<(), String> {
    pixel_data(b, lay).map(|_| ())
}

/// Where the data set's (7FE0,0010) PixelData value is, in bytes of the file.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum PixelData {
    /// Native samples.
    Native {
        /// Where the value starts.
        offset: usize,
        /// Its length in bytes.
        len: usize,
    },
    /// Encapsulated pixel data.
    Encapsulated {
        /// The items' values as (offset, length): the basic offset table
        /// first, then the fragments.
        items: Vec<(usize, usize)>,
    },
}

/// The most items of encapsulated pixel data recorded.
const MAX_ITEMS: usize = 1 << 20;

/// [`check_lengths`], also saying where the top-level PixelData is (`None`
/// when there is none, or for a Deflated data set).
pub fn pixel_data(b: &[u8], lay: Layout) -> Result<Option<PixelData>, String> {
    let (pos, explicit) = match lay {
        Layout::Bare { explicit } => (0, explicit),
        Layout::Preamble | Layout::Meta => {
            // The file meta group: explicit VR little endian, group 0002.
            let mut pos = if lay == Layout::Preamble { 132 } else { 4 };
            let mut ts = String::new();
            while pos + 8 <= b.len() && u16_at(b, pos) == 0x0002 {
                let elem = u16_at(b, pos + 2);
                let (len, hdr) = if long_vr(&b[pos + 4..pos + 6]) {
                    if pos + 12 > b.len() {
                        return Err(format!("the file meta group is cut short at byte {pos}"));
                    }
                    (u32_at(b, pos + 8) as usize, 12)
                } else {
                    (u16_at(b, pos + 6) as usize, 8)
                };
                if len > b.len() - pos - hdr {
                    return Err(format!("element (0002,{elem:04X}) at byte {pos} claims {len} bytes but {} remain", b.len() - pos - hdr));
                }
                if elem == 0x0010 {
                    ts = String::from_utf8_lossy(&b[pos + hdr..pos + hdr + len]).trim_matches(|c: char| c == '\0' || c.is_whitespace()).to_string();
                }
                pos += hdr + len;
            }
            match ts.as_str() {
                "1.2.840.10008.1.2" => (pos, false),
                "1.2.840.10008.1.2.2" => return walk(b, pos, true, true),
                "1.2.840.10008.1.2.1.99" => return Ok(None),
                _ => (pos, true),
            }
        }
    };
    walk(b, pos, explicit, false)
}

/// The data set's walk from byte `pos`: explicit or implicit VR, little or
/// big endian (Explicit VR Big Endian: every number after the meta group).
fn walk(b: &[u8], mut pos: usize, explicit: bool, big: bool) -> Result<Option<PixelData>, String> {
    let mut found = None;
    let u16_at = |b: &[u8], i: usize| if big { u16::from_be_bytes([b[i], b[i + 1]]) } else { u16_at(b, i) };
    let u32_at = |b: &[u8], i: usize| if big { u32::from_be_bytes([b[i], b[i + 1], b[i + 2], b[i + 3]]) } else { u32_at(b, i) };
    // Ends of the defined-length sequences and items we are in.
    let mut ends: Vec<usize> = vec![b.len()];
    while pos < b.len() {
        while ends.len() > 1 && pos >= *ends.last().unwrap() {
            if pos > ends.pop().unwrap() {
                return Err(format!("the element at byte {pos} overruns the sequence or item that holds it"));
            }
        }
        let end = *ends.last().unwrap();
        if end - pos < 8 {
            return Err(format!("an element header at byte {pos} is cut short"));
        }
        let (group, elem) = (u16_at(b, pos), u16_at(b, pos + 2));
        if group == 0xFFFE {
            let len = u32_at(b, pos + 4);
            pos += 8;
            match elem {
                0xE000 if len != UNDEFINED => {
                    if len as usize > end - pos {
                        return Err(format!("an item at byte {} claims {len} bytes but {} remain", pos - 8, end - pos));
                    }
                    ends.push(pos + len as usize);
                }
                0xE000 | 0xE00D | 0xE0DD => {}
                _ => return Err(format!("unknown delimiter (FFFE,{elem:04X}) at byte {}", pos - 8)),
            }
            continue;
        }
        let (len, hdr, sq, bulk) = if explicit {
            let vr = &b[pos + 4..pos + 6];
            if long_vr(vr) {
                if end - pos < 12 {
                    return Err(format!("an element header at byte {pos} is cut short"));
                }
                (u32_at(b, pos + 8), 12, vr == b"SQ", matches!(vr, b"OB" | b"OW"))
            } else {
                (u16_at(b, pos + 6) as u32, 8, false, false)
            }
        } else {
            (u32_at(b, pos + 4), 8, false, false)
        };
        let at = pos;
        pos += hdr;
        if len == UNDEFINED {
            if bulk {
                // Encapsulated pixel data: items (the offset table, then
                // the fragments) up to a sequence delimiter, each within
                // what holds it.
                if big {
                    return Err(format!("element ({group:04X},{elem:04X}) at byte {at}: encapsulated pixel data in Explicit VR Big Endian (PS3.5 A.4 allows it in little endian only)"));
                }
                let top = ends.len() == 1 && (group, elem) == (0x7FE0, 0x0010);
                let mut items = Vec::new();
                pos = fragments(b, pos, end, at, u32_at, top.then_some(&mut items))?;
                if top {
                    found = Some(PixelData::Encapsulated { items });
                }
                continue;
            }
            continue; // a sequence: its items follow
        }
        let len = len as usize;
        if len > end - pos {
            return Err(format!("element ({group:04X},{elem:04X}) at byte {at} claims {len} bytes but {} remain", end - pos));
        }
        if ends.len() == 1 && (group, elem) == (0x7FE0, 0x0010) {
            found = Some(PixelData::Native { offset: pos, len });
        }
        let items_follow = len >= 8 && u16_at(b, pos) == 0xFFFE && u16_at(b, pos + 2) == 0xE000;
        if sq || (!explicit && items_follow) {
            ends.push(pos + len);
        } else {
            pos += len;
        }
    }
    Ok(found)
}

/// Walks the items of encapsulated pixel data from `pos` (after the
/// element header at `at`) to its sequence delimiter; returns the byte
/// after it.
fn fragments(b: &[u8], mut pos: usize, end: usize, at: usize, u32_at: impl Fn(&[u8], usize) -> u32, mut record: Option<&mut Vec<(usize, usize)>>) -> Result<usize, String> {
    let u16_le = |i: usize| u16::from_le_bytes([b[i], b[i + 1]]);
    loop {
        if end - pos < 8 {
            return Err(format!("the pixel data fragments of the element at byte {at} are cut short at byte {pos}"));
        }
        let (group, elem, len) = (u16_le(pos), u16_le(pos + 2), u32_at(b, pos + 4));
        if group != 0xFFFE || !matches!(elem, 0xE000 | 0xE0DD) {
            return Err(format!("byte {pos}: ({group:04X},{elem:04X}) where a pixel data fragment or its delimiter should be"));
        }
        pos += 8;
        if elem == 0xE0DD {
            return Ok(pos);
        }
        if len == UNDEFINED || len as usize > end - pos {
            return Err(format!("a pixel data fragment at byte {} claims {len} bytes but {} remain", pos - 8, end - pos));
        }
        if let Some(items) = record.as_deref_mut() {
            if items.len() == MAX_ITEMS {
                return Err(format!("the pixel data of the element at byte {at} has more than {MAX_ITEMS} fragments"));
            }
            items.push((pos, len as usize));
        }
        pos += len as usize;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_shared_series_passes_and_damage_is_named() {
        let f = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/volumes/ct-chest-dicom-series-lungpetctdx/1-01.dcm");
        let bytes = std::fs::read(&f).unwrap();
        assert_eq!(layout(&bytes), Some(Layout::Preamble));
        assert_eq!(check_lengths(&bytes, Layout::Preamble), Ok(()));
        let e = check_lengths(&bytes[..bytes.len() - 1000], Layout::Preamble).unwrap_err();
        assert!(e.contains("(7FE0,0010)") && e.contains("claims 524288 bytes"), "{e}");
        // The same file's data set in Explicit VR Big Endian: walked, and a
        // huge length there refused (found by fuzzing: it went to the
        // parser, which sized a 1.8 GB buffer by it).
        let mut be = bytes[..132].to_vec();
        let mut meta = 132;
        while u16_at(&bytes, meta) == 0x0002 {
            let long = long_vr(&bytes[meta + 4..meta + 6]);
            meta += if long { 12 + u32_at(&bytes, meta + 8) as usize } else { 8 + u16_at(&bytes, meta + 6) as usize };
        }
        be.extend_from_slice(&bytes[132..meta]);
        let mut set = vec![0x00u8, 0x08, 0x00, 0x16, b'U', b'I', 0x00, 0x04];
        set.extend_from_slice(b"1.2\0");
        set.extend_from_slice(&[0x53, 0x65, 0x6E, 0x73, b'U', b'N', 0, 0, 0x6E, 0x20, 0x31, 0x30]);
        set.extend_from_slice(&[0u8; 16]);
        let ts_at = (132..meta).find(|&i| u16_at(&bytes, i) == 0x0002 && u16_at(&bytes, i + 2) == 0x0010).unwrap();
        let old = u16_at(&bytes, ts_at + 6) as usize;
        let mut fixed = be[..ts_at].to_vec();
        fixed.extend_from_slice(&[0x02, 0x00, 0x10, 0x00, b'U', b'I', 20, 0]);
        fixed.extend_from_slice(b"1.2.840.10008.1.2.2\0");
        fixed.extend_from_slice(&be[ts_at + 8 + old..]);
        // (The meta group's length element is now stale; the walk does not read it.)
        let mut ok = fixed.clone();
        ok.extend_from_slice(&set[..12]);
        assert_eq!(check_lengths(&ok, Layout::Preamble), Ok(()));
        fixed.extend_from_slice(&set);
        let e = check_lengths(&fixed, Layout::Preamble).unwrap_err();
        assert!(e.contains("(5365,6E73)") && e.contains("claims 1847603504 bytes"), "{e}");
        // A huge length anywhere before the pixels: refused, never a panic.
        for i in (132..3000).step_by(7) {
            let mut b = bytes.clone();
            b[i..i + 4].copy_from_slice(&0x7FFF_FFF0u32.to_le_bytes());
            let _ = check_lengths(&b, Layout::Preamble);
        }
    }
}

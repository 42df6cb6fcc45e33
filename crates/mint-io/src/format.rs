//! Which mesh format a file holds. [`Format::from_path`] trusts the file name
//! extension (case-insensitive) and otherwise sniffs the first bytes with
//! [`Format::sniff`]: the `ply` magic line, `#VRML`, a 3DS main chunk whose
//! length fits the file, an ASCII STL (`solid` followed by text that
//! contains `facet`/`endsolid`), a binary STL (the file size is exactly
//! `84 + 50 * count`), an `OFF`-family keyword, OBJ keywords, the `mesh`
//! header, or a first line of nine numbers (raw).

use std::fmt;
use std::fs::File;
use std::io::Read;
use std::path::Path;

use crate::error::Error;
use crate::text::{is_space, words, Lines};

/// True when `head` starts a binary glTF container (magic `glTF`).
pub(crate) fn is_glb(head: &[u8]) -> bool {
    head.len() >= 12 && &head[..4] == b"glTF"
}

/// A mesh file format.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Format {
    /// Stanford PLY: ascii, binary little- or big-endian.
    Ply,
    /// Wavefront OBJ (geometry only).
    Obj,
    /// STL, binary or ascii; a triangle soup.
    Stl,
    /// Geomview OFF (ascii).
    Off,
    /// The `mesh` text format of Dangl 1998: `v x y z` and `f i j k` lines.
    Mesh,
    /// Raw triangles: nine coordinates per line; a triangle soup.
    Raw,
    /// VRML 2.0 (VRML97): `IndexedFaceSet`s inside `Shape`s.
    Vrml,
    /// Autodesk 3D Studio, binary chunks.
    ThreeDs,
    /// glTF 2.0: `.gltf` (JSON and buffers) or `.glb` (binary container).
    Gltf,
    /// 3D Tiles: a `tileset.json` (read as one surface from its finest
    /// level) or a single `.b3dm` tile. Read only.
    Tiles,
}

impl Format {
    /// The format of the file at `path`: by extension (`.ply`, `.obj`,
    /// `.stl`, `.off`, `.mesh`, `.raw`, `.wrl`/`.vrml`, `.3ds`, any case),
    /// else by sniffing its first 4 KiB.
    /// Unknown formats give an [`ErrorKind::Unsupported`](crate::ErrorKind)
    /// error naming the file; an unreadable file an `Io` error.
    pub fn from_path(path: &Path) -> Result<Format, Error> {
        if let Some(f) = Format::from_extension(path) {
            return Ok(f);
        }
        let mut file = File::open(path).map_err(|e| Error::io(path, "cannot open to detect its format", e))?;
        let len = file.metadata().map_err(|e| Error::io(path, "cannot stat", e))?.len();
        let mut head = Vec::with_capacity(4096);
        (&mut file)
            .take(4096)
            .read_to_end(&mut head)
            .map_err(|e| Error::io(path, "cannot read to detect its format", e))?;
        Format::sniff(&head, len).ok_or_else(|| {
            Error::unsupported(
                path,
                "unknown mesh format (the extension is not .ply, .obj, .stl, .off, .mesh, .raw, .wrl, .3ds, .gltf or .glb and the content is none of them)",
            )
        })
    }

    /// The format named by the file extension, if any.
    pub fn from_extension(path: &Path) -> Option<Format> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "ply" => Some(Format::Ply),
            "obj" => Some(Format::Obj),
            "stl" => Some(Format::Stl),
            "off" => Some(Format::Off),
            "mesh" => Some(Format::Mesh),
            "raw" => Some(Format::Raw),
            "wrl" | "vrml" => Some(Format::Vrml),
            "3ds" => Some(Format::ThreeDs),
            "gltf" | "glb" => Some(Format::Gltf),
            "json" | "b3dm" => Some(Format::Tiles),
            _ => None,
        }
    }

    /// Guesses the format from the first bytes of a file (`head`, ideally a
    /// few KiB) and its total length.
    pub fn sniff(head: &[u8], file_len: u64) -> Option<Format> {
        if head.starts_with(b"ply\n") || head.starts_with(b"ply\r\n") {
            return Some(Format::Ply);
        }
        if is_glb(head) {
            return Some(Format::Gltf);
        }
        if head.starts_with(b"b3dm") {
            return Some(Format::Tiles);
        }
        if head.starts_with(b"#VRML") {
            return Some(Format::Vrml);
        }
        if sniff_3ds(head, file_len) {
            return Some(Format::ThreeDs);
        }
        if stl_looks_ascii(head) || stl_binary_size_matches(head, file_len) {
            return Some(Format::Stl);
        }
        let mut lines = Lines::new(head, 0);
        while let Some((_, line)) = lines.next_line() {
            let mut w = words(line);
            let Some(first) = w.next() else { continue };
            if first.starts_with(b"#") {
                continue;
            }
            if off_keyword(first).is_some() {
                return Some(Format::Off);
            }
            const OBJ: [&[u8]; 12] = [b"v", b"vt", b"vn", b"vp", b"f", b"o", b"g", b"s", b"l", b"p", b"mtllib", b"usemtl"];
            if OBJ.contains(&first) {
                return Some(Format::Obj);
            }
            if first == b"mesh" {
                return Some(Format::Mesh);
            }
            let n = words(line).take_while(|t| !t.starts_with(b"#")).count();
            if n == 9 && words(line).take(9).all(|t| crate::text::parse_f64(t).is_some()) {
                return Some(Format::Raw);
            }
            return None;
        }
        None
    }

    /// The usual file extension, without the dot.
    pub fn extension(self) -> &'static str {
        match self {
            Format::Ply => "ply",
            Format::Obj => "obj",
            Format::Stl => "stl",
            Format::Off => "off",
            Format::Mesh => "mesh",
            Format::Raw => "raw",
            Format::Vrml => "wrl",
            Format::ThreeDs => "3ds",
            Format::Gltf => "glb",
            Format::Tiles => "json",
        }
    }
}

impl fmt::Display for Format {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Format::Ply => "PLY",
            Format::Obj => "OBJ",
            Format::Stl => "STL",
            Format::Off => "OFF",
            Format::Mesh => "mesh",
            Format::Raw => "raw",
            Format::Vrml => "VRML 2.0",
            Format::ThreeDs => "3DS",
            Format::Gltf => "glTF",
            Format::Tiles => "3D Tiles",
        })
    }
}

/// The prefix letters of an OFF keyword (`OFF`, `COFF`, `NOFF`, `STCNOFF`,
/// `4OFF`, `nOFF`, ...), or `None` if `tok` is not one.
pub(crate) fn off_keyword(tok: &[u8]) -> Option<&[u8]> {
    let prefix = tok.strip_suffix(b"OFF")?;
    if prefix.iter().all(|b| b"STCN4n".contains(b)) {
        Some(prefix)
    } else {
        None
    }
}

/// True if `head` starts (after whitespace) with `solid`, its first 512
/// bytes are all text, and they mention `facet` or `endsolid`. Binary STL
/// headers may start with "solid" too; their facet data is not text.
pub(crate) fn stl_looks_ascii(head: &[u8]) -> bool {
    let start = head.iter().position(|&b| !is_space(b)).unwrap_or(head.len());
    let h = &head[start..];
    if !h.starts_with(b"solid") {
        return false;
    }
    let probe = &h[..h.len().min(512)];
    let text = probe.iter().all(|&b| b.is_ascii_graphic() || is_space(b));
    let has = |needle: &[u8]| probe.windows(needle.len()).any(|w| w == needle);
    text && (has(b"facet") || has(b"endsolid"))
}

/// True if the file length is exactly `84 + 50 * count` for the facet
/// count stored at byte 80.
pub(crate) fn stl_binary_size_matches(head: &[u8], file_len: u64) -> bool {
    if head.len() < 84 {
        return false;
    }
    let count = u32::from_le_bytes(head[80..84].try_into().unwrap()) as u64;
    file_len == 84 + 50 * count
}

/// A 3DS file: a main chunk (id 0x4D4D, little-endian) whose length fits
/// the file and covers at least its own header.
pub(crate) fn sniff_3ds(head: &[u8], len: u64) -> bool {
    if head.len() < 6 {
        return false;
    }
    let id = u16::from_le_bytes([head[0], head[1]]);
    let n = u32::from_le_bytes([head[2], head[3], head[4], head[5]]);
    id == 0x4D4D && n as u64 <= len && n >= 6
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn extension_is_case_insensitive() {
        assert_eq!(Format::from_extension(Path::new("a/B.PLY")), Some(Format::Ply));
        assert_eq!(Format::from_extension(Path::new("x.Off")), Some(Format::Off));
        assert_eq!(Format::from_extension(Path::new("x.txt")), None);
        assert_eq!(Format::from_extension(Path::new("noext")), None);
    }

    #[test]
    fn sniffing() {
        assert_eq!(Format::sniff(b"ply\nformat ascii 1.0\n", 20), Some(Format::Ply));
        assert_eq!(Format::sniff(b"# c\nCOFF\n3 1 0\n", 15), Some(Format::Off));
        assert_eq!(Format::sniff(b"# made by hand\n\nv 1 2 3\n", 24), Some(Format::Obj));
        assert_eq!(Format::sniff(b"solid x\n facet normal 0 0 1\n", 29), Some(Format::Stl));
        // A binary STL whose header starts with "solid": decided by size.
        let mut bin = b"solid but binary".to_vec();
        bin.resize(80, 0);
        bin.extend_from_slice(&1u32.to_le_bytes());
        bin.resize(134, 0);
        assert!(!stl_looks_ascii(&bin));
        assert_eq!(Format::sniff(&bin, 134), Some(Format::Stl));
        assert_eq!(Format::sniff(&bin, 135), None);
        assert_eq!(Format::sniff(b"hello world", 11), None);
        assert_eq!(off_keyword(b"STCNOFF"), Some(&b"STCN"[..]));
        assert_eq!(off_keyword(b"OFFX"), None);
    }
}

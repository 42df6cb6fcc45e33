//! The PLY header: `ply`, `format <encoding> <version>`, `comment`,
//! `obj_info`, `element <name> <count>`, `property <type> <name>`,
//! `property list <count type> <item type> <name>`, `end_header`.
//!
//! [`parse`] reads it from the start of a byte slice into a [`PlyHeader`]
//! whose [`Element`]s keep the declared order (elements may come in any
//! order and names may repeat) and whose `body` is the offset of the first
//! byte after the `end_header` line. Lines may end in `\n` or `\r\n`.
//! Problems are reported with element `header`, the line and byte offset.

use std::path::Path;

use crate::error::{show_token, Error, ErrorKind};
use crate::positions::Scalar;
use crate::text::{words, Lines};

/// How the body is encoded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Encoding {
    Ascii,
    BinaryLe,
    BinaryBe,
}

impl Encoding {
    pub(crate) fn name(self) -> &'static str {
        match self {
            Encoding::Ascii => "ascii",
            Encoding::BinaryLe => "binary_little_endian",
            Encoding::BinaryBe => "binary_big_endian",
        }
    }
}

/// The type of a property.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum PropType {
    Scalar(Scalar),
    List { count: Scalar, item: Scalar },
}

/// One `property` line.
#[derive(Debug, Clone)]
pub(crate) struct Property {
    pub(crate) name: String,
    pub(crate) ty: PropType,
    /// The declaration as written, without `property`: `float x`,
    /// `list uchar int vertex_indices`.
    pub(crate) decl: String,
}

/// One `element` line and its properties.
#[derive(Debug, Clone)]
pub(crate) struct Element {
    pub(crate) name: String,
    pub(crate) count: u64,
    pub(crate) props: Vec<Property>,
}

impl Element {
    /// The record size if no property is a list.
    pub(crate) fn fixed_size(&self) -> Option<usize> {
        let mut n = 0;
        for p in &self.props {
            match p.ty {
                PropType::Scalar(s) => n += s.size(),
                PropType::List { .. } => return None,
            }
        }
        Some(n)
    }

    /// Index of the first property called `name`.
    pub(crate) fn prop(&self, name: &str) -> Option<usize> {
        self.props.iter().position(|p| p.name == name)
    }
}

/// A parsed PLY header.
#[derive(Debug, Clone)]
pub(crate) struct PlyHeader {
    pub(crate) encoding: Encoding,
    pub(crate) elements: Vec<Element>,
    pub(crate) comments: Vec<String>,
    pub(crate) obj_info: Vec<String>,
    /// Offset of the first body byte.
    pub(crate) body: usize,
}

impl PlyHeader {
    /// The integer value of an `obj_info <key> <value>` line.
    pub(crate) fn obj_info_u64(&self, key: &str) -> Option<u64> {
        self.obj_info.iter().find_map(|l| {
            let mut w = l.split_ascii_whitespace();
            if w.next()? == key {
                w.next()?.parse().ok()
            } else {
                None
            }
        })
    }
}

/// Parses the header at the start of `data` (the whole file or a prefix
/// that contains the header). `path` is for error messages.
pub(crate) fn parse(data: &[u8], path: &Path) -> Result<PlyHeader, Error> {
    let mut lines = Lines::new(data, 0);
    let mut n: u64 = 0;
    let err = |kind: ErrorKind, msg: String, line: u64, at: usize| {
        Error::new(kind, path, msg).at_element("header").at_line(line).at_byte(at as u64)
    };
    match lines.next_line() {
        Some((_, b"ply")) => n += 1,
        _ => {
            return Err(err(ErrorKind::Format, "not a PLY file: the first line is not 'ply'".into(), 1, 0));
        }
    }
    let mut encoding = None;
    let mut elements: Vec<Element> = Vec::new();
    let mut comments = Vec::new();
    let mut obj_info = Vec::new();
    loop {
        let Some((at, line)) = lines.next_line() else {
            return Err(err(
                ErrorKind::Format,
                "the header has no 'end_header' line (truncated file, or not a PLY file)".into(),
                n + 1,
                data.len(),
            ));
        };
        n += 1;
        let text = match std::str::from_utf8(line) {
            Ok(t) if line.is_ascii() => t,
            _ => {
                return Err(err(
                    ErrorKind::Format,
                    format!("header line is not ASCII text: {}", show_token(line)),
                    n,
                    at,
                ))
            }
        };
        let mut w = words(line);
        let Some(keyword) = w.next() else { continue };
        match keyword {
            b"end_header" => {
                let Some(encoding) = encoding else {
                    return Err(err(ErrorKind::Format, "the header has no 'format' line".into(), n, at));
                };
                return Ok(PlyHeader { encoding, elements, comments, obj_info, body: lines.pos.min(data.len()) });
            }
            b"comment" => comments.push(rest_after(text, "comment")),
            b"obj_info" => obj_info.push(rest_after(text, "obj_info")),
            b"format" => {
                let enc = match w.next() {
                    Some(b"ascii") => Encoding::Ascii,
                    Some(b"binary_little_endian") => Encoding::BinaryLe,
                    Some(b"binary_big_endian") => Encoding::BinaryBe,
                    other => {
                        return Err(err(
                            ErrorKind::Unsupported,
                            format!("unknown PLY encoding {}", show_token(other.unwrap_or(b""))),
                            n,
                            at,
                        ))
                    }
                };
                encoding = Some(enc);
            }
            b"element" => {
                let (Some(name), Some(count), None) = (w.next(), w.next(), w.next()) else {
                    return Err(err(ErrorKind::Format, format!("expected 'element <name> <count>', found {}", show_token(line)), n, at));
                };
                let count = std::str::from_utf8(count).ok().and_then(|c| c.parse::<u64>().ok()).ok_or_else(|| {
                    err(ErrorKind::Format, format!("element count {} is not a non-negative integer", show_token(count)), n, at)
                })?;
                elements.push(Element { name: String::from_utf8_lossy(name).into_owned(), count, props: Vec::new() });
            }
            b"property" => {
                let toks: Vec<&[u8]> = w.collect();
                let scalar = |t: &[u8]| -> Result<Scalar, Error> {
                    let s = std::str::from_utf8(t).unwrap_or("");
                    Scalar::parse(s).ok_or_else(|| {
                        let kind = if matches!(s, "int64" | "uint64" | "long" | "ulong" | "float16" | "half") {
                            ErrorKind::Unsupported
                        } else {
                            ErrorKind::Format
                        };
                        err(kind, format!("unknown or unsupported property type {}", show_token(t)), n, at)
                    })
                };
                let (ty, name) = match toks.as_slice() {
                    [b"list", c, i, name] => {
                        let count = scalar(c)?;
                        if count.is_float() {
                            return Err(err(ErrorKind::Format, "a list count type must be an integer type".into(), n, at));
                        }
                        (PropType::List { count, item: scalar(i)? }, name)
                    }
                    [t, name] if *t != b"list" => (PropType::Scalar(scalar(t)?), name),
                    _ => {
                        return Err(err(
                            ErrorKind::Format,
                            format!("expected 'property <type> <name>' or 'property list <type> <type> <name>', found {}", show_token(line)),
                            n,
                            at,
                        ))
                    }
                };
                let Some(el) = elements.last_mut() else {
                    return Err(err(ErrorKind::Format, "a 'property' line before any 'element' line".into(), n, at));
                };
                let decl = toks.iter().map(|t| String::from_utf8_lossy(t)).collect::<Vec<_>>().join(" ");
                el.props.push(Property { name: String::from_utf8_lossy(name).into_owned(), ty, decl });
            }
            other => {
                return Err(err(ErrorKind::Format, format!("unknown header keyword {}", show_token(other)), n, at));
            }
        }
    }
}

/// The text of a line after its keyword and one separator, without
/// trailing whitespace (the PLY writer pads its comment with spaces).
fn rest_after(line: &str, keyword: &str) -> String {
    let t = line.trim_start();
    let t = &t[keyword.len()..];
    t.strip_prefix([' ', '\t']).unwrap_or(t).trim_end().to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_elements_in_order() {
        let h = b"ply\r\nformat binary_big_endian 1.0\r\ncomment hi there\r\nobj_info num_cols 3\r\n\
element face 2\r\nproperty list uint8 int32 vertex_indices\r\nelement vertex 4\r\nproperty float64 x\r\n\
end_header\r\nBODY";
        let p = parse(h, Path::new("t.ply")).unwrap();
        assert_eq!(p.encoding, Encoding::BinaryBe);
        assert_eq!(p.elements.len(), 2);
        assert_eq!(p.elements[0].name, "face");
        assert_eq!(p.elements[0].props[0].decl, "list uint8 int32 vertex_indices");
        assert_eq!(p.elements[0].props[0].ty, PropType::List { count: Scalar::U8, item: Scalar::I32 });
        assert_eq!(p.elements[1].fixed_size(), Some(8));
        assert_eq!(p.comments, vec!["hi there".to_string()]);
        assert_eq!(p.obj_info_u64("num_cols"), Some(3));
        assert_eq!(&h[p.body..], b"BODY");
    }

    #[test]
    fn header_errors_name_line() {
        let e = parse(b"ply\nformat ascii 1.0\nproperty float x\nend_header\n", Path::new("a.ply")).unwrap_err();
        assert_eq!(
            e.to_string(),
            "a.ply: a 'property' line before any 'element' line (element 'header', line 3, byte offset 21)"
        );
        let e = parse(b"ply\nformat ascii 1.0\nelement v 1\nproperty int64 x\nend_header\n", Path::new("a.ply")).unwrap_err();
        assert_eq!(e.kind(), ErrorKind::Unsupported);
        let e = parse(b"ply\nformat ascii 1.0\nelement v 1\n", Path::new("a.ply")).unwrap_err();
        assert_eq!(e.kind(), ErrorKind::Format);
        assert!(e.to_string().contains("no 'end_header'"));
        let e = parse(b"PLY\n", Path::new("a.ply")).unwrap_err();
        assert!(e.to_string().contains("not a PLY file"));
    }
}

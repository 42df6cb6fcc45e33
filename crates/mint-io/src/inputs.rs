//! Several files as one input: what a command's input arguments name.
//! An argument is a mesh file, a directory (every mesh file directly in
//! it, by extension, in name order) or a list file `@tiles.txt` (one path
//! a line, relative to the list's folder; blank lines and `#` comments
//! skipped). The files together are one surface; see docs/FORMATS.md.
//!
//! The order the files are given in does not matter to a resampling (the
//! engine sorts them, and its output does not depend on the order of
//! triangles); a file named twice would double its triangles and is
//! refused.

use crate::error::{Error, ErrorKind};
use crate::format::Format;
use std::path::{Path, PathBuf};

/// Lists longer than this are refused (a list naming itself through other
/// lists is caught by depth; this bounds a hostile one).
pub const MAX_INPUTS: usize = 1 << 20;

/// The files the arguments name, in the order given (a directory's files
/// in name order, a list's in its order). Errors name the argument, and for
/// a list the line.
pub fn expand_inputs(args: &[PathBuf]) -> Result<Vec<PathBuf>, Error> {
    let mut out: Vec<PathBuf> = Vec::new();
    for a in args {
        expand_one(a, &mut out, 0)?;
    }
    if out.is_empty() {
        return Err(Error::new(ErrorKind::Format, Path::new("(inputs)"), "no input files"));
    }
    // The same file twice (by identity, not by spelling) would count its
    // triangles twice.
    let mut ids: Vec<(u64, u64, usize)> = Vec::with_capacity(out.len());
    for (i, p) in out.iter().enumerate() {
        if let Some(id) = file_id(p) {
            ids.push((id.0, id.1, i));
        }
    }
    ids.sort_unstable();
    for w in ids.windows(2) {
        if (w[0].0, w[0].1) == (w[1].0, w[1].1) {
            let (a, b) = (&out[w[0].2.min(w[1].2)], &out[w[0].2.max(w[1].2)]);
            return Err(Error::new(
                ErrorKind::Format,
                b,
                format!("is named twice among the inputs (also as {}): its triangles would count twice", a.display()),
            ));
        }
    }
    Ok(out)
}

#[cfg(unix)]
fn file_id(p: &Path) -> Option<(u64, u64)> {
    use std::os::unix::fs::MetadataExt;
    std::fs::metadata(p).ok().map(|m| (m.dev(), m.ino()))
}

#[cfg(not(unix))]
fn file_id(p: &Path) -> Option<(u64, u64)> {
    let c = std::fs::canonicalize(p).ok()?;
    let mut h: u64 = 0xcbf29ce484222325;
    for b in c.to_string_lossy().bytes() {
        h = (h ^ b as u64).wrapping_mul(0x100000001b3);
    }
    Some((0, h))
}

fn expand_one(a: &Path, out: &mut Vec<PathBuf>, depth: usize) -> Result<(), Error> {
    let s = a.to_string_lossy();
    if let Some(list) = s.strip_prefix('@') {
        return read_list(Path::new(list), out, depth);
    }
    if a.is_dir() {
        let rd = std::fs::read_dir(a).map_err(|e| Error::io(a, "cannot list the directory", e))?;
        let mut files = Vec::new();
        for e in rd {
            let e = e.map_err(|e| Error::io(a, "cannot list the directory", e))?;
            let p = e.path();
            // A tileset (.json) or its tiles (.b3dm) are named, not
            // gathered: a directory of tiles would read them twice.
            if p.is_file() && Format::from_extension(&p).is_some_and(|f| f != Format::Tiles) {
                files.push(p);
            }
        }
        if files.is_empty() {
            return Err(Error::new(
                ErrorKind::Format,
                a,
                "the directory holds no mesh file (none with the extension .ply, .obj, .stl, .off, .mesh, .raw, .wrl, .3ds, .gltf or .glb)",
            ));
        }
        files.sort();
        push(out, files, a)?;
        return Ok(());
    }
    push(out, vec![a.to_path_buf()], a)
}

fn push(out: &mut Vec<PathBuf>, files: Vec<PathBuf>, arg: &Path) -> Result<(), Error> {
    if out.len() + files.len() > MAX_INPUTS {
        return Err(Error::new(ErrorKind::Format, arg, format!("more than {MAX_INPUTS} input files")));
    }
    out.extend(files);
    Ok(())
}

fn read_list(list: &Path, out: &mut Vec<PathBuf>, depth: usize) -> Result<(), Error> {
    if depth >= 8 {
        return Err(Error::new(ErrorKind::Format, list, "lists nest more than 8 deep (a list naming itself?)"));
    }
    let bytes = std::fs::read(list).map_err(|e| Error::io(list, "cannot read the input list", e))?;
    let text = std::str::from_utf8(&bytes).map_err(|_| Error::new(ErrorKind::Format, list, "the input list is not UTF-8 text"))?;
    let base = list.parent().unwrap_or(Path::new(""));
    let mut any = false;
    for (n, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let (at, rest) = match line.strip_prefix('@') {
            Some(r) => ("@", r),
            None => ("", line),
        };
        let p = Path::new(rest);
        let p = if p.is_absolute() { p.to_path_buf() } else { base.join(p) };
        if !p.exists() {
            return Err(Error::new(ErrorKind::Io, list, format!("line {}: {}: no such file or directory", n + 1, p.display())));
        }
        let arg = PathBuf::from(format!("{at}{}", p.display()));
        expand_one(&arg, out, depth + 1).map_err(|e| Error::new(e.kind(), list, format!("line {}: {e}", n + 1)))?;
        any = true;
    }
    if !any {
        return Err(Error::new(ErrorKind::Format, list, "the input list names no file"));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn directories_lists_and_files_expand_in_order_and_twice_is_refused() {
        let d = tempfile::tempdir().unwrap();
        let t = d.path().join("tiles");
        std::fs::create_dir(&t).unwrap();
        for n in ["b.obj", "a.ply", "c.txt", "d.GLB"] {
            std::fs::write(t.join(n), b"x").unwrap();
        }
        std::fs::create_dir(t.join("sub.ply")).unwrap();
        let one = d.path().join("one.stl");
        std::fs::write(&one, b"x").unwrap();
        let got = expand_inputs(&[one.clone(), t.clone()]).unwrap();
        assert_eq!(got, vec![one.clone(), t.join("a.ply"), t.join("b.obj"), t.join("d.GLB")]);
        let list = d.path().join("l.txt");
        std::fs::write(&list, "# tiles\n\ntiles/b.obj\r\n  one.stl  \n").unwrap();
        let got = expand_inputs(&[PathBuf::from(format!("@{}", list.display()))]).unwrap();
        assert_eq!(got, vec![d.path().join("tiles/b.obj"), d.path().join("one.stl")]);
        let e = expand_inputs(&[one.clone(), t.join("../one.stl")]).unwrap_err().to_string();
        assert!(e.contains("named twice") && !e.contains('\n'), "{e}");
        std::fs::write(&list, "tiles/b.obj\nmissing.ply\n").unwrap();
        let e = expand_inputs(&[PathBuf::from(format!("@{}", list.display()))]).unwrap_err().to_string();
        assert!(e.contains("l.txt: line 2: ") && e.contains("missing.ply: no such file"), "{e}");
        std::fs::write(&list, format!("@{}\n", list.display())).unwrap();
        let e = expand_inputs(&[PathBuf::from(format!("@{}", list.display()))]).unwrap_err().to_string();
        assert!(e.contains("nest more than 8"), "{e}");
        let empty = d.path().join("empty");
        std::fs::create_dir(&empty).unwrap();
        let e = expand_inputs(&[empty]).unwrap_err().to_string();
        assert!(e.contains("holds no mesh file"), "{e}");
    }
}

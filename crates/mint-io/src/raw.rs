//! The raw triangle format (Dangl 1998, A.2.4): one triangle per line, nine
//! coordinates `x1 y1 z1 x2 y2 z2 x3 y3 z3`. Like STL it is a soup: the
//! reader reports 3 vertices per line and triangle `k` is
//! `(3k, 3k + 1, 3k + 2)`; [`convert`](crate::convert) welds equal positions
//! when writing an indexed format.
//!
//! Read as a superset: blank lines are skipped and `#` starts a comment.
//! Any line with other than nine numbers is a format error naming the line.
//! [`open`] parses every line into a spill file of positions; the writer
//! spills vertex positions, because a line needs the positions of its
//! indices.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use crate::error::{show_token, Error};
use crate::mapped::{Mapped, SpillFile};
use crate::positions::not_finite;
use crate::positions::{Emit, Positions, Reject};
use crate::backend::{ElementInfo, FaceStream, MeshInfo, Opened, ReadStats};
use crate::text::{line_of, parse_f64, words, Lines};
use crate::backend::{write_coord, FormatWriter, OutFile, WriteOptions};
use crate::Format;

/// Parses every line; returns the triangle count.
fn parse(path: &Path, data: &[u8], mut spill: Option<&mut SpillFile>) -> Result<u64, Error> {
    let mut lines = Lines::new(data, 0);
    let mut tris = 0u64;
    while let Some((at, line)) = lines.next_line() {
        let line = match line.iter().position(|&b| b == b'#') {
            Some(n) => &line[..n],
            None => line,
        };
        let mut v = [0.0f64; 9];
        let mut n = 0;
        for tok in words(line) {
            let bad = |msg: String| Error::format(path, msg).at_element("triangle").at_record(tris).at_line(line_of(data, at)).at_byte(at as u64);
            if n == 9 {
                return Err(bad("a raw line holds exactly 9 coordinates, found more".into()));
            }
            v[n] = parse_f64(tok).ok_or_else(|| bad(format!("expected a number, found {}", show_token(tok))))?;
            n += 1;
        }
        match n {
            0 => continue,
            9 => {}
            _ => {
                return Err(Error::format(path, format!("a raw line holds exactly 9 coordinates, found {n}"))
                    .at_element("triangle")
                    .at_record(tris)
                    .at_line(line_of(data, at))
                    .at_byte(at as u64))
            }
        }
        if let Some(s) = spill.as_deref_mut() {
            for k in 0..3 {
                s.write_point([v[3 * k], v[3 * k + 1], v[3 * k + 2]])?;
            }
        }
        tris += 1;
    }
    Ok(tris)
}

fn make_info(tris: u64) -> MeshInfo {
    MeshInfo {
        format: Format::Raw,
        encoding: "ascii".into(),
        vertex_count: 3 * tris,
        face_count: Some(tris),
        elements: vec![ElementInfo { name: "triangle".into(), count: tris, properties: vec!["float[9] x1 y1 z1 x2 y2 z2 x3 y3 z3".into()] }],
        comments: Vec::new(),
        obj_info: Vec::new(),
    }
}

/// Counts the triangles (a full scan).
pub(crate) fn info(path: &Path, data: &[u8]) -> Result<MeshInfo, Error> {
    Ok(make_info(parse(path, data, None)?))
}

pub(crate) fn open(path: &Path, map: Arc<Mapped>, spill_dir: &Path) -> Result<Opened, Error> {
    let data = map.bytes();
    map.advise_sequential(0, data.len());
    let mut spill = SpillFile::new(spill_dir, path)?;
    let tris = parse(path, data, Some(&mut spill))?;
    if 3 * tris > u32::MAX as u64 {
        return Err(Error::unsupported(path, format!("{tris} triangles need more than {} vertices (32-bit indices)", u32::MAX)));
    }
    let positions = Positions::spilled(Arc::new(spill.into_mapped()?), 3 * tris as u32);
    let body = RawBody { path: path.to_path_buf(), tris, next: 0, total: data.len() as u64 };
    Ok(Opened { info: make_info(tris), positions, body: Box::new(body), range_grid: None, spilled_vertices: 3 * tris, colours: None, face_colours: None, texturing: None })
}

struct RawBody {
    path: PathBuf,
    tris: u64,
    next: u64,
    total: u64,
}

impl FaceStream for RawBody {
    fn fill(&mut self, out: &mut Emit, _stats: &mut ReadStats) -> Result<bool, Error> {
        while self.next < self.tris && out.room() {
            let k = self.next as u32 * 3;
            if let Err(Reject::NotFinite(v)) = out.tri_checked([k, k + 1, k + 2]) {
                return Err(not_finite(&self.path, v, out.pos).at_element("triangle").at_record(self.next));
            }
            self.next += 1;
        }
        Ok(self.next < self.tris)
    }

    fn bytes_done(&self) -> u64 {
        crate::backend::share_done(self.total, self.next, self.tris)
    }
}

/// Writes one line of nine coordinates per face.
pub(crate) struct RawWriter {
    out: OutFile,
    double: bool,
    spill: Option<SpillFile>,
    positions: Option<Positions>,
}

impl RawWriter {
    pub(crate) fn create(path: &Path, opts: &WriteOptions) -> Result<RawWriter, Error> {
        let spill_dir = opts.spill_dir.clone().unwrap_or_else(std::env::temp_dir);
        let spill = SpillFile::new(&spill_dir, path)?;
        Ok(RawWriter { out: OutFile::create(path)?, double: opts.double, spill: Some(spill), positions: None })
    }
}

impl FormatWriter for RawWriter {
    fn vertex(&mut self, p: [f64; 3]) -> Result<(), Error> {
        self.spill.as_mut().expect("vertices before faces").write_point(p)
    }

    fn face(&mut self, f: [u32; 3]) -> Result<(), Error> {
        if self.positions.is_none() {
            let spill = self.spill.take().expect("spill before positions");
            let n = (spill.len() / 24) as u32;
            self.positions = Some(Positions::spilled(Arc::new(spill.into_mapped()?), n));
        }
        let pos = self.positions.as_ref().unwrap();
        let t = self.out.text();
        for (k, &i) in f.iter().enumerate() {
            let p = pos.get(i);
            for (d, &c) in p.iter().enumerate() {
                if k + d > 0 {
                    t.push(b' ');
                }
                write_coord(t, c, self.double);
            }
        }
        t.push(b'\n');
        self.out.maybe_flush()
    }

    fn finish(self: Box<Self>, _vertices: u64, _faces: u64) -> Result<u64, Error> {
        self.out.commit()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_of_nine_numbers() {
        let p = Path::new("a.raw");
        assert_eq!(parse(p, b"0 0 0 1 0 0 0 1 0\n\n# c\n1 1 1 2 1 1 1 2 1 # t\n", None).unwrap(), 2);
        let e = parse(p, b"0 0 0 1 0 0 0 1 0\n0 0 0 1 0 0 0 1\n", None).err().unwrap();
        assert_eq!(e.to_string(), "a.raw: a raw line holds exactly 9 coordinates, found 8 (element 'triangle', record 1, line 2, byte offset 18)");
        let e = parse(p, b"0 0 0 1 0 0 0 1 x\n", None).err().unwrap();
        assert!(e.to_string().contains("expected a number, found 'x'"));
    }
}

//! Helpers shared by the suite: a deterministic generator, the shared data
//! folder, exact 2D overlap tests.
#![allow(dead_code)]
use mint_contour::geom2d::{orient, P2};
use std::path::PathBuf;

pub use mint_testkit::Rng;

/// The shared real-data folder, or `None` after printing why the test skips.
pub fn data_dir() -> Option<PathBuf> {
    let p = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared/data"));
    if p.is_dir() {
        Some(p)
    } else {
        if std::env::var_os("MINT_REQUIRE_DATA").is_some_and(|v| v != "0") {
            panic!("MINT_REQUIRE_DATA is set (CI): real-data folder {} not found", p.display());
        }
        eprintln!("SKIPPED: real-data folder {} not found", p.display());
        None
    }
}

/// True if the interiors of two counter-clockwise triangles intersect
/// (exact: they are disjoint iff an edge of one has the other on its
/// closed outer side).
pub fn interiors_overlap(t: [P2; 3], u: [P2; 3]) -> bool {
    for (a, b) in [(t, u), (u, t)] {
        for i in 0..3 {
            let (p, q) = (a[i], a[(i + 1) % 3]);
            if b.iter().all(|&v| orient(p, q, v) <= 0.0) {
                return false;
            }
        }
    }
    true
}

use mint_contour::profile::{read_all, ProfileOptions, Section, StackFrame};
use mint_core::TriMesh;
use robust::{orient3d, Coord3D};
use std::fmt::Write as _;

/// A profile text from sections of contours (each a list of points).
pub fn profile_text(sections: &[Vec<Vec<[f64; 3]>>]) -> String {
    let mut t = String::from("pro\n# made by a test\n");
    for s in sections {
        for (i, c) in s.iter().enumerate() {
            t.push_str(if i == 0 { "section\n" } else { "contour\n" });
            for p in c {
                let _ = writeln!(t, "{} {} {}", p[0], p[1], p[2]);
            }
        }
    }
    t
}

/// Parses a profile text (panics on error).
pub fn parse(text: &str) -> (StackFrame, Vec<Section>) {
    read_all(text.as_bytes(), std::path::Path::new("test.pro"), ProfileOptions::default()).unwrap_or_else(|e| panic!("{e}"))
}

/// `n` points of the ellipse with semi-axes `a`, `b`, centre `c`, turned
/// by `theta`, at height `z`, counter-clockwise.
pub fn ellipse(c: [f64; 2], a: f64, b: f64, theta: f64, z: f64, n: usize) -> Vec<[f64; 3]> {
    (0..n)
        .map(|k| {
            let t = std::f64::consts::TAU * k as f64 / n as f64;
            let (x, y) = (a * t.cos(), b * t.sin());
            let (s, co) = theta.sin_cos();
            [c[0] + co * x - s * y, c[1] + s * x + co * y, z]
        })
        .collect()
}

/// A closed reference solid from a function giving the ring at height z:
/// `rings` rings of `n` points between `z0` and `z1`, capped by fans.
pub fn reference_tube(ring: &dyn Fn(f64, usize) -> Vec<[f64; 3]>, z0: f64, z1: f64, rings: usize, n: usize) -> TriMesh {
    let mut m = TriMesh::default();
    for k in 0..rings {
        let z = z0 + (z1 - z0) * k as f64 / (rings - 1) as f64;
        m.positions.extend(ring(z, n));
    }
    let id = |k: usize, i: usize| (k * n + i % n) as u32;
    for k in 0..rings - 1 {
        for i in 0..n {
            m.faces.push([id(k, i), id(k, i + 1), id(k + 1, i + 1)]);
            m.faces.push([id(k, i), id(k + 1, i + 1), id(k + 1, i)]);
        }
    }
    for (k, top) in [(0, false), (rings - 1, true)] {
        let c = m.positions[k * n..(k + 1) * n].iter().fold([0.0; 3], |s, p| [s[0] + p[0], s[1] + p[1], s[2] + p[2]]).map(|x| x / n as f64);
        let ci = m.positions.len() as u32;
        m.positions.push(c);
        for i in 0..n {
            m.faces.push(if top { [ci, id(k, i), id(k, i + 1)] } else { [ci, id(k, i + 1), id(k, i)] });
        }
    }
    m
}

/// Largest sampled distance between two meshes, both ways, over the
/// reference's bounding-box diagonal; and the mean of the two directions.
pub fn max_and_mean_distance(m: &TriMesh, reference: &TriMesh, samples: usize) -> (f64, f64, f64) {
    let (ab, ba) = mint_mesh::symmetric_distance((&m.positions, &m.faces), (&reference.positions, &reference.faces), samples, 7);
    let diag = ab.bbox_diagonal;
    (ab.max.max(ba.max) / diag, ab.mean / diag, ba.mean / diag)
}

fn c3(p: [f64; 3]) -> Coord3D<f64> {
    Coord3D { x: p[0], y: p[1], z: p[2] }
}

fn o3(a: [f64; 3], b: [f64; 3], c: [f64; 3], d: [f64; 3]) -> f64 {
    orient3d(c3(a), c3(b), c3(c), c3(d))
}

/// Closed segment `pq` meets closed triangle `abc` (exact).
fn seg_tri(p: [f64; 3], q: [f64; 3], a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> bool {
    let (op, oq) = (o3(a, b, c, p), o3(a, b, c, q));
    if (op > 0.0 && oq > 0.0) || (op < 0.0 && oq < 0.0) {
        return false;
    }
    if op == 0.0 && oq == 0.0 {
        // Coplanar: drop the dominant axis of the normal and test in 2D.
        let n = {
            let (u, v) = ([b[0] - a[0], b[1] - a[1], b[2] - a[2]], [c[0] - a[0], c[1] - a[1], c[2] - a[2]]);
            [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]
        };
        let k = (0..3).max_by(|&x, &y| n[x].abs().total_cmp(&n[y].abs())).unwrap();
        let f = |x: [f64; 3]| -> P2 { [x[(k + 1) % 3], x[(k + 2) % 3]] };
        let (a2, b2, c2, p2, q2) = (f(a), f(b), f(c), f(p), f(q));
        let inside = |x: P2| {
            let s = [orient(a2, b2, x), orient(b2, c2, x), orient(c2, a2, x)];
            s.iter().all(|&v| v >= 0.0) || s.iter().all(|&v| v <= 0.0)
        };
        use mint_contour::geom2d::segments_touch;
        return inside(p2) || inside(q2) || segments_touch(p2, q2, a2, b2) || segments_touch(p2, q2, b2, c2) || segments_touch(p2, q2, c2, a2);
    }
    let s = [o3(p, q, a, b), o3(p, q, b, c), o3(p, q, c, a)];
    s.iter().all(|&v| v >= 0.0) || s.iter().all(|&v| v <= 0.0)
}

/// Do two faces of a mesh intersect anywhere but in their shared vertices
/// and edge? (Exact.)
fn faces_clash(m: &TriMesh, f: [u32; 3], g: [u32; 3]) -> bool {
    let p = |i: u32| m.positions[i as usize];
    let shared: Vec<u32> = f.iter().copied().filter(|v| g.contains(v)).collect();
    match shared.len() {
        3 => true,
        2 => {
            let (s0, s1) = (shared[0], shared[1]);
            let r1 = *f.iter().find(|&&v| v != s0 && v != s1).unwrap();
            let r2 = *g.iter().find(|&&v| v != s0 && v != s1).unwrap();
            if o3(p(s0), p(s1), p(r1), p(r2)) != 0.0 {
                return false;
            }
            // Coplanar: the far vertices on the same side of the edge overlap.
            seg_tri(p(r1), p(r1), p(s0), p(s1), p(r2)) || seg_tri(p(r2), p(r2), p(s0), p(s1), p(r1))
        }
        1 => {
            let v = shared[0];
            let fo: Vec<u32> = f.iter().copied().filter(|&x| x != v).collect();
            let go: Vec<u32> = g.iter().copied().filter(|&x| x != v).collect();
            seg_tri(p(fo[0]), p(fo[1]), p(g[0]), p(g[1]), p(g[2])) || seg_tri(p(go[0]), p(go[1]), p(f[0]), p(f[1]), p(f[2]))
        }
        _ => {
            (0..3).any(|e| seg_tri(p(f[e]), p(f[(e + 1) % 3]), p(g[0]), p(g[1]), p(g[2])))
                || (0..3).any(|e| seg_tri(p(g[e]), p(g[(e + 1) % 3]), p(f[0]), p(f[1]), p(f[2])))
        }
    }
}

/// Pairs of faces that cross or overlap (sort-and-sweep on x, exact tests).
pub fn clashing_faces(m: &TriMesh) -> Vec<(usize, usize)> {
    let boxes: Vec<([f64; 3], [f64; 3])> = m
        .faces
        .iter()
        .map(|f| {
            let mut lo = [f64::INFINITY; 3];
            let mut hi = [f64::NEG_INFINITY; 3];
            for &v in f {
                for d in 0..3 {
                    lo[d] = lo[d].min(m.positions[v as usize][d]);
                    hi[d] = hi[d].max(m.positions[v as usize][d]);
                }
            }
            (lo, hi)
        })
        .collect();
    let mut order: Vec<usize> = (0..m.faces.len()).collect();
    order.sort_by(|&a, &b| boxes[a].0[0].total_cmp(&boxes[b].0[0]));
    let mut active: Vec<usize> = Vec::new();
    let mut out = Vec::new();
    for &i in &order {
        active.retain(|&j| boxes[j].1[0] >= boxes[i].0[0]);
        for &j in &active {
            let (a, b) = (&boxes[i], &boxes[j]);
            if (1..3).any(|d| a.1[d] < b.0[d] || b.1[d] < a.0[d]) {
                continue;
            }
            if faces_clash(m, m.faces[i], m.faces[j]) {
                out.push((i.min(j), i.max(j)));
            }
        }
        active.push(i);
    }
    out
}

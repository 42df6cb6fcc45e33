//! Tiny hand-made meshes for the tests: platonic solids, a UV sphere, a
//! torus grid, and the outer surface of a set of unit cubes (polycube),
//! all outward oriented. (mint-gen has streaming generators, but it depends
//! on this crate, so the tests keep their own small builders.)

#![allow(dead_code)]

use std::collections::BTreeMap;
use std::f64::consts::PI;

pub type Mesh = (Vec<[f64; 3]>, Vec<[u32; 3]>);

pub fn tetrahedron() -> Mesh {
    (
        vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ],
        vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
    )
}

/// Unit cube, 12 triangles; faces 0 and 1 are the two halves of x = 1.
pub fn cube() -> Mesh {
    polycube(&[[0, 0, 0]], |_, _| true)
}

pub fn octahedron() -> Mesh {
    let p = vec![
        [1.0, 0.0, 0.0],
        [-1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, -1.0, 0.0],
        [0.0, 0.0, 1.0],
        [0.0, 0.0, -1.0],
    ];
    let f = vec![
        [0, 2, 4],
        [2, 1, 4],
        [1, 3, 4],
        [3, 0, 4],
        [2, 0, 5],
        [1, 2, 5],
        [3, 1, 5],
        [0, 3, 5],
    ];
    (p, f)
}

/// UV sphere: `rings` latitude bands, `segs` longitudes, poles at ±z.
pub fn uv_sphere(r: f64, rings: u32, segs: u32) -> Mesh {
    let mut p = vec![[0.0, 0.0, r]];
    for i in 1..rings {
        let t = PI * f64::from(i) / f64::from(rings);
        for j in 0..segs {
            let ph = 2.0 * PI * f64::from(j) / f64::from(segs);
            p.push([r * t.sin() * ph.cos(), r * t.sin() * ph.sin(), r * t.cos()]);
        }
    }
    p.push([0.0, 0.0, -r]);
    let south = p.len() as u32 - 1;
    let v = |i: u32, j: u32| 1 + (i - 1) * segs + j % segs;
    let mut f = Vec::new();
    for j in 0..segs {
        f.push([0, v(1, j), v(1, j + 1)]);
    }
    for i in 1..rings - 1 {
        for j in 0..segs {
            let (a, b, c, d) = (v(i, j), v(i, j + 1), v(i + 1, j), v(i + 1, j + 1));
            f.push([a, c, d]);
            f.push([a, d, b]);
        }
    }
    for j in 0..segs {
        f.push([south, v(rings - 1, j + 1), v(rings - 1, j)]);
    }
    (p, f)
}

/// Torus around the z axis: `nu` steps around the axis, `nv` around the tube.
pub fn torus(big: f64, small: f64, nu: u32, nv: u32) -> Mesh {
    let mut p = Vec::new();
    for i in 0..nu {
        let u = 2.0 * PI * f64::from(i) / f64::from(nu);
        for j in 0..nv {
            let w = 2.0 * PI * f64::from(j) / f64::from(nv);
            let rr = big + small * w.cos();
            p.push([rr * u.cos(), rr * u.sin(), small * w.sin()]);
        }
    }
    let v = |i: u32, j: u32| (i % nu) * nv + j % nv;
    let mut f = Vec::new();
    for i in 0..nu {
        for j in 0..nv {
            let (a, b, c, d) = (v(i, j), v(i + 1, j), v(i + 1, j + 1), v(i, j + 1));
            f.push([a, b, c]);
            f.push([a, c, d]);
        }
    }
    (p, f)
}

/// Outer surface of a set of unit cubes at integer cells: each square between
/// a filled and an empty cell, split into two triangles, outward oriented.
/// `keep(axis, cell)` can drop squares by axis to make open surfaces.
pub fn polycube(cells: &[[i32; 3]], keep: impl Fn(usize, [i32; 3]) -> bool) -> Mesh {
    let filled: std::collections::BTreeSet<[i32; 3]> = cells.iter().copied().collect();
    let mut index: BTreeMap<[i32; 3], u32> = BTreeMap::new();
    let mut p = Vec::new();
    let mut vid = |q: [i32; 3], p: &mut Vec<[f64; 3]>| {
        *index.entry(q).or_insert_with(|| {
            p.push(q.map(f64::from));
            p.len() as u32 - 1
        })
    };
    let mut f = Vec::new();
    for &c in cells {
        for axis in 0..3 {
            for side in [1, -1] {
                let mut n = c;
                n[axis] += side;
                if filled.contains(&n) || !keep(axis, c) {
                    continue;
                }
                let (u, w) = ((axis + 1) % 3, (axis + 2) % 3);
                let mut corner = |du: i32, dw: i32| {
                    let mut q = c;
                    if side > 0 {
                        q[axis] += 1;
                    }
                    q[u] += du;
                    q[w] += dw;
                    vid(q, &mut p)
                };
                let mut quad = [corner(0, 0), corner(1, 0), corner(1, 1), corner(0, 1)];
                if side < 0 {
                    quad.reverse();
                }
                f.push([quad[0], quad[1], quad[2]]);
                f.push([quad[0], quad[2], quad[3]]);
            }
        }
    }
    (p, f)
}

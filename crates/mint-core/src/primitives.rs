//! Analytic solids on the grid: each primitive answers "where does this line
//! cross you?" exactly, so it can join meshes in CSG expressions without
//! being tessellated first (Rocchini et al. 2001, §3.3: booleans on
//! intersection lists).
//!
//! A [`Primitive`] is a [`Shape`] in its own canonical frame plus an affine
//! [`Transform`] to the world. A line `o + t·d` is mapped into the shape's
//! frame by the inverse transform (affine maps keep the parameter `t`), where
//! the shape is an intersection of simple regions — a quadric `q(t) ≤ 0` and
//! slabs `a ≤ t ≤ b` — so the inside of the line is a union of intervals,
//! found in closed form. The torus is quartic: its intervals are found by
//! sampling the implicit function every 1/8 of a grid cell along the line and
//! bisecting each sign change to machine precision; two crossings closer
//! than 1/8 cell (a line grazing the tube) are missed, which is detail below
//! the cell size that the resampling would remove anyway.
//!
//! [`Primitive::plane_intercepts`] turns the intervals into the same
//! [`Intercept`] records the mesh discretization produces: entering at an
//! interval's start, leaving at its end, kept [`MARGIN`] inside their cell.
//! Intervals reaching past the grid (a half-space) are clipped to the
//! padding cells, so every line starts and ends outside.
//!
//! Primitives often have faces exactly on grid planes (a box sized to the
//! grid). As for meshes, the grid is taken as translated by a small vector
//! [`PERTURBATION`] (largest along local axis a, smallest along s): lines are
//! evaluated at their perturbed positions and an intercept's cell is decided
//! against the perturbed nodes, so a line lying in a face and the lines
//! crossing that face agree on which side the face's nodes are.

use crate::grid::Grid;
use crate::intercept::{Intercept, FAMILY_A, FAMILY_B, FAMILY_S};
use crate::MARGIN;

/// The numeric stand-in for the symbolic perturbation of the mesh path, in
/// grid units along local axes (a, b, s): far above f64 rounding of grid
/// coordinates, far below anything visible.
pub const PERTURBATION: [f64; 3] = [1e-7, 1e-8, 1e-9];

/// A shape in its canonical frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Shape {
    /// Ball of this radius around the origin.
    Sphere { radius: f64 },
    /// Axis-aligned box `[-half, half]`.
    Box { half: [f64; 3] },
    /// Cylinder around z, `|z| <= half_height`.
    Cylinder { radius: f64, half_height: f64 },
    /// Cone around z: base of `radius` at z = 0, apex at z = `height`.
    Cone { radius: f64, height: f64 },
    /// Torus around z: tube of radius `minor` around a circle of radius `major`.
    Torus { major: f64, minor: f64 },
    /// The half-space `z <= 0`.
    HalfSpace,
}

impl Shape {
    /// The same shape with every length multiplied by `k`.
    fn scaled(self, k: f64) -> Shape {
        match self {
            Shape::Sphere { radius } => Shape::Sphere { radius: radius * k },
            Shape::Box { half } => Shape::Box { half: half.map(|h| h * k) },
            Shape::Cylinder { radius, half_height } => Shape::Cylinder { radius: radius * k, half_height: half_height * k },
            Shape::Cone { radius, height } => Shape::Cone { radius: radius * k, height: height * k },
            Shape::Torus { major, minor } => Shape::Torus { major: major * k, minor: minor * k },
            Shape::HalfSpace => Shape::HalfSpace,
        }
    }
}

/// The power of two `k` that brings the largest component of `d` into
/// `[0.5, 2)`-ish (1 for a zero or non-finite `d`).
fn pow2_scale(d: [f64; 3]) -> f64 {
    let m = d.iter().fold(0.0f64, |a, x| a.max(x.abs()));
    if !(m > 0.0 && m.is_finite()) {
        return 1.0;
    }
    let e = m.log2().round().clamp(-1000.0, 1000.0) as i32;
    // 2^-e, built in two steps so that neither factor is subnormal or infinite.
    2f64.powi(-e / 2) * 2f64.powi(-e + e / 2)
}

/// An affine map `p ↦ m·p + t` (row-major 3×3 `m`), with its inverse.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Transform {
    pub m: [[f64; 3]; 3],
    pub t: [f64; 3],
    inv: [[f64; 3]; 3],
}

impl Default for Transform {
    fn default() -> Self {
        let id = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        Transform { m: id, t: [0.0; 3], inv: id }
    }
}

fn mul(a: &[[f64; 3]; 3], b: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let mut c = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            c[i][j] = (0..3).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    c
}

fn apply(m: &[[f64; 3]; 3], v: [f64; 3]) -> [f64; 3] {
    [0, 1, 2].map(|i| m[i][0] * v[0] + m[i][1] * v[1] + m[i][2] * v[2])
}

fn inverse(m: &[[f64; 3]; 3]) -> Option<[[f64; 3]; 3]> {
    let det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    if !(det.is_finite() && det.abs() > 1e-300) {
        return None;
    }
    let c = |i: usize, j: usize| {
        let (r0, r1) = ((i + 1) % 3, (i + 2) % 3);
        let (c0, c1) = ((j + 1) % 3, (j + 2) % 3);
        m[r0][c0] * m[r1][c1] - m[r0][c1] * m[r1][c0]
    };
    let mut inv = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            inv[j][i] = c(i, j) / det;
        }
    }
    Some(inv)
}

impl Transform {
    /// Translation.
    pub fn translate(t: [f64; 3]) -> Transform {
        Transform { t, ..Default::default() }
    }
    /// A general linear part `m` and translation; `None` if `m` is singular.
    pub fn new(m: [[f64; 3]; 3], t: [f64; 3]) -> Option<Transform> {
        Some(Transform { m, t, inv: inverse(&m)? })
    }
    /// Rotation by `deg` degrees about world axis `axis` (right-handed).
    pub fn rotation(axis: usize, deg: f64) -> Transform {
        let (s, c) = deg.to_radians().sin_cos();
        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
        let mut m = [[0.0; 3]; 3];
        m[axis][axis] = 1.0;
        m[u][u] = c;
        m[u][v] = -s;
        m[v][u] = s;
        m[v][v] = c;
        Transform::new(m, [0.0; 3]).unwrap()
    }
    /// Scaling per axis; `None` if a factor is zero.
    pub fn scale(s: [f64; 3]) -> Option<Transform> {
        Transform::new([[s[0], 0.0, 0.0], [0.0, s[1], 0.0], [0.0, 0.0, s[2]]], [0.0; 3])
    }
    /// `self` after `first` (apply `first`, then `self`).
    pub fn after(&self, first: &Transform) -> Transform {
        Transform { m: mul(&self.m, &first.m), t: apply(&self.m, first.t).map3(self.t), inv: mul(&first.inv, &self.inv) }
    }
    pub fn apply_point(&self, p: [f64; 3]) -> [f64; 3] {
        let q = apply(&self.m, p);
        [q[0] + self.t[0], q[1] + self.t[1], q[2] + self.t[2]]
    }
    fn inverse_point(&self, p: [f64; 3]) -> [f64; 3] {
        apply(&self.inv, [p[0] - self.t[0], p[1] - self.t[1], p[2] - self.t[2]])
    }
    fn inverse_vector(&self, d: [f64; 3]) -> [f64; 3] {
        apply(&self.inv, d)
    }
}

trait Add3 {
    fn map3(self, t: [f64; 3]) -> [f64; 3];
}
impl Add3 for [f64; 3] {
    fn map3(self, t: [f64; 3]) -> [f64; 3] {
        [self[0] + t[0], self[1] + t[1], self[2] + t[2]]
    }
}

/// A shape placed in the world.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Primitive {
    pub shape: Shape,
    pub transform: Transform,
}

/// Intervals `[t0, t1]` of a line inside a solid, sorted and disjoint.
pub type Intervals = Vec<(f64, f64)>;

fn intersect(a: &Intervals, b: &Intervals) -> Intervals {
    let mut out = Vec::new();
    let (mut i, mut j) = (0, 0);
    while i < a.len() && j < b.len() {
        let lo = a[i].0.max(b[j].0);
        let hi = a[i].1.min(b[j].1);
        if lo < hi {
            out.push((lo, hi));
        }
        if a[i].1 < b[j].1 {
            i += 1;
        } else {
            j += 1;
        }
    }
    out
}

/// Where `a t² + b t + c <= 0`.
fn quadric(a: f64, b: f64, c: f64) -> Intervals {
    const INF: f64 = f64::INFINITY;
    if a == 0.0 {
        if b == 0.0 {
            return if c <= 0.0 { vec![(-INF, INF)] } else { vec![] };
        }
        let t = -c / b;
        return if b > 0.0 { vec![(-INF, t)] } else { vec![(t, INF)] };
    }
    let disc = b * b - 4.0 * a * c;
    if disc < 0.0 {
        return if a > 0.0 { vec![] } else { vec![(-INF, INF)] };
    }
    let sq = disc.sqrt();
    // Numerically stable roots.
    let q = -0.5 * (b + b.signum() * sq);
    let (mut r0, mut r1) = (q / a, if q != 0.0 { c / q } else { 0.0 });
    if r0 > r1 {
        std::mem::swap(&mut r0, &mut r1);
    }
    if a > 0.0 {
        vec![(r0, r1)]
    } else {
        vec![(-INF, r0), (r1, INF)]
    }
}

/// Where `lo <= o + t d <= hi` for one coordinate.
fn slab(o: f64, d: f64, lo: f64, hi: f64) -> Intervals {
    if d == 0.0 {
        return if o >= lo && o <= hi { vec![(f64::NEG_INFINITY, f64::INFINITY)] } else { vec![] };
    }
    let (a, b) = ((lo - o) / d, (hi - o) / d);
    vec![(a.min(b), a.max(b))]
}

impl Primitive {
    pub fn new(shape: Shape, transform: Transform) -> Primitive {
        Primitive { shape, transform }
    }

    /// The parameter intervals where the world line `o + t d` is inside.
    /// `step` is the sampling step in `t` for the torus.
    pub fn intervals(&self, o: [f64; 3], d: [f64; 3], t_range: (f64, f64), step: f64) -> Intervals {
        let o = self.transform.inverse_point(o);
        let d = self.transform.inverse_vector(d);
        // Work in units of the line's step (a grid cell in the shape's
        // frame), scaled by a power of two: exact, so results are unchanged
        // wherever nothing under- or overflows, and the quadrics' products
        // (cell² · radius², ...) stay in range for shapes of any size. A
        // sphere of radius 1e-100 used to underflow its discriminant to
        // nonsense, and its lines to disagree on which nodes are inside.
        let k = pow2_scale(d);
        let (o, d) = (o.map(|x| x * k), d.map(|x| x * k));
        let shape = self.shape.scaled(k);
        let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        match shape {
            Shape::Sphere { radius } => quadric(dot(d, d), 2.0 * dot(o, d), dot(o, o) - radius * radius),
            Shape::Box { half } => {
                let mut iv = slab(o[0], d[0], -half[0], half[0]);
                iv = intersect(&iv, &slab(o[1], d[1], -half[1], half[1]));
                intersect(&iv, &slab(o[2], d[2], -half[2], half[2]))
            }
            Shape::Cylinder { radius, half_height } => {
                let q = quadric(d[0] * d[0] + d[1] * d[1], 2.0 * (o[0] * d[0] + o[1] * d[1]), o[0] * o[0] + o[1] * o[1] - radius * radius);
                intersect(&q, &slab(o[2], d[2], -half_height, half_height))
            }
            Shape::Cone { radius, height } => {
                // x² + y² - k²(h - z)² <= 0 with k = r / h, and 0 <= z <= h.
                let k2 = (radius / height).powi(2);
                let (zo, zd) = (height - o[2], -d[2]);
                let a = d[0] * d[0] + d[1] * d[1] - k2 * zd * zd;
                let b = 2.0 * (o[0] * d[0] + o[1] * d[1] - k2 * zo * zd);
                let c = o[0] * o[0] + o[1] * o[1] - k2 * zo * zo;
                intersect(&quadric(a, b, c), &slab(o[2], d[2], 0.0, height))
            }
            Shape::HalfSpace => slab(o[2], d[2], f64::NEG_INFINITY, 0.0),
            Shape::Torus { major, minor } => {
                let f = |t: f64| {
                    let p = [o[0] + t * d[0], o[1] + t * d[1], o[2] + t * d[2]];
                    let s = dot(p, p) + major * major - minor * minor;
                    s * s - 4.0 * major * major * (p[0] * p[0] + p[1] * p[1])
                };
                // Only where the line meets the torus's bounding box.
                let r = major + minor;
                let mut iv = slab(o[0], d[0], -r, r);
                iv = intersect(&iv, &slab(o[1], d[1], -r, r));
                iv = intersect(&iv, &slab(o[2], d[2], -minor, minor));
                iv = intersect(&iv, &vec![t_range]);
                let Some(&(t0, t1)) = iv.first() else { return vec![] };
                let n = (((t1 - t0) / step).ceil() as usize).max(1);
                let mut out = Vec::new();
                let mut start: Option<f64> = None;
                let mut prev_t = t0;
                let mut prev = f(t0);
                if prev <= 0.0 {
                    start = Some(t0);
                }
                for s in 1..=n {
                    let t = t0 + (t1 - t0) * s as f64 / n as f64;
                    let v = f(t);
                    if (prev <= 0.0) != (v <= 0.0) {
                        let (mut a, mut b) = (prev_t, t);
                        for _ in 0..100 {
                            let mid = 0.5 * (a + b);
                            if mid <= a || mid >= b {
                                break;
                            }
                            if (f(mid) <= 0.0) == (prev <= 0.0) {
                                a = mid;
                            } else {
                                b = mid;
                            }
                        }
                        let root = 0.5 * (a + b);
                        if v <= 0.0 {
                            start = Some(root);
                        } else if let Some(s0) = start.take() {
                            out.push((s0, root));
                        }
                    }
                    prev_t = t;
                    prev = v;
                }
                if let Some(s0) = start {
                    out.push((s0, t1));
                }
                out
            }
        }
    }

    /// World-space bounding box (infinite for the half-space).
    pub fn bounds(&self) -> ([f64; 3], [f64; 3]) {
        let local: ([f64; 3], [f64; 3]) = match self.shape {
            Shape::Sphere { radius: r } => ([-r; 3], [r; 3]),
            Shape::Box { half } => ([-half[0], -half[1], -half[2]], half),
            Shape::Cylinder { radius: r, half_height: h } => ([-r, -r, -h], [r, r, h]),
            Shape::Cone { radius: r, height: h } => ([-r, -r, 0.0], [r, r, h]),
            Shape::Torus { major, minor } => ([-(major + minor), -(major + minor), -minor], [major + minor, major + minor, minor]),
            Shape::HalfSpace => return ([f64::NEG_INFINITY; 3], [f64::INFINITY; 3]),
        };
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for c in 0..8 {
            let p = [0, 1, 2].map(|a| if c >> a & 1 == 0 { local.0[a] } else { local.1[a] });
            let w = self.transform.apply_point(p);
            for a in 0..3 {
                lo[a] = lo[a].min(w[a]);
                hi[a] = hi[a].max(w[a]);
            }
        }
        (lo, hi)
    }

    /// The primitive's raw intercepts in plane `k` of `grid`: families A and
    /// B of the lines lying in plane `k`, and, when `with_s`, family S of
    /// layer `k` (the same records a mesh would give through the store).
    pub fn plane_intercepts(&self, grid: &Grid, k: u32, with_s: bool) -> Vec<Intercept> {
        let [na, nb, ns] = grid.local_dims();
        let mut out = Vec::new();
        // Lines at their perturbed positions (see PERTURBATION).
        let origin = |q: [f64; 3]| grid.to_world([q[0] + PERTURBATION[0], q[1] + PERTURBATION[1], q[2] + PERTURBATION[2]]);
        let push_line = |family: u32, index: u32, o: [f64; 3], dir: [f64; 3], n: u32, window: (f64, f64), plane: u32, out: &mut Vec<Intercept>| {
            let clip = (0.25, n as f64 - 0.25);
            // Nodes along this line sit at integers + the perturbation of its axis.
            let delta = PERTURBATION[family as usize];
            for (a, b) in self.intervals(o, dir, (clip.0 - delta, clip.1 - delta), 0.125) {
                // The origin carries the perturbation along the line too: shift back.
                let (a, b) = (a + delta, b + delta);
                for (t, entering) in [(a.max(clip.0), true), (b.min(clip.1), false)] {
                    if a.max(clip.0) >= b.min(clip.1) {
                        break;
                    }
                    let cell = (t - delta).floor();
                    if cell < window.0 || cell >= window.1 {
                        continue;
                    }
                    let v = t.clamp(cell + MARGIN, cell + 1.0 - MARGIN);
                    out.push(Intercept::new(plane, family, index, v, entering));
                }
            }
        };
        let (lo, hi) = self.bounds();
        let (llo, lhi) = (grid.to_local(lo), grid.to_local(hi));
        let range = |a: usize, n: u32| -> (u32, u32) {
            // One more on each side: a face on a grid plane puts its
            // crossings in the layer below (perturbed nodes sit above).
            let l = if llo[a].is_finite() { (llo[a].floor() - 1.0).max(0.0) as u32 } else { 0 };
            let h = if lhi[a].is_finite() { ((lhi[a].ceil() + 1.0).max(0.0) as u32).min(n) } else { n };
            (l.min(n), h)
        };
        let to_dir = |axis: usize| {
            let mut e = [0.0; 3];
            e[axis] = 1.0;
            let a = grid.to_world([0.0; 3]);
            let b = grid.to_world(e);
            [b[0] - a[0], b[1] - a[1], b[2] - a[2]]
        };
        let (ra, rb, rs) = (range(0, na), range(1, nb), range(2, ns));
        if k < rs.0 || k > rs.1 {
            return out;
        }
        // Family A: lines along a at (b = j, s = k).
        for j in rb.0..=rb.1 {
            push_line(FAMILY_A, j, origin([0.0, j as f64, k as f64]), to_dir(0), na, (0.0, f64::INFINITY), k, &mut out);
        }
        // Family B: lines along b at (a = i, s = k).
        for i in ra.0..=ra.1 {
            push_line(FAMILY_B, i, origin([i as f64, 0.0, k as f64]), to_dir(1), nb, (0.0, f64::INFINITY), k, &mut out);
        }
        if with_s {
            for i in ra.0..=ra.1 {
                for j in rb.0..=rb.1 {
                    push_line(FAMILY_S, i * (nb + 1) + j, origin([i as f64, j as f64, 0.0]), to_dir(2), ns, (k as f64, k as f64 + 1.0), k, &mut out);
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A sphere of radius 1e-100 cut by lines a tenth of its radius apart
    /// (its own grid) gives the unit sphere's intervals: the quadric's
    /// products (1e-400) used to underflow.
    #[test]
    fn tiny_and_huge_shapes_cut_lines_like_unit_ones() {
        for scale in [1e-100, 1e-200, 1e-300, 1e100, 1e200] {
            let unit = Primitive::new(Shape::Sphere { radius: 1.0 }, Transform::default());
            let tiny = Primitive::new(Shape::Sphere { radius: scale }, Transform::default());
            let o = [-5.0, 0.3, 0.2];
            let want = unit.intervals(o, [0.1, 0.0, 0.0], (-100.0, 100.0), 0.125);
            let got = tiny.intervals(o.map(|x| x * scale), [0.1 * scale, 0.0, 0.0], (-100.0, 100.0), 0.125);
            assert_eq!(want.len(), 1);
            assert_eq!(got.len(), 1, "{scale}: {got:?}");
            assert!((got[0].0 - want[0].0).abs() < 1e-9 && (got[0].1 - want[0].1).abs() < 1e-9, "{scale}: {got:?} vs {want:?}");
        }
        // Normal sizes: exactly the same numbers as without the scaling.
        let s = Primitive::new(Shape::Sphere { radius: 0.7 }, Transform::default());
        let iv = s.intervals([-3.0, 0.1, 0.2], [0.3, 0.0, 0.0], (-100.0, 100.0), 0.125);
        let (o, d) = ([-3.0f64, 0.1, 0.2], [0.3f64, 0.0, 0.0]);
        let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        let (a, b, c) = (dot(d, d), 2.0 * dot(o, d), dot(o, o) - 0.7 * 0.7);
        assert_eq!(iv, quadric(a, b, c));
    }

    #[test]
    fn a_sphere_line_enters_and_leaves_where_it_should() {
        let s = Primitive::new(Shape::Sphere { radius: 1.0 }, Transform::translate([1.0, 0.0, 0.0]));
        let iv = s.intervals([-5.0, 0.0, 0.0], [1.0, 0.0, 0.0], (-10.0, 10.0), 0.1);
        assert_eq!(iv.len(), 1);
        assert!((iv[0].0 - 5.0).abs() < 1e-12 && (iv[0].1 - 7.0).abs() < 1e-12);
    }

    #[test]
    fn rotated_boxes_cylinders_cones_and_tori_cut_lines_correctly() {
        let b = Primitive::new(Shape::Box { half: [1.0, 2.0, 3.0] }, Transform::rotation(2, 90.0));
        // Rotated 90° about z: the x extent is now 2.
        let iv = b.intervals([-10.0, 0.0, 0.0], [1.0, 0.0, 0.0], (-20.0, 20.0), 0.1);
        assert!((iv[0].0 - 8.0).abs() < 1e-12 && (iv[0].1 - 12.0).abs() < 1e-12, "{iv:?}");
        let c = Primitive::new(Shape::Cylinder { radius: 1.0, half_height: 1.0 }, Transform::default());
        assert_eq!(c.intervals([0.0, 0.0, -5.0], [0.0, 0.0, 1.0], (-9.0, 9.0), 0.1), vec![(4.0, 6.0)]);
        let cone = Primitive::new(Shape::Cone { radius: 1.0, height: 2.0 }, Transform::default());
        let iv = cone.intervals([-5.0, 0.0, 1.0], [1.0, 0.0, 0.0], (-9.0, 9.0), 0.1);
        assert!((iv[0].0 - 4.5).abs() < 1e-12 && (iv[0].1 - 5.5).abs() < 1e-12, "{iv:?}");
        let t = Primitive::new(Shape::Torus { major: 2.0, minor: 0.5 }, Transform::default());
        let iv = t.intervals([-5.0, 0.0, 0.0], [1.0, 0.0, 0.0], (-9.0, 9.0), 0.01);
        assert_eq!(iv.len(), 2);
        assert!((iv[0].0 - 2.5).abs() < 1e-9 && (iv[1].1 - 7.5).abs() < 1e-9, "{iv:?}");
    }
}

#[cfg(test)]
mod plane_tests {
    use super::*;
    use crate::grid::{Grid, GridSize};
    use crate::cells::intercept_local_position;

    #[test]
    fn plane_intercepts_lie_on_the_surface() {
        let b = Primitive::new(Shape::Box { half: [0.8; 3] }, Transform::default());
        let (lo, hi) = b.bounds();
        let g = Grid::around(lo, hi, GridSize::Cells(100_000), [0.0; 3], None).unwrap();
        let [_, nb, ns] = g.local_dims();
        for k in 0..=ns {
            for r in b.plane_intercepts(&g, k, k < ns) {
                let p = g.to_world(intercept_local_position(&r, nb));
                let m = p.iter().fold(0.0f64, |m, x| m.max(x.abs()));
                assert!((m - 0.8).abs() < 0.001, "family {} plane {k}: {p:?}", r.family());
            }
        }
    }
}

//! [`Rigid`], a rigid motion `p ↦ R·p + t`, with conversions to and from
//! unit quaternions (Shepperd's method for matrix → quaternion) and 4×4
//! matrices; the 3×3 matrix helpers it rests on ([`transpose`],
//! [`mat_vec`], [`mat_mul`]); and [`pose_error`]. Vector arithmetic is
//! glam's `DVec3` throughout mint-range; stored positions stay `[f64; 3]`
//! (they are shared with mint-core, mint-mesh and mint-io), and
//! [`Rigid::apply`] and [`Rigid::rotate`] take either. Every pose in
//! mint-range is a [`Rigid`] that maps a scan's own coordinates to world
//! coordinates; the set-file readers translate their conventions into it
//! (see [`crate::scanset`]).

use glam::DVec3;

/// A rigid motion `p ↦ r·p + t` (`r` row-major, a rotation).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rigid {
    pub r: [[f64; 3]; 3],
    pub t: [f64; 3],
}

impl Default for Rigid {
    fn default() -> Self {
        Rigid::IDENTITY
    }
}

impl Rigid {
    pub const IDENTITY: Rigid = Rigid { r: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]], t: [0.0; 3] };

    /// Applies the motion to a point: a stored `[f64; 3]` position or a
    /// `DVec3`, and gives the same type back.
    #[inline]
    pub fn apply<P: Into<DVec3> + From<DVec3>>(&self, p: P) -> P {
        P::from(mat_vec(self.r, p.into()) + DVec3::from(self.t))
    }
    /// Applies the rotation only (to a direction); `[f64; 3]` or `DVec3`.
    #[inline]
    pub fn rotate<P: Into<DVec3> + From<DVec3>>(&self, v: P) -> P {
        P::from(mat_vec(self.r, v.into()))
    }
    /// The inverse motion.
    pub fn inverse(&self) -> Rigid {
        let rt = transpose(self.r);
        let t = mat_vec(rt, DVec3::from(self.t));
        Rigid { r: rt, t: (-t).to_array() }
    }
    /// `self ∘ other`: first `other`, then `self`.
    pub fn after(&self, other: &Rigid) -> Rigid {
        Rigid { r: mat_mul(self.r, other.r), t: self.apply(other.t) }
    }
    /// The rotation of the unit quaternion `q = [x, y, z, w]` (normalized
    /// here), with translation `t`.
    pub fn from_quat(q: [f64; 4], t: [f64; 3]) -> Rigid {
        let n = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]).sqrt();
        let [x, y, z, w] = q.map(|c| c / n);
        let r = [
            [1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y - z * w), 2.0 * (x * z + y * w)],
            [2.0 * (x * y + z * w), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z - x * w)],
            [2.0 * (x * z - y * w), 2.0 * (y * z + x * w), 1.0 - 2.0 * (x * x + y * y)],
        ];
        Rigid { r, t }
    }
    /// The unit quaternion `[x, y, z, w]` of the rotation, with `w ≥ 0`
    /// (Shepperd's method: pivot on the largest diagonal term).
    pub fn quat(&self) -> [f64; 4] {
        let m = self.r;
        let tr = m[0][0] + m[1][1] + m[2][2];
        let q = if tr > m[0][0].max(m[1][1]).max(m[2][2]) {
            let s = (1.0 + tr).sqrt() * 2.0;
            [(m[2][1] - m[1][2]) / s, (m[0][2] - m[2][0]) / s, (m[1][0] - m[0][1]) / s, 0.25 * s]
        } else if m[0][0] >= m[1][1] && m[0][0] >= m[2][2] {
            let s = (1.0 + m[0][0] - m[1][1] - m[2][2]).sqrt() * 2.0;
            [0.25 * s, (m[0][1] + m[1][0]) / s, (m[0][2] + m[2][0]) / s, (m[2][1] - m[1][2]) / s]
        } else if m[1][1] >= m[2][2] {
            let s = (1.0 + m[1][1] - m[0][0] - m[2][2]).sqrt() * 2.0;
            [(m[0][1] + m[1][0]) / s, 0.25 * s, (m[1][2] + m[2][1]) / s, (m[0][2] - m[2][0]) / s]
        } else {
            let s = (1.0 + m[2][2] - m[0][0] - m[1][1]).sqrt() * 2.0;
            [(m[0][2] + m[2][0]) / s, (m[1][2] + m[2][1]) / s, 0.25 * s, (m[1][0] - m[0][1]) / s]
        };
        let n = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]).sqrt();
        let sgn = if q[3] < 0.0 { -1.0 } else { 1.0 };
        q.map(|c| sgn * c / n)
    }
    /// Rotation by `angle` radians about the unit `axis`, no translation.
    pub fn from_axis_angle(axis: DVec3, angle: f64) -> Rigid {
        let a = axis.normalize_or_zero();
        let (s, c) = (0.5 * angle).sin_cos();
        Rigid::from_quat([a[0] * s, a[1] * s, a[2] * s, c], [0.0; 3])
    }
    /// Rotation by the vector `w` (axis `w/|w|`, angle `|w|`).
    pub fn from_rotation_vector(w: DVec3, t: [f64; 3]) -> Rigid {
        let a = w.length();
        if a == 0.0 {
            return Rigid { t, ..Rigid::IDENTITY };
        }
        let mut m = Rigid::from_axis_angle(w, a);
        m.t = t;
        m
    }
    /// The angle of the rotation, in radians, in `[0, π]`.
    pub fn angle(&self) -> f64 {
        let tr = self.r[0][0] + self.r[1][1] + self.r[2][2];
        ((tr - 1.0) * 0.5).clamp(-1.0, 1.0).acos()
    }
    /// The 4×4 homogeneous matrix, row-major.
    pub fn to_matrix4(&self) -> [[f64; 4]; 4] {
        let r = self.r;
        [
            [r[0][0], r[0][1], r[0][2], self.t[0]],
            [r[1][0], r[1][1], r[1][2], self.t[1]],
            [r[2][0], r[2][1], r[2][2], self.t[2]],
            [0.0, 0.0, 0.0, 1.0],
        ]
    }
    /// How far `self` is from being a rotation: max |RᵀR − I|.
    pub fn orthogonality_error(&self) -> f64 {
        let p = mat_mul(transpose(self.r), self.r);
        let mut e: f64 = 0.0;
        for i in 0..3 {
            for j in 0..3 {
                e = e.max((p[i][j] - if i == j { 1.0 } else { 0.0 }).abs());
            }
        }
        e
    }
    /// Re-orthonormalizes the rotation (through its quaternion).
    pub fn orthonormalized(&self) -> Rigid {
        Rigid::from_quat(self.quat(), self.t)
    }
}

pub fn transpose(m: [[f64; 3]; 3]) -> [[f64; 3]; 3] {
    [[m[0][0], m[1][0], m[2][0]], [m[0][1], m[1][1], m[2][1]], [m[0][2], m[1][2], m[2][2]]]
}
/// `m·v` for a row-major `m`: each row dotted with `v`.
pub fn mat_vec(m: [[f64; 3]; 3], v: DVec3) -> DVec3 {
    let [r0, r1, r2] = m.map(DVec3::from);
    DVec3::new(r0.dot(v), r1.dot(v), r2.dot(v))
}
pub fn mat_mul(a: [[f64; 3]; 3], b: [[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let mut m = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            m[i][j] = a[i][0] * b[0][j] + a[i][1] * b[1][j] + a[i][2] * b[2][j];
        }
    }
    m
}

/// Differences between two poses of one scan, as they matter for
/// registration: the angle of `a⁻¹∘b` in degrees, and the largest
/// displacement of the given points (e.g. the scan's bounding-box corners)
/// between the two poses.
pub fn pose_error(a: &Rigid, b: &Rigid, points: &[[f64; 3]]) -> (f64, f64) {
    let d = a.inverse().after(b);
    let shift = points.iter().map(|&p| a.apply(DVec3::from(p)).distance(b.apply(DVec3::from(p)))).fold(0.0, f64::max);
    (d.angle().to_degrees(), shift)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quaternions_round_trip_and_compose() {
        for q in [[0.0, 0.0, 0.0, 1.0], [0.00548449, -0.294635, -0.0038555, 0.955586], [0.908911, -0.0569874, 0.154429, 0.383126], [1.0, 0.0, 0.0, 0.0]] {
            let m = Rigid::from_quat(q, [1.0, 2.0, 3.0]);
            assert!(m.orthogonality_error() < 1e-12);
            let back = m.quat();
            let s = if q[3] < 0.0 { -1.0 } else { 1.0 };
            for k in 0..4 {
                assert!((back[k] - s * q[k]).abs() < 1e-6, "{back:?} vs {q:?}");
            }
            let i = m.inverse().after(&m);
            assert!(i.angle() < 1e-7 && DVec3::from(i.t).length() < 1e-12);
        }
        // 90° about z maps x to y.
        let r = Rigid::from_axis_angle(DVec3::Z, std::f64::consts::FRAC_PI_2);
        let p = r.apply([1.0, 0.0, 0.0]);
        assert!((p[0]).abs() < 1e-15 && (p[1] - 1.0).abs() < 1e-15);
        assert!((r.angle() - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
    }
}

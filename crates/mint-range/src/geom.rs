//! Small 3D helpers: vector arithmetic on `[f64; 3]`, and [`Rigid`], a
//! rigid motion `p ↦ R·p + t` with conversions to and from unit
//! quaternions (Shepperd's method for matrix → quaternion) and 4×4
//! matrices. Every pose in mint-range is a [`Rigid`] that maps a scan's own
//! coordinates to world coordinates; the set-file readers translate their
//! conventions into it (see [`crate::scanset`]).

/// A point or vector.
pub type V3 = [f64; 3];

#[inline]
pub fn add(a: V3, b: V3) -> V3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
#[inline]
pub fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
#[inline]
pub fn scale(a: V3, s: f64) -> V3 {
    [a[0] * s, a[1] * s, a[2] * s]
}
#[inline]
pub fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
#[inline]
pub fn cross(a: V3, b: V3) -> V3 {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}
#[inline]
pub fn norm(a: V3) -> f64 {
    dot(a, a).sqrt()
}
#[inline]
pub fn dist(a: V3, b: V3) -> f64 {
    norm(sub(a, b))
}
/// `a / |a|`, or `[0, 0, 0]` for the zero vector.
#[inline]
pub fn normalize(a: V3) -> V3 {
    let n = norm(a);
    if n > 0.0 {
        scale(a, 1.0 / n)
    } else {
        [0.0; 3]
    }
}
/// Twice the area vector of triangle `abc` (right-hand normal, length = 2·area).
#[inline]
pub fn tri_normal(a: V3, b: V3, c: V3) -> V3 {
    cross(sub(b, a), sub(c, a))
}

/// A rigid motion `p ↦ r·p + t` (`r` row-major, a rotation).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rigid {
    pub r: [[f64; 3]; 3],
    pub t: V3,
}

impl Default for Rigid {
    fn default() -> Self {
        Rigid::IDENTITY
    }
}

impl Rigid {
    pub const IDENTITY: Rigid = Rigid { r: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]], t: [0.0; 3] };

    /// Applies the motion to a point.
    #[inline]
    pub fn apply(&self, p: V3) -> V3 {
        add(self.rotate(p), self.t)
    }
    /// Applies the rotation only (to a direction).
    #[inline]
    pub fn rotate(&self, v: V3) -> V3 {
        [dot(self.r[0], v), dot(self.r[1], v), dot(self.r[2], v)]
    }
    /// The inverse motion.
    pub fn inverse(&self) -> Rigid {
        let rt = transpose(self.r);
        let t = mat_vec(rt, self.t);
        Rigid { r: rt, t: scale(t, -1.0) }
    }
    /// `self ∘ other`: first `other`, then `self`.
    pub fn after(&self, other: &Rigid) -> Rigid {
        Rigid { r: mat_mul(self.r, other.r), t: self.apply(other.t) }
    }
    /// The rotation of the unit quaternion `q = [x, y, z, w]` (normalized
    /// here), with translation `t`.
    pub fn from_quat(q: [f64; 4], t: V3) -> Rigid {
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
    pub fn from_axis_angle(axis: V3, angle: f64) -> Rigid {
        let a = normalize(axis);
        let (s, c) = (0.5 * angle).sin_cos();
        Rigid::from_quat([a[0] * s, a[1] * s, a[2] * s, c], [0.0; 3])
    }
    /// Rotation by the vector `w` (axis `w/|w|`, angle `|w|`).
    pub fn from_rotation_vector(w: V3, t: V3) -> Rigid {
        let a = norm(w);
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
pub fn mat_vec(m: [[f64; 3]; 3], v: V3) -> V3 {
    [dot(m[0], v), dot(m[1], v), dot(m[2], v)]
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
pub fn pose_error(a: &Rigid, b: &Rigid, points: &[V3]) -> (f64, f64) {
    let d = a.inverse().after(b);
    let shift = points.iter().map(|&p| dist(a.apply(p), b.apply(p))).fold(0.0, f64::max);
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
            assert!(i.angle() < 1e-7 && norm(i.t) < 1e-12);
        }
        // 90° about z maps x to y.
        let r = Rigid::from_axis_angle([0.0, 0.0, 1.0], std::f64::consts::FRAC_PI_2);
        let p = r.apply([1.0, 0.0, 0.0]);
        assert!((p[0]).abs() < 1e-15 && (p[1] - 1.0).abs() < 1e-15);
        assert!((r.angle() - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
    }
}

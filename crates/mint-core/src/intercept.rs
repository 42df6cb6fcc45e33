//! Intercepts: the compact record of one kept intersection, and the sorted,
//! filtered lists of them along grid lines (the "intersection lists" of
//! Rocchini et al. 2001, §2.2).
//!
//! An [`Intercept`] is 16 bytes: the slab-axis *plane* it belongs to, a *line*
//! id within that plane (2 family bits + 30 bits of line index) and the
//! position along the line with the sign packed into the f64 sign bit. Lines of
//! families A and B (parallel to local axes a and b) lie in plane `s = k` and
//! belong to plane `k`; lines of family S (parallel to the slab axis) are cut
//! per layer, and an intercept between planes `k` and `k+1` belongs to `k`.
//!
//! Sorting a plane's intercepts by [`Intercept::sort_key`] groups them by
//! family, then line, then position; that order is also the order in which
//! the output vertices are numbered, which is what makes the output identical
//! whatever the slab partition (see `reconstruct`).
//!
//! [`filter_plane`] applies the paper's *removal*: along each line,
//! consecutive intercepts in the same cell with discordant signs are removed
//! in pairs. It never changes a node's state and leaves each cell edge of a
//! clean closed input with at most one intercept.

/// Family id of lines parallel to local axis a (named by `b`).
pub const FAMILY_A: u32 = 0;
/// Family id of lines parallel to local axis b (named by `a`).
pub const FAMILY_B: u32 = 1;
/// Family id of lines parallel to the slab axis (named by `a * (nb + 1) + b`).
pub const FAMILY_S: u32 = 2;

const FAMILY_SHIFT: u32 = 30;
const INDEX_MASK: u32 = (1 << FAMILY_SHIFT) - 1;

/// The `line` field of the records of line (`family`, `index`).
#[inline]
pub const fn line_id(family: u32, index: u32) -> u32 {
    (family << FAMILY_SHIFT) | index
}

/// One kept intersection of the surface with a grid line. 16 bytes, `repr(C)`,
/// written to disk as is (little-endian); see docs/FORMATS.md.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Intercept {
    /// Slab-axis plane (families A, B) or layer (family S).
    pub plane: u32,
    /// `family << 30 | index`.
    pub line: u32,
    /// Position along the line in grid units (always positive); negative
    /// means the line *leaves* the solid there.
    pub signed_value: f64,
}

impl Intercept {
    /// Packs a record.
    #[inline]
    pub fn new(plane: u32, family: u32, index: u32, value: f64, entering: bool) -> Intercept {
        debug_assert!(index <= INDEX_MASK && family <= 2 && value > 0.0);
        Intercept {
            plane,
            line: (family << FAMILY_SHIFT) | index,
            signed_value: if entering { value } else { -value },
        }
    }
    #[inline]
    pub fn family(&self) -> u32 {
        self.line >> FAMILY_SHIFT
    }
    #[inline]
    pub fn index(&self) -> u32 {
        self.line & INDEX_MASK
    }
    #[inline]
    pub fn value(&self) -> f64 {
        self.signed_value.abs()
    }
    #[inline]
    pub fn entering(&self) -> bool {
        self.signed_value > 0.0
    }
    /// The cell along the line holding the intercept (values stay a margin
    /// inside their cell, so the floor is exact).
    #[inline]
    pub fn cell(&self) -> u32 {
        self.value() as u32
    }
    /// Total order used everywhere: line, then position, then sign (leaving
    /// after entering at an equal position). Deterministic for any input order.
    #[inline]
    pub fn sort_key(&self) -> (u32, u64) {
        let v = self.value().to_bits(); // positive: top bit clear
        (self.line, (v << 1) | (!self.entering()) as u64)
    }
    /// Serializes to 16 little-endian bytes.
    #[inline]
    pub fn to_le_bytes(&self) -> [u8; 16] {
        let mut b = [0u8; 16];
        b[0..4].copy_from_slice(&self.plane.to_le_bytes());
        b[4..8].copy_from_slice(&self.line.to_le_bytes());
        b[8..16].copy_from_slice(&self.signed_value.to_le_bytes());
        b
    }
    /// Deserializes from 16 little-endian bytes.
    #[inline]
    pub fn from_le_bytes(b: &[u8]) -> Intercept {
        Intercept {
            plane: u32::from_le_bytes(b[0..4].try_into().unwrap()),
            line: u32::from_le_bytes(b[4..8].try_into().unwrap()),
            signed_value: f64::from_le_bytes(b[8..16].try_into().unwrap()),
        }
    }
}

/// What the removal step did to one plane.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct FilterStats {
    pub kept: u64,
    pub removed: u64,
}

impl std::ops::AddAssign for FilterStats {
    fn add_assign(&mut self, o: FilterStats) {
        self.kept += o.kept;
        self.removed += o.removed;
    }
}

/// Sorts one plane's intercepts and applies the removal step in place.
/// All records must share the same `plane`.
pub fn filter_plane(records: &mut Vec<Intercept>) -> FilterStats {
    records.sort_unstable_by_key(|r| r.sort_key());
    let before = records.len();
    // Stack-based pairing per line: `out` is the stack; a record cancels the
    // top when both are on the same line and cell with opposite signs.
    let mut out = 0usize;
    for i in 0..records.len() {
        let r = records[i];
        if out > 0 {
            let top = records[out - 1];
            if top.line == r.line && top.cell() == r.cell() && top.entering() != r.entering() {
                out -= 1;
                continue;
            }
        }
        records[out] = r;
        out += 1;
    }
    records.truncate(out);
    FilterStats { kept: out as u64, removed: (before - out) as u64 }
}

/// Read access to one plane's sorted, filtered intercepts, by line.
#[derive(Debug, Clone)]
pub struct PlaneLines<'a> {
    records: &'a [Intercept],
}

impl<'a> PlaneLines<'a> {
    /// Wraps records already sorted by [`Intercept::sort_key`].
    pub fn new(records: &'a [Intercept]) -> PlaneLines<'a> {
        PlaneLines { records }
    }

    /// All records of the plane, in vertex order.
    pub fn records(&self) -> &'a [Intercept] {
        self.records
    }

    /// The index range (into `records`) of one line.
    #[inline]
    pub fn line(&self, family: u32, index: u32) -> std::ops::Range<usize> {
        let id = line_id(family, index);
        let start = self.records.partition_point(|r| r.line < id);
        let len = self.records[start..].partition_point(|r| r.line == id);
        start..start + len
    }

    /// Index range of the records of `line` that lie in `cell`.
    #[inline]
    pub fn in_cell(&self, line: std::ops::Range<usize>, cell: u32) -> std::ops::Range<usize> {
        let l = &self.records[line.clone()];
        let a = l.partition_point(|r| r.cell() < cell);
        let b = a + l[a..].partition_point(|r| r.cell() == cell);
        line.start + a..line.start + b
    }

    /// Inside/outside state of node `node` on `line` by the orientation rule:
    /// inside when the last intercept before the node enters the solid.
    #[inline]
    pub fn state_before(&self, line: std::ops::Range<usize>, node: u32) -> bool {
        let l = &self.records[line];
        let n = l.partition_point(|r| r.cell() < node);
        n > 0 && l[n - 1].entering()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rec(line: u32, v: f64, enter: bool) -> Intercept {
        Intercept::new(0, FAMILY_A, line, v, enter)
    }

    #[test]
    fn round_trips_through_bytes() {
        let r = Intercept::new(7, FAMILY_S, 12345, 3.25, false);
        assert_eq!(Intercept::from_le_bytes(&r.to_le_bytes()), r);
        assert_eq!(r.family(), FAMILY_S);
        assert_eq!(r.index(), 12345);
        assert_eq!(r.cell(), 3);
        assert!(!r.entering());
        assert_eq!(std::mem::size_of::<Intercept>(), 16);
    }

    #[test]
    fn removal_pairs_discordant_intercepts_in_one_cell() {
        // Line 1: +2.2 -2.5 (same cell, removed), +3.1 kept, -5.5 kept.
        // Line 2: +1.1 +1.2 -1.3 -1.4: nested pairs, all removed.
        // Line 3: +4.9 -5.1: different cells, kept.
        let mut v = vec![
            rec(1, 5.5, false),
            rec(1, 2.5, false),
            rec(2, 1.3, false),
            rec(1, 3.1, true),
            rec(2, 1.2, true),
            rec(3, 5.1, false),
            rec(1, 2.2, true),
            rec(2, 1.4, false),
            rec(2, 1.1, true),
            rec(3, 4.9, true),
        ];
        let s = filter_plane(&mut v);
        assert_eq!(s, FilterStats { kept: 4, removed: 6 });
        let got: Vec<(u32, f64)> = v.iter().map(|r| (r.index(), r.signed_value)).collect();
        assert_eq!(got, vec![(1, 3.1), (1, -5.5), (3, 4.9), (3, -5.1)]);
        let p = PlaneLines::new(&v);
        let l1 = p.line(FAMILY_A, 1);
        assert_eq!(l1, 0..2);
        assert!(!p.state_before(l1.clone(), 3));
        assert!(p.state_before(l1.clone(), 4));
        assert!(p.state_before(l1.clone(), 5));
        assert!(!p.state_before(l1.clone(), 6));
        assert_eq!(p.in_cell(l1.clone(), 5), 1..2);
        assert_eq!(p.in_cell(l1, 4), 1..1);
        assert_eq!(p.line(FAMILY_A, 2), 2..2);
    }

    #[test]
    fn removal_never_changes_node_states_of_alternating_lines() {
        // Random alternating sequences: states at integer nodes are unchanged.
        let mut seed = 0x9e3779b97f4a7c15u64;
        let mut next = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            seed
        };
        for _ in 0..500 {
            let n = 2 * (next() % 6) as usize;
            let mut vals: Vec<f64> = (0..n).map(|_| 1.0 + (next() % 4000) as f64 / 1000.0 + 1e-3).collect();
            vals.sort_by(|a, b| a.partial_cmp(b).unwrap());
            vals.dedup();
            if vals.len() % 2 == 1 {
                vals.pop();
            }
            let raw: Vec<Intercept> = vals.iter().enumerate().map(|(i, &v)| rec(0, v, i % 2 == 0)).collect();
            let mut f = raw.clone();
            filter_plane(&mut f);
            let (pr, pf) = (PlaneLines::new(&raw), PlaneLines::new(&f));
            for node in 0..7 {
                assert_eq!(pr.state_before(0..raw.len(), node), pf.state_before(0..f.len(), node));
            }
            // At most one intercept per cell remains.
            for w in f.windows(2) {
                assert_ne!(w[0].cell(), w[1].cell());
            }
        }
    }
}

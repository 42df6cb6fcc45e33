//! Signs that survive bad orientation: how a line's intercepts become
//! inside/outside states of the grid nodes on it, for dirty real scans.
//!
//! The paper (Rocchini et al. 2001) reads each intercept's sign from its
//! face's orientation ([`SignRule::Orient`]): a node is inside when the last
//! intercept before it enters the solid. That breaks on flipped faces, on
//! overlapping scans of one surface, and on lines through holes. Two more
//! rules, applied per line of families A and B (which lie whole in one
//! slab-axis plane, so every decision below is local to a plane and the
//! output does not depend on the slab partition):
//!
//! - [`SignRule::Union`]: the *winding number* `w` along the line (+1 per
//!   entering, −1 per leaving intercept, orientation kept). A node is inside
//!   when `w > 0`. Overlapping, consistently oriented layers (two scans of
//!   one surface) then merge into one solid instead of cancelling. A line is
//!   *valid* when `w` never goes negative and returns to 0.
//! - [`SignRule::Parity`]: orientation ignored; states alternate at every
//!   intercept (ray-parity point-in-solid). Exact for any closed surface,
//!   whatever its faces' orientation; wrong for overlaps. A line is valid
//!   when its intercept count is even.
//! - [`SignRule::Sheet`]: for open inputs (terrain tiles, single-sided
//!   photogrammetry, a lone triangle), which have no inside. A node is
//!   inside when the intercepts next to it on its six incident edges put it
//!   behind the surface (against its faces' normals) more often than in
//!   front; every other node is outside. The states then hold a layer at
//!   most one cell thick behind the surface; the cells that close that layer
//!   (its back and its rim, all with synthesized vertices) are left open, so
//!   the output is the input's sheet resampled, with the faces' orientation
//!   and a boundary within about a cell of the input's (see
//!   [`crate::robust`]). This rule reads the S intercepts of the layers
//!   above *and below* a plane.
//! - [`SignRule::Auto`] (the default) picks one rule for the whole run
//!   from a census of all A and B lines ([`LineCensus`]): when more than a
//!   third of the lines that cross the input cross it an odd number of times,
//!   the input is open and Sheet is used; else, if almost every line with
//!   intercepts is winding-valid (at most 1% of the even ones are not), the
//!   input is consistently oriented and Union is used; otherwise faces are
//!   flipped and Parity is used. A per-line choice cannot tell a flipped
//!   face from an overlap (both break alternation), nor a hole from an open
//!   edge; a whole mesh can.
//!
//! Within the chosen rule a line that is not valid is handled as follows:
//! under Union, an even line falls back to Parity (a few flipped faces);
//! a line with an odd count passes through a hole and is *inconsistent*: its
//! nodes take their state from the line of the other in-plane family through
//! them when that line is valid, else from the nearest intercept's
//! orientation along the line (inside if the previous intercept enters or
//! the next one leaves), else outside. This confines a hole's damage to the
//! nodes near it instead of flipping the rest of the line.
//!
//! The states of a plane's nodes are kept in a [`NodeStates`] bitmap; they
//! are the single source of truth for reconstruction.

use crate::intercept::{Intercept, FAMILY_B};

crate::choice! {
    /// How intercept signs become node states (`--signs`).
    pub enum SignRule {
        /// Union, Parity or Sheet for the whole run, chosen by a census of lines.
        Auto => "auto",
        /// The paper's rule: the face's orientation gives the sign.
        Orient => "orient",
        /// Winding number > 0 (orientation kept; overlaps merge).
        Union => "union",
        /// Alternation along the line (orientation ignored).
        Parity => "parity",
        /// Open inputs: states only next to the surface, on its back side;
        /// the output is the open sheet resampled, orientation kept.
        Sheet => "sheet",
    }
}

/// Counts of A and B lines by validity, summed over planes; decides Auto.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct LineCensus {
    /// Lines with at least one intercept.
    pub lines: u64,
    /// Of those, lines whose winding never goes negative and ends at 0.
    pub winding_valid: u64,
    /// Lines with an odd number of intercepts (through a hole or an open edge).
    pub odd: u64,
}

impl std::ops::AddAssign for LineCensus {
    fn add_assign(&mut self, o: LineCensus) {
        self.lines += o.lines;
        self.winding_valid += o.winding_valid;
        self.odd += o.odd;
    }
}

impl LineCensus {
    /// Counts the A and B lines of one plane's records, sorted by
    /// [`Intercept::sort_key`].
    pub fn of_plane(records: &[Intercept]) -> LineCensus {
        let mut c = LineCensus::default();
        for line in lines(records) {
            let l = &records[line];
            if l[0].family() > FAMILY_B {
                break;
            }
            c.lines += 1;
            if winding_valid(l) {
                c.winding_valid += 1;
            }
            if l.len() % 2 == 1 {
                c.odd += 1;
            }
        }
        c
    }

    /// True when more than a third of the lines that cross the input cross
    /// it an odd number of times: the input is open (a sheet, a soup, a
    /// single range scan, a room seen from inside), not a closed surface
    /// with holes. Measured: closed scans with holes 0-6% (Stanford bunny,
    /// Laurana bust), a room scan 42%, photogrammetry sheets and single
    /// range scans 89-95%.
    pub fn open(&self) -> bool {
        self.odd * 3 > self.lines
    }

    /// The rule Auto resolves to: Sheet for an open input; else Union when
    /// at most 1% of the lines that are not odd break the winding rule;
    /// else Parity.
    pub fn resolve(&self) -> SignRule {
        if self.open() {
            return SignRule::Sheet;
        }
        self.resolve_closed()
    }

    /// The rule Auto resolves to for an input read as a solid whatever its
    /// census (operands of `bool` and `csg`): Union or Parity.
    pub fn resolve_closed(&self) -> SignRule {
        let even = self.lines - self.odd;
        let even_invalid = even.saturating_sub(self.winding_valid.min(even));
        if even_invalid * 100 <= even {
            SignRule::Union
        } else {
            SignRule::Parity
        }
    }
}

/// Index ranges of consecutive records sharing a line.
pub fn lines(records: &[Intercept]) -> impl Iterator<Item = std::ops::Range<usize>> + '_ {
    let mut start = 0;
    std::iter::from_fn(move || {
        if start >= records.len() {
            return None;
        }
        let id = records[start].line;
        let len = records[start..].iter().take_while(|r| r.line == id).count();
        let r = start..start + len;
        start += len;
        Some(r)
    })
}

/// Winding never negative and back to zero at the end.
pub fn winding_valid(line: &[Intercept]) -> bool {
    let mut w = 0i64;
    for r in line {
        w += if r.entering() { 1 } else { -1 };
        if w < 0 {
            return false;
        }
    }
    w == 0
}

/// Inside/outside of every node of one plane, `(na + 1) × (nb + 1)` bits.
#[derive(Debug, Clone)]
pub struct NodeStates {
    width: usize,
    len: usize,
    pub(crate) bits: Vec<u64>,
}

impl NodeStates {
    pub fn new(na: u32, nb: u32) -> NodeStates {
        let width = na as usize + 1;
        let n = width * (nb as usize + 1);
        NodeStates { width, len: n, bits: vec![0; n.div_ceil(64)] }
    }
    /// Clears the padding bits past the last node (after word-wise operations).
    pub(crate) fn mask_tail(&mut self) {
        let r = self.len % 64;
        if r != 0 {
            if let Some(last) = self.bits.last_mut() {
                *last &= (1u64 << r) - 1;
            }
        }
    }
    #[inline]
    pub fn get(&self, i: u32, j: u32) -> bool {
        let k = j as usize * self.width + i as usize;
        (self.bits[k >> 6] >> (k & 63)) & 1 == 1
    }
    #[inline]
    pub fn set(&mut self, i: u32, j: u32) {
        let k = j as usize * self.width + i as usize;
        self.bits[k >> 6] |= 1 << (k & 63);
    }
    /// Sets nodes `i0 .. i1` of row `j`, a word at a time.
    pub fn set_run(&mut self, j: u32, i0: u32, i1: u32) {
        if i0 >= i1 {
            return;
        }
        let (a, b) = (j as usize * self.width + i0 as usize, j as usize * self.width + i1 as usize);
        let (wa, wb) = (a >> 6, (b - 1) >> 6);
        let lo = !0u64 << (a & 63);
        let hi = !0u64 >> (63 - ((b - 1) & 63));
        if wa == wb {
            self.bits[wa] |= lo & hi;
            return;
        }
        self.bits[wa] |= lo;
        self.bits[wa + 1..wb].fill(!0);
        self.bits[wb] |= hi;
    }

    /// Word `w` of the bits shifted down by `s` (bit `k` of the result is
    /// node `k + s`; zero past the end).
    #[inline]
    fn shifted_word(&self, w: usize, s: usize) -> u64 {
        let (q, r) = (w + s / 64, s % 64);
        let at = |q: usize| self.bits.get(q).copied().unwrap_or(0);
        if r == 0 {
            at(q)
        } else {
            (at(q) >> r) | (at(q + 1) << (64 - r))
        }
    }

    /// Calls `f(k)` for each flat node index `k < self.len - s` whose
    /// state differs from node `k + s`'s (in `other` when given, else in
    /// `self`), in increasing `k`. Word-wise: the cost is the plane's words
    /// plus the changes, not its nodes.
    fn for_each_difference(&self, other: Option<&NodeStates>, s: usize, mut f: impl FnMut(usize)) {
        let end = self.len.saturating_sub(s);
        for w in 0..end.div_ceil(64) {
            let there = match other {
                Some(o) => o.shifted_word(w, s),
                None => self.shifted_word(w, s),
            };
            let mut d = self.bits[w] ^ there;
            let rem = end - 64 * w;
            if rem < 64 {
                d &= (1u64 << rem) - 1;
            }
            while d != 0 {
                f(64 * w + d.trailing_zeros() as usize);
                d &= d - 1;
            }
        }
    }

    /// The nodes `(i, j)`, `i < na`, whose state differs from `(i + 1, j)`'s,
    /// ordered by `j`, then `i` (the order of family-A edge vertices).
    pub fn changes_along_a(&self, mut f: impl FnMut(u32, u32)) {
        let width = self.width;
        self.for_each_difference(None, 1, |k| {
            let (i, j) = (k % width, k / width);
            if i + 1 < width {
                f(i as u32, j as u32);
            }
        });
    }

    /// The nodes `(i, j)`, `j < nb`, whose state differs from `(i, j + 1)`'s,
    /// ordered by `i`, then `j` (the order of family-B edge vertices).
    pub fn changes_along_b(&self) -> Vec<(u32, u32)> {
        self.differences_by_column(None, self.width)
    }

    /// The nodes `(i, j)` whose state here differs from `upper`'s, ordered by
    /// `i`, then `j` (the order of family-S edge vertices).
    pub fn changes_to(&self, upper: &NodeStates) -> Vec<(u32, u32)> {
        assert_eq!((self.width, self.len), (upper.width, upper.len), "node states of different planes");
        self.differences_by_column(Some(upper), 0)
    }

    /// [`NodeStates::for_each_difference`]'s nodes as `(i, j)`, ordered by
    /// `i`, then `j`.
    fn differences_by_column(&self, other: Option<&NodeStates>, s: usize) -> Vec<(u32, u32)> {
        let width = self.width;
        let mut keys = Vec::new();
        self.for_each_difference(other, s, |k| keys.push(((k % width) as u64) << 32 | (k / width) as u64));
        keys.sort_unstable();
        keys.into_iter().map(|key| ((key >> 32) as u32, key as u32)).collect()
    }
}

/// Re-signs one line's records (sorted by position) in place under `rule`
/// (Union keeps the orientation; Parity alternates starting with entering).
pub fn resign_parity(line: &mut [Intercept]) {
    for (k, r) in line.iter_mut().enumerate() {
        let v = r.value();
        r.signed_value = if k % 2 == 0 { v } else { -v };
    }
}

/// The state a line gives node `node` (`None` when the line is not valid
/// under `rule`, i.e. inconsistent): records sorted by position.
pub fn line_state(line: &[Intercept], node: u32, rule: SignRule) -> Option<bool> {
    let before = line.partition_point(|r| r.cell() < node);
    match rule {
        SignRule::Parity => (line.len() % 2 == 0).then_some(before % 2 == 1),
        _ => {
            if !winding_valid(line) {
                return None;
            }
            let w: i64 = line[..before].iter().map(|r| if r.entering() { 1 } else { -1 }).sum();
            Some(w > 0)
        }
    }
}

/// The fallback for a node on an inconsistent line: the nearest intercept's
/// orientation (previous enters, or next leaves, means inside).
pub fn nearest_vote(line: &[Intercept], node: u32) -> bool {
    let before = line.partition_point(|r| r.cell() < node);
    if before > 0 {
        return line[before - 1].entering();
    }
    line.get(before).is_some_and(|r| !r.entering())
}

/// The effective rule of one A/B line under a run's rule (Auto already
/// resolved to Union or Parity): Union lines that are not winding-valid but
/// even fall back to Parity.
pub fn effective_rule(line: &[Intercept], rule: SignRule) -> SignRule {
    match rule {
        SignRule::Union if !winding_valid(line) && line.len() % 2 == 0 => SignRule::Parity,
        r => r,
    }
}

/// Statistics of a robust reconstruction.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct RepairStats {
    /// A/B lines with an odd count (through holes), whose nodes took their
    /// states from the other family or the nearest intercept.
    pub inconsistent_lines: u64,
    /// Edges whose end states differ but that had no intercept: a vertex was
    /// made at the edge's midpoint (this is how holes get closed).
    pub synthesized_vertices: u64,
    /// Edges with several intercepts of the change's sign, merged into
    /// their mean (overlapping layers).
    pub merged_edges: u64,
    /// Intercepts on edges whose end states are equal, dropped.
    pub dropped_intercepts: u64,
}

impl std::ops::AddAssign for RepairStats {
    fn add_assign(&mut self, o: RepairStats) {
        self.inconsistent_lines += o.inconsistent_lines;
        self.synthesized_vertices += o.synthesized_vertices;
        self.merged_edges += o.merged_edges;
        self.dropped_intercepts += o.dropped_intercepts;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::intercept::FAMILY_A;

    fn line(signs: &[(f64, bool)]) -> Vec<Intercept> {
        signs.iter().map(|&(v, e)| Intercept::new(0, FAMILY_A, 0, v, e)).collect()
    }

    #[test]
    fn winding_validity() {
        assert!(winding_valid(&line(&[(1.5, true), (3.5, false)])));
        assert!(winding_valid(&line(&[(1.5, true), (1.6, true), (3.5, false), (3.6, false)])));
        assert!(!winding_valid(&line(&[(1.5, false), (3.5, true)])));
        assert!(!winding_valid(&line(&[(1.5, true)])));
    }

    #[test]
    fn union_merges_overlaps_and_parity_ignores_orientation() {
        let overlap = line(&[(1.5, true), (2.5, true), (5.5, false), (6.5, false)]);
        assert_eq!(line_state(&overlap, 2, SignRule::Union), Some(true));
        assert_eq!(line_state(&overlap, 4, SignRule::Union), Some(true));
        assert_eq!(line_state(&overlap, 7, SignRule::Union), Some(false));
        assert_eq!(line_state(&overlap, 4, SignRule::Parity), Some(false), "parity cancels overlaps");
        let flipped = line(&[(1.5, false), (3.5, true)]);
        assert_eq!(line_state(&flipped, 2, SignRule::Parity), Some(true));
        assert_eq!(line_state(&flipped, 2, SignRule::Union), None);
        let holed = line(&[(1.5, true)]);
        assert_eq!(line_state(&holed, 2, SignRule::Parity), None);
        assert!(nearest_vote(&holed, 2));
        assert!(!nearest_vote(&holed, 1) || holed[0].entering());
    }

    #[test]
    fn census_resolves_auto() {
        let good = line(&[(1.5, true), (3.5, false)]);
        let bad = line(&[(1.5, false), (3.5, true)]);
        let mut c = LineCensus::default();
        for _ in 0..200 {
            c += LineCensus::of_plane(&good);
        }
        c += LineCensus::of_plane(&bad);
        assert_eq!(c.resolve(), SignRule::Union);
        for _ in 0..10 {
            c += LineCensus::of_plane(&bad);
        }
        assert_eq!(c.resolve(), SignRule::Parity);
        // A sheet: many crossing lines are odd. Exactly a third is still closed.
        let holed = line(&[(1.5, true)]);
        let mut c = LineCensus::default();
        c += LineCensus::of_plane(&good);
        c += LineCensus::of_plane(&good);
        c += LineCensus::of_plane(&holed);
        assert!(!c.open());
        assert_eq!(c.resolve(), SignRule::Union);
        c += LineCensus::of_plane(&holed);
        assert!(c.open());
        assert_eq!(c.resolve(), SignRule::Sheet);
        assert_eq!(c.resolve_closed(), SignRule::Union);
    }

    /// Node states from runs: `(row, first, length)` set with `set_run`.
    fn states_of(na: u32, nb: u32, runs: &[(u32, u32, u32)]) -> NodeStates {
        let mut st = NodeStates::new(na, nb);
        for &(j, i0, len) in runs {
            let (j, i0) = (j % (nb + 1), i0 % (na + 1));
            st.set_run(j, i0, (i0 + len).min(na + 1));
        }
        st
    }

    proptest::proptest! {
        /// The word-wise runs and change scans equal the per-node loops
        /// they replace, on planes whose rows straddle word boundaries.
        #[test]
        fn word_wise_scans_equal_node_loops(
            na in 0u32..150, nb in 0u32..9,
            runs in proptest::collection::vec((0u32..10, 0u32..151, 0u32..151), 0..12),
            runs2 in proptest::collection::vec((0u32..10, 0u32..151, 0u32..151), 0..12),
        ) {
            let (st, up) = (states_of(na, nb, &runs), states_of(na, nb, &runs2));
            let mut want = NodeStates::new(na, nb);
            for &(j, i0, len) in &runs {
                let (j, i0) = (j % (nb + 1), i0 % (na + 1));
                for i in i0..(i0 + len).min(na + 1) {
                    want.set(i, j);
                }
            }
            proptest::prop_assert_eq!(&st.bits, &want.bits);
            let mut a = Vec::new();
            st.changes_along_a(|i, j| a.push((i, j)));
            let naive_a: Vec<(u32, u32)> = (0..=nb).flat_map(|j| (0..na).map(move |i| (i, j))).filter(|&(i, j)| st.get(i, j) != st.get(i + 1, j)).collect();
            proptest::prop_assert_eq!(a, naive_a);
            let naive_b: Vec<(u32, u32)> = (0..=na).flat_map(|i| (0..nb).map(move |j| (i, j))).filter(|&(i, j)| st.get(i, j) != st.get(i, j + 1)).collect();
            proptest::prop_assert_eq!(st.changes_along_b(), naive_b);
            let naive_s: Vec<(u32, u32)> = (0..=na).flat_map(|i| (0..=nb).map(move |j| (i, j))).filter(|&(i, j)| st.get(i, j) != up.get(i, j)).collect();
            proptest::prop_assert_eq!(st.changes_to(&up), naive_s);
        }
    }
}

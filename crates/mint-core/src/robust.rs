//! Robust reconstruction for dirty scans: node states first, then exactly
//! one vertex on every edge whose end states differ.
//!
//! The paper's reconstruction ([`crate::reconstruct::reconstruct_slab`])
//! trusts the intercepts: a cell whose edges disagree with its nodes is
//! *non-canonical* and left empty, which leaves holes. Here the order is
//! reversed. Every node of a plane first gets one state from the sign rules
//! of [`crate::signs`] ([`NodeStates`]); then every edge whose two end
//! states differ gets exactly one vertex:
//! - the intercepts of that cell edge are filtered as usual (discordant
//!   pairs removed), and those whose sign matches the change (entering when
//!   going from outside to inside along the axis) are merged into their mean
//!   — overlapping layers become one vertex;
//! - with no matching intercept, the mean of the others;
//! - with no intercept at all (a hole in the input), a vertex at the
//!   edge's midpoint is *synthesized*.
//! Intercepts on edges with equal end states are dropped (detail below a
//! cell). Because every cell is then canonical by construction, the
//! marching-cubes table's guarantee applies to the whole output: it is a
//! closed, oriented 2-manifold for *any* input, and holes of any size are
//! closed by the states around them (see docs/INVARIANTS.md).
//!
//! Vertex ids follow the same scheme as the strict path: per plane, the
//! final records sorted (A, then B, then S of the layer above), planes in
//! order; a plane's A/B records and states depend on that plane alone, and
//! its S records on it and the plane above, so the output is the same for
//! any slab partition.

use crate::cells::{push_cell_triangles, walk_slab, SlabResult};
use crate::expr::{result_vertex, Expr};
use crate::grid::Grid;
use crate::holes::{cell_id, OpenCells};
use crate::intercept::{filter_plane, Intercept, PlaneLines, FAMILY_A, FAMILY_B, FAMILY_S};
use crate::mc_table::{corner_offset, EDGE_CORNERS};
use crate::signs::{effective_rule, lines, nearest_vote, resign_parity, winding_valid, LineCensus, NodeStates, RepairStats, SignRule};
use crate::MARGIN;

/// A plane's edge vertices in vertex order (sorted by
/// [`Intercept::sort_key`]), each with a flag that says it was synthesized:
/// its edge had no intercept, so it caps a hole.
#[derive(Debug, Clone, Default)]
struct EdgeVertices {
    records: Vec<Intercept>,
    synthesized: Vec<bool>,
}

impl EdgeVertices {
    fn push(&mut self, (record, synthesized): (Intercept, bool)) {
        debug_assert!(self.records.last().is_none_or(|l| l.sort_key() < record.sort_key()), "edge vertices out of order");
        self.records.push(record);
        self.synthesized.push(synthesized);
    }
    fn extend(&mut self, other: &EdgeVertices) {
        for k in 0..other.records.len() {
            self.push((other.records[k], other.synthesized[k]));
        }
    }
    /// Keeps the vertices for which `keep` is true.
    fn retain(&mut self, keep: impl Fn(&Intercept) -> bool) {
        let mut out = 0;
        for k in 0..self.records.len() {
            if keep(&self.records[k]) {
                self.records[out] = self.records[k];
                self.synthesized[out] = self.synthesized[k];
                out += 1;
            }
        }
        self.records.truncate(out);
        self.synthesized.truncate(out);
    }
    /// The vertex on cell `cell` of line (`family`, `index`), if any: its
    /// position and whether it was synthesized.
    fn on_edge(&self, family: u32, index: u32, cell: u32) -> Option<(f64, bool)> {
        let pl = PlaneLines::new(&self.records);
        let r = pl.in_cell(pl.line(family, index), cell);
        (!r.is_empty()).then(|| (self.records[r.start].value(), self.synthesized[r.start]))
    }
}

/// One plane after its states and A/B vertices are decided.
struct Prepared {
    /// One vertex per A/B edge with a state change.
    ab: EdgeVertices,
    /// The plane's raw family-S records (layer above), sorted.
    s_raw: Vec<Intercept>,
    states: NodeStates,
}

/// A line after filtering under its effective rule.
struct Line {
    records: Vec<Intercept>,
    /// None: inconsistent (odd count): states come from elsewhere.
    rule: Option<SignRule>,
}

/// Filters one line's raw records (sorted) under `rule` (Union or Parity).
fn filter_line(raw: &[Intercept], rule: SignRule) -> Line {
    let mut own = raw.to_vec();
    filter_plane(&mut own);
    if rule == SignRule::Sheet {
        return Line { records: own, rule: Some(SignRule::Sheet) };
    }
    if rule == SignRule::Union && winding_valid(&own) {
        return Line { records: own, rule: Some(SignRule::Union) };
    }
    let eff = effective_rule(&own, rule);
    if own.len() % 2 == 1 {
        return Line { records: own, rule: None };
    }
    debug_assert_eq!(eff, SignRule::Parity);
    let mut p = raw.to_vec();
    resign_parity(&mut p);
    filter_plane(&mut p);
    Line { records: p, rule: Some(SignRule::Parity) }
}

/// The census of one plane's A/B lines (for resolving [`SignRule::Auto`]):
/// validity is judged after the removal filter, as reconstruction does.
pub fn census_plane(raw: &mut [Intercept]) -> LineCensus {
    raw.sort_unstable_by_key(|r| r.sort_key());
    let mut c = LineCensus::default();
    for range in lines(raw) {
        if raw[range.start].family() > FAMILY_B {
            break;
        }
        let mut own = raw[range].to_vec();
        filter_plane(&mut own);
        if own.is_empty() {
            continue;
        }
        c.lines += 1;
        if winding_valid(&own) {
            c.winding_valid += 1;
        }
        if own.len() % 2 == 1 {
            c.odd += 1;
        }
    }
    c
}

/// Walks a valid line and sets the states of its inside nodes, a run
/// `set(i0, i1)` (nodes `i0 .. i1`) at a time.
fn line_states(line: &Line, n_nodes: u32, mut set: impl FnMut(u32, u32)) {
    let mut w = 0i64;
    let mut next_node = 0u32;
    for (k, r) in line.records.iter().enumerate() {
        let c = r.cell();
        // Nodes next_node ..= c lie before this record.
        let inside = match line.rule {
            Some(SignRule::Parity) => k % 2 == 1,
            _ => w > 0,
        };
        if inside {
            set(next_node, (c + 1).min(n_nodes));
        }
        next_node = next_node.max(c + 1);
        w += if r.entering() { 1 } else { -1 };
    }
    let inside = match line.rule {
        Some(SignRule::Parity) => line.records.len() % 2 == 1,
        _ => w > 0,
    };
    if inside {
        set(next_node, n_nodes);
    }
}

/// Picks the one vertex of an edge with a state change from the records of
/// that cell edge (sorted by position); `None` means synthesize.
fn select(cell_records: &[Intercept], entering: bool, rule: SignRule, stats: &mut RepairStats) -> Option<f64> {
    if cell_records.is_empty() {
        return None;
    }
    let mut v = cell_records.to_vec();
    if rule == SignRule::Parity {
        // Alternate from the change's sign, as the line would.
        for (k, r) in v.iter_mut().enumerate() {
            let e = if k % 2 == 0 { entering } else { !entering };
            let x = r.value();
            r.signed_value = if e { x } else { -x };
        }
    }
    filter_plane(&mut v);
    let matching: Vec<f64> = v.iter().filter(|r| r.entering() == entering).map(|r| r.value()).collect();
    let pick = if !matching.is_empty() { matching } else { cell_records.iter().map(|r| r.value()).collect() };
    if pick.len() > 1 {
        stats.merged_edges += 1;
    }
    Some(pick.iter().sum::<f64>() / pick.len() as f64)
}

/// The vertex of an edge with a state change: the selected position kept
/// a margin inside its cell, or, with none, a synthesized one at the
/// edge's midpoint (flagged).
fn vertex_record(plane: u32, family: u32, index: u32, cell: u32, value: Option<f64>, entering: bool, stats: &mut RepairStats) -> (Intercept, bool) {
    let c = cell as f64;
    match value {
        Some(v) => (Intercept::new(plane, family, index, v.clamp(c + MARGIN, c + 1.0 - MARGIN), entering), false),
        None => {
            stats.synthesized_vertices += 1;
            (Intercept::new(plane, family, index, c + 0.5, entering), true)
        }
    }
}

/// Splits a plane's raw records into its A/B records and its S records
/// (the layer above), both sorted.
fn split_plane(mut raw: Vec<Intercept>) -> (Vec<Intercept>, Vec<Intercept>) {
    raw.sort_unstable_by_key(|r| r.sort_key());
    let s_start = raw.partition_point(|r| r.family() < FAMILY_S);
    let s_raw = raw.split_off(s_start);
    (raw, s_raw)
}

/// Votes of one filtered line's intercepts for the nodes next to them
/// (Sheet rule): in each cell with intercepts, the first one votes for the
/// node before it and the last one for the node after it, +1 when that
/// node is behind the surface (inside), -1 when in front.
fn sheet_votes(records: &[Intercept], mut vote: impl FnMut(u32, i8)) {
    let mut k = 0;
    while k < records.len() {
        let c = records[k].cell();
        let mut e = k;
        while e + 1 < records.len() && records[e + 1].cell() == c {
            e += 1;
        }
        // Entering along the axis: the node before is in front, the one after behind.
        vote(c, if records[k].entering() { -1 } else { 1 });
        vote(c + 1, if records[e].entering() { 1 } else { -1 });
        k = e + 1;
    }
}

/// A plane's node states under [`SignRule::Sheet`], from its filtered A and
/// B lines and the raw S records of the layers below and above it: a node
/// is inside when the votes of the intercepts next to it on its (up to six)
/// edges sum to more than zero.
fn sheet_states(a_lines: &[Option<Line>], b_lines: &[Option<Line>], s_below: &[Intercept], s_above: &[Intercept], na: u32, nb: u32) -> NodeStates {
    let w = na as u64 + 1;
    let mut votes: Vec<(u64, i8)> = Vec::new();
    for (j, l) in a_lines.iter().enumerate() {
        if let Some(l) = l {
            sheet_votes(&l.records, |i, v| votes.push((j as u64 * w + i as u64, v)));
        }
    }
    for (i, l) in b_lines.iter().enumerate() {
        if let Some(l) = l {
            sheet_votes(&l.records, |j, v| votes.push((j as u64 * w + i as u64, v)));
        }
    }
    // S columns: the node is the upper end of the layer below (the last
    // intercept votes) and the lower end of the layer above (the first).
    let mut below = s_below.to_vec();
    filter_plane(&mut below);
    let mut above = s_above.to_vec();
    filter_plane(&mut above);
    let node_of = |r: &Intercept| {
        let idx = r.index();
        let (i, j) = (idx / (nb + 1), idx % (nb + 1));
        j as u64 * w + i as u64
    };
    for range in lines(&below) {
        let r = below[range.end - 1];
        votes.push((node_of(&r), if r.entering() { 1 } else { -1 }));
    }
    for range in lines(&above) {
        let r = above[range.start];
        votes.push((node_of(&r), if r.entering() { -1 } else { 1 }));
    }
    votes.sort_unstable_by_key(|v| v.0);
    let mut states = NodeStates::new(na, nb);
    let mut front = NodeStates::new(na, nb);
    let mut grown: Vec<(u32, u32)> = Vec::new();
    let mut k = 0;
    while k < votes.len() {
        let n = votes[k].0;
        let mut sum = 0i32;
        while k < votes.len() && votes[k].0 == n {
            sum += votes[k].1 as i32;
            k += 1;
        }
        let (i, j) = ((n % w) as u32, (n / w) as u32);
        if i == 0 || j == 0 || i == na || j == nb {
            continue;
        }
        if sum > 0 {
            states.set(i, j);
            grown.push((i, j));
        } else if sum < 0 {
            front.set(i, j);
        }
    }
    // A cell the surface crosses has back corners that no edge of it
    // crosses to (the far corners of a cut-off corner). Each face of such a
    // cell has a voted back corner within two in-plane steps, so the inside
    // grows twice along in-plane edges the surface does not cross, never
    // into a node voted in front; else those cells would hold synthesized
    // vertices and open holes in the sheet.
    let crossed = |line: &Option<Line>, cell: u32| line.as_ref().is_some_and(|l| !cell_slice(&l.records, cell).is_empty());
    for _ in 0..2 {
        let mut next = Vec::new();
        for &(i, j) in &grown {
            let mut try_set = |i2: u32, j2: u32, line: &Option<Line>, cell: u32| {
                let border = i2 == 0 || j2 == 0 || i2 == na || j2 == nb;
                if !border && !states.get(i2, j2) && !front.get(i2, j2) && !crossed(line, cell) {
                    states.set(i2, j2);
                    next.push((i2, j2));
                }
            };
            if i > 0 {
                try_set(i - 1, j, &a_lines[j as usize], i - 1);
            }
            if i < na {
                try_set(i + 1, j, &a_lines[j as usize], i);
            }
            if j > 0 {
                try_set(i, j - 1, &b_lines[i as usize], j - 1);
            }
            if j < nb {
                try_set(i, j + 1, &b_lines[i as usize], j);
            }
        }
        grown = next;
    }
    states
}

/// Decides a plane's node states and its A/B edge vertices. `raw` is the
/// plane's A/B records and `s_raw` its S records (sorted, [`split_plane`]);
/// `s_below` the S records of the layer below (used by Sheet only).
/// `border_plane`: the grid's first or last plane, whose nodes the Sheet
/// rule leaves outside (as every other rule does, the grid being larger
/// than the input), so that the states' surface never meets the border.
fn prepare_plane(raw: Vec<Intercept>, s_raw: Vec<Intercept>, s_below: &[Intercept], plane: u32, border_plane: bool, na: u32, nb: u32, rule: SignRule, stats: &mut RepairStats) -> Prepared {
    // Filter every A and B line under the rule.
    let mut a_lines: Vec<Option<Line>> = (0..=nb).map(|_| None).collect();
    let mut b_lines: Vec<Option<Line>> = (0..=na).map(|_| None).collect();
    for range in lines(&raw) {
        let r0 = raw[range.start];
        let line = filter_line(&raw[range.clone()], rule);
        if line.rule.is_none() {
            stats.inconsistent_lines += 1;
        }
        if r0.family() == FAMILY_A {
            a_lines[r0.index() as usize] = Some(line);
        } else {
            b_lines[r0.index() as usize] = Some(line);
        }
    }
    // States: from the A line when it is consistent, else from the B line,
    // else from the nearest intercept's orientation.
    let mut states = NodeStates::new(na, nb);
    if rule == SignRule::Sheet && !border_plane {
        states = sheet_states(&a_lines, &b_lines, s_below, &s_raw, na, nb);
    }
    for j in (0..=nb).filter(|_| rule != SignRule::Sheet) {
        match &a_lines[j as usize] {
            None => {}
            Some(l) if l.rule.is_some() => line_states(l, na + 1, |i0, i1| states.set_run(j, i0, i1)),
            Some(l) => {
                for i in 0..=na {
                    let from_b = b_lines[i as usize].as_ref().map(|b| match b.rule {
                        Some(_) => state_on(b, j),
                        None => None,
                    });
                    let s = match from_b {
                        Some(Some(s)) => s,
                        Some(None) => nearest_vote(&l.records, i),
                        None => false, // the B line has no intercept: outside
                    };
                    if s {
                        states.set(i, j);
                    }
                }
            }
        }
    }
    // One vertex per A edge and per B edge whose end states differ.
    let mut ab = EdgeVertices::default();
    let empty = Line { records: Vec::new(), rule: Some(rule) };
    let mut used = 0u64;
    let total: u64 = a_lines.iter().chain(&b_lines).flatten().map(|l| l.records.len() as u64).sum();
    // (The changes come word-wise from the states, in vertex order: A by
    // row then cell, B by column then cell.)
    states.changes_along_a(|i, j| {
        let l = a_lines[j as usize].as_ref().unwrap_or(&empty);
        let s1 = states.get(i + 1, j);
        let cell = cell_slice(&l.records, i);
        used += cell.len() as u64;
        let v = select(cell, s1, l.rule.unwrap_or(rule), stats);
        ab.push(vertex_record(plane, FAMILY_A, j, i, v, s1, stats));
    });
    for (i, j) in states.changes_along_b() {
        let l = b_lines[i as usize].as_ref().unwrap_or(&empty);
        let s1 = states.get(i, j + 1);
        let cell = cell_slice(&l.records, j);
        used += cell.len() as u64;
        let v = select(cell, s1, l.rule.unwrap_or(rule), stats);
        ab.push(vertex_record(plane, FAMILY_B, i, j, v, s1, stats));
    }
    stats.dropped_intercepts += total - used;
    Prepared { ab, s_raw, states }
}

/// The state a consistent line gives node `node`.
fn state_on(l: &Line, node: u32) -> Option<bool> {
    let before = l.records.partition_point(|r| r.cell() < node);
    match l.rule {
        Some(SignRule::Parity) => Some(before % 2 == 1),
        Some(_) => Some(l.records[..before].iter().map(|r| if r.entering() { 1i64 } else { -1 }).sum::<i64>() > 0),
        None => None,
    }
}

fn cell_slice(records: &[Intercept], cell: u32) -> &[Intercept] {
    let a = records.partition_point(|r| r.cell() < cell);
    let b = a + records[a..].partition_point(|r| r.cell() == cell);
    &records[a..b]
}

/// The family-S vertices of layer `k` (between planes with `lower` and
/// `upper` states), one per node whose state changes across the layer.
fn layer_s_vertices(s_raw: &[Intercept], lower: &NodeStates, upper: &NodeStates, k: u32, nb: u32, rule: SignRule, stats: &mut RepairStats) -> EdgeVertices {
    let mut out = EdgeVertices::default();
    let lines_view = PlaneLines::new(s_raw);
    let mut used = 0usize;
    for (i, j) in lower.changes_to(upper) {
        let s1 = upper.get(i, j);
        let idx = i * (nb + 1) + j;
        let range = lines_view.line(FAMILY_S, idx);
        used += range.len();
        let v = select(&s_raw[range], s1, rule, stats);
        out.push(vertex_record(k, FAMILY_S, idx, k, v, s1, stats));
    }
    stats.dropped_intercepts += (s_raw.len() - used) as u64;
    out
}

/// Robust reconstruction of layers `k0 .. k0 + planes.len() - 1` from the
/// *raw* (unsorted, unfiltered) intercepts of planes `k0 ..= k1`, under
/// `rule` (Union or Parity; resolve Auto first with [`census_plane`]).
pub fn reconstruct_slab_robust(grid: &Grid, k0: u32, planes: Vec<Vec<Intercept>>, rule: SignRule) -> (SlabResult, RepairStats) {
    assert!(k0 == 0 || rule != SignRule::Sheet, "the sheet rule needs the layer below: use reconstruct_slab_solids");
    reconstruct_slab_solids(grid, k0, vec![planes], &[rule], &Expr::Operand(0), None, &[])
}

/// Robust reconstruction of a CSG expression over several solids on one
/// grid: `operands[o][p]` are the raw intercepts of operand `o` in plane
/// `k0 + p`, read under `rules[o]`. Each operand's node states and edge
/// vertices are decided alone (as in the single-solid case); the result's
/// states are the expression of theirs, and each result edge takes the
/// vertex at which the expression changes ([`result_vertex`]). The output
/// is closed for any operands, and identical to the robust resampling of
/// operand 0 when the expression is just that operand.
///
/// Cells in `open` (holes too large to close, see [`crate::holes`]) emit no
/// triangles, and vertices all of whose cells are open are left out.
///
/// `below[o]`, when given, holds operand `o`'s raw records of plane
/// `k0 - 1`, of which only the S records (layer `k0 - 1`) are read: the
/// Sheet rule decides a plane's states from the layers on both sides, so it
/// needs them whenever `k0 > 0`, and the last plane's S records too.
pub fn reconstruct_slab_solids(
    grid: &Grid,
    k0: u32,
    operands: Vec<Vec<Vec<Intercept>>>,
    rules: &[SignRule],
    expr: &Expr,
    open: Option<&OpenCells>,
    below: &[Vec<Intercept>],
) -> (SlabResult, RepairStats) {
    assert!(rules.iter().all(|r| matches!(r, SignRule::Union | SignRule::Parity | SignRule::Sheet)), "resolve the sign rules first");
    assert_eq!(rules.len(), operands.len());
    assert!(expr.operands() <= operands.len());
    let [na, nb, ns] = grid.local_dims();
    let mut stats = RepairStats::default();
    let n = operands[0].len();
    let m = operands.len();
    // Per operand, per plane: states and the operand's own edge vertices.
    let prepared: Vec<Vec<Prepared>> = operands
        .into_iter()
        .zip(rules)
        .enumerate()
        .map(|(o, (planes, &rule))| {
            let split: Vec<(Vec<Intercept>, Vec<Intercept>)> = planes.into_iter().map(split_plane).collect();
            let first_below = match below.get(o) {
                Some(raw) if rule == SignRule::Sheet => split_plane(raw.clone()).1,
                _ => Vec::new(),
            };
            let mut out: Vec<Prepared> = Vec::with_capacity(split.len());
            for (p, (ab, s_raw)) in split.into_iter().enumerate() {
                let s_below = if p == 0 { first_below.as_slice() } else { out[p - 1].s_raw.as_slice() };
                let k = k0 + p as u32;
                let pr = prepare_plane(ab, s_raw, s_below, k, k == 0 || k == ns, na, nb, rule, &mut stats);
                out.push(pr);
            }
            out
        })
        .collect();
    let single = m == 1 && *expr == Expr::Operand(0);
    // Result states per plane.
    let states: Vec<NodeStates> = (0..n)
        .map(|p| {
            if single {
                return prepared[0][p].states.clone();
            }
            let mut st = NodeStates::new(na, nb);
            let mut w = vec![0u64; m];
            for k in 0..st.bits.len() {
                for o in 0..m {
                    w[o] = prepared[o][p].states.bits[k];
                }
                st.bits[k] = expr.eval_words(&w);
            }
            st.mask_tail();
            st
        })
        .collect();
    // Per operand, per owned layer: its S vertices.
    let s_finals: Vec<Vec<EdgeVertices>> = (0..m)
        .map(|o| {
            (0..n - 1)
                .map(|p| {
                    let pr = &prepared[o];
                    layer_s_vertices(&pr[p].s_raw, &pr[p].states, &pr[p + 1].states, k0 + p as u32, nb, rules[o], &mut stats)
                })
                .collect()
        })
        .collect();
    // Final vertices per plane: A/B (every plane), then S (owned planes);
    // each part is built in vertex order, so the whole is too.
    let mut finals: Vec<EdgeVertices> = Vec::with_capacity(n);
    for p in 0..n {
        let mut f = if single { prepared[0][p].ab.clone() } else { combine_ab(&prepared, p, &states[p], k0 + p as u32, expr) };
        if p + 1 < n {
            if single {
                f.extend(&s_finals[0][p]);
            } else {
                f.extend(&combine_s(&prepared, &s_finals, p, &states[p], &states[p + 1], k0 + p as u32, nb, expr));
            }
        }
        if let Some(open) = open {
            f.retain(|r| !open.surrounds(r, [na, nb]));
        }
        finals.push(f);
    }
    let records: Vec<&[Intercept]> = finals.iter().map(|f| f.records.as_slice()).collect();
    let mut out = SlabResult::default();
    walk_slab(grid, k0, &records, &mut out, |layer, i, j, out| {
        let cell = cell_id([i, j, layer.k], [na, nb]);
        if open.is_some_and(|o| o.contains(cell)) {
            return;
        }
        let st = [&states[layer.index], &states[layer.index + 1]];
        let mut code = 0u8;
        for c in 0..8u8 {
            let [x, y, z] = corner_offset(c);
            if st[z as usize].get(i + x, j + y) {
                code |= 1 << c;
            }
        }
        let mut hole = false;
        let mut ids = [u32::MAX; 12];
        for e in 0..12u8 {
            let [c0, c1] = EDGE_CORNERS[e as usize];
            if ((code >> c0) & 1) == ((code >> c1) & 1) {
                continue;
            }
            let (z, range) = layer.edge(i, j, e);
            assert_eq!(range.len(), 1, "robust reconstruction: edge {e} of cell ({i},{j},{}) has {} vertices", layer.k, range.len());
            hole |= finals[layer.index + z].synthesized[range.start];
            ids[e as usize] = layer.vertex_id(z, range.start);
        }
        if hole {
            out.hole_cells.push(cell);
        }
        push_cell_triangles(code, &ids, &mut out.faces);
    });
    (out, stats)
}

/// The result's vertex on one edge: where the expression changes along it
/// ([`result_vertex`]), given each operand's vertex on that edge; a
/// synthesized operand vertex, or no change at all, makes a synthesized one.
fn combined_vertex(expr: &Expr, lower: &mut [bool], changes: &mut Vec<(f64, usize)>, synthesized: &[bool], cell: u32) -> (f64, bool) {
    match result_vertex(expr, lower, changes) {
        Some((v, o)) => (v, synthesized[o]),
        None => (cell as f64 + 0.5, true),
    }
}

/// The result's A/B edge vertices of plane `p`.
#[allow(clippy::too_many_arguments)]
fn combine_ab(prepared: &[Vec<Prepared>], p: usize, states: &NodeStates, plane: u32, expr: &Expr) -> EdgeVertices {
    let m = prepared.len();
    let mut out = EdgeVertices::default();
    let mut lower = vec![false; m];
    let mut synthesized = vec![false; m];
    let mut changes = Vec::with_capacity(m);
    let mut edge = |family: u32, index: u32, cell: u32, n0: (u32, u32), entering: bool, out: &mut EdgeVertices| {
        changes.clear();
        for o in 0..m {
            lower[o] = prepared[o][p].states.get(n0.0, n0.1);
            if let Some((v, synth)) = prepared[o][p].ab.on_edge(family, index, cell) {
                changes.push((v, o));
                synthesized[o] = synth;
            }
        }
        let (v, synth) = combined_vertex(expr, &mut lower, &mut changes, &synthesized, cell);
        out.push((Intercept::new(plane, family, index, v, entering), synth));
    };
    states.changes_along_a(|i, j| edge(FAMILY_A, j, i, (i, j), states.get(i + 1, j), &mut out));
    for (i, j) in states.changes_along_b() {
        edge(FAMILY_B, i, j, (i, j), states.get(i, j + 1), &mut out);
    }
    out
}

/// The result's S edge vertices of layer `p` (between planes `p`, `p + 1`).
#[allow(clippy::too_many_arguments)]
fn combine_s(prepared: &[Vec<Prepared>], s_finals: &[Vec<EdgeVertices>], p: usize, lo: &NodeStates, hi: &NodeStates, k: u32, nb: u32, expr: &Expr) -> EdgeVertices {
    let m = prepared.len();
    let mut out = EdgeVertices::default();
    let mut lower = vec![false; m];
    let mut synthesized = vec![false; m];
    let mut changes = Vec::with_capacity(m);
    for (i, j) in lo.changes_to(hi) {
        let s1 = hi.get(i, j);
        let idx = i * (nb + 1) + j;
        changes.clear();
        for o in 0..m {
            lower[o] = prepared[o][p].states.get(i, j);
            if let Some((v, synth)) = s_finals[o][p].on_edge(FAMILY_S, idx, k) {
                changes.push((v, o));
                synthesized[o] = synth;
            }
        }
        let (v, synth) = combined_vertex(expr, &mut lower, &mut changes, &synthesized, k);
        out.push((Intercept::new(k, FAMILY_S, idx, v, s1), synth));
    }
    out
}

#[cfg(test)]
mod tests {
    use crate::grid::{Grid, GridSize};
    use crate::in_core::resample_in_core_with;
    use crate::reconstruct::tests::sphere;
    use crate::signs::SignRule;
    use crate::TriMesh;
    use std::collections::HashMap;

    fn same(a: &TriMesh, b: &TriMesh, ctx: &str) {
        assert_eq!(a.positions.len(), b.positions.len(), "{ctx}: vertex count");
        assert_eq!(a.faces.len(), b.faces.len(), "{ctx}: face count");
        if let Some(i) = (0..a.positions.len()).find(|&i| a.positions[i] != b.positions[i]) {
            panic!("{ctx}: vertex {i} differs: {:?} vs {:?}", a.positions[i], b.positions[i]);
        }
        if let Some(i) = (0..a.faces.len()).find(|&i| a.faces[i] != b.faces[i]) {
            let norm = |f: &[u32; 3]| { let k = (0..3).min_by_key(|&k| f[k]).unwrap(); [f[k], f[(k + 1) % 3], f[(k + 2) % 3]] };
            let mut sa: Vec<_> = a.faces.iter().map(norm).collect();
            let mut sb: Vec<_> = b.faces.iter().map(norm).collect();
            sa.sort();
            sb.sort();
            eprintln!("{ctx}: as sets equal: {}", sa == sb);
            panic!("{ctx}: face {i} differs: {:?} vs {:?}", a.faces[i], b.faces[i]);
        }
    }

    fn closed(m: &TriMesh) -> bool {
        let mut half = HashMap::new();
        for f in &m.faces {
            for i in 0..3 {
                if half.insert((f[i], f[(i + 1) % 3]), ()).is_some() {
                    return false;
                }
            }
        }
        half.keys().all(|&(a, b)| half.contains_key(&(b, a)))
    }

    fn run(tris: &[[[f64; 3]; 3]], rule: SignRule, cells: u64) -> (TriMesh, SignRule) {
        let g = Grid::around([-1.5; 3], [1.5; 3], GridSize::Cells(cells), [0.1, 0.2, 0.3], None).unwrap();
        let mut m = TriMesh::default();
        let (_, _, r) = resample_in_core_with(&g, tris.iter().copied(), rule, &mut m).unwrap();
        (m, r)
    }

    #[test]
    fn clean_input_gives_the_same_mesh_under_every_rule() {
        let s = sphere([0.0; 3], 1.0, 30, 60);
        let (orient, _) = run(&s, SignRule::Orient, 20_000);
        for rule in [SignRule::Union, SignRule::Parity, SignRule::Auto] {
            let (m, _) = run(&s, rule, 20_000);
            same(&m, &orient, &format!("{rule:?}"));
        }
    }

    #[test]
    fn flipped_faces_resolve_to_parity_and_match_the_clean_output() {
        let s = sphere([0.0; 3], 1.0, 30, 60);
        let flipped: Vec<_> = s.iter().enumerate().map(|(k, t)| if (k * 7919) % 5 < 2 { [t[0], t[2], t[1]] } else { *t }).collect();
        let (clean, _) = run(&s, SignRule::Orient, 20_000);
        let (m, rule) = run(&flipped, SignRule::Auto, 20_000);
        assert_eq!(rule, SignRule::Parity);
        same(&m, &clean, "flipped");
    }

    #[test]
    fn a_real_vertex_at_an_edge_midpoint_is_kept_and_not_taken_for_a_hole() {
        // A box whose faces lie halfway between grid planes: every crossing
        // value is exactly `cell + 0.5`, the position a synthesized vertex
        // takes. The flag, not the value, marks holes: none here, and the
        // values are kept as they are.
        let (lo, hi) = ([0.5, 1.5, -0.5], [3.5, 3.5, 2.5]);
        for axis in 0..3 {
            let g = Grid::around([0.0, 0.0, -2.0], [4.0, 5.0, 3.0], GridSize::CellSize(1.0), [0.0; 3], Some(axis)).unwrap();
            let mut m = TriMesh::default();
            let (r, repair, rule, holes) = crate::in_core::resample_in_core_holes(&g, crate::reconstruct::tests::cube(lo, hi), SignRule::Auto, Some(0), &mut m).unwrap();
            assert_eq!(rule, SignRule::Union);
            assert_eq!((repair.synthesized_vertices, r.hole_cells.len(), holes), (0, 0, Default::default()));
            assert!(closed(&m) && !m.faces.is_empty());
            for p in &m.positions {
                let on_face = (0..3).any(|d| p[d] == lo[d] || p[d] == hi[d]);
                assert!(on_face, "vertex {p:?} is not on a face of the box");
            }
        }
    }

    #[test]
    fn a_sphere_with_a_hole_is_closed_and_two_overlapping_copies_merge() {
        let s = sphere([0.0; 3], 1.0, 30, 60);
        // Remove a cap of faces near the north pole: a hole ~ 0.5 wide.
        let holed: Vec<_> = s.iter().copied().filter(|t| t.iter().map(|p| p[2]).sum::<f64>() / 3.0 < 0.97).collect();
        let (m, rule) = run(&holed, SignRule::Auto, 20_000);
        assert_eq!(rule, SignRule::Union);
        assert!(closed(&m));
        let mut two = s.clone();
        two.extend(sphere([0.013, 0.0, 0.0], 1.0, 30, 60));
        let (m, rule) = run(&two, SignRule::Auto, 20_000);
        assert_eq!(rule, SignRule::Union);
        assert!(closed(&m));
        let (single, _) = run(&s, SignRule::Orient, 20_000);
        // One shell, about the size of one sphere (not two shells).
        assert!((m.faces.len() as f64) < 1.2 * single.faces.len() as f64, "{} vs {}", m.faces.len(), single.faces.len());
    }
}

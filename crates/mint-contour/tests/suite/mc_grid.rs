//! Marching cubes where degeneracy lives: contour vertices exactly on grid
//! nodes and edges exactly on grid lines (coordinates on a quarter lattice
//! with 2 cubes per unit, so grid coordinates are `2u + 1.5`), nested and
//! side-by-side contours, sections that appear and vanish. Every stack must
//! reconstruct to a closed, consistently oriented surface with zero
//! non-canonical cells; and the output must not depend on the window size.
use super::util::{parse, profile_text, Rng};
use mint_contour::geom2d::{first_crossing, signed_area, P2};
use mint_contour::mc::{self, McOptions};
use mint_core::TriMesh;
use mint_testkit::topology::check_closed_oriented;

const E: f64 = 6.0;

/// A random star polygon snapped to the quarter lattice inside (0, E)².
fn lattice_star(rng: &mut Rng) -> Option<Vec<P2>> {
    let c = [rng.range(1.0, E - 1.0), rng.range(1.0, E - 1.0)];
    let n = 3 + (rng.next_u64() % 9) as usize;
    let rmax = rng.range(0.3, 2.5);
    let step = std::f64::consts::TAU / n as f64;
    let snap = |x: f64| ((x * 4.0).round() / 4.0).clamp(0.25, E - 0.25);
    let mut p: Vec<P2> = (0..n)
        .map(|i| {
            let a = (i as f64 + rng.range(0.1, 0.9)) * step;
            let r = rng.range(0.2, 1.0) * rmax;
            [snap(c[0] + r * a.cos()), snap(c[1] + r * a.sin())]
        })
        .collect();
    p.dedup();
    while p.len() > 1 && p[0] == p[p.len() - 1] {
        p.pop();
    }
    (p.len() >= 3 && signed_area(&p) != 0.0 && first_crossing(&[&p]).is_none()).then_some(p)
}

/// A random stack: section 0 holds the square [0, E]² (fixing the grid);
/// every section holds up to four disjoint lattice polygons.
fn random_stack(rng: &mut Rng) -> String {
    let layers = 2 + (rng.next_u64() % 7) as usize;
    let mut sections = Vec::new();
    for k in 0..layers {
        let mut polys: Vec<Vec<P2>> = Vec::new();
        if k == 0 {
            polys.push(vec![[0.0, 0.0], [E, 0.0], [E, E], [0.0, E]]);
        }
        for _ in 0..8 {
            if polys.len() >= 4 {
                break;
            }
            if let Some(p) = lattice_star(rng) {
                let mut all: Vec<&[P2]> = polys.iter().map(|q| q.as_slice()).collect();
                all.push(&p);
                if first_crossing(&all).is_none() {
                    polys.push(p);
                }
            }
        }
        if polys.is_empty() {
            polys.push(vec![[1.0, 1.0], [2.0, 1.0], [1.5, 2.0]]);
        }
        let z = k as f64 * 0.5;
        sections.push(polys.iter().map(|p| p.iter().map(|q| [q[0], q[1], z]).collect()).collect());
    }
    profile_text(&sections)
}

fn run(text: &str, window: usize, caps: bool) -> (TriMesh, mc::McStats) {
    let (frame, s) = parse(text);
    let mut m = TriMesh::default();
    let st = mc::reconstruct(frame, &s, McOptions { cubes: (2.0 * E) as u32, caps, window }, &mut m).unwrap();
    (m, st)
}

#[test]
fn lattice_stacks_close_with_no_non_canonical_cell() {
    let mut rng = Rng(11);
    for case in 0..300 {
        let text = random_stack(&mut rng);
        let (m, st) = run(&text, 3, true);
        assert_eq!(st.grid_cells[0], 15, "case {case}: the grid must be 2 cubes per unit");
        assert_eq!(st.non_canonical_cells, 0, "case {case}:\n{text}");
        if let Err(e) = check_closed_oriented(&m) {
            panic!("case {case}: {e}\n{text}");
        }
    }
}

#[test]
fn squares_on_grid_lines_and_diamonds_on_nodes() {
    // Grid coordinate a = 2u + 1.5: u = 0.25 is node 2, u = 0.5 is mid-cell.
    let sq = |z: f64, lo: f64, hi: f64| vec![[lo, lo, z], [hi, lo, z], [hi, hi, z], [lo, hi, z]];
    let diamond = |z: f64| vec![[3.25, 1.25, z], [4.25, 2.25, z], [3.25, 3.25, z], [2.25, 2.25, z]];
    let text = profile_text(&[
        vec![sq(0.0, 0.0, E)],
        vec![sq(1.0, 0.25, 5.75), diamond(1.0)],
        vec![sq(2.0, 0.25, 5.75)],
        vec![diamond(3.0)],
    ]);
    let (m, st) = run(&text, 8, true);
    assert_eq!(st.non_canonical_cells, 0);
    let c = check_closed_oriented(&m).unwrap();
    assert_eq!(c.components, 2);
}

#[test]
fn the_output_does_not_depend_on_the_window() {
    let mut rng = Rng(5);
    for _ in 0..20 {
        let text = random_stack(&mut rng);
        for caps in [true, false] {
            let (reference, _) = run(&text, 1_000, caps);
            for window in [1, 2, 3, 8] {
                assert_eq!(run(&text, window, caps).0, reference, "window {window}, caps {caps}");
            }
        }
    }
}

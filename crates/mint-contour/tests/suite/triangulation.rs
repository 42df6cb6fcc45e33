//! Smallest-inner-angle triangulation on random simple polygons: stars,
//! spirals, combs, lattice polygons full of collinear runs, and polygons
//! with holes. Each result must have exactly `n - 2 + 2h` triangles over the
//! input vertices, all counter-clockwise, with no two overlapping, every
//! one inside the polygon, and areas summing to the polygon's area.
use super::util::{interiors_overlap, Rng};
use mint_contour::geom2d::{first_crossing, inside, orient, signed_area, P2};
use mint_contour::triangulate::triangulate;

fn star(rng: &mut Rng, n: usize, c: P2, r0: f64, r1: f64) -> Vec<P2> {
    // Stratified angles: every gap is below π, so the star is simple.
    let step = std::f64::consts::TAU / n as f64;
    let angles: Vec<f64> = (0..n).map(|i| (i as f64 + rng.range(0.05, 0.95)) * step).collect();
    angles.iter().map(|&a| {
        let r = rng.range(r0, r1);
        [c[0] + r * a.cos(), c[1] + r * a.sin()]
    }).collect()
}

fn spiral(turns: f64, n: usize, width: f64) -> Vec<P2> {
    let t_max = turns * std::f64::consts::TAU;
    let r = |t: f64| 1.0 + t; // arm spacing 2π > width
    let mut out: Vec<P2> = (0..n).map(|i| {
        let t = t_max * i as f64 / (n - 1) as f64;
        [(r(t) + width / 2.0) * t.cos(), (r(t) + width / 2.0) * t.sin()]
    }).collect();
    out.extend((0..n).rev().map(|i| {
        let t = t_max * i as f64 / (n - 1) as f64;
        [(r(t) - width / 2.0) * t.cos(), (r(t) - width / 2.0) * t.sin()]
    }));
    out
}

fn comb(rng: &mut Rng, teeth: usize) -> Vec<P2> {
    // Integer coordinates: the base and the tooth gaps share collinear runs.
    let mut p = vec![[0.0, 0.0]];
    for k in 0..teeth {
        let x = (2 * k) as f64;
        p.push([x + 2.0, 0.0]);
        if k + 1 == teeth {
            break;
        }
    }
    let top = teeth as f64 * 2.0;
    p.push([top, 1.0]);
    for k in (0..teeth).rev() {
        let x = (2 * k) as f64;
        let h = 2.0 + rng.range(0.0, 6.0).floor();
        p.push([x + 2.0, h]);
        p.push([x + 1.0, h]);
        p.push([x + 1.0, 1.0]);
        p.push([x, 1.0]);
    }
    p.pop();
    p.dedup();
    p
}

fn lattice_star(rng: &mut Rng, n: usize, grid: f64) -> Option<Vec<P2>> {
    let mut p: Vec<P2> = star(rng, n, [0.0, 0.0], 0.3, 1.0).iter().map(|q| [(q[0] * grid).round(), (q[1] * grid).round()]).collect();
    p.dedup();
    while p.len() > 1 && p[0] == p[p.len() - 1] {
        p.pop();
    }
    (p.len() >= 3 && signed_area(&p) != 0.0 && first_crossing(&[&p]).is_none()).then_some(p)
}

/// Runs the triangulation and checks everything the module promises.
fn check(outer: &[P2], holes: &[Vec<P2>], what: &str) {
    let hole_refs: Vec<&[P2]> = holes.iter().map(|h| h.as_slice()).collect();
    let mut all: Vec<&[P2]> = vec![outer];
    all.extend(hole_refs.iter().copied());
    assert!(first_crossing(&all).is_none(), "{what}: generator made a non-simple input");
    let t = triangulate(outer, &hole_refs).unwrap_or_else(|e| panic!("{what}: {e}"));
    let pts: Vec<P2> = all.iter().flat_map(|p| p.iter().copied()).collect();
    let n = pts.len();
    assert_eq!(t.forced, 0, "{what}: forced ears");
    assert_eq!(t.triangles.len(), n - 2 + 2 * holes.len(), "{what}: triangle count");
    let tris: Vec<[P2; 3]> = t.triangles.iter().map(|f| f.map(|i| pts[i as usize])).collect();
    for (k, tri) in tris.iter().enumerate() {
        assert!(t.triangles[k].iter().all(|&i| (i as usize) < n), "{what}: new vertex");
        assert!(orient(tri[0], tri[1], tri[2]) > 0.0, "{what}: triangle {k} not counter-clockwise");
        let c = [(tri[0][0] + tri[1][0] + tri[2][0]) / 3.0, (tri[0][1] + tri[1][1] + tri[2][1]) / 3.0];
        let inside_count = all.iter().filter(|p| inside(p, c)).count();
        assert!(inside_count % 2 == 1, "{what}: triangle {k} lies outside the polygon");
    }
    let area: f64 = tris.iter().map(|t| 0.5 * orient(t[0], t[1], t[2])).sum();
    let expect = signed_area(outer).abs() - holes.iter().map(|h| signed_area(h).abs()).sum::<f64>();
    assert!((area - expect).abs() <= 1e-9 * expect.abs().max(1.0), "{what}: area {area} vs {expect}");
    // No two triangles overlap (boxes first).
    let boxes: Vec<[f64; 4]> = tris.iter().map(|t| {
        [t.iter().map(|p| p[0]).fold(f64::INFINITY, f64::min), t.iter().map(|p| p[0]).fold(f64::NEG_INFINITY, f64::max),
         t.iter().map(|p| p[1]).fold(f64::INFINITY, f64::min), t.iter().map(|p| p[1]).fold(f64::NEG_INFINITY, f64::max)]
    }).collect();
    for i in 0..tris.len() {
        for j in i + 1..tris.len() {
            let (a, b) = (boxes[i], boxes[j]);
            if a[1] < b[0] || b[1] < a[0] || a[3] < b[2] || b[3] < a[2] {
                continue;
            }
            assert!(!interiors_overlap(tris[i], tris[j]), "{what}: triangles {i} and {j} overlap");
        }
    }
}

#[test]
fn random_stars() {
    let mut rng = Rng(1);
    for k in 0..200 {
        let n = 3 + (rng.next_u64() % 60) as usize;
        let p = star(&mut rng, n, [0.0, 0.0], 0.1, 1.0);
        if p.len() >= 3 {
            check(&p, &[], &format!("star {k}"));
        }
    }
}

#[test]
fn spirals() {
    for (turns, n, w) in [(1.5, 40, 1.0), (3.0, 200, 2.0), (5.0, 500, 0.5), (0.75, 7, 0.3)] {
        check(&spiral(turns, n, w), &[], &format!("spiral {turns} {n} {w}"));
    }
}

#[test]
fn combs() {
    let mut rng = Rng(2);
    for teeth in [1, 2, 3, 7, 20, 50] {
        check(&comb(&mut rng, teeth), &[], &format!("comb {teeth}"));
    }
}

#[test]
fn lattice_polygons_with_collinear_runs() {
    let mut rng = Rng(3);
    let mut done = 0;
    for k in 0..600 {
        if let Some(p) = lattice_star(&mut rng, 4 + (k % 40), 6.0) {
            check(&p, &[], &format!("lattice {k}"));
            done += 1;
        }
    }
    assert!(done > 200, "only {done} lattice polygons were simple");
}

#[test]
fn polygons_with_holes() {
    let mut rng = Rng(4);
    for k in 0..100 {
        let outer = star(&mut rng, 30 + (k % 30), [0.0, 0.0], 0.85, 1.0);
        // Holes on a ring of radius 0.45, small enough not to touch.
        let h = 1 + k % 6;
        let holes: Vec<Vec<P2>> = (0..h).map(|i| {
            let a = std::f64::consts::TAU * i as f64 / h as f64;
            let mut hole = star(&mut rng, 3 + (k + i) % 12, [0.45 * a.cos(), 0.45 * a.sin()], 0.05, 0.2);
            if i % 2 == 1 {
                hole.reverse(); // any orientation is accepted
            }
            hole
        }).collect();
        check(&outer, &holes, &format!("holes {k}"));
    }
    // A hole whose rightmost vertex is level with outer vertices, and
    // square holes on the lattice (shared x and y coordinates everywhere).
    let outer: Vec<P2> = vec![[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0]];
    let holes: Vec<Vec<P2>> = vec![
        vec![[2.0, 2.0], [4.0, 2.0], [4.0, 4.0], [2.0, 4.0]],
        vec![[6.0, 2.0], [8.0, 2.0], [8.0, 4.0], [6.0, 4.0]],
        vec![[2.0, 6.0], [8.0, 6.0], [8.0, 8.0], [2.0, 8.0]],
        vec![[5.0, 0.5], [5.5, 3.0], [5.0, 5.5], [4.5, 3.0]],
    ];
    check(&outer, &holes, "lattice holes");
}

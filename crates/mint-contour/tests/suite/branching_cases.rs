//! Every branching case, one small synthetic stack each: one contour into
//! two and into three, two into one, two into two crossing over (each
//! contour overlapping both of the other section), a contour appearing and
//! one vanishing inside the stack, a hole that opens and closes (a cavity),
//! an island inside a hole, a branch right at the first section (its single
//! contour is capped, so it cannot be split by a chord) and a merge followed
//! by a branch at the same contour. With caps, both methods must give a
//! watertight surface (`mint_mesh::check`) with no intersecting faces
//! (`mint_mesh::selfx`, exact), and the angle method must join every group
//! (none paired off or capped apart).
use super::util::{ellipse, parse, profile_text};
use mint_contour::angle::{self, AngleOptions, AngleStats};
use mint_contour::mc::{self, McOptions};
use mint_core::TriMesh;

type Stack = Vec<Vec<Vec<[f64; 3]>>>;

const DZ: f64 = 0.25;

fn circle(c: [f64; 2], r: f64, z: f64, n: usize) -> Vec<[f64; 3]> {
    ellipse(c, r, r, 0.0, z, n)
}

/// `k` sections from height `z0` on, each made by `f(z)`.
fn run(stack: &mut Stack, k: usize, f: &dyn Fn(f64) -> Vec<Vec<[f64; 3]>>) {
    for _ in 0..k {
        let z = DZ * stack.len() as f64;
        stack.push(f(z));
    }
}

fn arms(centres: &[[f64; 2]], r: f64, n: usize) -> impl Fn(f64) -> Vec<Vec<[f64; 3]>> + '_ {
    move |z| centres.iter().map(|&c| circle(c, r, z, n)).collect()
}

fn one_to_two() -> Stack {
    let mut s = Stack::new();
    run(&mut s, 4, &|z| vec![ellipse([0.0, 0.0], 2.2, 1.0, 0.0, z, 48)]);
    run(&mut s, 4, &arms(&[[-1.2, 0.0], [1.2, 0.0]], 0.8, 32));
    s
}

fn two_to_one() -> Stack {
    let mut s = one_to_two();
    s.reverse();
    for (k, sec) in s.iter_mut().enumerate() {
        for c in sec.iter_mut() {
            for p in c.iter_mut() {
                p[2] = DZ * k as f64;
            }
        }
    }
    s
}

fn two_to_two() -> Stack {
    // Two ellipses along x, then two along y: each overlaps both others.
    let mut s = Stack::new();
    run(&mut s, 3, &|z| vec![ellipse([-0.9, 0.0], 0.7, 1.6, 0.0, z, 40), ellipse([0.9, 0.0], 0.7, 1.6, 0.0, z, 40)]);
    run(&mut s, 3, &|z| vec![ellipse([0.0, -0.9], 1.6, 0.7, 0.0, z, 40), ellipse([0.0, 0.9], 1.6, 0.7, 0.0, z, 40)]);
    s
}

fn one_to_three() -> Stack {
    let mut s = Stack::new();
    run(&mut s, 4, &|z| vec![ellipse([0.0, 0.0], 3.0, 1.0, 0.0, z, 64)]);
    run(&mut s, 4, &arms(&[[-2.0, 0.0], [0.0, 0.0], [2.0, 0.0]], 0.6, 24));
    s
}

fn appear() -> Stack {
    let mut s = Stack::new();
    run(&mut s, 3, &|z| vec![circle([0.0, 0.0], 1.5, z, 40)]);
    run(&mut s, 4, &|z| vec![circle([0.0, 0.0], 1.5, z, 40), circle([3.0, 0.0], 0.7, z, 20)]);
    s
}

fn vanish() -> Stack {
    let mut s = Stack::new();
    run(&mut s, 4, &|z| vec![circle([0.0, 0.0], 1.5, z, 40), circle([3.0, 0.0], 0.7, z, 20)]);
    run(&mut s, 3, &|z| vec![circle([0.0, 0.0], 1.5, z, 40)]);
    s
}

fn cavity() -> Stack {
    // A hole in sections 2..5 only: a closed void inside the solid.
    let mut s = Stack::new();
    run(&mut s, 2, &|z| vec![circle([0.0, 0.0], 2.0, z, 48)]);
    run(&mut s, 4, &|z| vec![circle([0.0, 0.0], 2.0, z, 48), circle([0.2, 0.1], 0.9, z, 24)]);
    run(&mut s, 2, &|z| vec![circle([0.0, 0.0], 2.0, z, 48)]);
    s
}

fn island_in_hole() -> Stack {
    // A tube with a bore; a rod inside the bore for a few sections.
    let mut s = Stack::new();
    run(&mut s, 2, &|z| vec![circle([0.0, 0.0], 3.0, z, 56), circle([0.0, 0.0], 2.0, z, 40)]);
    run(&mut s, 3, &|z| vec![circle([0.0, 0.0], 3.0, z, 56), circle([0.0, 0.0], 2.0, z, 40), circle([0.3, 0.0], 0.8, z, 20)]);
    run(&mut s, 2, &|z| vec![circle([0.0, 0.0], 3.0, z, 56), circle([0.0, 0.0], 2.0, z, 40)]);
    s
}

fn branch_at_the_bottom() -> Stack {
    let mut s = Stack::new();
    run(&mut s, 1, &|z| vec![ellipse([0.0, 0.0], 2.2, 1.0, 0.0, z, 48)]);
    run(&mut s, 4, &arms(&[[-1.2, 0.0], [1.2, 0.0]], 0.8, 32));
    s
}

fn merge_then_branch() -> Stack {
    let mut s = Stack::new();
    run(&mut s, 3, &arms(&[[-1.2, 0.0], [1.2, 0.0]], 0.8, 32));
    run(&mut s, 1, &|z| vec![ellipse([0.0, 0.0], 2.2, 1.0, 0.0, z, 48)]);
    run(&mut s, 3, &arms(&[[-1.2, 0.3], [1.2, -0.3]], 0.8, 30));
    s
}

/// Watertight and free of intersecting faces.
fn assert_clean(name: &str, m: &TriMesh) {
    let r = mint_mesh::check(&m.positions, &m.faces);
    assert!(r.watertight, "{name}: not watertight: {r:?}");
    let x = mint_mesh::selfx::self_intersections(&m.positions, &m.faces, 4);
    assert_eq!(x.pairs, 0, "{name}: intersecting faces {:?}", x.examples);
    assert!(r.signed_volume > 0.0, "{name}: volume {}", r.signed_volume);
}

fn both(name: &str, stack: &Stack) -> AngleStats {
    let (frame, s) = parse(&profile_text(stack));
    let mut m = TriMesh::default();
    let st = mc::reconstruct(frame, &s, McOptions { cubes: 48, caps: true, ..Default::default() }, &mut m).unwrap();
    assert_eq!(st.non_canonical_cells, 0, "{name} mc");
    assert_clean(&format!("{name} mc"), &m);
    let mut a = TriMesh::default();
    let st = angle::reconstruct(&s, AngleOptions { caps: true, ..Default::default() }, &mut a).unwrap();
    eprintln!("{name} angle: {st:?}");
    assert_clean(&format!("{name} angle"), &a);
    assert_eq!((st.paired, st.apart, st.isolated, st.forced_ears), (0, 0, 0, 0), "{name} angle");
    st
}

#[test]
fn one_contour_into_two() {
    let st = both("1->2", &one_to_two());
    assert_eq!((st.splits, st.bridged), (1, 0));
}

#[test]
fn two_contours_into_one() {
    let st = both("2->1", &two_to_one());
    assert_eq!((st.splits, st.bridged), (0, 1));
}

#[test]
fn two_contours_into_two_crossing_over() {
    let st = both("2->2", &two_to_two());
    assert_eq!((st.splits, st.bridged), (0, 1));
}

#[test]
fn one_contour_into_three() {
    let st = both("1->3", &one_to_three());
    assert_eq!(st.splits + st.bridged, 1);
}

#[test]
fn a_contour_appears_and_one_vanishes() {
    // Each contour has a bottom and a top cap.
    let st = both("appear", &appear());
    assert_eq!(st.caps, 4);
    let st = both("vanish", &vanish());
    assert_eq!(st.caps, 4);
}

#[test]
fn a_hole_opens_and_closes_into_a_cavity() {
    let st = both("cavity", &cavity());
    // Outer: bottom and top; hole: its own bottom and top.
    assert_eq!(st.caps, 4);
}

#[test]
fn an_island_inside_a_hole() {
    both("island", &island_in_hole());
}

#[test]
fn a_branch_at_the_first_section_is_bridged_above() {
    let st = both("bottom branch", &branch_at_the_bottom());
    assert_eq!((st.splits, st.bridged), (0, 1));
}

#[test]
fn a_merge_then_a_branch_at_the_same_contour() {
    let st = both("merge-branch", &merge_then_branch());
    assert_eq!((st.splits, st.bridged), (1, 1));
}

fn hole_splits() -> Stack {
    // A block with one bore that forks into two bores.
    let mut s = Stack::new();
    run(&mut s, 3, &|z| vec![circle([0.0, 0.0], 4.0, z, 64), ellipse([0.0, 0.0], 2.4, 1.0, 0.0, z, 48)]);
    run(&mut s, 3, &|z| vec![circle([0.0, 0.0], 4.0, z, 64), circle([-1.3, 0.0], 0.8, z, 28), circle([1.3, 0.0], 0.8, z, 28)]);
    s
}

#[test]
fn a_hole_forks_and_two_holes_join() {
    let st = both("hole fork", &hole_splits());
    assert_eq!((st.splits, st.bridged), (1, 0));
    let mut s = hole_splits();
    s.reverse();
    for (k, sec) in s.iter_mut().enumerate() {
        for c in sec.iter_mut() {
            for p in c.iter_mut() {
                p[2] = DZ * k as f64;
            }
        }
    }
    let st = both("hole join", &s);
    assert_eq!((st.splits, st.bridged), (0, 1));
}

/// A random stack of wobbly blobs: 1 to 3 per section, placed apart, some
/// with a hole, so that consecutive sections branch, merge, appear and
/// vanish in every combination.
fn random_blobs(seed: u64) -> Stack {
    let mut rng = super::util::Rng(seed);
    let sections = 4 + (rng.next_u64() % 6) as usize;
    let mut s = Stack::new();
    for k in 0..sections {
        let z = DZ * k as f64;
        let mut blobs: Vec<([f64; 2], f64)> = Vec::new();
        let want = 1 + (rng.next_u64() % 3) as usize;
        for _ in 0..20 {
            if blobs.len() == want {
                break;
            }
            let (c, r) = ([rng.range(-3.0, 3.0), rng.range(-3.0, 3.0)], rng.range(0.4, 1.8));
            if blobs.iter().all(|&(d, q)| (c[0] - d[0]).hypot(c[1] - d[1]) > 1.45 * (r + q) + 0.05) {
                blobs.push((c, r));
            }
        }
        let mut sec = Vec::new();
        for (c, r) in blobs {
            let n = 12 + (rng.next_u64() % 30) as usize;
            let (a, f, ph) = (rng.range(0.0, 0.35), 1.0 + (rng.next_u64() % 5) as f64, rng.range(0.0, 6.3));
            sec.push(
                (0..n)
                    .map(|i| {
                        let t = std::f64::consts::TAU * i as f64 / n as f64;
                        let rr = r * (1.0 + a * (f * t + ph).sin());
                        [c[0] + rr * t.cos(), c[1] + rr * t.sin(), z]
                    })
                    .collect(),
            );
            if r > 1.0 && rng.f64() < 0.3 {
                sec.push(circle([c[0] + rng.range(-0.1, 0.1), c[1]], 0.25 * r, z, 10));
            }
        }
        s.push(sec);
    }
    s
}

#[test]
fn random_blob_stacks_are_watertight_and_crossing_free() {
    let (mut paired, mut apart) = (0, 0);
    let seeds: u64 = std::env::var("MINT_BLOB_SEEDS").ok().and_then(|v| v.parse().ok()).unwrap_or(150);
    for seed in 0..seeds {
        let stack = random_blobs(seed);
        let (_, s) = parse(&profile_text(&stack));
        let mut a = TriMesh::default();
        let st = angle::reconstruct(&s, AngleOptions { caps: true, ..Default::default() }, &mut a).unwrap();
        if a.faces.is_empty() {
            continue;
        }
        assert_clean(&format!("blobs {seed} angle"), &a);
        paired += st.paired;
        apart += st.apart;
    }
    eprintln!("random blobs: {paired} groups paired, {apart} capped apart");
}

#[test]
fn two_bridges_in_one_plane_from_both_sides() {
    // One contour (capped below, so it cannot be split), two for one
    // section, one again: the two arms are bridged from below and from
    // above in the same plane, by bridges that must not touch.
    let mut s = Stack::new();
    run(&mut s, 1, &|z| vec![ellipse([0.0, 0.0], 2.2, 1.0, 0.0, z, 48)]);
    run(&mut s, 1, &arms(&[[-1.2, 0.0], [1.2, 0.0]], 0.8, 32));
    run(&mut s, 1, &|z| vec![ellipse([0.0, 0.0], 2.2, 1.0, 0.0, z, 44)]);
    let st = both("bridged twice", &s);
    assert_eq!((st.splits, st.bridged), (0, 2));
}

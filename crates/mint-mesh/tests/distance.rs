//! Sampled distances between known surfaces, and their independence from
//! the thread count.

mod shapes;

use mint_mesh::{distance, symmetric_distance, TriangleBvh};
use shapes::*;

#[test]
fn concentric_spheres_are_a_hundredth_apart_both_ways() {
    // Different tessellations, so no sample lands on a shared structure.
    let a = uv_sphere(1.0, 60, 120);
    let b = uv_sphere(1.01, 90, 170);
    let (ab, ba) = symmetric_distance((&a.0, &a.1), (&b.0, &b.1), 20_000, 42);
    for r in [&ab, &ba] {
        assert_eq!(r.samples, 20_000);
        assert!((r.mean / 0.01 - 1.0).abs() < 0.1, "mean {}", r.mean);
        assert!((r.rms / 0.01 - 1.0).abs() < 0.1, "rms {}", r.rms);
        assert!(r.max > 0.009 && r.max < 0.012, "max {}", r.max);
        assert!(r.mean <= r.rms && r.rms <= r.max);
    }
    // Relative to B's bbox diagonal: 2r·√3.
    assert!((ab.bbox_diagonal - 2.0 * 1.01 * 3f64.sqrt()).abs() < 1e-3);
    assert!((ab.mean_rel - ab.mean / ab.bbox_diagonal).abs() < 1e-15);
    assert!((ba.bbox_diagonal - 2.0 * 3f64.sqrt()).abs() < 1e-3);
    // Sampled area is the polyhedron's, a little under 4πr².
    let area = 4.0 * std::f64::consts::PI;
    assert!(ab.area_sampled < area && ab.area_sampled > 0.99 * area);
}

#[test]
fn a_mesh_is_at_distance_zero_from_itself() {
    let a = torus(2.0, 0.5, 40, 20);
    let r = distance((&a.0, &a.1), (&a.0, &a.1), 5_000, 3);
    assert!(r.max < 1e-12, "max {}", r.max);
}

#[test]
fn same_result_under_every_thread_count_and_seed_matters() {
    let a = uv_sphere(1.0, 40, 80);
    let b = torus(0.8, 0.4, 60, 30);
    let run = |threads: usize, seed: u64| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| distance((&a.0, &a.1), (&b.0, &b.1), 10_000, seed))
    };
    let r1 = run(1, 7);
    assert_eq!(r1, run(2, 7));
    assert_eq!(r1, run(3, 7));
    assert_ne!(r1.mean, run(2, 8).mean);
}

#[test]
fn bvh_nearest_agrees_with_brute_force_on_a_sphere() {
    let m = uv_sphere(1.0, 30, 60);
    let bvh = TriangleBvh::new(&m.0, &m.1).unwrap();
    let mut s = mint_mesh::SplitMix64::new(5);
    for _ in 0..300 {
        let p: [f64; 3] = std::array::from_fn(|_| s.next_f64() * 4.0 - 2.0);
        let (d, q, id) = bvh.nearest(p);
        let brute =
            m.1.iter()
                .map(|f| {
                    let [a, b, c] = f.map(|i| m.0[i as usize]);
                    let q = mint_mesh::closest_point_on_triangle(p, a, b, c);
                    ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt()
                })
                .fold(f64::INFINITY, f64::min);
        assert_eq!(d, brute);
        let f = m.1[id as usize].map(|i| m.0[i as usize]);
        assert_eq!(mint_mesh::closest_point_on_triangle(p, f[0], f[1], f[2]), q);
    }
}

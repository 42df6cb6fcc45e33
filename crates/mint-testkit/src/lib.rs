//! Generators and checkers shared by mint's tests.
//!
//! - [`hull`]: random convex polyhedra (an incremental convex hull with exact
//!   visibility tests), for property tests of the resampler;
//! - [`topology`]: a strict, self-contained checker of closed oriented
//!   2-manifolds (half-edges, vertex fans, zero-area faces, volume), written
//!   independently of mint-mesh so the two can check each other;
//! - [`Rng`]: a tiny deterministic PRNG.
//! - [`shared_data`]: the path of `../shared/data`, or a skip message.
//! - [`flat_grid`]: an n×n grid of unit squares, an open mesh with a known
//!   boundary, for mesh-surgery tests.

pub mod hull;
pub mod topology;

/// SplitMix64: small, deterministic, good enough for test inputs.
#[derive(Debug, Clone)]
pub struct Rng(pub u64);

impl Rng {
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E3779B97F4A7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58476D1CE4E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D049BB133111EB);
        z ^ (z >> 31)
    }
    /// Uniform in [0, 1).
    pub fn f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.f64()
    }
}

/// The shared real-data folder (`../shared/data` beside the project root), or
/// `None` after printing why tests that need it are skipped.
pub fn shared_data() -> Option<std::path::PathBuf> {
    let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data");
    if p.is_dir() {
        Some(p.canonicalize().unwrap_or(p))
    } else {
        if std::env::var_os("MINT_REQUIRE_DATA").is_some_and(|v| v != "0") {
            panic!("MINT_REQUIRE_DATA is set (CI) but the real-data folder {} is absent", p.display());
        }
        eprintln!("skipping: real-data folder {} is absent (set MINT_REQUIRE_DATA=1 to make this an error)", p.display());
        None
    }
}

/// An n×n grid of unit squares in the plane z = 0, two triangles each
/// (2 n² faces, (n + 1)² vertices, row-major), facing +z.
pub fn flat_grid(n: u32) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
    let mut p = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            p.push([i as f64, j as f64, 0.0]);
        }
    }
    let id = |i: u32, j: u32| j * (n + 1) + i;
    let mut f = Vec::new();
    for j in 0..n {
        for i in 0..n {
            f.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            f.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    (p, f)
}

//! A strict checker of closed, oriented 2-manifold triangle meshes, kept
//! deliberately simple (hash maps, no cleverness) so it can serve as an
//! independent oracle in tests. Degenerate faces count as failures.

use mint_core::TriMesh;
use std::collections::HashMap;

/// What a successful check measured.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClosedStats {
    pub vertices_used: usize,
    pub faces: usize,
    pub components: usize,
    pub euler: i64,
    /// Sum over components of (2 − χ_c) / 2.
    pub genus: i64,
    pub volume: f64,
    pub min_area: f64,
}

/// Checks that `m` is closed, edge- and vertex-manifold, consistently
/// oriented, with no repeated index and no zero-area face. Returns the first
/// violation as a message.
pub fn check_closed_oriented(m: &TriMesh) -> Result<ClosedStats, String> {
    let mut half: HashMap<(u32, u32), u32> = HashMap::new();
    let mut min_area = f64::INFINITY;
    let mut volume = 0.0;
    for (fi, f) in m.faces.iter().enumerate() {
        if f[0] == f[1] || f[1] == f[2] || f[0] == f[2] {
            return Err(format!("face {fi} repeats a vertex: {f:?}"));
        }
        let [a, b, c] = f.map(|i| m.positions[i as usize]);
        let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
        let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
        let n = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]];
        let area = 0.5 * (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        if area == 0.0 {
            return Err(format!("face {fi} has zero area"));
        }
        min_area = min_area.min(area);
        volume += (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) + a[2] * (b[0] * c[1] - b[1] * c[0])) / 6.0;
        for k in 0..3 {
            if half.insert((f[k], f[(k + 1) % 3]), fi as u32).is_some() {
                return Err(format!("half-edge {}->{} used twice (non-manifold or misoriented)", f[k], f[(k + 1) % 3]));
            }
        }
    }
    for &(a, b) in half.keys() {
        if !half.contains_key(&(b, a)) {
            return Err(format!("edge {a}-{b} is on the boundary"));
        }
    }
    // Vertex manifoldness: around each vertex, the faces form one cycle.
    let mut out_of: HashMap<u32, Vec<(u32, u32)>> = HashMap::new(); // v -> (next, prev) per face
    for f in &m.faces {
        for k in 0..3 {
            out_of.entry(f[k]).or_default().push((f[(k + 1) % 3], f[(k + 2) % 3]));
        }
    }
    for (v, fan) in &out_of {
        let next: HashMap<u32, u32> = fan.iter().copied().collect();
        if next.len() != fan.len() {
            return Err(format!("vertex {v}: fan is not simple"));
        }
        let start = fan[0].0;
        let mut x = start;
        let mut steps = 0;
        loop {
            x = *next.get(&x).ok_or_else(|| format!("vertex {v}: open fan"))?;
            steps += 1;
            if x == start || steps > fan.len() {
                break;
            }
        }
        if steps != fan.len() {
            return Err(format!("vertex {v}: {} faces form more than one fan (non-manifold vertex)", fan.len()));
        }
    }
    // Components through shared vertices.
    let nv = m.positions.len();
    let mut parent: Vec<usize> = (0..nv).collect();
    fn find(p: &mut [usize], mut x: usize) -> usize {
        while p[x] != x {
            p[x] = p[p[x]];
            x = p[x];
        }
        x
    }
    for f in &m.faces {
        for k in 1..3 {
            let (a, b) = (find(&mut parent, f[0] as usize), find(&mut parent, f[k] as usize));
            parent[a] = b;
        }
    }
    let used: Vec<usize> = out_of.keys().map(|&v| v as usize).collect();
    let mut roots = std::collections::HashSet::new();
    for &v in &used {
        roots.insert(find(&mut parent, v));
    }
    let e = half.len() as i64 / 2;
    let euler = used.len() as i64 - e + m.faces.len() as i64;
    let components = roots.len();
    Ok(ClosedStats {
        vertices_used: used.len(),
        faces: m.faces.len(),
        components,
        euler,
        genus: (2 * components as i64 - euler) / 2,
        volume,
        min_area: if m.faces.is_empty() { 0.0 } else { min_area },
    })
}

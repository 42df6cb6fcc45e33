//! A scan-like mesh with known defects: [`scan_like()`] streams a noisy UV
//! sphere (the numbering of [`mod@crate::sphere`]) with holes, flipped faces,
//! duplicated patches and non-manifold slivers, and returns
//! [`ScanDefects`]: where each defect is and the exact totals
//! `mint_mesh::check` must report ([`ExpectedCheck`]).
//!
//! Surface: every sphere vertex in unit direction `u` sits at radius
//! `radius·(1 + noise_amplitude·n(u))`, `n` a sum of four random smooth
//! waves ([`ScanSurface`], seeded). Defects are placed on *sites*: the
//! band of quad rows with polar angle in about `[30°, 150°]` is cut into
//! equal rectangular slots of quads, each big enough for the largest defect
//! plus a margin of [`MARGIN`] quads on every side, and the seed picks
//! distinct slots (Floyd's sampling, then a shuffle), holes first, then
//! flips, patches, slivers. Defects are therefore at least `2·MARGIN` quads apart and away
//! from the poles and the `φ = 0` seam, which is what makes their effect on
//! the counts exact:
//!
//! - **Hole**: a digital disk of quads removed around a centre vertex
//!   `(i0, j0)`: quad row `q` loses columns `j0-h_q .. j0+h_q-1` with
//!   `h_q = round(√(ρ² - δ_q²) / (Δφ sin θ0))`, `δ_q` the polar offset of
//!   the row's middle and `ρ = hole_radius` (the two middle rows keep
//!   `h ≥ 1`). The rows' column ranges are nested and centred, so the hole
//!   is a simply connected, orthogonally convex polyomino without pinches:
//!   its rim is one simple loop of `2·rows + 2·h_top + 2·h_bottom +
//!   Σ 2|h_q - h_(q+1)|` edges. Vertices left inside the hole are not
//!   emitted (later indices shift down), so no vertex is unreferenced.
//! - **Flipped face**: the first triangle `(a,c,d)` of quad `(i0, j0)` is
//!   written `(a,d,c)`: 3 inconsistently oriented edges.
//! - **Duplicated patch**: the `P × P` quads around `(i0, j0)` copied with
//!   `(P+1)²` new vertices pushed out by `patch_offset·radius` along the
//!   radial direction: a separate open component, one boundary loop of
//!   `4P` edges.
//! - **Sliver**: an extra triangle `(a, d, n)` on the interior diagonal
//!   `a–d` of quad `(i0, j0)`, `n` a new vertex at the diagonal's midpoint
//!   pushed out by `sliver_height·radius`: one non-manifold edge (used three
//!   times) and two boundary edges that form no loop (their ends `a` and
//!   `d` are not simple boundary vertices), no non-manifold vertex.
//!
//! Output order: sphere vertices (hole interiors skipped), sliver apexes,
//! patch vertices; sphere faces (north fan, bands, south fan, hole quads
//! skipped), sliver faces, patch faces. Memory is `O(rings + segments +
//! defects)`.

use glam::DVec3;
use crate::error::GenError;
use crate::rng::SplitMix64;
use crate::sphere::{SphereGrid, TrigTables};
use crate::surface::{ScanSurface, Wave};
use crate::{check_vertex_count, finite3, positive};
use mint_core::MeshSink;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// Quads of clearance kept around every defect inside its slot.
pub const MARGIN: u32 = 2;

/// What to damage and how. Every field has a documented default
/// ([`ScanOptions::default`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct ScanOptions {
    /// Number of holes. Default 6.
    pub holes: u32,
    /// Number of flipped faces. Default 6.
    pub flips: u32,
    /// Number of duplicated patches. Default 3.
    pub patches: u32,
    /// Number of non-manifold slivers. Default 3.
    pub slivers: u32,
    /// Geodesic radius of a hole as a fraction of `radius` (an angle in
    /// radians), in `(0, 1]`. At least a 2×2 block of quads is removed
    /// whatever the resolution. Default 0.06.
    pub hole_radius: f64,
    /// Radial noise amplitude as a fraction of `radius`, in `[0, 0.25]`.
    /// Default 0.01.
    pub noise_amplitude: f64,
    /// Side of a duplicated patch in quads, in `1..=64`. Default 3.
    pub patch_size: u32,
    /// Outward offset of a patch copy as a fraction of `radius`, in
    /// `[0, 0.1]`. Default 0.003.
    pub patch_offset: f64,
    /// Outward height of a sliver's new vertex as a fraction of `radius`, in
    /// `(0, 0.1]`. Default 0.002.
    pub sliver_height: f64,
    /// Sphere radius. Default 1.
    pub radius: f64,
    /// Sphere centre. Default the origin.
    pub center: [f64; 3],
}

impl Default for ScanOptions {
    fn default() -> Self {
        Self {
            holes: 6,
            flips: 6,
            patches: 3,
            slivers: 3,
            hole_radius: 0.06,
            noise_amplitude: 0.01,
            patch_size: 3,
            patch_offset: 0.003,
            sliver_height: 0.002,
            radius: 1.0,
            center: [0.0; 3],
        }
    }
}

/// A removed disk of faces.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Hole {
    /// The surface point at the hole's centre vertex (which is removed).
    pub centre: [f64; 3],
    /// Geodesic radius in model units (`hole_radius · radius`).
    pub radius: f64,
    /// Edges on the hole's rim: one simple boundary loop.
    pub boundary_edges: u64,
    /// Faces removed.
    pub faces_removed: u64,
    /// Vertices inside the hole, not emitted.
    pub vertices_removed: u64,
}

/// A duplicated patch: a separate open component.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Patch {
    /// Index of its first face in the output.
    pub first_face: u64,
    /// Faces, `2·P²`.
    pub faces: u64,
    /// Index of its first vertex in the output.
    pub first_vertex: u64,
    /// Vertices, `(P+1)²`.
    pub vertices: u64,
}

/// An extra triangle hung on an interior edge.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Sliver {
    /// Index of the sliver face in the output.
    pub face: u64,
    /// The interior edge it shares (now non-manifold).
    pub edge: [u32; 2],
    /// Its new vertex.
    pub apex: u32,
}

/// How many defects of each kind were made.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct DefectCounts {
    pub holes: u64,
    pub flipped_faces: u64,
    pub duplicated_patches: u64,
    pub slivers: u64,
}

/// The values `mint_mesh::check` must report for the mesh, exactly.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct ExpectedCheck {
    pub vertices: u64,
    pub faces: u64,
    pub unreferenced_vertices: u64,
    pub components: u64,
    pub boundary_edges: u64,
    pub boundary_loops: u64,
    pub non_simple_boundary_edges: u64,
    pub non_manifold_edges: u64,
    pub non_manifold_vertices: u64,
    pub inconsistently_oriented_edges: u64,
    pub degenerate_faces: u64,
    pub duplicate_faces: u64,
    /// Closed components: the sphere itself when no hole, flip or sliver
    /// touches it (patches are separate), each of genus 0.
    pub closed_components: u64,
    pub watertight: bool,
}

/// The sidecar of a [`scan_like()`] mesh: inputs, the surface, every defect
/// and the expected check totals. Serialises to JSON for files beside the
/// mesh.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ScanDefects {
    pub seed: u64,
    pub target_faces: u64,
    pub options: ScanOptions,
    /// Resolution of the underlying sphere (`rings`, `segments`).
    pub rings: u32,
    pub segments: u32,
    pub surface: ScanSurface,
    pub counts: DefectCounts,
    pub holes: Vec<Hole>,
    /// Output indices of the flipped faces.
    pub flipped_faces: Vec<u64>,
    pub duplicated_patches: Vec<Patch>,
    pub slivers: Vec<Sliver>,
    pub expected: ExpectedCheck,
}

/// Streams a scan-like mesh: the noisy sphere of about `target_faces` faces
/// (resolution from [`SphereGrid::for_faces`]) with the defects of `opts`
/// placed by `seed`; each default hole removes about 0.1% of the faces and
/// patches and slivers add a few dozen, so the default options land about
/// 0.4% under the target (exact counts in [`ExpectedCheck`]). With default
/// options the smallest workable target is about 6,000 faces. See the
/// module docs for the construction.
///
/// Errors: [`GenError::InvalidParameter`] for options out of range,
/// [`GenError::TooSmallForDefects`] when the defects cannot be kept apart
/// on a mesh this size, and sink errors.
pub fn scan_like(
    target_faces: u64,
    seed: u64,
    opts: &ScanOptions,
    sink: &mut dyn MeshSink,
) -> Result<ScanDefects, GenError> {
    validate(opts)?;
    let grid = SphereGrid::for_faces(target_faces);
    grid.validate()?;
    let surface = noise_surface(seed, opts);
    let plan = Plan::new(&grid, target_faces, seed, opts)?;
    let layout = Layout::new(&grid, &plan);
    check_vertex_count(layout.total_vertices(&plan, opts))?;
    let geo = Geometry {
        grid,
        tables: TrigTables::new(&grid),
        surface: &surface,
    };
    emit(&geo, &plan, &layout, opts, sink, target_faces, seed)
}

fn validate(o: &ScanOptions) -> Result<(), GenError> {
    positive("radius", o.radius)?;
    finite3("center", o.center)?;
    let range = |name: &'static str, x: f64, lo: f64, hi: f64, open_lo: bool| {
        let ok = x.is_finite() && x <= hi && if open_lo { x > lo } else { x >= lo };
        if ok {
            Ok(())
        } else {
            let l = if open_lo { "(" } else { "[" };
            Err(GenError::InvalidParameter {
                name,
                reason: format!("{x} is outside {l}{lo}, {hi}]"),
            })
        }
    };
    range("hole_radius", o.hole_radius, 0.0, 1.0, true)?;
    range("noise_amplitude", o.noise_amplitude, 0.0, 0.25, false)?;
    range("patch_offset", o.patch_offset, 0.0, 0.1, false)?;
    range("sliver_height", o.sliver_height, 0.0, 0.1, true)?;
    if !(1..=64).contains(&o.patch_size) {
        return Err(GenError::InvalidParameter {
            name: "patch_size",
            reason: format!("{} is outside 1..=64", o.patch_size),
        });
    }
    Ok(())
}

/// Four waves with random directions, frequencies in `[2, 5)` and phases.
fn noise_surface(seed: u64, o: &ScanOptions) -> ScanSurface {
    let mut rng = SplitMix64::for_stream(seed, 0x5CA7);
    let waves = (0..4)
        .map(|_| {
            let z = 2.0 * rng.next_f64() - 1.0;
            let phi = 2.0 * PI * rng.next_f64();
            let s = (1.0 - z * z).sqrt();
            let f = 2.0 + 3.0 * rng.next_f64();
            Wave {
                k: [f * s * phi.cos(), f * s * phi.sin(), f * z],
                phase: 2.0 * PI * rng.next_f64(),
            }
        })
        .collect();
    ScanSurface {
        center: o.center,
        radius: o.radius,
        amplitude: o.noise_amplitude,
        waves,
    }
}

/// A hole: centre vertex and the half-width of each of its quad rows.
struct HolePlan {
    i0: u32,
    j0: u32,
    /// `(quad row, h)`, consecutive rows, `h ≥ 1`; row `q` loses columns
    /// `j0-h .. j0+h-1`.
    rows: Vec<(u32, u32)>,
}

impl HolePlan {
    fn boundary_edges(&self) -> u64 {
        let h: Vec<u64> = self.rows.iter().map(|r| u64::from(r.1)).collect();
        let steps: u64 = h.windows(2).map(|w| 2 * w[0].abs_diff(w[1])).sum();
        2 * h.len() as u64 + 2 * h[0] + 2 * h[h.len() - 1] + steps
    }

    fn faces_removed(&self) -> u64 {
        self.rows.iter().map(|r| 4 * u64::from(r.1)).sum()
    }

    /// `(vertex row, first col, last col)` of the interior vertices: those
    /// between two hole rows, inside both rows' ranges.
    fn removed_vertices(&self) -> impl Iterator<Item = (u32, u32, u32)> + '_ {
        self.rows.windows(2).map(|w| {
            let h = w[0].1.min(w[1].1);
            (w[1].0, self.j0 + 1 - h, self.j0 + h - 1)
        })
    }
}

/// Where every defect goes.
struct Plan {
    holes: Vec<HolePlan>,
    /// Quad `(i0, j0)` of each flip, sliver and (centre of each) patch.
    flips: Vec<(u32, u32)>,
    patches: Vec<(u32, u32)>,
    slivers: Vec<(u32, u32)>,
    patch_size: u32,
}

impl Plan {
    fn new(grid: &SphereGrid, target: u64, seed: u64, o: &ScanOptions) -> Result<Self, GenError> {
        let (nr, ns) = (grid.rings, grid.segments);
        let dtheta = PI / f64::from(nr);
        let dphi = 2.0 * PI / f64::from(ns);
        let rho = o.hole_radius;
        // Usable band of quad rows, polar angle about 30°..150°.
        let row_lo = nr.div_ceil(6).max(2);
        let row_hi = nr.saturating_sub(row_lo);
        let sin_min = (f64::from(row_lo) * dtheta).sin();
        // Largest hole extents anywhere in the band.
        let k_rows = ((rho / dtheta + 0.5).ceil() as u32).max(1);
        let h_max = ((rho / (dphi * sin_min) + 0.5).floor() as u32).max(1);
        let p = o.patch_size;
        let (mut need_r, mut need_c) = (p.max(1), p.max(1));
        if o.holes > 0 {
            need_r = need_r.max(2 * k_rows);
            need_c = need_c.max(2 * h_max);
        }
        let (sr, sc) = (need_r + 2 * MARGIN + 1, need_c + 2 * MARGIN + 1);
        let slot_rows = row_hi.saturating_sub(row_lo) / sr;
        let slot_cols = ns.saturating_sub(2) / sc;
        let available = u64::from(slot_rows) * u64::from(slot_cols);
        let needed =
            u64::from(o.holes) + u64::from(o.flips) + u64::from(o.patches) + u64::from(o.slivers);
        if needed > available {
            return Err(GenError::TooSmallForDefects {
                target_faces: target,
                needed,
                available,
            });
        }
        // Floyd's sampling of `needed` distinct slots out of `available`
        // (memory O(needed)), then a Fisher-Yates shuffle so the kinds of
        // defect are spread at random over them.
        let mut rng = SplitMix64::for_stream(seed, 0x51075);
        let mut chosen = std::collections::BTreeSet::new();
        for j in available - needed..available {
            let t = rng.below(j + 1);
            if !chosen.insert(t) {
                chosen.insert(j);
            }
        }
        let mut slots: Vec<u32> = chosen.into_iter().map(|s| s as u32).collect();
        for i in (1..slots.len()).rev() {
            let j = rng.below(i as u64 + 1) as usize;
            slots.swap(i, j);
        }
        let anchor = |s: u32| {
            let (r, c) = (s / slot_cols, s % slot_cols);
            (row_lo + r * sr + sr / 2, 1 + c * sc + sc / 2)
        };
        let mut picks = slots.iter().map(|&s| anchor(s));
        let mut take = |n: u32| -> Vec<(u32, u32)> { picks.by_ref().take(n as usize).collect() };
        let hole_sites = take(o.holes);
        let flips = take(o.flips);
        let patches = take(o.patches);
        let slivers = take(o.slivers);
        let holes = hole_sites
            .into_iter()
            .map(|(i0, j0)| {
                let sin0 = (f64::from(i0) * dtheta).sin();
                let rows = (i0 - k_rows..i0 + k_rows)
                    .filter_map(|q| {
                        let delta = (f64::from(q) + 0.5 - f64::from(i0)) * dtheta;
                        let mut h = if delta.abs() <= rho {
                            ((rho * rho - delta * delta).sqrt() / (dphi * sin0) + 0.5).floor()
                                as u32
                        } else {
                            0
                        };
                        if q + 1 == i0 || q == i0 {
                            h = h.max(1);
                        }
                        (h > 0).then_some((q, h.min(h_max)))
                    })
                    .collect();
                HolePlan { i0, j0, rows }
            })
            .collect();
        Ok(Plan {
            holes,
            flips,
            patches,
            slivers,
            patch_size: p,
        })
    }
}

/// Per-row tables of what is missing or changed, and where each vertex row
/// starts in the output numbering.
struct Layout {
    rings: u32,
    segments: u32,
    /// Per vertex row: removed column ranges (inclusive), sorted.
    vskip: Vec<Vec<(u32, u32)>>,
    /// Per quad row: removed column ranges (inclusive).
    qremove: Vec<Vec<(u32, u32)>>,
    /// Per quad row: columns whose first triangle is flipped.
    qflip: Vec<Vec<u32>>,
    /// Output index of the first vertex of each vertex row (`rings + 1`
    /// entries; the last is the south pole).
    base: Vec<u32>,
}

impl Layout {
    fn new(grid: &SphereGrid, plan: &Plan) -> Self {
        let (nr, ns) = (grid.rings as usize, grid.segments);
        let mut vskip = vec![Vec::new(); nr + 1];
        let mut qremove = vec![Vec::new(); nr];
        let mut qflip = vec![Vec::new(); nr];
        for h in &plan.holes {
            for &(q, w) in &h.rows {
                qremove[q as usize].push((h.j0 - w, h.j0 + w - 1));
            }
            for (r, lo, hi) in h.removed_vertices() {
                vskip[r as usize].push((lo, hi));
            }
        }
        for v in vskip.iter_mut().chain(qremove.iter_mut()) {
            v.sort_unstable();
        }
        for &(i, j) in &plan.flips {
            qflip[i as usize].push(j);
        }
        let mut base = vec![0u32; nr + 1];
        base[1] = 1;
        for r in 1..nr {
            let removed: u32 = vskip[r].iter().map(|&(lo, hi)| hi - lo + 1).sum();
            base[r + 1] = base[r] + ns - removed;
        }
        Layout {
            rings: grid.rings,
            segments: ns,
            vskip,
            qremove,
            qflip,
            base,
        }
    }

    /// Sphere vertices actually emitted (poles included).
    fn sphere_vertices(&self) -> u32 {
        self.base[self.rings as usize] + 1
    }

    fn total_vertices(&self, plan: &Plan, o: &ScanOptions) -> u64 {
        let p = u64::from(o.patch_size);
        u64::from(self.sphere_vertices())
            + plan.slivers.len() as u64
            + plan.patches.len() as u64 * (p + 1) * (p + 1)
    }

    /// Output index of sphere vertex `(r, j)`, `j` modulo `segments`.
    #[inline]
    fn index(&self, r: u32, j: u32) -> u32 {
        if r == 0 {
            return 0;
        }
        if r == self.rings {
            return self.base[r as usize];
        }
        let j = if j >= self.segments {
            j - self.segments
        } else {
            j
        };
        let mut i = self.base[r as usize] + j;
        for &(lo, hi) in &self.vskip[r as usize] {
            if j > hi {
                i -= hi - lo + 1;
            } else {
                debug_assert!(j < lo, "vertex ({r}, {j}) is inside a hole");
            }
        }
        i
    }
}

/// Everything needed to place a sphere vertex.
struct Geometry<'a> {
    grid: SphereGrid,
    tables: TrigTables,
    surface: &'a ScanSurface,
}

impl Geometry<'_> {
    /// Unit direction of sphere vertex `(r, j)`.
    #[inline]
    fn dir(&self, r: u32, j: u32) -> [f64; 3] {
        if r == 0 {
            return [0.0, 0.0, 1.0];
        }
        if r == self.grid.rings {
            return [0.0, 0.0, -1.0];
        }
        let (st, ct) = self.tables.rings[r as usize - 1];
        let (cp, sp) = self.tables.segments[(j % self.grid.segments) as usize];
        [st * cp, st * sp, ct]
    }

    /// Position on the noisy surface in direction `u`, pushed out by `extra`.
    #[inline]
    fn at(&self, u: [f64; 3], extra: f64) -> [f64; 3] {
        let s = self.surface;
        let r = s.radius_at(u) + extra;
        [
            s.center[0] + r * u[0],
            s.center[1] + r * u[1],
            s.center[2] + r * u[2],
        ]
    }
}

fn emit(
    geo: &Geometry,
    plan: &Plan,
    lay: &Layout,
    o: &ScanOptions,
    sink: &mut dyn MeshSink,
    target_faces: u64,
    seed: u64,
) -> Result<ScanDefects, GenError> {
    let (nr, ns) = (lay.rings, lay.segments);
    let p = plan.patch_size;

    // Vertices: sphere (hole interiors skipped), sliver apexes, patches.
    sink.vertex(geo.at(geo.dir(0, 0), 0.0))?;
    for r in 1..nr {
        let skips = &lay.vskip[r as usize];
        for j in 0..ns {
            if !skips.is_empty() && skips.iter().any(|&(lo, hi)| j >= lo && j <= hi) {
                continue;
            }
            sink.vertex(geo.at(geo.dir(r, j), 0.0))?;
        }
    }
    sink.vertex(geo.at(geo.dir(nr, 0), 0.0))?;
    let mut next_vertex = u64::from(lay.sphere_vertices());
    let apex_base = next_vertex as u32;
    for &(i, j) in &plan.slivers {
        let a = geo.at(geo.dir(i, j), 0.0);
        let d = geo.at(geo.dir(i + 1, j + 1), 0.0);
        let mid: [f64; 3] = std::array::from_fn(|k| 0.5 * (a[k] + d[k]));
        let out = (DVec3::from(mid) - DVec3::from(o.center)).to_array();
        let len = DVec3::from(out).length();
        let h = o.sliver_height * o.radius / len;
        sink.vertex(std::array::from_fn(|k| mid[k] + h * out[k]))?;
        next_vertex += 1;
    }
    let patch_base = next_vertex;
    let extra = o.patch_offset * o.radius;
    for &(i, j) in &plan.patches {
        let (r0, c0) = (i - p / 2, j - p / 2);
        for r in r0..=r0 + p {
            for c in c0..=c0 + p {
                sink.vertex(geo.at(geo.dir(r, c), extra))?;
            }
        }
    }

    // Sphere faces.
    let mut face = 0u64;
    let mut flipped = Vec::new();
    let b1 = lay.base[1];
    for j in 0..ns {
        let jn = if j + 1 == ns { 0 } else { j + 1 };
        sink.face([0, b1 + j, b1 + jn])?;
    }
    face += u64::from(ns);
    for q in 1..nr - 1 {
        let qi = q as usize;
        let plain = lay.qremove[qi].is_empty()
            && lay.qflip[qi].is_empty()
            && lay.vskip[qi].is_empty()
            && lay.vskip[qi + 1].is_empty();
        if plain {
            let (top, bot) = (lay.base[qi], lay.base[qi + 1]);
            for j in 0..ns {
                let jn = if j + 1 == ns { 0 } else { j + 1 };
                let (a, b, c, d) = (top + j, top + jn, bot + j, bot + jn);
                sink.face([a, c, d])?;
                sink.face([a, d, b])?;
            }
            face += 2 * u64::from(ns);
            continue;
        }
        for j in 0..ns {
            if lay.qremove[qi].iter().any(|&(lo, hi)| j >= lo && j <= hi) {
                continue;
            }
            let (a, b) = (lay.index(q, j), lay.index(q, j + 1));
            let (c, d) = (lay.index(q + 1, j), lay.index(q + 1, j + 1));
            if lay.qflip[qi].contains(&j) {
                flipped.push(face);
                sink.face([a, d, c])?;
            } else {
                sink.face([a, c, d])?;
            }
            sink.face([a, d, b])?;
            face += 2;
        }
    }
    let (last, south) = (lay.base[nr as usize - 1], lay.base[nr as usize]);
    for j in 0..ns {
        let jn = if j + 1 == ns { 0 } else { j + 1 };
        sink.face([south, last + jn, last + j])?;
    }
    face += u64::from(ns);

    // Slivers, then patches.
    let mut slivers = Vec::new();
    for (s, &(i, j)) in plan.slivers.iter().enumerate() {
        let (a, d) = (lay.index(i, j), lay.index(i + 1, j + 1));
        let apex = apex_base + s as u32;
        sink.face([a, d, apex])?;
        slivers.push(Sliver {
            face,
            edge: [a, d],
            apex,
        });
        face += 1;
    }
    let mut patches = Vec::new();
    let w = p + 1;
    for (n, _) in plan.patches.iter().enumerate() {
        let vb = (patch_base + n as u64 * u64::from(w * w)) as u32;
        let first_face = face;
        for r in 0..p {
            for c in 0..p {
                let (a, b) = (vb + r * w + c, vb + r * w + c + 1);
                let (cc, d) = (a + w, b + w);
                sink.face([a, cc, d])?;
                sink.face([a, d, b])?;
                face += 2;
            }
        }
        patches.push(Patch {
            first_face,
            faces: 2 * u64::from(p * p),
            first_vertex: u64::from(vb),
            vertices: u64::from(w * w),
        });
    }

    // The sidecar.
    let holes: Vec<Hole> = plan
        .holes
        .iter()
        .map(|h| Hole {
            centre: geo.at(geo.dir(h.i0, h.j0), 0.0),
            radius: o.hole_radius * o.radius,
            boundary_edges: h.boundary_edges(),
            faces_removed: h.faces_removed(),
            vertices_removed: h
                .removed_vertices()
                .map(|(_, lo, hi)| u64::from(hi - lo + 1))
                .sum(),
        })
        .collect();
    let counts = DefectCounts {
        holes: holes.len() as u64,
        flipped_faces: flipped.len() as u64,
        duplicated_patches: patches.len() as u64,
        slivers: slivers.len() as u64,
    };
    let pp = u64::from(p);
    let sphere_touched = counts.holes + counts.flipped_faces + counts.slivers > 0;
    let expected = ExpectedCheck {
        vertices: next_vertex + counts.duplicated_patches * (pp + 1) * (pp + 1),
        faces: face,
        unreferenced_vertices: 0,
        components: 1 + counts.duplicated_patches,
        boundary_edges: holes.iter().map(|h| h.boundary_edges).sum::<u64>()
            + counts.duplicated_patches * 4 * pp
            + 2 * counts.slivers,
        boundary_loops: counts.holes + counts.duplicated_patches,
        non_simple_boundary_edges: 2 * counts.slivers,
        non_manifold_edges: counts.slivers,
        non_manifold_vertices: 0,
        inconsistently_oriented_edges: 3 * counts.flipped_faces,
        degenerate_faces: 0,
        duplicate_faces: 0,
        closed_components: u64::from(!sphere_touched),
        watertight: !sphere_touched && counts.duplicated_patches == 0,
    };
    Ok(ScanDefects {
        seed,
        target_faces,
        options: o.clone(),
        rings: nr,
        segments: ns,
        surface: geo.surface.clone(),
        counts,
        holes,
        flipped_faces: flipped,
        duplicated_patches: patches,
        slivers,
        expected,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use mint_core::TriMesh;

    #[test]
    fn a_single_small_hole_has_the_rim_of_its_polyomino() {
        let o = ScanOptions {
            holes: 1,
            flips: 0,
            patches: 0,
            slivers: 0,
            ..ScanOptions::default()
        };
        let mut m = TriMesh::default();
        let d = scan_like(20_000, 1, &o, &mut m).unwrap();
        let h = &d.holes[0];
        // Rim edges = 2·(rows + widest row width) for a nested, centred disk.
        let plan = Plan::new(&SphereGrid::for_faces(20_000), 20_000, 1, &o).unwrap();
        let rows = plan.holes[0].rows.len() as u64;
        let widest = plan.holes[0]
            .rows
            .iter()
            .map(|r| 2 * u64::from(r.1))
            .max()
            .unwrap();
        assert_eq!(h.boundary_edges, 2 * (rows + widest));
        assert_eq!(d.expected.faces, m.faces.len() as u64);
        assert_eq!(d.expected.vertices, m.positions.len() as u64);
        assert_eq!(
            m.faces.len() as u64,
            SphereGrid::for_faces(20_000).faces() - h.faces_removed
        );
    }

    #[test]
    fn no_defects_is_a_plain_noisy_sphere() {
        let o = ScanOptions {
            holes: 0,
            flips: 0,
            patches: 0,
            slivers: 0,
            ..ScanOptions::default()
        };
        let mut m = TriMesh::default();
        let d = scan_like(1000, 3, &o, &mut m).unwrap();
        assert!(d.expected.watertight);
        assert_eq!(d.expected.closed_components, 1);
        for p in &m.positions {
            assert!(d.surface.radial_offset(*p).abs() < 1e-12);
        }
    }

    #[test]
    fn too_small_is_a_typed_error() {
        let mut s = mint_core::CountingSink::default();
        let e = scan_like(500, 0, &ScanOptions::default(), &mut s).unwrap_err();
        assert!(
            matches!(e, GenError::TooSmallForDefects { needed: 18, .. }),
            "{e}"
        );
        let bad = ScanOptions {
            noise_amplitude: 0.5,
            ..ScanOptions::default()
        };
        assert!(matches!(
            scan_like(50_000, 0, &bad, &mut s),
            Err(GenError::InvalidParameter {
                name: "noise_amplitude",
                ..
            })
        ));
    }
}

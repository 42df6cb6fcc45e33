//! `mint render`: pictures of meshes of any size. A streaming z-buffer
//! rasterizer: each triangle is projected and rasterized on its own, in file
//! order, so memory is the framebuffer (about 7 bytes per pixel) whatever
//! the mesh size. One pass over the vertices finds the box that frames the
//! picture; one pass over the faces draws them.
//!
//! - [`Camera`]: an orthographic view along one of seven directions, fitted
//!   to a box ([`View`]); orthographic so that areas in the picture are areas
//!   on the mesh, scaled.
//! - [`Canvas`]: depth and colour per pixel; [`Canvas::triangle`] fills the
//!   pixels whose centres a triangle covers (closed edge test, so a surface
//!   tiled by triangles leaves no gaps between them), nearest first.
//! - Shading: flat Lambert from each face's normal and a fixed light above
//!   and to the left of the viewer; faces seen from behind (inside-out parts,
//!   the inside seen through holes) in a distinct orange. A file with
//!   colour is drawn in its colours (per vertex, interpolated; per face;
//!   textures sampled per pixel) on front faces, lit more gently
//!   ([`Canvas::triangle_painted`]).
//! - [`render_files`]: several meshes side by side under one camera
//!   (`--preview`: input and output), each view a tile; `View::All` tiles
//!   the six axis views and the iso view. Encoded as PNG (the `png` crate).
//!
//! Deterministic: f64 arithmetic and a depth test with a fixed tie rule (the
//! earliest triangle in file order at the nearest depth keeps the pixel).
//! Worker threads draw whole chunks into tiles of their own, merged by that
//! same rule, so the bytes do not depend on the number of threads.

use glam::DVec3;
use mint_core::progress::{Phase, Progress};

/// Finding the meshes' joint box (units: vertices).
pub const BOUNDS_PHASE: Phase = Phase::named("bounds");
/// Drawing the triangles (units: faces).
pub const RENDER_PHASE: Phase = Phase::named("render");
use mint_io::{MeshReader, ReadOptions, TriangleChunk};
use std::path::{Path, PathBuf};

/// Why rendering failed.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// Reading a mesh failed (bad input…).
    #[error(transparent)]
    Io(#[from] mint_io::Error),
    /// Writing the picture failed.
    #[error("{path}: {message}")]
    Write { path: PathBuf, message: String },
    /// An option is out of range; the message says which.
    #[error("{0}")]
    Option(String),
    /// The meshes have no finite vertex to frame.
    #[error("{path}: nothing to draw (no vertices with finite coordinates)")]
    Empty { path: PathBuf },
    /// The user interrupted; nothing was written.
    #[error("interrupted; no output written")]
    Cancelled,
}

/// Which world axis points up in the picture. glTF, most OBJ exporters,
/// MeshLab and the Stanford scans are y-up (the model's front faces +z);
/// CAD, terrain and medical stacks are often z-up (front faces −y).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Up {
    X,
    #[default]
    Y,
    Z,
}

impl Up {
    /// The world vector of a vector given in the z-up frame the views are
    /// stated in (x right, y away from the front camera, z up): a rotation.
    fn map(self, v: [f64; 3]) -> [f64; 3] {
        let [a, b, c] = v;
        match self {
            Up::Z => [a, b, c],
            Up::Y => [a, c, -b],
            Up::X => [c, a, b],
        }
    }
}

/// Where the camera looks from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum View {
    /// Right, front and top at once (z-up: from (+1, −1, +1); y-up: from
    /// (+1, +1, +1)).
    Iso,
    /// From the front (z-up: from −y, x right, z up; y-up: from +z, x
    /// right, y up).
    Front,
    /// From behind.
    Back,
    /// From the left (−x when x is not up).
    Left,
    /// From the right.
    Right,
    /// From above.
    Top,
    /// From below.
    Bottom,
    /// The six above and iso, tiled.
    All,
}

impl View {
    /// The single views `self` stands for, in tile order.
    pub fn singles(self) -> Vec<View> {
        match self {
            View::All => vec![View::Iso, View::Front, View::Right, View::Top, View::Back, View::Left, View::Bottom],
            v => vec![v],
        }
    }

    /// Unit direction the camera looks along, and the up direction, in the
    /// z-up frame ([`Up::map`] turns them into the world's).
    fn frame(self) -> ([f64; 3], [f64; 3]) {
        let s = 1.0 / 3f64.sqrt();
        match self {
            View::Iso | View::All => ([-s, s, -s], [0.0, 0.0, 1.0]),
            View::Front => ([0.0, 1.0, 0.0], [0.0, 0.0, 1.0]),
            View::Back => ([0.0, -1.0, 0.0], [0.0, 0.0, 1.0]),
            View::Left => ([1.0, 0.0, 0.0], [0.0, 0.0, 1.0]),
            View::Right => ([-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]),
            View::Top => ([0.0, 0.0, -1.0], [0.0, 1.0, 0.0]),
            View::Bottom => ([0.0, 0.0, 1.0], [0.0, 1.0, 0.0]),
        }
    }
}

/// An orthographic camera: world point → (pixel x, pixel y, depth).
#[derive(Debug, Clone, Copy)]
pub struct Camera {
    dir: DVec3,
    right: DVec3,
    up: DVec3,
    center: DVec3,
    /// Pixels per world unit.
    pub scale: f64,
    width: u32,
    height: u32,
}

impl Camera {
    /// Looks at the box `lo..hi` from `view`, fitting its projection into
    /// `width × height` pixels with a 5% margin.
    pub fn fit(view: View, lo: [f64; 3], hi: [f64; 3], width: u32, height: u32) -> Camera {
        Camera::fit_up(view, Up::Z, lo, hi, width, height)
    }

    /// [`Camera::fit`] with `up` the world axis drawn upwards.
    pub fn fit_up(view: View, up: Up, lo: [f64; 3], hi: [f64; 3], width: u32, height: u32) -> Camera {
        let (dir, up0) = view.frame();
        let (dir, up0) = (up.map(dir), up.map(up0));
        let (dir, up0) = (DVec3::from(dir), DVec3::from(up0));
        let right = dir.cross(up0).normalize();
        let up = right.cross(dir);
        let center = 0.5 * (DVec3::from(lo) + DVec3::from(hi));
        let (mut ex, mut ey) = (0.0f64, 0.0f64);
        for i in 0..8 {
            let c = DVec3::new(if i & 1 == 0 { lo[0] } else { hi[0] }, if i & 2 == 0 { lo[1] } else { hi[1] }, if i & 4 == 0 { lo[2] } else { hi[2] });
            let d = c - center;
            ex = ex.max(d.dot(right).abs());
            ey = ey.max(d.dot(up).abs());
        }
        let sx = if ex > 0.0 { 0.45 * width as f64 / ex } else { f64::INFINITY };
        let sy = if ey > 0.0 { 0.45 * height as f64 / ey } else { f64::INFINITY };
        let mut scale = sx.min(sy);
        if !scale.is_finite() {
            scale = 1.0;
        }
        Camera { dir, right, up, center, scale, width, height }
    }

    /// Pixel coordinates (x right, y down) and depth (larger is farther).
    #[inline]
    pub fn project(&self, p: [f64; 3]) -> [f64; 3] {
        let d = DVec3::from(p) - self.center;
        [0.5 * self.width as f64 + d.dot(self.right) * self.scale, 0.5 * self.height as f64 - d.dot(self.up) * self.scale, d.dot(self.dir)]
    }

    /// The direction the camera looks along.
    pub fn direction(&self) -> [f64; 3] {
        self.dir.to_array()
    }
}

/// A depth buffer and an RGB picture.
pub struct Canvas {
    pub width: u32,
    pub height: u32,
    depth: Vec<f32>,
    rgb: Vec<[u8; 3]>,
    /// Lambert factor of the face that keeps each pixel (for recolouring).
    shade: Vec<f32>,
    /// Index in file order of the triangle that keeps each pixel.
    index: Vec<u64>,
    /// The index [`Canvas::triangle`] records for the next triangle.
    pub order: u64,
    /// Pixels covered by at least one triangle.
    pub covered: u64,
    /// Per line layer ([`WIRE`], [`BOUNDARY`]), the nearest depth of a line
    /// at each pixel (empty until the layer is drawn on).
    lines: [Vec<f32>; 2],
}

/// The line layer of `--wireframe`: every triangle's edges, dark grey.
pub const WIRE: usize = 0;
/// The line layer of `--show-boundary`: boundary edges, red and thick.
pub const BOUNDARY: usize = 1;
const LINE_COLOURS: [[u8; 3]; 2] = [[50, 50, 60], [220, 20, 30]];

/// The background colour.
pub const BACKGROUND: [u8; 3] = [250, 250, 250];
const FRONT: [f64; 3] = [0.55, 0.68, 0.85];
const BACK: [f64; 3] = [0.95, 0.55, 0.15];

impl Canvas {
    pub fn new(width: u32, height: u32) -> Canvas {
        let n = width as usize * height as usize;
        Canvas { width, height, depth: vec![f32::INFINITY; n], rgb: vec![BACKGROUND; n], shade: vec![0.0; n], index: vec![u64::MAX; n], order: 0, covered: 0, lines: [Vec::new(), Vec::new()] }
    }

    /// Draws the segment `a`–`b` seen by `cam` into line `layer`, keeping
    /// the nearest depth per pixel (one pixel wide; three for
    /// [`BOUNDARY`]). Lines show where [`Canvas::show_lines`] finds them not
    /// hidden by the surface.
    pub fn segment(&mut self, cam: &Camera, a: [f64; 3], b: [f64; 3], layer: usize) {
        let (p, q) = (cam.project(a), cam.project(b));
        if !(p.iter().chain(&q).all(|c| c.is_finite())) {
            return;
        }
        if self.lines[layer].is_empty() {
            self.lines[layer] = vec![f32::INFINITY; self.depth.len()];
        }
        let r: i64 = if layer == BOUNDARY { 1 } else { 0 };
        let steps = (q[0] - p[0]).abs().max((q[1] - p[1]).abs()).ceil().min(1e5) as u64 + 1;
        let (w, h) = (self.width as i64, self.height as i64);
        for k in 0..=steps {
            let t = k as f64 / steps as f64;
            let (x, y, z) = (p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1]), (p[2] + t * (q[2] - p[2])) as f32);
            let (xi, yi) = (x.floor() as i64, y.floor() as i64);
            for dy in -r..=r {
                for dx in -r..=r {
                    let (px, py) = (xi + dx, yi + dy);
                    if px >= 0 && py >= 0 && px < w && py < h {
                        let i = py as usize * self.width as usize + px as usize;
                        let l = &mut self.lines[layer][i];
                        if z < *l {
                            *l = z;
                        }
                    }
                }
            }
        }
    }

    /// Paints the line layers over the picture where a line is not behind
    /// the surface by more than `bias` (in depth units): wires first, then
    /// boundaries on top.
    pub fn show_lines(&mut self, bias: f32) {
        for layer in [WIRE, BOUNDARY] {
            if self.lines[layer].is_empty() {
                continue;
            }
            for i in 0..self.depth.len() {
                let l = self.lines[layer][i];
                if l.is_finite() && l <= self.depth[i] + bias {
                    self.rgb[i] = LINE_COLOURS[layer];
                }
            }
        }
    }

    /// Draws one triangle seen by `cam`, its front in the corners' colours
    /// (interpolated across it, lit more gently than the flat blue so that
    /// the colours stay recognisable), its back in the back colour.
    #[inline]
    pub fn triangle_coloured(&mut self, cam: &Camera, p: &[[f64; 3]; 3], rgba: [[u8; 4]; 3]) {
        let col = rgba.map(|c| c.map(|x| x as f64));
        self.triangle_painted(cam, p, |w| std::array::from_fn(|ch| w[0] * col[0][ch] + w[1] * col[1][ch] + w[2] * col[2][ch]));
    }

    /// [`Canvas::triangle_coloured`] with each pixel's colour (channels in
    /// [0, 255]) from `paint` at its barycentric weights on the triangle:
    /// textures are sampled per pixel.
    #[inline]
    pub fn triangle_painted(&mut self, cam: &Camera, p: &[[f64; 3]; 3], paint: impl Fn([f64; 3]) -> [f64; 4]) {
        let (a, b, c) = (DVec3::from(p[0]), DVec3::from(p[1]), DVec3::from(p[2]));
        let n = (b - a).cross(c - a);
        let nn = n.length();
        if !(nn > 0.0) {
            return;
        }
        let n = n / nn;
        let front = n.dot(cam.dir) < 0.0;
        if !front {
            return self.triangle(cam, p);
        }
        let light = (-cam.dir + 0.5 * cam.up - 0.4 * cam.right).normalize();
        let k = 0.55 + 0.45 * n.dot(light).max(0.0);
        self.fill_by(cam, p, k as f32, |w| {
            let c = paint(w);
            let v = |ch: usize| (c[ch] * k).round().clamp(0.0, 255.0) as u8;
            [v(0), v(1), v(2)]
        });
    }

    /// Draws one triangle seen by `cam`, flat-shaded.
    #[inline]
    pub fn triangle(&mut self, cam: &Camera, p: &[[f64; 3]; 3]) {
        let (a, b, c) = (DVec3::from(p[0]), DVec3::from(p[1]), DVec3::from(p[2]));
        let n = (b - a).cross(c - a);
        let nn = n.length();
        if !(nn > 0.0) {
            return; // zero area (or non-finite): nothing to see
        }
        let n = n / nn;
        let front = n.dot(cam.dir) < 0.0;
        // Light from above-left of the viewer; faces seen from behind are
        // lit as if their normal pointed at the viewer.
        let light = (-cam.dir + 0.5 * cam.up - 0.4 * cam.right).normalize();
        let ns = if front { n } else { -n };
        let lambert = ns.dot(light).max(0.0);
        let base = if front { FRONT } else { BACK };
        let k = 0.25 + 0.75 * lambert;
        let color = base.map(|c| (255.0 * (c * k).min(1.0)).round() as u8);
        self.fill(cam, p, color, k as f32);
    }

    /// Fills the pixels whose centres `p` covers (edges included), keeping
    /// the nearest depth; the first triangle at a depth keeps the pixel.
    #[inline]
    pub fn fill(&mut self, cam: &Camera, p: &[[f64; 3]; 3], color: [u8; 3], shade: f32) {
        self.fill_by(cam, p, shade, |_| color)
    }

    /// [`Canvas::fill`] with each pixel's colour from its barycentric
    /// weights on the projected triangle.
    #[inline(always)]
    fn fill_by(&mut self, cam: &Camera, p: &[[f64; 3]; 3], shade: f32, color: impl Fn([f64; 3]) -> [u8; 3]) {
        let q = [cam.project(p[0]), cam.project(p[1]), cam.project(p[2])];
        let (w, h) = (self.width as f64, self.height as f64);
        let minx = q[0][0].min(q[1][0]).min(q[2][0]);
        let maxx = q[0][0].max(q[1][0]).max(q[2][0]);
        let miny = q[0][1].min(q[1][1]).min(q[2][1]);
        let maxy = q[0][1].max(q[1][1]).max(q[2][1]);
        // Pixel centres i + 0.5 inside [min, max].
        let x0 = (minx - 0.5).ceil().max(0.0);
        let x1 = (maxx - 0.5).floor().min(w - 1.0);
        let y0 = (miny - 0.5).ceil().max(0.0);
        let y1 = (maxy - 0.5).floor().min(h - 1.0);
        if !(x0 <= x1 && y0 <= y1) {
            return;
        }
        let area = (q[1][0] - q[0][0]) * (q[2][1] - q[0][1]) - (q[1][1] - q[0][1]) * (q[2][0] - q[0][0]);
        if area == 0.0 || !area.is_finite() {
            return;
        }
        let edge = |a: [f64; 3], b: [f64; 3], x: f64, y: f64| (b[0] - a[0]) * (y - a[1]) - (b[1] - a[1]) * (x - a[0]);
        for yi in y0 as u32..=y1 as u32 {
            let y = yi as f64 + 0.5;
            for xi in x0 as u32..=x1 as u32 {
                let x = xi as f64 + 0.5;
                let w0 = edge(q[1], q[2], x, y) / area;
                let w1 = edge(q[2], q[0], x, y) / area;
                let w2 = edge(q[0], q[1], x, y) / area;
                if w0 < 0.0 || w1 < 0.0 || w2 < 0.0 {
                    continue;
                }
                let z = (w0 * q[0][2] + w1 * q[1][2] + w2 * q[2][2]) as f32;
                let i = yi as usize * self.width as usize + xi as usize;
                if z < self.depth[i] {
                    if self.depth[i] == f32::INFINITY {
                        self.covered += 1;
                    }
                    self.depth[i] = z;
                    self.rgb[i] = color([w0, w1, w2]);
                    self.shade[i] = shade;
                    self.index[i] = self.order;
                }
            }
        }
    }

    /// Takes from `other` (same size) every pixel it holds nearer, or at
    /// the same depth from an earlier triangle.
    pub fn merge(&mut self, other: &Canvas) {
        for i in 0..self.depth.len() {
            let (z, k) = (other.depth[i], other.index[i]);
            if z < self.depth[i] || (z == self.depth[i] && k < self.index[i]) {
                if self.depth[i] == f32::INFINITY {
                    self.covered += 1;
                }
                self.depth[i] = z;
                self.rgb[i] = other.rgb[i];
                self.shade[i] = other.shade[i];
                self.index[i] = k;
            }
        }
        for layer in [WIRE, BOUNDARY] {
            if other.lines[layer].is_empty() {
                continue;
            }
            if self.lines[layer].is_empty() {
                self.lines[layer] = vec![f32::INFINITY; self.depth.len()];
            }
            for (l, &o) in self.lines[layer].iter_mut().zip(&other.lines[layer]) {
                *l = l.min(o);
            }
        }
    }

    /// The world point seen at each covered pixel, with its index.
    pub fn surface_points(&self, cam: &Camera) -> Vec<(usize, [f64; 3])> {
        let mut v = Vec::new();
        for (i, &z) in self.depth.iter().enumerate() {
            if z.is_finite() {
                let (x, y) = ((i % self.width as usize) as f64 + 0.5, (i / self.width as usize) as f64 + 0.5);
                let (a, b) = ((x - 0.5 * self.width as f64) / cam.scale, (0.5 * self.height as f64 - y) / cam.scale);
                v.push((i, (cam.center + a * cam.right + b * cam.up + z as f64 * cam.dir).to_array()));
            }
        }
        v
    }

    /// Colours pixel `i` by `t` in [0, 1] on the distance scale, keeping its shading.
    pub fn tint(&mut self, i: usize, t: f64) {
        let c = colormap(t);
        let k = self.shade[i] as f64;
        self.rgb[i] = c.map(|x| (255.0 * (x * (0.35 + 0.65 * k)).min(1.0)).round() as u8);
    }

    /// Draws a vertical colour bar (low at the bottom) in the rectangle.
    pub fn colour_bar(&mut self, x: u32, y: u32, w: u32, h: u32) {
        for row in 0..h {
            let t = 1.0 - row as f64 / (h.max(2) - 1) as f64;
            let c = colormap(t).map(|x| (255.0 * x).round() as u8);
            for col in 0..w {
                let (px, py) = (x + col, y + row);
                if px < self.width && py < self.height {
                    self.rgb[py as usize * self.width as usize + px as usize] = c;
                }
            }
        }
    }

    /// Writes `text` (digits, '.', 'e', '-', '+', '%') in a 3×5 pixel font
    /// scaled by `s`, top-left at (x, y), in dark grey.
    pub fn text(&mut self, x: u32, y: u32, s: u32, text: &str) {
        let mut cx = x;
        for ch in text.chars() {
            let rows = glyph(ch);
            for (r, bits) in rows.iter().enumerate() {
                for c in 0..3 {
                    if bits & (4 >> c) != 0 {
                        for dy in 0..s {
                            for dx in 0..s {
                                let (px, py) = (cx + c * s + dx, y + r as u32 * s + dy);
                                if px < self.width && py < self.height {
                                    self.rgb[py as usize * self.width as usize + px as usize] = [40, 40, 40];
                                }
                            }
                        }
                    }
                }
            }
            cx += 4 * s;
        }
    }

    /// Copies `other` into this canvas with its top-left corner at (x, y).
    pub fn blit(&mut self, other: &Canvas, x: u32, y: u32) {
        for row in 0..other.height.min(self.height.saturating_sub(y)) {
            for col in 0..other.width.min(self.width.saturating_sub(x)) {
                let src = row as usize * other.width as usize + col as usize;
                let dst = (y + row) as usize * self.width as usize + (x + col) as usize;
                self.rgb[dst] = other.rgb[src];
            }
        }
    }

    /// The RGB bytes, row by row.
    pub fn rgb_bytes(&self) -> Vec<u8> {
        self.rgb.iter().flatten().copied().collect()
    }

    /// Encodes the picture as PNG into `path`, through a temporary file
    /// beside it renamed at the end.
    pub fn write_png(&self, path: &Path) -> Result<(), RenderError> {
        let err = |e: String| RenderError::Write { path: path.to_path_buf(), message: e };
        let mut bytes = Vec::new();
        {
            let mut enc = png::Encoder::new(&mut bytes, self.width, self.height);
            enc.set_color(png::ColorType::Rgb);
            enc.set_depth(png::BitDepth::Eight);
            let mut w = enc.write_header().map_err(|e| err(e.to_string()))?;
            w.write_image_data(&self.rgb_bytes()).map_err(|e| err(e.to_string()))?;
        }
        let mut file = mint_io::AtomicFile::create(path).map_err(RenderError::Io)?;
        use std::io::Write;
        file.write_all(&bytes).map_err(|e| err(format!("writing: {e}")))?;
        file.commit().map_err(RenderError::Io)?;
        Ok(())
    }
}

/// A blue → cyan → yellow → red scale for `t` in [0, 1].
pub fn colormap(t: f64) -> [f64; 3] {
    let t = if t.is_finite() { t.clamp(0.0, 1.0) } else { 1.0 };
    let stops = [[0.15, 0.25, 0.85], [0.1, 0.75, 0.85], [0.95, 0.9, 0.2], [0.9, 0.15, 0.1]];
    let f = t * 3.0;
    let i = (f.floor() as usize).min(2);
    let u = f - i as f64;
    [0, 1, 2].map(|k| stops[i][k] * (1.0 - u) + stops[i + 1][k] * u)
}

/// Rows of a 3×5 glyph, top first, bit 2 the left column.
fn glyph(c: char) -> [u8; 5] {
    match c {
        '0' => [7, 5, 5, 5, 7],
        '1' => [2, 6, 2, 2, 7],
        '2' => [7, 1, 7, 4, 7],
        '3' => [7, 1, 7, 1, 7],
        '4' => [5, 5, 7, 1, 1],
        '5' => [7, 4, 7, 1, 7],
        '6' => [7, 4, 7, 5, 7],
        '7' => [7, 1, 1, 1, 1],
        '8' => [7, 5, 7, 5, 7],
        '9' => [7, 5, 7, 1, 7],
        '.' => [0, 0, 0, 0, 2],
        '-' => [0, 0, 7, 0, 0],
        '+' => [0, 2, 7, 2, 0],
        'e' => [0, 7, 7, 4, 7],
        '%' => [5, 1, 2, 4, 5],
        _ => [0; 5],
    }
}

/// Options of [`render_files`].
#[derive(Debug, Clone)]
pub struct RenderOptions {
    /// Size of one tile (one view of one mesh), in pixels. Default 1200×900.
    pub width: u32,
    pub height: u32,
    /// The view, or all of them. Default iso.
    pub view: View,
    /// Worker threads drawing triangles; the bytes are the same for any
    /// number. Default: all cores.
    pub threads: usize,
    /// Colour the surface by its distance to this mesh (read in core, with
    /// a BVH), on one scale for the whole picture, with a colour bar and
    /// its top value at the right. Default `None`: shading only.
    pub distance_to: Option<PathBuf>,
    /// Draw every triangle's edges (hidden ones stay hidden). Default off.
    pub wireframe: bool,
    /// Segments drawn thick in red over each input (one list per input, in
    /// order; empty lists draw nothing): the boundary edges for
    /// `--show-boundary`, which the caller finds. Default: none.
    pub marks: Vec<Vec<[[f64; 3]; 2]>>,
    /// The world axis drawn upwards. Default y (glTF's convention).
    pub up: Up,
    /// Draw per-vertex colours where a file has them (`--color vertex`,
    /// and by default). Default true; ignored when colouring by distance.
    pub vertex_colours: bool,
}

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions { width: 1200, height: 900, view: View::Iso, threads: std::thread::available_parallelism().map_or(1, |n| n.get()), distance_to: None, wireframe: false, marks: Vec::new(), up: Up::Y, vertex_colours: true }
    }
}

/// What a render drew.
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct RenderSummary {
    pub output: String,
    pub width: u32,
    pub height: u32,
    pub triangles: u64,
    /// Pixels covered by the meshes, over all tiles.
    pub covered_pixels: u64,
    /// Pixels per world unit of the camera.
    pub scale: f64,
    /// With a distance reference: the largest and mean distance over the
    /// covered pixels (the colour bar spans 0 to the largest).
    pub distance_max: Option<f64>,
    pub distance_mean: Option<f64>,
    /// Files drawn in their colours (per vertex, per face, or textures).
    pub coloured_files: u64,
    pub seconds: f64,
}

/// Where a file's colours come from: its vertices, its faces (by the
/// triangle's place in the file), or its textures, sampled per pixel
/// (decoded when they take at most [`MAX_TEXTURE_BYTES`]; larger ones are
/// drawn in their materials' colours).
enum Paint {
    Vertex(mint_io::VertexColours),
    Face(mint_io::FaceColours),
    Texture(mint_io::textures::Texturing, Vec<mint_io::textures::Image>),
}

/// The decoded textures a picture may hold in memory.
pub const MAX_TEXTURE_BYTES: u64 = 1 << 30;

impl Paint {
    fn of(r: &MeshReader) -> Result<Option<Paint>, RenderError> {
        if let Some(c) = r.colours() {
            return Ok(Some(Paint::Vertex(c)));
        }
        if let Some(c) = r.face_colours() {
            return Ok(Some(Paint::Face(c)));
        }
        let Some(t) = r.texturing() else { return Ok(None) };
        let images = if t.decoded_bytes() <= MAX_TEXTURE_BYTES { t.decode(r.path())? } else { Vec::new() };
        Ok(Some(Paint::Texture(t, images)))
    }

    /// The colour of triangle `t` (vertex indices `tri`) at barycentric
    /// weights `w`.
    #[inline]
    fn at(&self, t: u64, tri: [u32; 3], w: [f64; 3]) -> [f64; 4] {
        match self {
            Paint::Vertex(c) => {
                let col = tri.map(|i| c.get(i));
                std::array::from_fn(|ch| w[0] * col[0][ch] as f64 + w[1] * col[1][ch] as f64 + w[2] * col[2][ch] as f64)
            }
            Paint::Face(c) => c.get(t).map(|x| x as f64),
            Paint::Texture(tex, images) => tex.colour(images, t, w).map(|x| x as f64),
        }
    }
}

/// Renders `inputs` side by side (one column each, one row per view), all
/// under the cameras fitted to their joint bounding box, into `output`.
pub fn render_files(inputs: &[&Path], output: &Path, o: &RenderOptions, progress: &dyn Progress) -> Result<RenderSummary, RenderError> {
    let sets: Vec<Vec<PathBuf>> = inputs.iter().map(|p| vec![p.to_path_buf()]).collect();
    render_surfaces(&sets, output, o, progress)
}

/// Renders surfaces side by side, each given as one or more files (tiles
/// drawn together in one column), as [`render_files`] does.
pub fn render_surfaces(inputs: &[Vec<PathBuf>], output: &Path, o: &RenderOptions, progress: &dyn Progress) -> Result<RenderSummary, RenderError> {
    let t = std::time::Instant::now();
    if o.width == 0 || o.height == 0 || o.width > 16384 || o.height > 16384 {
        return Err(RenderError::Option(format!("--size {}x{}: each side must be 1 to 16384 pixels", o.width, o.height)));
    }
    let views = o.view.singles();
    if (inputs.len() * views.len()) as u64 * o.width as u64 * o.height as u64 > 1 << 28 {
        return Err(RenderError::Option("the picture would exceed 268 million pixels; choose a smaller --size".into()));
    }
    // 1. The joint box, from the vertex maps.
    let read = ReadOptions { chunk_triangles: 1 << 16, spill_dir: None, resolve_positions: true };
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for path in inputs.iter().flatten() {
        let r = MeshReader::open(path, read.clone())?;
        let pos = r.positions();
        progress.start(BOUNDS_PHASE, pos.len() as u64);
        let mut at = 0u32;
        while at < pos.len() {
            let to = at.saturating_add(1 << 20).min(pos.len());
            match pos.bounds(at, to) {
                Ok(Some((l, h))) => {
                    for d in 0..3 {
                        lo[d] = lo[d].min(l[d]);
                        hi[d] = hi[d].max(h[d]);
                    }
                }
                Ok(None) => {}
                Err((i, _)) => {
                    return Err(RenderError::Io(mint_io::Error::new(mint_io::ErrorKind::Value, path, format!("vertex {i} has a non-finite coordinate"))))
                }
            }
            progress.advance((to - at) as u64);
            at = to;
        }
        progress.finish();
    }
    if !(lo[0] <= hi[0]) {
        return Err(RenderError::Empty { path: inputs.iter().flatten().next().cloned().unwrap_or_default() });
    }
    // 2. Every triangle of every input into its tiles (a strip on the right
    // for the colour bar when colouring by distance).
    let reference = match &o.distance_to {
        Some(r) => {
            let (p, f) = mint_io::read_mesh(r)?;
            let bvh = mint_mesh::TriangleBvh::new(&p, &f).map_err(|e| RenderError::Option(format!("{}: {e}", r.display())))?;
            Some(bvh)
        }
        None => None,
    };
    let bar = if reference.is_some() { 90 } else { 0 };
    let mut picture = Canvas::new(o.width * inputs.len() as u32 + bar, o.height * views.len() as u32);
    let mut distances: Vec<(usize, u32, u32, Vec<(usize, f64)>)> = Vec::new();
    let mut stash: Vec<(u32, u32, Canvas)> = Vec::new();
    let mut summary = RenderSummary { output: output.display().to_string(), width: picture.width, height: picture.height, ..Default::default() };
    for (col, paths) in inputs.iter().enumerate() {
        let cams: Vec<Camera> = views.iter().map(|&v| Camera::fit_up(v, o.up, lo, hi, o.width, o.height)).collect();
        summary.scale = cams[0].scale;
        let mut tiles: Vec<Canvas> = views.iter().map(|_| Canvas::new(o.width, o.height)).collect();
        // Triangles are numbered on through a column's files, so that ties
        // in depth keep the earliest as one file would.
        let mut first = 0u64;
        for path in paths {
        let mut r = MeshReader::open(path, read.clone())?;
        let colours = if o.vertex_colours && reference.is_none() { Paint::of(&r)? } else { None };
        summary.coloured_files += colours.is_some() as u64;
        let file_first = first;
        progress.start(RENDER_PHASE, r.info().face_count.unwrap_or(0));
        // Workers draw whole chunks into tiles of their own; the tiles are
        // merged pixel by pixel keeping the nearest depth, and among equal
        // depths the earliest triangle: what one thread drawing in file
        // order keeps. So the bytes do not depend on the threads.
        let threads = o.threads.max(1);
        let (tx, rx) = crossbeam_channel::bounded::<(u64, TriangleChunk)>(2 * threads);
        let (free_tx, free_rx) = crossbeam_channel::bounded::<TriangleChunk>(3 * threads);
        let worker_tiles: Vec<Vec<Canvas>> = std::thread::scope(|scope| -> Result<Vec<Vec<Canvas>>, RenderError> {
            let handles: Vec<_> = (0..threads)
                .map(|_| {
                    let (rx, free_tx, cams, views, colours) = (rx.clone(), free_tx.clone(), &cams, &views, &colours);
                    scope.spawn(move || {
                        let mut tiles: Vec<Canvas> = views.iter().map(|_| Canvas::new(o.width, o.height)).collect();
                        for (base, chunk) in rx {
                            for (k, p) in chunk.positions.iter().enumerate() {
                                let t = base + k as u64 - file_first;
                                let tri = chunk.indices[k];
                                for (tile, cam) in tiles.iter_mut().zip(cams) {
                                    tile.order = base + k as u64;
                                    match colours {
                                        Some(c) => tile.triangle_painted(cam, p, |w| c.at(t, tri, w)),
                                        None => tile.triangle(cam, p),
                                    }
                                    if o.wireframe {
                                        for e in 0..3 {
                                            tile.segment(cam, p[e], p[(e + 1) % 3], WIRE);
                                        }
                                    }
                                }
                            }
                            let _ = free_tx.try_send(chunk);
                        }
                        tiles
                    })
                })
                .collect();
            drop(rx);
            let read: Result<(), RenderError> = (|| {
                let mut base = first;
                loop {
                    if progress.cancelled() {
                        return Err(RenderError::Cancelled);
                    }
                    let mut chunk = free_rx.try_recv().unwrap_or_default();
                    if !r.next_chunk(&mut chunk)? {
                        return Ok(());
                    }
                    let n = chunk.len() as u64;
                    if tx.send((base, chunk)).is_err() {
                        return Ok(());
                    }
                    base += n;
                    progress.advance(n);
                }
            })();
            drop(tx);
            let tiles: Vec<Vec<Canvas>> = handles.into_iter().map(|h| h.join().expect("render worker panicked")).collect();
            read?;
            Ok(tiles)
        })?;
        for wt in &worker_tiles {
            for (tile, w) in tiles.iter_mut().zip(wt) {
                tile.merge(w);
            }
        }
        drop(worker_tiles);
        summary.triangles += r.stats().triangles;
        first += r.stats().triangles;
        progress.finish();
        }
        // Lines may sit up to two pixels' worth of depth behind the surface
        // they lie on (rasterization rounding on slanted faces).
        let bias = (2.0 / cams[0].scale) as f32;
        for (tile, cam) in tiles.iter_mut().zip(&cams) {
            for seg in o.marks.get(col).into_iter().flatten() {
                tile.segment(cam, seg[0], seg[1], BOUNDARY);
            }
            if reference.is_none() {
                tile.show_lines(bias);
            }
        }
        for (row, tile) in tiles.iter().enumerate() {
            summary.covered_pixels += tile.covered;
            if let Some(bvh) = &reference {
                let d: Vec<(usize, f64)> = tile.surface_points(&cams[row]).into_iter().map(|(i, q)| (i, bvh.nearest(q).0)).collect();
                distances.push((row, col as u32, row as u32, d));
            }
            picture.blit(tile, col as u32 * o.width, row as u32 * o.height);
        }
        if reference.is_some() {
            // Keep the tiles for recolouring on the common scale.
            for (row, tile) in tiles.into_iter().enumerate() {
                stash.push((col as u32, row as u32, tile));
            }
        }
    }
    if reference.is_some() {
        let all: Vec<f64> = distances.iter().flat_map(|(_, _, _, d)| d.iter().map(|x| x.1)).filter(|x| x.is_finite()).collect();
        let max = all.iter().copied().fold(0.0f64, f64::max);
        let mean = if all.is_empty() { 0.0 } else { all.iter().sum::<f64>() / all.len() as f64 };
        summary.distance_max = Some(max);
        summary.distance_mean = Some(mean);
        for ((_, _, _, d), (col, row, tile)) in distances.iter().zip(stash.iter_mut()) {
            for &(i, x) in d {
                tile.tint(i, if max > 0.0 { x / max } else { 0.0 });
            }
            tile.show_lines((2.0 / summary.scale) as f32);
            picture.blit(tile, *col * o.width, *row * o.height);
        }
        let (x0, h) = (o.width * inputs.len() as u32 + 20, picture.height.saturating_sub(80).min(600));
        picture.colour_bar(x0, 40, 24, h);
        picture.text(x0 - 12, 20, 2, &format!("{max:.2e}"));
        picture.text(x0 - 12, 50 + h, 2, "0");
    }
    picture.write_png(output)?;
    summary.seconds = t.elapsed().as_secs_f64();
    Ok(summary)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_square_tiled_by_two_triangles_covers_every_pixel_once_without_gaps() {
        let cam = Camera::fit(View::Top, [0.0, 0.0, 0.0], [1.0, 1.0, 0.0], 100, 100);
        let mut c = Canvas::new(100, 100);
        let (a, b, cc, d) = ([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]);
        c.triangle(&cam, &[a, b, cc]);
        c.triangle(&cam, &[a, cc, d]);
        // The square spans 90% of the tile: 90 x 90 pixel centres.
        assert_eq!(c.covered, 90 * 90);
    }

    #[test]
    fn lines_show_on_the_surface_and_hide_behind_it() {
        let cam = Camera::fit(View::Top, [0.0, 0.0, -1.0], [1.0, 1.0, 0.0], 100, 100);
        let mut c = Canvas::new(100, 100);
        // A square at z = 0 seen from above; one segment on it, one below it
        // (z = -1, hidden), one beside it over the background.
        c.triangle(&cam, &[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0]]);
        c.triangle(&cam, &[[0.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]]);
        c.segment(&cam, [0.1, 0.5, 0.0], [0.9, 0.5, 0.0], WIRE);
        c.segment(&cam, [0.5, 0.1, -1.0], [0.5, 0.9, -1.0], WIRE);
        c.segment(&cam, [0.5, 0.2, 0.0], [0.5, 0.4, 0.0], BOUNDARY);
        c.show_lines((2.0 / cam.scale) as f32);
        let px = |x: f64, y: f64| {
            let q = cam.project([x, y, 0.0]);
            c.rgb[q[1] as usize * 100 + q[0] as usize]
        };
        assert_eq!(px(0.3, 0.5), LINE_COLOURS[WIRE], "a wire on the surface shows");
        assert_ne!(px(0.5, 0.75), LINE_COLOURS[WIRE], "a wire behind the surface stays hidden");
        assert_eq!(px(0.5, 0.3), LINE_COLOURS[BOUNDARY], "boundaries draw over the surface");
    }

    #[test]
    fn back_faces_get_the_back_colour() {
        let cam = Camera::fit(View::Top, [0.0, 0.0, 0.0], [1.0, 1.0, 0.0], 10, 10);
        let mut up = Canvas::new(10, 10);
        up.triangle(&cam, &[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]);
        let mut down = Canvas::new(10, 10);
        down.triangle(&cam, &[[0.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]]);
        let i = 8 * 10 + 2; // a pixel near the right angle
        assert_ne!(up.rgb[i], BACKGROUND);
        assert!(down.rgb[i][0] > down.rgb[i][2], "back faces are orange: {:?}", down.rgb[i]);
        assert!(up.rgb[i][2] > up.rgb[i][0], "front faces are blue: {:?}", up.rgb[i]);
    }
}

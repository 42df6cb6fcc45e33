//! Textured surfaces: which material and which texture coordinates each
//! triangle has, the materials, and their images (PNG or JPEG, in files or
//! embedded in a GLB).
//!
//! A reader that finds texture coordinates builds a [`Texturing`]: per
//! triangle (in the order the reader delivers triangles, as
//! [`crate::FaceColours`]) a material index and three indices into a table
//! of (u, v) pairs, both spilled to anonymous files; the materials (a base
//! colour, an optional texture, the texture's wrap rules and whether v
//! runs upwards, as in OBJ, or downwards, as in glTF); the textures by
//! source and size (read from the image header: nothing is decoded at
//! open). [`Texturing::decode`] decodes them all, once, when a run needs the
//! colours ([`Texturing::decoded_bytes`] says how much memory that takes,
//! so that the caller can check it against its budget first).
//!
//! The colour of a point of a triangle ([`Texturing::colour`]) is the
//! material's base colour times the texture's bilinear sample at the
//! barycentric mix of the corners' (u, v), with the format's wrap rules
//! (OBJ: repeat; glTF: the sampler's). A corner without texture
//! coordinates gives the material's colour alone.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use crate::error::{Error, ErrorKind};
use crate::mapped::{Mapped, SpillFile};

/// What a texture coordinate outside [0, 1] samples.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Wrap {
    /// Tiled (OBJ's and glTF's default).
    Repeat,
    /// The edge texel.
    Clamp,
    /// Tiled, every other copy reflected.
    Mirror,
}

/// A material: base colour (RGBA in [0, 1]), optional texture.
#[derive(Debug, Clone, PartialEq)]
pub struct Material {
    /// Its name in the file (OBJ `usemtl`, glTF `name`).
    pub name: String,
    /// Base colour, multiplied with the texture's.
    pub colour: [f32; 4],
    /// Index into [`Texturing::textures`].
    pub texture: Option<usize>,
    /// Wrap rules along u and v.
    pub wrap: [Wrap; 2],
    /// v = 0 is the image's bottom row (OBJ, PLY) rather than its top (glTF).
    pub v_up: bool,
}

impl Material {
    /// A plain white material.
    pub fn white(name: &str) -> Material {
        Material { name: name.to_string(), colour: [1.0; 4], texture: None, wrap: [Wrap::Repeat; 2], v_up: true }
    }
}

/// Where an image's encoded bytes are: a file, or a range of a mapped file
/// (a GLB's buffer view).
#[derive(Debug, Clone)]
pub struct ImageSource(Source);

#[derive(Debug, Clone)]
enum Source {
    File(PathBuf),
    Embedded { map: Arc<Mapped>, range: (usize, usize), name: String },
    Bytes(Arc<Vec<u8>>, String),
}

impl ImageSource {
    /// An image file.
    pub fn file(path: PathBuf) -> ImageSource {
        ImageSource(Source::File(path))
    }

    /// Bytes `range` of `map`, called `name` in messages.
    pub(crate) fn embedded(map: Arc<Mapped>, range: (usize, usize), name: String) -> ImageSource {
        ImageSource(Source::Embedded { map, range, name })
    }

    /// Decoded bytes (a `data:` URI), called `name` in messages.
    pub(crate) fn bytes(bytes: Vec<u8>, name: String) -> ImageSource {
        ImageSource(Source::Bytes(Arc::new(bytes), name))
    }

    /// How errors name the image.
    pub fn name(&self) -> String {
        match &self.0 {
            Source::File(p) => p.display().to_string(),
            Source::Embedded { name, .. } | Source::Bytes(_, name) => name.clone(),
        }
    }
}

/// A texture: its source and its size.
#[derive(Debug, Clone)]
pub struct TextureInfo {
    /// Where its bytes are.
    pub source: ImageSource,
    /// Size in texels, from its header.
    pub width: u32,
    /// Size in texels, from its header.
    pub height: u32,
}

/// A decoded image: RGBA bytes, row 0 at the top.
#[derive(Debug, Clone, PartialEq)]
pub struct Image {
    /// Texels per row.
    pub width: u32,
    /// Rows.
    pub height: u32,
    /// Four bytes per texel, row by row.
    pub rgba: Vec<u8>,
}

impl Image {
    /// The bilinear sample at (u, v) (texel centres at (i + ½) / width),
    /// channels in [0, 255]; v counts from the top row.
    pub fn sample(&self, u: f64, v: f64, wrap: [Wrap; 2]) -> [f64; 4] {
        let (w, h) = (self.width as i64, self.height as i64);
        let u = if u.is_finite() { u } else { 0.0 };
        let v = if v.is_finite() { v } else { 0.0 };
        // Keep the arithmetic in range for absurd coordinates (repeat is
        // periodic anyway).
        let x = (u.clamp(-1e9, 1e9)) * w as f64 - 0.5;
        let y = (v.clamp(-1e9, 1e9)) * h as f64 - 0.5;
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let (x0, y0) = (x0 as i64, y0 as i64);
        let at = |i: i64, n: i64, wrap: Wrap| -> usize {
            (match wrap {
                Wrap::Repeat => i.rem_euclid(n),
                Wrap::Clamp => i.clamp(0, n - 1),
                Wrap::Mirror => {
                    let m = i.rem_euclid(2 * n);
                    if m < n {
                        m
                    } else {
                        2 * n - 1 - m
                    }
                }
            }) as usize
        };
        let (xa, xb) = (at(x0, w, wrap[0]), at(x0 + 1, w, wrap[0]));
        let (ya, yb) = (at(y0, h, wrap[1]), at(y0 + 1, h, wrap[1]));
        let px = |x: usize, y: usize, k: usize| self.rgba[(y * w as usize + x) * 4 + k] as f64;
        std::array::from_fn(|k| {
            let top = px(xa, ya, k) * (1.0 - fx) + px(xb, ya, k) * fx;
            let bottom = px(xa, yb, k) * (1.0 - fx) + px(xb, yb, k) * fx;
            top * (1.0 - fy) + bottom * fy
        })
    }
}

/// Per-triangle texture coordinates and the materials of one file.
#[derive(Debug, Clone)]
pub struct Texturing {
    /// By index, as triangles name them.
    pub materials: Vec<Material>,
    /// By index, as materials name them.
    pub textures: Vec<TextureInfo>,
    /// Per triangle: material, then three indices into `uvs` (u32 LE each;
    /// `u32::MAX`: none).
    tris: Arc<Mapped>,
    /// (u, v) pairs, f32 LE.
    uvs: Arc<Mapped>,
    /// What the reader accepted but a user should know (a missing texture).
    pub warnings: Vec<String>,
}

/// No material or no texture coordinate.
pub const NONE: u32 = u32::MAX;

impl Texturing {
    /// Number of triangles described.
    pub fn triangles(&self) -> u64 {
        self.tris.bytes().len() as u64 / 16
    }

    /// Triangle `t`'s material and (u, v) indices ([`NONE`] past the end).
    #[inline]
    pub fn triangle(&self, t: u64) -> (u32, [u32; 3]) {
        let Some(b) = self.tris.bytes().get(t as usize * 16..t as usize * 16 + 16) else { return (NONE, [NONE; 3]) };
        let w = |k: usize| u32::from_le_bytes(b[4 * k..4 * k + 4].try_into().unwrap());
        (w(0), [w(1), w(2), w(3)])
    }

    /// The (u, v) pair `i`, if there is one.
    #[inline]
    pub fn uv(&self, i: u32) -> Option<[f32; 2]> {
        let b = self.uvs.bytes();
        let at = i as usize * 8;
        (i != NONE && at + 8 <= b.len()).then(|| [f32::from_le_bytes(b[at..at + 4].try_into().unwrap()), f32::from_le_bytes(b[at + 4..at + 8].try_into().unwrap())])
    }

    /// Bytes the decoded textures take (RGBA, four per texel).
    pub fn decoded_bytes(&self) -> u64 {
        self.textures.iter().map(|t| t.width as u64 * t.height as u64 * 4).sum()
    }

    /// Decodes every texture. Errors name the image (and the file that
    /// uses it).
    pub fn decode(&self, about: &Path) -> Result<Vec<Image>, Error> {
        self.textures.iter().map(|t| decode(&t.source, about)).collect()
    }

    /// The colour of triangle `t` at barycentric weights `w`, with
    /// `images` from [`Texturing::decode`].
    pub fn colour(&self, images: &[Image], t: u64, w: [f64; 3]) -> [u8; 4] {
        let (m, corners) = self.triangle(t);
        let Some(mat) = self.materials.get(m as usize) else { return [255; 4] };
        let mut c = mat.colour.map(|x| x as f64 * 255.0);
        if let (Some(tex), Some(a), Some(b), Some(d)) = (mat.texture.and_then(|i| images.get(i)), self.uv(corners[0]), self.uv(corners[1]), self.uv(corners[2])) {
            let u = w[0] * a[0] as f64 + w[1] * b[0] as f64 + w[2] * d[0] as f64;
            let v = w[0] * a[1] as f64 + w[1] * b[1] as f64 + w[2] * d[1] as f64;
            let s = tex.sample(u, if mat.v_up { 1.0 - v } else { v }, mat.wrap);
            c = std::array::from_fn(|k| c[k] * s[k] / 255.0);
        }
        c.map(|x| x.round().clamp(0.0, 255.0) as u8)
    }
}

/// Collects a [`Texturing`] while a reader walks a file: triangles'
/// records and (u, v) pairs go to spills.
pub(crate) struct TexturingBuilder {
    tris: SpillFile,
    uvs: SpillFile,
    uv_count: u64,
}

impl TexturingBuilder {
    pub(crate) fn new(spill_dir: &Path, about: &Path) -> Result<TexturingBuilder, Error> {
        Ok(TexturingBuilder { tris: SpillFile::new(spill_dir, about)?, uvs: SpillFile::new(spill_dir, about)?, uv_count: 0 })
    }

    /// Appends a (u, v) pair; returns its index.
    pub(crate) fn uv(&mut self, uv: [f32; 2]) -> Result<u32, Error> {
        let mut b = [0u8; 8];
        b[..4].copy_from_slice(&uv[0].to_le_bytes());
        b[4..].copy_from_slice(&uv[1].to_le_bytes());
        self.uvs.write_bytes(&b)?;
        self.uv_count += 1;
        Ok((self.uv_count - 1).min(NONE as u64 - 1) as u32)
    }

    /// Pairs appended so far.
    pub(crate) fn uv_count(&self) -> u64 {
        self.uv_count
    }

    /// Appends a triangle's record.
    pub(crate) fn triangle(&mut self, material: u32, uvs: [u32; 3]) -> Result<(), Error> {
        let mut b = [0u8; 16];
        b[..4].copy_from_slice(&material.to_le_bytes());
        for k in 0..3 {
            b[4 + 4 * k..8 + 4 * k].copy_from_slice(&uvs[k].to_le_bytes());
        }
        self.tris.write_bytes(&b)
    }

    pub(crate) fn finish(self, materials: Vec<Material>, textures: Vec<TextureInfo>, warnings: Vec<String>) -> Result<Texturing, Error> {
        Ok(Texturing { materials, textures, tris: Arc::new(self.tris.into_mapped()?), uvs: Arc::new(self.uvs.into_mapped()?), warnings })
    }
}

/// The largest texture side mint decodes (larger images are refused by
/// name rather than allocated).
pub const MAX_SIDE: u32 = 1 << 15;

fn bad(about: &Path, name: &str, what: impl std::fmt::Display) -> Error {
    Error::new(ErrorKind::Format, about, format!("texture '{name}': {what}"))
}

/// An image's size from its header (PNG or JPEG, by signature), without
/// decoding it.
pub(crate) fn image_size(source: &ImageSource, about: &Path) -> Result<(u32, u32), Error> {
    // The header is near the start (a JPEG's frame header after its
    // metadata): the first MiB, else the whole file.
    if let Source::File(p) = &source.0 {
        let mut head = Vec::new();
        let f = std::fs::File::open(p).map_err(|e| Error::io(about, &format!("cannot read texture '{}'", p.display()), e))?;
        std::io::Read::read_to_end(&mut std::io::Read::take(f, 1 << 20), &mut head).map_err(|e| Error::io(about, &format!("cannot read texture '{}'", p.display()), e))?;
        if let Ok(size) = size_from(&head, source, about) {
            return Ok(size);
        }
    }
    size_from(&read_source(source, about)?, source, about)
}

fn size_from(bytes: &[u8], source: &ImageSource, about: &Path) -> Result<(u32, u32), Error> {
    let name = source.name();
    let (w, h) = if bytes.starts_with(b"\x89PNG") {
        let r = png::Decoder::new(&bytes[..]).read_info().map_err(|e| bad(about, &name, e))?;
        let i = r.info();
        (i.width, i.height)
    } else if bytes.starts_with(&[0xFF, 0xD8]) {
        let mut d = jpeg_decoder::Decoder::new(&bytes[..]);
        d.read_info().map_err(|e| bad(about, &name, e))?;
        let i = d.info().ok_or_else(|| bad(about, &name, "no JPEG frame header"))?;
        (i.width as u32, i.height as u32)
    } else {
        return Err(bad(about, &name, "neither PNG nor JPEG (mint reads those two)"));
    };
    if w == 0 || h == 0 || w > MAX_SIDE || h > MAX_SIDE {
        return Err(bad(about, &name, format!("{w}x{h} texels (mint reads sides of 1 to {MAX_SIDE})")));
    }
    Ok((w, h))
}

fn read_source<'a>(source: &'a ImageSource, about: &Path) -> Result<std::borrow::Cow<'a, [u8]>, Error> {
    Ok(match &source.0 {
        Source::File(p) => std::borrow::Cow::Owned(std::fs::read(p).map_err(|e| Error::io(about, &format!("cannot read texture '{}'", p.display()), e))?),
        Source::Embedded { map, range, .. } => std::borrow::Cow::Borrowed(&map.bytes()[range.0..range.1]),
        Source::Bytes(b, _) => std::borrow::Cow::Borrowed(&b[..]),
    })
}

/// Decodes a PNG or JPEG into RGBA bytes.
pub(crate) fn decode(source: &ImageSource, about: &Path) -> Result<Image, Error> {
    let name = source.name();
    let bytes = read_source(source, about)?;
    let (w, h) = size_from(&bytes, source, about)?;
    let n = w as usize * h as usize;
    let mut rgba = vec![255u8; n * 4];
    if bytes.starts_with(b"\x89PNG") {
        let mut dec = png::Decoder::new(&bytes[..]);
        dec.set_transformations(png::Transformations::EXPAND | png::Transformations::STRIP_16);
        let mut r = dec.read_info().map_err(|e| bad(about, &name, e))?;
        let mut buf = vec![0u8; r.output_buffer_size()];
        let f = r.next_frame(&mut buf).map_err(|e| bad(about, &name, e))?;
        let chans = f.color_type.samples();
        if f.width != w || f.height != h || f.line_size < w as usize * chans {
            return Err(bad(about, &name, "a frame of another size than its header"));
        }
        for y in 0..h as usize {
            let row = &buf[y * f.line_size..];
            for x in 0..w as usize {
                let p = &row[x * chans..x * chans + chans];
                let o = &mut rgba[(y * w as usize + x) * 4..][..4];
                match chans {
                    1 => o[..3].fill(p[0]),
                    2 => {
                        o[..3].fill(p[0]);
                        o[3] = p[1];
                    }
                    3 => o[..3].copy_from_slice(p),
                    _ => o.copy_from_slice(&p[..4]),
                }
            }
        }
    } else {
        let mut d = jpeg_decoder::Decoder::new(&bytes[..]);
        let px = d.decode().map_err(|e| bad(about, &name, e))?;
        let info = d.info().ok_or_else(|| bad(about, &name, "no JPEG frame header"))?;
        use jpeg_decoder::PixelFormat::*;
        let chans = match info.pixel_format {
            L8 => 1,
            L16 => 2,
            RGB24 => 3,
            CMYK32 => 4,
        };
        if px.len() < n * chans {
            return Err(bad(about, &name, "fewer pixels than its header says"));
        }
        for i in 0..n {
            let p = &px[i * chans..i * chans + chans];
            let o = &mut rgba[i * 4..i * 4 + 4];
            match info.pixel_format {
                L8 => o[..3].fill(p[0]),
                L16 => o[..3].fill(p[0]),
                RGB24 => o[..3].copy_from_slice(p),
                // Adobe's inverted CMYK, as decoders hand it out.
                CMYK32 => {
                    let k = p[3] as u32;
                    for c in 0..3 {
                        o[c] = (p[c] as u32 * k / 255) as u8;
                    }
                }
            }
        }
    }
    Ok(Image { width: w, height: h, rgba })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn checker() -> Image {
        // 2x2: red, green / blue, white.
        Image { width: 2, height: 2, rgba: vec![255, 0, 0, 255, 0, 255, 0, 255, 0, 0, 255, 255, 255, 255, 255, 255] }
    }

    #[test]
    fn texel_centres_sample_exactly_and_between_them_bilinearly() {
        let im = checker();
        let r = [Wrap::Repeat; 2];
        assert_eq!(im.sample(0.25, 0.25, r), [255.0, 0.0, 0.0, 255.0]);
        assert_eq!(im.sample(0.75, 0.75, r), [255.0; 4]);
        assert_eq!(im.sample(0.5, 0.25, r), [127.5, 127.5, 0.0, 255.0]);
        // Repeat: one period on; clamp: the edge texel; mirror: reflected.
        assert_eq!(im.sample(1.25, 0.25, r), im.sample(0.25, 0.25, r));
        assert_eq!(im.sample(-3.0, 0.25, [Wrap::Clamp; 2]), [255.0, 0.0, 0.0, 255.0]);
        assert_eq!(im.sample(1.25, 0.25, [Wrap::Mirror, Wrap::Repeat]), im.sample(0.75, 0.25, r));
        // NaN and absurd coordinates stay finite.
        assert!(im.sample(f64::NAN, 1e300, r).iter().all(|c| c.is_finite()));
    }
}

//! The colour a baked scene shows at any point of any face: the facet's
//! look (tiled tissue texture, overlay over it, mixed with its continuation
//! from across a seam in the seam bands), then the rings of later facets
//! blended over it, each sampled through its texture transform exactly as a
//! glTF viewer does (KHR_texture_transform), blended in linear light.
//! Atlas baking, the preview and the seam contrast figures all read
//! colours from here, so they agree with each other and with the .glb.

use glam::DVec2;

use crate::error::{Error, Result};

/// A texture's transform, as KHR_texture_transform applies it:
/// `offset + R(rotation) (scale * uv)`, R = [[cos, sin], [-sin, cos]].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transform {
    pub scale: [f64; 2],
    /// Radians.
    pub rotation: f64,
    pub offset: [f64; 2],
}

impl Transform {
    pub const IDENTITY: Transform = Transform {
        scale: [1.0, 1.0],
        rotation: 0.0,
        offset: [0.0, 0.0],
    };

    pub fn apply(&self, uv: DVec2) -> DVec2 {
        let (s, c) = self.rotation.sin_cos();
        let (x, y) = (uv.x * self.scale[0], uv.y * self.scale[1]);
        DVec2::new(
            self.offset[0] + c * x + s * y,
            self.offset[1] - s * x + c * y,
        )
    }
}

/// How a texture repeats past its edges.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Wrap {
    Repeat,
    /// Every other copy mirrored: continuous even for an image that does
    /// not tile (a vessel overlay).
    Mirrored,
}

/// An RGBA image in linear light, ready to sample, with its mip levels.
#[derive(Clone, Debug)]
pub struct Texture {
    pub width: usize,
    pub height: usize,
    /// Level 0 is the image; each next one half the size, box-filtered.
    levels: Vec<Level>,
}

#[derive(Clone, Debug)]
struct Level {
    width: usize,
    height: usize,
    texels: Vec<[f32; 4]>,
}

impl Level {
    /// Half the size, each texel the mean of the 2x2 it covers.
    fn half(&self) -> Level {
        let (w, h) = ((self.width / 2).max(1), (self.height / 2).max(1));
        let at = |x: usize, y: usize| {
            self.texels[y.min(self.height - 1) * self.width + x.min(self.width - 1)]
        };
        let texels = (0..w * h)
            .map(|i| {
                let (x, y) = (2 * (i % w), 2 * (i / w));
                let q = [at(x, y), at(x + 1, y), at(x, y + 1), at(x + 1, y + 1)];
                std::array::from_fn(|c| (q[0][c] + q[1][c] + q[2][c] + q[3][c]) / 4.0)
            })
            .collect();
        Level {
            width: w,
            height: h,
            texels,
        }
    }

    /// Bilinear sample at texture coordinates `t`.
    fn sample(&self, t: DVec2, wrap: Wrap) -> [f32; 4] {
        let x = t.x * self.width as f64 - 0.5;
        let y = t.y * self.height as f64 - 0.5;
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = ((x - x0) as f32, (y - y0) as f32);
        let (i, j) = (x0 as i64, y0 as i64);
        let index = |k: i64, n: usize| match wrap {
            Wrap::Repeat => k.rem_euclid(n as i64) as usize,
            Wrap::Mirrored => {
                let period = 2 * n as i64;
                let k = k.rem_euclid(period);
                (if k < n as i64 { k } else { period - 1 - k }) as usize
            }
        };
        let at =
            |i: i64, j: i64| self.texels[index(j, self.height) * self.width + index(i, self.width)];
        let corners = [at(i, j), at(i + 1, j), at(i, j + 1), at(i + 1, j + 1)];
        std::array::from_fn(|c| {
            let top = corners[0][c] * (1.0 - fx) + corners[1][c] * fx;
            let bottom = corners[2][c] * (1.0 - fx) + corners[3][c] * fx;
            top * (1.0 - fy) + bottom * fy
        })
    }
}

pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

pub fn linear_to_srgb(c: f32) -> f32 {
    let c = c.clamp(0.0, 1.0);
    if c <= 0.0031308 {
        c * 12.92
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

impl Texture {
    /// Read a PNG colour (sRGB) texture.
    pub fn load(path: &std::path::Path) -> Result<Texture> {
        let img = crate::synth::exemplar::read_image(path)?.to_rgba8();
        if img.width() == 0 || img.height() == 0 {
            return Err(Error::format(path, "the texture has no pixels"));
        }
        let texels = img
            .pixels()
            .map(|p| {
                [
                    srgb_to_linear(p[0] as f32 / 255.0),
                    srgb_to_linear(p[1] as f32 / 255.0),
                    srgb_to_linear(p[2] as f32 / 255.0),
                    p[3] as f32 / 255.0,
                ]
            })
            .collect();
        Ok(Texture::new(
            img.width() as usize,
            img.height() as usize,
            texels,
        ))
    }

    /// A texture of `texels` (linear RGBA, row by row), with its mip levels.
    pub fn new(width: usize, height: usize, texels: Vec<[f32; 4]>) -> Texture {
        let mut levels = vec![Level {
            width,
            height,
            texels,
        }];
        while let Some(last) = levels.last()
            && (last.width > 1 || last.height > 1)
        {
            let next = last.half();
            levels.push(next);
        }
        Texture {
            width,
            height,
            levels,
        }
    }

    /// Bilinear sample at texture coordinates `t` (0..1 across the image,
    /// v downwards as in glTF), of the full-size image.
    pub fn sample(&self, t: DVec2, wrap: Wrap) -> [f32; 4] {
        self.levels[0].sample(t, wrap)
    }

    /// Trilinear sample for a footprint `texels` image texels wide: the
    /// image averaged over what one output sample covers, as a GPU's
    /// mipmapping does, so an output coarser than the texture does not alias.
    pub fn sample_filtered(&self, t: DVec2, wrap: Wrap, texels: f64) -> [f32; 4] {
        let lod = texels.max(1.0).log2().min((self.levels.len() - 1) as f64);
        let k = lod.floor() as usize;
        let f = (lod - k as f64) as f32;
        let a = self.levels[k].sample(t, wrap);
        if f == 0.0 || k + 1 >= self.levels.len() {
            return a;
        }
        let b = self.levels[k + 1].sample(t, wrap);
        std::array::from_fn(|c| a[c] * (1.0 - f) + b[c] * f)
    }
}

/// A vessel overlay over a tissue: an RGBA texture (mirrored, since it
/// need not tile) whose alpha, times `opacity`, says where it shows.
#[derive(Clone, Debug, PartialEq)]
pub struct Overlay {
    pub texture: usize,
    pub transform: Transform,
    pub opacity: f32,
}

/// What a facet looks like: its tissue texture, tiled, with its overlay
/// over it.
#[derive(Clone, Debug, PartialEq)]
pub struct Look {
    pub colour: usize,
    pub transform: Transform,
    pub overlay: Option<Overlay>,
}

impl Look {
    /// The side of one texel of the tissue texture in chart (mesh) units.
    pub fn texel_size(&self, textures: &[Texture]) -> f64 {
        let texture = &textures[self.colour];
        let scale = self.transform.scale[0]
            .abs()
            .max(self.transform.scale[1].abs());
        1.0 / (scale * texture.width.max(texture.height) as f64).max(1e-300)
    }

    /// Linear RGB at chart coordinates `uv`, averaged over `footprint`
    /// mesh units (0: the full-size textures).
    pub fn colour(&self, textures: &[Texture], uv: DVec2, footprint: f64) -> [f32; 3] {
        let sample = |texture: &Texture, transform: &Transform, wrap| {
            let texels = footprint
                * transform.scale[0].abs().max(transform.scale[1].abs())
                * texture.width.max(texture.height) as f64;
            texture.sample_filtered(transform.apply(uv), wrap, texels)
        };
        let t = sample(&textures[self.colour], &self.transform, Wrap::Repeat);
        let mut c = [t[0], t[1], t[2]];
        if let Some(o) = &self.overlay {
            let v = sample(&textures[o.texture], &o.transform, Wrap::Mirrored);
            let a = (v[3] * o.opacity).clamp(0.0, 1.0);
            for i in 0..3 {
                c[i] = c[i] * (1.0 - a) + v[i] * a;
            }
        }
        c
    }
}

/// One layer over a face: a look through per-corner chart coordinates,
/// with per-corner alpha, and where the face lies in a seam band the look
/// continued from across the seam mixed in.
#[derive(Clone, Debug, PartialEq)]
pub struct Layer {
    pub look: usize,
    pub uv: [DVec2; 3],
    pub alpha: [f32; 3],
    pub band: Option<Band>,
}

/// A face's seam band (`blend::seam`): chart coordinates continued from
/// across the nearest seam, and how much of that to mix in (1/2 on the
/// seam, 0 at the band's edge).
#[derive(Clone, Debug, PartialEq)]
pub struct Band {
    pub uv: [DVec2; 3],
    pub alpha: [f32; 3],
}

fn interpolate<T: Copy + Into<f64>>(v: [T; 3], w: [f64; 3]) -> f64 {
    v[0].into() * w[0] + v[1].into() * w[1] + v[2].into() * w[2]
}

impl Layer {
    /// Linear RGB and alpha at barycentric `w`, averaged over `footprint`
    /// mesh units.
    pub fn colour(
        &self,
        looks: &[Look],
        textures: &[Texture],
        w: [f64; 3],
        footprint: f64,
    ) -> ([f32; 3], f32) {
        let at = |uv: [DVec2; 3]| uv[0] * w[0] + uv[1] * w[1] + uv[2] * w[2];
        let look = &looks[self.look];
        let mut c = look.colour(textures, at(self.uv), footprint);
        if let Some(band) = &self.band {
            let t = interpolate(band.alpha, w).clamp(0.0, 1.0) as f32;
            if t > 0.0 {
                let d = look.colour(textures, at(band.uv), footprint);
                for i in 0..3 {
                    c[i] = c[i] * (1.0 - t) + d[i] * t;
                }
            }
        }
        (c, interpolate(self.alpha, w).clamp(0.0, 1.0) as f32)
    }
}

/// Every face's layers, bottom first (the first is the facet's own,
/// opaque).
#[derive(Clone, Debug, Default)]
pub struct Compositor {
    pub textures: Vec<Texture>,
    pub looks: Vec<Look>,
    pub layers: Vec<Vec<Layer>>,
}

impl Compositor {
    /// Linear RGB of `face` at barycentric `w`, layers blended "over". A
    /// layer's whole look (tissue and overlay, and its seam band's mix) goes
    /// in at its alpha, so at a seam both sides show exactly the same
    /// half-and-half mix, under a later facet's ring as on its own faces.
    pub fn colour(&self, face: usize, w: [f64; 3]) -> [f32; 3] {
        self.colour_over(face, w, 0.0)
    }

    /// `colour` averaged over `footprint` mesh units, for outputs coarser
    /// than the textures (atlases, the preview's distant pixels).
    pub fn colour_over(&self, face: usize, w: [f64; 3], footprint: f64) -> [f32; 3] {
        let mut out = [0.0f32; 3];
        for (k, layer) in self.layers[face].iter().enumerate() {
            let (c, alpha) = layer.colour(&self.looks, &self.textures, w, footprint);
            let a = if k == 0 { 1.0 } else { alpha };
            for i in 0..3 {
                out[i] = out[i] * (1.0 - a) + c[i] * a;
            }
        }
        out
    }
}

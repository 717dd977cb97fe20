//! Exemplars: a source photograph with a mask of the pixels that may be
//! copied (seed 004, section 3.1: in-vivo frames are cropped and masked to
//! keep only the tissue), and their image pyramids.
//!
//! Mask convention: in a mask image, pixels at least half white are usable,
//! darker ones are masked out; in an alpha channel, alpha below half is
//! masked out.

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// A rectangle of an image, in pixels.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Crop {
    pub x: u32,
    pub y: u32,
    pub width: u32,
    pub height: u32,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Exemplar {
    pub width: usize,
    pub height: usize,
    pub pixels: Vec<[u8; 3]>,
    /// Whether each pixel may be copied.
    pub valid: Vec<bool>,
}

impl Exemplar {
    /// An exemplar from pixels and validity, row by row from the top left.
    pub fn new(
        width: usize,
        height: usize,
        pixels: Vec<[u8; 3]>,
        valid: Vec<bool>,
    ) -> Result<Exemplar> {
        if width == 0 || height == 0 {
            return Err(Error::invalid("the exemplar has no pixels"));
        }
        assert_eq!(pixels.len(), width * height);
        assert_eq!(valid.len(), width * height);
        if !valid.iter().any(|&v| v) {
            return Err(Error::invalid("the mask hides every pixel of the exemplar"));
        }
        Ok(Exemplar {
            width,
            height,
            pixels,
            valid,
        })
    }

    /// Read an exemplar: the image, its mask (a separate image, else the
    /// image's alpha channel, else everything usable), cropped.
    pub fn load(path: &Path, mask: Option<&Path>, crop: Option<Crop>) -> Result<Exemplar> {
        let image = read_image(path)?;
        let (w, h) = (image.width(), image.height());
        let rgba = image.to_rgba8();
        let mut valid: Vec<bool> = rgba.pixels().map(|p| p[3] >= 128).collect();
        if let Some(mask_path) = mask {
            let m = read_image(mask_path)?;
            if (m.width(), m.height()) != (w, h) {
                return Err(Error::format(
                    mask_path,
                    format!(
                        "the mask is {}x{} but the image {} is {w}x{h}",
                        m.width(),
                        m.height(),
                        path.display()
                    ),
                ));
            }
            for (v, p) in valid.iter_mut().zip(m.to_luma8().pixels()) {
                *v &= p[0] >= 128;
            }
        }
        let pixels: Vec<[u8; 3]> = rgba.pixels().map(|p| [p[0], p[1], p[2]]).collect();
        let c = crop.unwrap_or(Crop {
            x: 0,
            y: 0,
            width: w,
            height: h,
        });
        if c.width == 0
            || c.height == 0
            || c.x.checked_add(c.width).is_none_or(|r| r > w)
            || c.y.checked_add(c.height).is_none_or(|b| b > h)
        {
            return Err(Error::format(
                path,
                format!(
                    "the crop {}x{} at ({}, {}) lies outside the {w}x{h} image",
                    c.width, c.height, c.x, c.y
                ),
            ));
        }
        let take = |x: u32, y: u32| ((c.y + y) * w + c.x + x) as usize;
        let cropped: Vec<usize> = (0..c.height)
            .flat_map(|y| (0..c.width).map(move |x| take(x, y)))
            .collect();
        Exemplar::new(
            c.width as usize,
            c.height as usize,
            cropped.iter().map(|&i| pixels[i]).collect(),
            cropped.iter().map(|&i| valid[i]).collect(),
        )
        .map_err(|e| e.in_file(mask.unwrap_or(path)))
    }

    #[inline]
    pub fn index(&self, x: usize, y: usize) -> usize {
        y * self.width + x
    }

    /// Half the size: each pixel the mean of its usable 2 x 2 children,
    /// usable when most of them (at least 3) are. Asking all four would let
    /// a vessel mask eat the coarse levels until only vessel-free regions
    /// remain, and the synthesis would copy from those alone. `None` once a
    /// side would drop below `min_side` or nothing is usable.
    pub fn downsample(&self, min_side: usize) -> Option<Exemplar> {
        let (w, h) = (self.width / 2, self.height / 2);
        if w < min_side || h < min_side {
            return None;
        }
        let mut pixels = Vec::with_capacity(w * h);
        let mut valid = Vec::with_capacity(w * h);
        for y in 0..h {
            for x in 0..w {
                let children = self.children(x, y);
                let usable: Vec<usize> = children
                    .iter()
                    .copied()
                    .filter(|&i| self.valid[i])
                    .collect();
                let from: &[usize] = if usable.is_empty() {
                    &children
                } else {
                    &usable
                };
                let mut sum = [0u32; 3];
                for &i in from {
                    for (s, &c) in sum.iter_mut().zip(&self.pixels[i]) {
                        *s += c as u32;
                    }
                }
                let n = from.len() as u32;
                pixels.push(sum.map(|s| ((s + n / 2) / n) as u8));
                valid.push(usable.len() >= 3);
            }
        }
        valid.iter().any(|&v| v).then_some(Exemplar {
            width: w,
            height: h,
            pixels,
            valid,
        })
    }

    /// The 2 x 2 pixels under coarse pixel (x, y): top left, top right,
    /// bottom left, bottom right.
    pub fn children(&self, x: usize, y: usize) -> [usize; 4] {
        [
            self.index(2 * x, 2 * y),
            self.index(2 * x + 1, 2 * y),
            self.index(2 * x, 2 * y + 1),
            self.index(2 * x + 1, 2 * y + 1),
        ]
    }
}

pub fn read_image(path: &Path) -> Result<image::DynamicImage> {
    if path.is_dir() {
        return Err(Error::format(path, "is a directory, not an image"));
    }
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    let image = image::load_from_memory(&bytes)
        .map_err(|e| Error::format(path, format!("cannot read the image: {e}")))?;
    if image.width() == 0 || image.height() == 0 {
        return Err(Error::format(path, "the image has no pixels"));
    }
    Ok(image)
}

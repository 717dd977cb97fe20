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
    /// Per pixel, whether the window of radius `r` about it lies inside
    /// the exemplar and every pixel of it is usable: candidates there are
    /// costed without a check per pixel.
    pub fn whole_windows(&self, r: usize) -> Vec<bool> {
        let (w, h) = (self.width, self.height);
        (0..w * h)
            .map(|i| {
                let (x, y) = (i % w, i / w);
                x >= r
                    && y >= r
                    && x + r < w
                    && y + r < h
                    && (y - r..=y + r).all(|yy| {
                        self.valid[yy * w + x - r..=yy * w + x + r]
                            .iter()
                            .all(|&v| v)
                    })
            })
            .collect()
    }

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
        if pixels.len() != width * height || valid.len() != width * height {
            return Err(Error::invalid(format!(
                "a {width}x{height} exemplar needs {} pixels and validities, not {} and {}",
                width * height,
                pixels.len(),
                valid.len()
            )));
        }
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

    /// The exemplar as an RGBA image whose alpha is 255 on usable pixels
    /// and 0 on masked ones: what `load` reads back as the same exemplar.
    pub fn to_rgba(&self) -> image::DynamicImage {
        let raw = self
            .pixels
            .iter()
            .zip(&self.valid)
            .flat_map(|(p, &v)| [p[0], p[1], p[2], if v { 255 } else { 0 }])
            .collect();
        // One RGBA pixel per exemplar pixel: width x height of them.
        let img =
            image::RgbaImage::from_raw(self.width as u32, self.height as u32, raw).expect("sized");
        image::DynamicImage::ImageRgba8(img)
    }

    /// Read an exemplar: the image, its mask (a separate image, else the
    /// image's alpha channel, else everything usable), cropped. Any PNG or
    /// JPEG the image crate decodes (grey, grey and alpha, RGB, RGBA, 8 or
    /// 16 bits) is converted to 8-bit RGB; alpha below half masks a pixel.
    pub fn load(path: &Path, mask: Option<&Path>, crop: Option<Crop>) -> Result<Exemplar> {
        // Beyond the decoded image: its RGBA copy (4 bytes a pixel), the
        // exemplar's colour and validity (4) and the mask's grey copy (1).
        let image = read_image_holding(path, 9)?;
        let (w, h) = (image.width(), image.height());
        let rgba = image.to_rgba8();
        drop(image);
        let mask_grey = match mask {
            Some(mask_path) => {
                let m = read_image_holding(mask_path, 1)?;
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
                Some(m.to_luma8())
            }
            None => None,
        };
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
        let count = c.width as usize * c.height as usize;
        let mut pixels = Vec::with_capacity(count);
        let mut valid = Vec::with_capacity(count);
        // Within the image: the crop was checked against it above.
        for y in c.y..c.y + c.height {
            for x in c.x..c.x + c.width {
                let p = rgba.get_pixel(x, y).0;
                let masked = mask_grey
                    .as_ref()
                    .is_some_and(|m| m.get_pixel(x, y).0[0] < 128);
                pixels.push([p[0], p[1], p[2]]);
                valid.push(p[3] >= 128 && !masked);
            }
        }
        Exemplar::new(c.width as usize, c.height as usize, pixels, valid)
            .map_err(|e| e.in_file(mask.unwrap_or(path)))
    }

    /// Refuse an exemplar smaller than one `neighbourhood`-wide square:
    /// synthesis copies whole neighbourhoods, and a smaller exemplar has
    /// none to copy (a 1 x 1 one would only give its flat colour).
    pub fn check_neighbourhood(&self, neighbourhood: usize) -> Result<()> {
        if self.width < neighbourhood || self.height < neighbourhood {
            return Err(Error::invalid(format!(
                "the exemplar is {}x{} pixels (after any crop), smaller than one {k}x{k} \
                 neighbourhood: it needs at least {k}x{k} pixels to copy from",
                self.width,
                self.height,
                k = neighbourhood
            )));
        }
        Ok(())
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

    /// The exemplar scaled to `height` rows, its width in proportion
    /// (layered synthesis wants as many rows as the block has depth):
    /// colours filtered (triangle), validity by nearest pixel.
    pub fn with_height(&self, height: usize) -> Result<Exemplar> {
        let width = ((self.width * height) as f64 / self.height as f64)
            .round()
            .max(1.0) as usize;
        if width == self.width && height == self.height {
            return Ok(self.clone());
        }
        let (w, h) = (self.width as u32, self.height as u32);
        let colour = image::RgbImage::from_fn(w, h, |x, y| {
            image::Rgb(self.pixels[self.index(x as usize, y as usize)])
        });
        let mask = image::GrayImage::from_fn(w, h, |x, y| {
            image::Luma([255 * self.valid[self.index(x as usize, y as usize)] as u8])
        });
        let (nw, nh) = (width as u32, height as u32);
        let colour =
            image::imageops::resize(&colour, nw, nh, image::imageops::FilterType::Triangle);
        let mask = image::imageops::resize(&mask, nw, nh, image::imageops::FilterType::Nearest);
        Exemplar::new(
            width,
            height,
            colour.pixels().map(|p| p.0).collect(),
            mask.pixels().map(|p| p.0[0] > 127).collect(),
        )
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

/// The largest image side organtex reads (a 16384 x 16384 RGBA image is
/// already 1 GiB).
pub const MAX_IMAGE_SIDE: u32 = 16384;

/// Read a PNG or JPEG. The size in its header is checked before anything
/// is decoded: at most `MAX_IMAGE_SIDE` a side, and the decoded image and
/// an 8-bit RGBA copy of it must fit in memory.
pub fn read_image(path: &Path) -> Result<image::DynamicImage> {
    read_image_holding(path, 4)
}

/// `read_image` for a caller that then holds `extra` bytes per pixel.
/// Refuse a PNG whose palette (PLTE chunk) is not whole RGB entries: the
/// png crate (0.18.1, image-rs/image-png#694) panics on one instead of
/// returning an error. Found by fuzzing (tests/data/fuzz-regressions/image).
/// Reads only chunk headers up to the first image data.
fn check_png_palette(path: &Path) -> Result<()> {
    use std::io::{Read, Seek, SeekFrom};
    let mut file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    let mut header = [0u8; 8];
    // The signature; a short file is left for the decoder to report.
    if file.read_exact(&mut header).is_err() {
        return Ok(());
    }
    while file.read_exact(&mut header).is_ok() {
        let len = u32::from_be_bytes([header[0], header[1], header[2], header[3]]);
        match &header[4..8] {
            b"PLTE" if len % 3 != 0 || len > 3 * 256 => {
                return Err(Error::format(
                    path,
                    format!(
                        "cannot read the image: its palette chunk is {len} bytes, \
                         not whole RGB entries (at most 256 of 3 bytes)"
                    ),
                ));
            }
            b"IDAT" | b"IEND" => return Ok(()),
            _ => {}
        }
        // The chunk's data and its CRC.
        if file.seek(SeekFrom::Current(len as i64 + 4)).is_err() {
            return Ok(());
        }
    }
    Ok(())
}

fn read_image_holding(path: &Path, extra: u64) -> Result<image::DynamicImage> {
    use image::ImageDecoder;

    if path.is_dir() {
        return Err(Error::format(path, "is a directory, not an image"));
    }
    let file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    let cannot = |e: image::ImageError| Error::format(path, format!("cannot read the image: {e}"));
    let mut reader = image::ImageReader::new(std::io::BufReader::new(file))
        .with_guessed_format()
        .map_err(|e| Error::io(path, e))?;
    match reader.format() {
        None => {
            return Err(Error::format(
                path,
                "cannot read the image: it is neither a PNG nor a JPEG file",
            ));
        }
        Some(image::ImageFormat::Png) => check_png_palette(path)?,
        Some(_) => {}
    }
    // The side limit is checked below with a clearer message; this bounds
    // what the decoder may allocate while reading the header.
    let mut header_limits = image::Limits::default();
    header_limits.max_alloc = Some(64 << 20);
    reader.limits(header_limits);
    let mut decoder = reader.into_decoder().map_err(cannot)?;
    let (w, h) = decoder.dimensions();
    if w == 0 || h == 0 {
        return Err(Error::format(path, "the image has no pixels"));
    }
    if w > MAX_IMAGE_SIDE || h > MAX_IMAGE_SIDE {
        return Err(Error::format(
            path,
            format!(
                "the image is {w}x{h} pixels; organtex reads images of at most \
                 {MAX_IMAGE_SIDE} pixels a side"
            ),
        ));
    }
    let decoded = decoder.total_bytes();
    let pixels = w as u64 * h as u64;
    crate::memory::ensure_fits(
        &format!("decoding this {w}x{h} image"),
        decoded.saturating_add(pixels * extra),
    )
    .map_err(|e| e.in_file(path))?;
    let mut limits = image::Limits::default();
    limits.max_image_width = Some(MAX_IMAGE_SIDE);
    limits.max_image_height = Some(MAX_IMAGE_SIDE);
    // The image itself and the decoder's working buffers (a few rows).
    limits.max_alloc = Some(decoded.saturating_mul(2).max(64 << 20));
    decoder.set_limits(limits).map_err(cannot)?;
    image::DynamicImage::from_decoder(decoder).map_err(cannot)
}

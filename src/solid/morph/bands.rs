//! An exemplar split into a low-frequency band (a Gaussian blur) and the
//! detail band (what the blur removed). Beyond seed 003, the morph
//! interpolates the low band and morphs only the detail band, with its
//! local histogram matched (5.3): coarse structure lands where the
//! exemplars agree it is, and fine structure stays sharp (`point`).
//!
//! Pixels the mask hides take the colour of the nearest tissue pixel
//! first, so neither band near the mask's edge blends in what the
//! photograph shows beyond the tissue.

use std::collections::VecDeque;

use glam::DVec2;

use super::sections::Exemplar;
use crate::synth::filter::Plane;

#[derive(Clone, Debug)]
pub struct Bands {
    width: usize,
    height: usize,
    pub low: Vec<[f32; 3]>,
    pub detail: Vec<[f32; 3]>,
}

impl Bands {
    /// The bands of `e`, the low band blurred with standard deviation
    /// `sigma` pixels.
    pub fn new(e: &Exemplar, sigma: f32) -> Bands {
        let rgb = filled(e);
        let (w, h) = (e.width, e.height);
        let ones = vec![1.0; w * h];
        let channels: Vec<Vec<f32>> = (0..3)
            .map(|c| {
                Plane::new(w, h, rgb.iter().map(|p| p[c]).collect())
                    .blur(sigma, &ones)
                    .data
            })
            .collect();
        let low: Vec<[f32; 3]> = (0..w * h)
            .map(|i| [channels[0][i], channels[1][i], channels[2][i]])
            .collect();
        let detail = rgb
            .iter()
            .zip(&low)
            .map(|(p, l)| [p[0] - l[0], p[1] - l[1], p[2] - l[2]])
            .collect();
        Bands {
            width: w,
            height: h,
            low,
            detail,
        }
    }

    /// Bilinear sample of `band` at pixel coordinates `q` (pixel (i, j)'s
    /// centre at (i + 0.5, j + 0.5)), clamped to the image.
    #[inline]
    pub fn sample(&self, band: &[[f32; 3]], q: DVec2) -> [f32; 3] {
        let x = (q.x - 0.5).clamp(0.0, (self.width - 1) as f64);
        let y = (q.y - 0.5).clamp(0.0, (self.height - 1) as f64);
        let (x0, y0) = (x as usize, y as usize);
        let (x1, y1) = ((x0 + 1).min(self.width - 1), (y0 + 1).min(self.height - 1));
        let (fx, fy) = ((x - x0 as f64) as f32, (y - y0 as f64) as f32);
        let at = |x: usize, y: usize| band[y * self.width + x];
        let (a, b, c, d) = (at(x0, y0), at(x1, y0), at(x0, y1), at(x1, y1));
        std::array::from_fn(|k| {
            let top = a[k] + (b[k] - a[k]) * fx;
            let bottom = c[k] + (d[k] - c[k]) * fx;
            top + (bottom - top) * fy
        })
    }

    /// Luminance of the full image (both bands), for the warps.
    pub fn luminance(&self) -> Plane {
        Plane::new(
            self.width,
            self.height,
            self.low
                .iter()
                .zip(&self.detail)
                .map(|(l, d)| 0.299 * (l[0] + d[0]) + 0.587 * (l[1] + d[1]) + 0.114 * (l[2] + d[2]))
                .collect(),
        )
    }
}

/// The exemplar's colours with masked pixels set to their nearest tissue
/// pixel's (breadth-first from the tissue, so 4-connected steps).
fn filled(e: &Exemplar) -> Vec<[f32; 3]> {
    let Some(mask) = &e.mask else {
        return e.rgb.clone();
    };
    let (w, h) = (e.width, e.height);
    let mut rgb = e.rgb.clone();
    let mut done = mask.clone();
    let mut queue: VecDeque<usize> = (0..w * h).filter(|&i| mask[i]).collect();
    while let Some(i) = queue.pop_front() {
        let (x, y) = (i % w, i / w);
        let neighbours = [
            (x > 0).then(|| i - 1),
            (x + 1 < w).then(|| i + 1),
            (y > 0).then(|| i - w),
            (y + 1 < h).then(|| i + w),
        ];
        for j in neighbours.into_iter().flatten() {
            if !done[j] {
                done[j] = true;
                rgb[j] = rgb[i];
                queue.push_back(j);
            }
        }
    }
    rgb
}

//! Gaussian filtering of single-channel float images that respects a mask:
//! normalised convolution (Knutsson and Westin 1993), so masked pixels (a
//! black photo border) never bleed into their neighbours, and the edges of
//! the image are not darkened.

use rayon::prelude::*;

/// A single-channel float image, row by row from the top left.
#[derive(Clone, Debug, PartialEq)]
pub struct Plane {
    pub width: usize,
    pub height: usize,
    pub data: Vec<f32>,
}

impl Plane {
    pub fn new(width: usize, height: usize, data: Vec<f32>) -> Plane {
        assert_eq!(data.len(), width * height);
        Plane {
            width,
            height,
            data,
        }
    }

    #[inline]
    pub fn at(&self, x: usize, y: usize) -> f32 {
        self.data[y * self.width + x]
    }

    /// Gaussian blur with standard deviation `sigma` over the pixels where
    /// `weight` is positive, each weighted by it.
    pub fn blur(&self, sigma: f32, weight: &[f32]) -> Plane {
        let kernel = gaussian_kernel(sigma);
        let weighted: Vec<f32> = self.data.iter().zip(weight).map(|(v, w)| v * w).collect();
        let num = separable(&weighted, self.width, self.height, &kernel);
        let den = separable(weight, self.width, self.height, &kernel);
        Plane::new(
            self.width,
            self.height,
            num.iter()
                .zip(&den)
                .map(|(n, d)| if *d > 1e-6 { n / d } else { 0.0 })
                .collect(),
        )
    }
}

fn gaussian_kernel(sigma: f32) -> Vec<f32> {
    let r = (3.0 * sigma).ceil().max(1.0) as i32;
    let k: Vec<f32> = (-r..=r)
        .map(|i| (-(i * i) as f32 / (2.0 * sigma * sigma)).exp())
        .collect();
    let sum: f32 = k.iter().sum();
    k.iter().map(|v| v / sum).collect()
}

/// Convolve rows then columns with `kernel`, treating outside pixels as 0;
/// rows in parallel (each output pixel is one fixed sum, so the result does
/// not depend on the thread count).
fn separable(data: &[f32], w: usize, h: usize, kernel: &[f32]) -> Vec<f32> {
    let r = (kernel.len() / 2) as isize;
    let pass = |src: &[f32], along_rows: bool| -> Vec<f32> {
        let mut out = vec![0.0; w * h];
        out.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
            for (x, slot) in row.iter_mut().enumerate() {
                let mut acc = 0.0;
                for (k, &kv) in kernel.iter().enumerate() {
                    let d = k as isize - r;
                    let (sx, sy) = if along_rows {
                        (x as isize + d, y as isize)
                    } else {
                        (x as isize, y as isize + d)
                    };
                    if sx >= 0 && sy >= 0 && (sx as usize) < w && (sy as usize) < h {
                        acc += kv * src[sy as usize * w + sx as usize];
                    }
                }
                *slot = acc;
            }
        });
        out
    };
    pass(&pass(data, true), false)
}

/// Grow the `true` pixels by a disc of `radius` pixels.
pub fn dilate(mask: &[bool], w: usize, h: usize, radius: usize) -> Vec<bool> {
    let r = radius as isize;
    let mut out = vec![false; w * h];
    for y in 0..h as isize {
        for x in 0..w as isize {
            if !mask[y as usize * w + x as usize] {
                continue;
            }
            for dy in -r..=r {
                for dx in -r..=r {
                    let (nx, ny) = (x + dx, y + dy);
                    if dx * dx + dy * dy <= r * r
                        && nx >= 0
                        && ny >= 0
                        && (nx as usize) < w
                        && (ny as usize) < h
                    {
                        out[ny as usize * w + nx as usize] = true;
                    }
                }
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blurring_a_constant_keeps_it_even_next_to_masked_pixels() {
        let (w, h) = (20, 10);
        let plane = Plane::new(w, h, vec![5.0; w * h]);
        let weight: Vec<f32> = (0..w * h)
            .map(|i| if i % w < 4 { 0.0 } else { 1.0 })
            .collect();
        let blurred = plane.blur(2.0, &weight);
        for y in 0..h {
            for x in 4..w {
                assert!((blurred.at(x, y) - 5.0).abs() < 1e-4);
            }
        }
    }
}

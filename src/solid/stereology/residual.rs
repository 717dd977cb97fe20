//! Fine detail (seed 001, sec. 4.3): the residual, the photograph less
//! each profile's mean colour and the binder's, lacks the particles'
//! structure and is resynthesised as a volume by Heeger and Bergen's
//! pyramid histogram matching in 3D: white noise whose Laplacian pyramid
//! bands, band by band, and whole take the histograms of the residual's
//! 2D bands. The volume wraps in x, y and z, so the block still tiles.
//!
//! Colour: the residual's luminance (mean of its channels) is what is
//! synthesised; each channel gets it times its regression gain on the
//! luminance (stain residuals move the three channels together, so one
//! volume carries most of the detail for a third of the work).

use rayon::prelude::*;

use crate::rng;

/// Heeger-Bergen iterations.
const ROUNDS: usize = 4;
/// The coarsest pyramid level keeps at least this many pixels a side.
const COARSEST: usize = 8;

/// The residual of a photograph: per pixel, its colour less `mean[i]`
/// (its profile's mean colour, or the binder's); `None` pixels (masked)
/// are left out.
pub fn residual(pixels: &[[u8; 3]], mean: &[Option<[f64; 3]>]) -> Vec<Option<[f64; 3]>> {
    pixels
        .iter()
        .zip(mean)
        .map(|(p, m)| m.map(|m| [0, 1, 2].map(|k| p[k] as f64 - m[k])))
        .collect()
}

/// Luminance samples of one residual image (`width` x `height`, `None`
/// masked) and each channel's gain on it.
#[derive(Clone, Debug)]
pub struct Residual2d {
    pub width: usize,
    pub height: usize,
    /// Luminance per pixel (masked pixels 0).
    pub luminance: Vec<f32>,
    pub valid: Vec<bool>,
    pub gain: [f64; 3],
}

impl Residual2d {
    pub fn new(width: usize, height: usize, r: &[Option<[f64; 3]>]) -> Residual2d {
        let luminance: Vec<f32> = r
            .iter()
            .map(|c| c.map_or(0.0, |c| ((c[0] + c[1] + c[2]) / 3.0) as f32))
            .collect();
        let valid: Vec<bool> = r.iter().map(Option::is_some).collect();
        let (mut sll, mut slc) = (0.0, [0.0; 3]);
        for (c, &l) in r.iter().zip(&luminance) {
            if let Some(c) = c {
                let l = l as f64;
                sll += l * l;
                for k in 0..3 {
                    slc[k] += l * c[k];
                }
            }
        }
        let gain = slc.map(|s| if sll > 0.0 { s / sll } else { 1.0 });
        Residual2d {
            width,
            height,
            luminance,
            valid,
            gain,
        }
    }
}

/// Blur by [1 4 6 4 1] / 16 along one axis of a `dims` grid, wrapping
/// (3D) or clamping (2D images).
fn blur_axis(v: &[f32], dims: [usize; 3], axis: usize, wrap: bool) -> Vec<f32> {
    const K: [f32; 5] = [1.0 / 16.0, 4.0 / 16.0, 6.0 / 16.0, 4.0 / 16.0, 1.0 / 16.0];
    let [nx, ny, _] = dims;
    let n = dims[axis] as i64;
    (0..v.len())
        .into_par_iter()
        .map(|i| {
            let p = [i % nx, i / nx % ny, i / (nx * ny)];
            let mut acc = 0.0;
            for (t, &w) in K.iter().enumerate() {
                let c = p[axis] as i64 + t as i64 - 2;
                let c = if wrap {
                    c.rem_euclid(n)
                } else {
                    c.clamp(0, n - 1)
                } as usize;
                let mut q = p;
                q[axis] = c;
                acc += w * v[(q[2] * ny + q[1]) * nx + q[0]];
            }
            acc
        })
        .collect()
}

fn blur(v: &[f32], dims: [usize; 3], wrap: bool) -> Vec<f32> {
    let mut out = v.to_vec();
    for axis in 0..3 {
        if dims[axis] > 1 {
            out = blur_axis(&out, dims, axis, wrap);
        }
    }
    out
}

/// Half the size along every axis longer than 1, after blurring.
fn reduce(v: &[f32], dims: [usize; 3], wrap: bool) -> (Vec<f32>, [usize; 3]) {
    let b = blur(v, dims, wrap);
    let half = dims.map(|d| if d > 1 { d / 2 } else { 1 });
    let step = dims.map(|d| if d > 1 { 2 } else { 1 });
    let out = (0..half[0] * half[1] * half[2])
        .map(|i| {
            let p = [i % half[0], i / half[0] % half[1], i / (half[0] * half[1])];
            b[((p[2] * step[2]) * dims[1] + p[1] * step[1]) * dims[0] + p[0] * step[0]]
        })
        .collect();
    (out, half)
}

/// Back to `dims`: nearest parent, then blurred (the smoothing the
/// reduction took out, near enough for a band decomposition that is
/// exact by construction: bands are G - expand(reduce(G))).
fn expand(v: &[f32], small: [usize; 3], dims: [usize; 3], wrap: bool) -> Vec<f32> {
    let up: Vec<f32> = (0..dims[0] * dims[1] * dims[2])
        .map(|i| {
            let p = [i % dims[0], i / dims[0] % dims[1], i / (dims[0] * dims[1])];
            let q = [0, 1, 2].map(|k| (p[k] * small[k] / dims[k]).min(small[k] - 1));
            v[(q[2] * small[1] + q[1]) * small[0] + q[0]]
        })
        .collect();
    blur(&up, dims, wrap)
}

/// Laplacian pyramid: bands finest first, then the coarsest Gaussian.
fn pyramid(v: &[f32], dims: [usize; 3], levels: usize, wrap: bool) -> Vec<(Vec<f32>, [usize; 3])> {
    let mut out = Vec::new();
    let (mut g, mut d) = (v.to_vec(), dims);
    for _ in 1..levels {
        let (small, sd) = reduce(&g, d, wrap);
        let up = expand(&small, sd, d, wrap);
        out.push((g.iter().zip(&up).map(|(a, b)| a - b).collect(), d));
        g = small;
        d = sd;
    }
    out.push((g, d));
    out
}

fn collapse(p: &[(Vec<f32>, [usize; 3])], wrap: bool) -> Vec<f32> {
    let mut g = p.last().expect("a level").0.clone();
    let mut d = p.last().expect("a level").1;
    for (band, bd) in p.iter().rev().skip(1) {
        let up = expand(&g, d, *bd, wrap);
        g = band.iter().zip(&up).map(|(a, b)| a + b).collect();
        d = *bd;
    }
    g
}

/// Give `v` the distribution of `sorted` (ascending): each value replaced
/// by the target quantile at its rank (ties by index, for determinism).
fn match_histogram(v: &mut [f32], sorted: &[f32]) {
    if sorted.is_empty() {
        return;
    }
    let mut order: Vec<u32> = (0..v.len() as u32).collect();
    order.par_sort_unstable_by(|&a, &b| v[a as usize].total_cmp(&v[b as usize]).then(a.cmp(&b)));
    let n = v.len().max(2) as f64;
    let m = sorted.len();
    for (rank, &i) in order.iter().enumerate() {
        let q = rank as f64 / (n - 1.0) * (m - 1) as f64;
        let (lo, t) = (q.floor() as usize, (q - q.floor()) as f32);
        let hi = (lo + 1).min(m - 1);
        v[i as usize] = sorted[lo] * (1.0 - t) + sorted[hi] * t;
    }
}

/// An `n`^3 volume of the residual's luminance (Heeger-Bergen in 3D),
/// seeded; wraps in x, y and z.
pub fn synthesize(r: &Residual2d, n: usize, seed: u64) -> Vec<f32> {
    let dims2 = [r.width, r.height, 1];
    let levels = {
        let mut l = 1;
        while (r.width.min(r.height) >> l) >= COARSEST && (n >> l) >= COARSEST {
            l += 1;
        }
        l
    };
    // The 2D bands' sorted values (usable pixels only where the mask
    // reaches the finest level; coarser levels take every value).
    let p2 = pyramid(&r.luminance, dims2, levels, false);
    let targets: Vec<Vec<f32>> = p2
        .iter()
        .enumerate()
        .map(|(l, (band, _))| {
            let mut s: Vec<f32> = if l == 0 {
                band.iter()
                    .zip(&r.valid)
                    .filter(|(_, v)| **v)
                    .map(|(x, _)| *x)
                    .collect()
            } else {
                band.clone()
            };
            s.sort_unstable_by(f32::total_cmp);
            s
        })
        .collect();
    let mut whole: Vec<f32> = r
        .luminance
        .iter()
        .zip(&r.valid)
        .filter(|(_, v)| **v)
        .map(|(x, _)| *x)
        .collect();
    whole.sort_unstable_by(f32::total_cmp);
    let dims3 = [n, n, n];
    let mut v: Vec<f32> = (0..n * n * n)
        .map(|i| rng::unit(seed, &[i as u64, 0x5e5]) as f32)
        .collect();
    match_histogram(&mut v, &whole);
    for _ in 0..ROUNDS {
        let mut p3 = pyramid(&v, dims3, levels, true);
        for ((band, _), target) in p3.iter_mut().zip(&targets) {
            match_histogram(band, target);
        }
        v = collapse(&p3, true);
        match_histogram(&mut v, &whole);
    }
    v
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_pyramid_collapses_back_to_its_input() {
        let dims = [16, 8, 4];
        let v: Vec<f32> = (0..16 * 8 * 4).map(|i| ((i * 37) % 11) as f32).collect();
        let back = collapse(&pyramid(&v, dims, 3, true), true);
        assert!(v.iter().zip(&back).all(|(a, b)| (a - b).abs() < 1e-4));
    }

    #[test]
    fn the_volume_takes_the_residuals_histogram() {
        let (w, h) = (64, 64);
        let r: Vec<Option<[f64; 3]>> = (0..w * h)
            .map(|i| {
                let x = (i % w) as f64;
                let s = 20.0 * (x * 0.7).sin() + 5.0 * ((i / w) as f64 * 1.3).cos();
                Some([s, s * 0.5, -s])
            })
            .collect();
        let res = Residual2d::new(w, h, &r);
        assert!(
            (res.gain[0] - 6.0).abs() < 1e-6 && (res.gain[2] + 6.0).abs() < 1e-6,
            "{:?}",
            res.gain
        );
        let v = synthesize(&res, 32, 1);
        let mut a = v.clone();
        a.sort_unstable_by(f32::total_cmp);
        let mut b = res.luminance.clone();
        b.sort_unstable_by(f32::total_cmp);
        for q in [0.05, 0.5, 0.95] {
            let (x, y) = (
                a[(q * (a.len() - 1) as f64) as usize],
                b[(q * (b.len() - 1) as f64) as usize],
            );
            assert!((x - y).abs() < 0.5, "quantile {q}: {x} vs {y}");
        }
        assert_eq!(v, synthesize(&res, 32, 1));
    }
}

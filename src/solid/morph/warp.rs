//! Warps between exemplars that bound a common region (seed 003, 5.1.1,
//! after Matusik et al. 2005): a dense map f_ij from X_i to X_j, found
//! once per pair by multilevel feature matching.
//!
//! 1. The two subdomains are first aligned by their bounding boxes.
//! 2. Each exemplar's luminance becomes a Gaussian stack (one blur per
//!    level, σ = 2^l reduced pixels) and each level a feature image: the
//!    blurred luminance and its gradient magnitude (the edge detector),
//!    each scaled to unit deviation. Blurring first and sampling coarser
//!    afterwards is the paper's point against plain downsampling (Fig. 4).
//! 3. From the coarsest level down, every node of a grid over X_i moves to
//!    the best of its 3x3 candidate displacements: the feature difference
//!    over a 3x3 patch at the level's spacing, plus a deformation
//!    regulariser (the squared distance from its neighbours' mean
//!    displacement, in search steps). Nodes move together (Jacobi), so the
//!    result does not depend on the thread count.
//!
//! The maps are not constrained to be inverse to each other: the morph
//! (eq. 4) reads f_ji only at source points, where the approximation it
//! makes is larger than that error.

use glam::DVec2;
use rayon::prelude::*;

use super::bands::Bands;
use crate::synth::filter::Plane;

/// Reduced pixels a side of the images the matching reads.
const MATCH_SIDE: usize = 256;
/// Stack levels: σ = 1, 2, 4, 8, 16 reduced pixels.
const LEVELS: usize = 5;
/// Grid nodes a side of a warp.
const NODES: usize = 64;
/// Candidate moves per node and level.
const ITERATIONS: usize = 6;
/// The moves a node tries besides staying.
const MOVES: [(f64, f64); 8] = [
    (-1.0, -1.0),
    (0.0, -1.0),
    (1.0, -1.0),
    (-1.0, 0.0),
    (1.0, 0.0),
    (-1.0, 1.0),
    (0.0, 1.0),
    (1.0, 1.0),
];
/// Weight of the regulariser against the feature difference.
const STIFFNESS: f32 = 8.0;

/// One exemplar's feature images for matching.
pub struct Stack {
    /// Image pixels per reduced pixel.
    scale: f64,
    w: usize,
    h: usize,
    /// Per level, (luminance, edge) per reduced pixel.
    levels: Vec<Vec<[f32; 2]>>,
}

impl Stack {
    pub fn new(bands: &Bands) -> Stack {
        let full = bands.luminance();
        let factor = full.width.max(full.height).div_ceil(MATCH_SIDE).max(1);
        let (w, h) = (full.width.div_ceil(factor), full.height.div_ceil(factor));
        // Box-average the image down by `factor`.
        let mut reduced = vec![0.0f32; w * h];
        let mut counts = vec![0.0f32; w * h];
        for y in 0..full.height {
            for x in 0..full.width {
                let i = (y / factor) * w + x / factor;
                reduced[i] += full.at(x, y);
                counts[i] += 1.0;
            }
        }
        for (r, c) in reduced.iter_mut().zip(&counts) {
            *r /= c;
        }
        let reduced = Plane::new(w, h, reduced);
        let ones = vec![1.0; w * h];
        let levels = (0..LEVELS)
            .map(|l| {
                let blurred = reduced.blur((1u32 << l) as f32, &ones);
                let at = |x: isize, y: isize| {
                    blurred.at(
                        x.clamp(0, w as isize - 1) as usize,
                        y.clamp(0, h as isize - 1) as usize,
                    )
                };
                let mut f: Vec<[f32; 2]> = (0..w * h)
                    .map(|i| {
                        let (x, y) = ((i % w) as isize, (i / w) as isize);
                        let gx = at(x + 1, y) - at(x - 1, y);
                        let gy = at(x, y + 1) - at(x, y - 1);
                        [blurred.data[i], (gx * gx + gy * gy).sqrt()]
                    })
                    .collect();
                for k in 0..2 {
                    let n = f.len() as f32;
                    let mean = f.iter().map(|v| v[k]).sum::<f32>() / n;
                    let var = f.iter().map(|v| (v[k] - mean).powi(2)).sum::<f32>() / n;
                    let inv = 1.0 / var.sqrt().max(1e-6);
                    for v in &mut f {
                        v[k] = (v[k] - mean) * inv;
                    }
                }
                f
            })
            .collect();
        Stack {
            scale: factor as f64,
            w,
            h,
            levels,
        }
    }

    /// Features at level `l` at image pixel coordinates `q`, bilinear.
    #[inline]
    fn at(&self, l: usize, q: DVec2) -> [f32; 2] {
        let x = (q.x / self.scale - 0.5).clamp(0.0, (self.w - 1) as f64);
        let y = (q.y / self.scale - 0.5).clamp(0.0, (self.h - 1) as f64);
        let (x0, y0) = (x as usize, y as usize);
        let (x1, y1) = ((x0 + 1).min(self.w - 1), (y0 + 1).min(self.h - 1));
        let (fx, fy) = ((x - x0 as f64) as f32, (y - y0 as f64) as f32);
        let f = &self.levels[l];
        let (a, b, c, d) = (
            f[y0 * self.w + x0],
            f[y0 * self.w + x1],
            f[y1 * self.w + x0],
            f[y1 * self.w + x1],
        );
        std::array::from_fn(|k| {
            let top = a[k] + (b[k] - a[k]) * fx;
            let bottom = c[k] + (d[k] - c[k]) * fx;
            top + (bottom - top) * fy
        })
    }
}

/// A map from one exemplar's pixel coordinates to another's, on a grid of
/// nodes over the first one's subdomain, bilinear between them.
#[derive(Clone, Debug)]
pub struct Warp {
    lo: DVec2,
    step: DVec2,
    w: usize,
    h: usize,
    target: Vec<DVec2>,
}

impl Warp {
    /// Bytes held.
    pub fn bytes(&self) -> usize {
        16 * self.target.len()
    }
}

impl Warp {
    /// The image of `q` (clamped to the grid).
    #[inline]
    pub fn at(&self, q: DVec2) -> DVec2 {
        let c = (q - self.lo) / self.step;
        let x = c.x.clamp(0.0, (self.w - 1) as f64);
        let y = c.y.clamp(0.0, (self.h - 1) as f64);
        let (x0, y0) = (x as usize, y as usize);
        let (x1, y1) = ((x0 + 1).min(self.w - 1), (y0 + 1).min(self.h - 1));
        let (fx, fy) = (x - x0 as f64, y - y0 as f64);
        let t = |x: usize, y: usize| self.target[y * self.w + x];
        let top = t(x0, y0).lerp(t(x1, y0), fx);
        let bottom = t(x0, y1).lerp(t(x1, y1), fx);
        top.lerp(bottom, fy)
    }

    /// The warp from the subdomain with pixel-coordinate bounds `from`
    /// (on the exemplar whose stack is `a`) to the one with bounds `to`
    /// (stack `b`).
    pub fn matched(a: &Stack, from: (DVec2, DVec2), b: &Stack, to: (DVec2, DVec2)) -> Warp {
        let size_a = (from.1 - from.0).max(DVec2::splat(1e-9));
        let size_b = (to.1 - to.0).max(DVec2::splat(1e-9));
        let ratio = size_b / size_a;
        let (w, h) = (NODES, NODES);
        let step = size_a / (NODES - 1) as f64;
        let node = |i: usize| from.0 + DVec2::new((i % w) as f64, (i / w) as f64) * step;
        let aligned = |q: DVec2| to.0 + (q - from.0) * ratio;
        let mut shift = vec![DVec2::ZERO; w * h];
        for l in (0..LEVELS).rev() {
            // The patch spacing and the search step, in each image's pixels.
            let spacing = (1u32 << l) as f64 * a.scale;
            let search = 0.5 * (1u32 << l) as f64 * b.scale;
            let offsets: Vec<DVec2> = (-1..=1)
                .flat_map(|y| (-1..=1).map(move |x| DVec2::new(x as f64, y as f64) * spacing))
                .collect();
            let patches: Vec<Vec<[f32; 2]>> = (0..w * h)
                .into_par_iter()
                .map(|i| offsets.iter().map(|&o| a.at(l, node(i) + o)).collect())
                .collect();
            for _ in 0..ITERATIONS {
                let mean = neighbour_mean(&shift, w, h);
                shift = (0..w * h)
                    .into_par_iter()
                    .map(|i| {
                        let base = aligned(node(i));
                        let cost = |d: DVec2| {
                            let q = base + d;
                            let mut cost =
                                STIFFNESS * ((d - mean[i]) / search).length_squared() as f32;
                            for (o, pa) in offsets.iter().zip(&patches[i]) {
                                let pb = b.at(l, q + *o * ratio);
                                cost += (pa[0] - pb[0]).powi(2) + (pa[1] - pb[1]).powi(2);
                            }
                            cost
                        };
                        // Staying put first, so a tie keeps the node still.
                        let mut best = (cost(shift[i]), shift[i]);
                        for (dx, dy) in MOVES {
                            let d = shift[i] + DVec2::new(dx, dy) * search;
                            let c = cost(d);
                            if c < best.0 {
                                best = (c, d);
                            }
                        }
                        best.1
                    })
                    .collect();
            }
        }
        Warp {
            lo: from.0,
            step,
            w,
            h,
            target: (0..w * h).map(|i| aligned(node(i)) + shift[i]).collect(),
        }
    }
}

/// Each node's mean of its 4-neighbours (itself at the grid's edges).
fn neighbour_mean(v: &[DVec2], w: usize, h: usize) -> Vec<DVec2> {
    (0..w * h)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            let mut sum = DVec2::ZERO;
            let mut n = 0.0;
            for (ok, j) in [
                (x > 0, i.wrapping_sub(1)),
                (x + 1 < w, i + 1),
                (y > 0, i.wrapping_sub(w)),
                (y + 1 < h, i + w),
            ] {
                if ok {
                    sum += v[j];
                    n += 1.0;
                }
            }
            sum / n
        })
        .collect()
}

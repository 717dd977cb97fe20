//! Quality figures of a synthesised texture against its exemplar, on 7 x 7
//! RGB patches (values 0-255), the output read with wrap-around:
//! - coherence: mean over output patches of the RMS distance to the nearest
//!   usable exemplar patch (is every part of the output like the source?);
//! - completeness: mean over usable exemplar patches of the RMS distance to
//!   the nearest output patch (does the output show all the source has?);
//! - seam: mean jump across the wrap-around edges over the mean jump between
//!   interior neighbours (1 = seamless tiling).
//!
//! Nearest patches are found in two steps: a k-d tree (kiddo) over the
//! patches' first 8 principal components gives 32 candidates, whose exact
//! 147-dimensional distances decide. Both means are taken over at most
//! 20,000 patches, evenly spaced, which fixes their cost on large images and
//! moves them by well under 1%.

use std::num::NonZero;

use faer::{Mat, Side};
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use rayon::prelude::*;
use serde::Serialize;

use super::exemplar::Exemplar;

const SIDE: usize = 7;
const DIM: usize = SIDE * SIDE * 3;
const PCA_DIM: usize = 8;
const CANDIDATES: usize = 32;
const MAX_PATCHES: usize = 20_000;

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Quality {
    pub coherence: f64,
    pub completeness: f64,
    pub seam: f64,
}

/// An RGB image, row by row from the top left.
pub struct Rgb<'a> {
    pub width: usize,
    pub height: usize,
    pub pixels: &'a [[u8; 3]],
}

/// Figures of `output` against `exemplar`.
pub fn measure(exemplar: &Exemplar, output: &Rgb) -> Quality {
    let r = SIDE / 2;
    // Usable exemplar patches: fully inside, every pixel usable.
    let source: Vec<(usize, usize)> = (r..exemplar.height.saturating_sub(r))
        .flat_map(|y| (r..exemplar.width.saturating_sub(r)).map(move |x| (x, y)))
        .filter(|&(x, y)| {
            (0..SIDE).all(|dy| {
                (0..SIDE).all(|dx| exemplar.valid[exemplar.index(x + dx - r, y + dy - r)])
            })
        })
        .collect();
    let outputs: Vec<(usize, usize)> = (0..output.height)
        .flat_map(|y| (0..output.width).map(move |x| (x, y)))
        .collect();
    let source_patch = |&(x, y): &(usize, usize)| {
        patch(|dx, dy| {
            exemplar.pixels[exemplar.index((x as isize + dx) as usize, (y as isize + dy) as usize)]
        })
    };
    let output_patch = |&(x, y): &(usize, usize)| {
        patch(|dx, dy| {
            let px = (x as isize + dx).rem_euclid(output.width as isize) as usize;
            let py = (y as isize + dy).rem_euclid(output.height as isize) as usize;
            output.pixels[py * output.width + px]
        })
    };
    if source.is_empty() || outputs.is_empty() {
        return Quality {
            coherence: f64::NAN,
            completeness: f64::NAN,
            seam: seam(output),
        };
    }
    let pca = Pca::fit(&sample(&source).iter().map(source_patch).collect::<Vec<_>>());
    Quality {
        coherence: mean_nearest(&pca, &sample(&outputs), output_patch, &source, source_patch),
        completeness: mean_nearest(&pca, &sample(&source), source_patch, &outputs, output_patch),
        seam: seam(output),
    }
}

/// At most `MAX_PATCHES` of `all`, evenly spaced.
fn sample<T: Copy>(all: &[T]) -> Vec<T> {
    all.iter()
        .step_by(all.len().div_ceil(MAX_PATCHES).max(1))
        .copied()
        .collect()
}

fn patch(pixel: impl Fn(isize, isize) -> [u8; 3]) -> [f32; DIM] {
    let r = (SIDE / 2) as isize;
    let mut v = [0.0; DIM];
    let mut k = 0;
    for dy in -r..=r {
        for dx in -r..=r {
            for c in pixel(dx, dy) {
                v[k] = c as f32;
                k += 1;
            }
        }
    }
    v
}

/// Mean over `queries` of the RMS distance to the nearest of `targets`;
/// patches are read from the images as needed, never all held at once.
fn mean_nearest<Q: Sync, T: Sync>(
    pca: &Pca,
    queries: &[Q],
    query_patch: impl Fn(&Q) -> [f32; DIM] + Sync,
    targets: &[T],
    target_patch: impl Fn(&T) -> [f32; DIM] + Sync,
) -> f64 {
    let projected: Vec<[f32; PCA_DIM]> = targets
        .par_iter()
        .map(|t| pca.project(&target_patch(t)))
        .collect();
    let tree: ImmutableKdTree<f32, PCA_DIM> =
        ImmutableKdTree::new_from_slice(&projected).expect("a non-empty set of finite points");
    let k = NonZero::new(CANDIDATES.min(targets.len())).expect("targets are not empty");
    let total: f64 = queries
        .par_iter()
        .map(|q| {
            let q = query_patch(q);
            tree.query(&pca.project(&q))
                .nearest_n::<SquaredEuclidean<f32>>(k)
                .execute()
                .iter()
                .map(|hit| squared(&q, &target_patch(&targets[hit.item as usize])))
                .fold(f64::INFINITY, f64::min)
        })
        .map(|d2| (d2 / DIM as f64).sqrt())
        .sum();
    total / queries.len() as f64
}

fn squared(a: &[f32; DIM], b: &[f32; DIM]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| ((x - y) * (x - y)) as f64)
        .sum()
}

/// Principal components of patches, for the k-d tree.
struct Pca {
    mean: [f32; DIM],
    axes: [[f32; DIM]; PCA_DIM],
}

impl Pca {
    fn fit(sample: &[[f32; DIM]]) -> Pca {
        let n = sample.len() as f64;
        let mut mean = [0.0f64; DIM];
        for p in sample {
            for (m, &x) in mean.iter_mut().zip(p.iter()) {
                *m += x as f64 / n;
            }
        }
        // Covariance as one matrix product of the centred samples.
        let centred = Mat::<f64>::from_fn(sample.len(), DIM, |r, c| sample[r][c] as f64 - mean[c]);
        let cov = centred.transpose() * &centred * faer::Scale(1.0 / n);
        let axes = match cov.self_adjoint_eigen(Side::Lower) {
            // Eigenvalues ascend: the last columns are the main axes.
            Ok(eigen) => std::array::from_fn(|k| {
                let col = DIM - 1 - k;
                std::array::from_fn(|i| eigen.U()[(i, col)] as f32)
            }),
            // Coordinate axes still give a correct (slower) search.
            Err(_) => std::array::from_fn(|k| std::array::from_fn(|i| (i == k) as u8 as f32)),
        };
        Pca {
            mean: mean.map(|m| m as f32),
            axes,
        }
    }

    fn project(&self, p: &[f32; DIM]) -> [f32; PCA_DIM] {
        std::array::from_fn(|k| {
            self.axes[k]
                .iter()
                .zip(p.iter().zip(&self.mean))
                .map(|(a, (x, m))| a * (x - m))
                .sum()
        })
    }
}

/// Figures of a solid texture across each axis against that axis's
/// exemplar (one exemplar: the same for all): coherence and completeness
/// are means over `slices` evenly spaced slices, the seam is
/// `Volume::seam` across that axis.
pub fn measure_block(
    volume: &super::volume::Volume,
    exemplars: &[Exemplar],
    slices: usize,
) -> [Quality; 3] {
    std::array::from_fn(|axis| {
        let exemplar = &exemplars[axis.min(exemplars.len() - 1)];
        let n = volume.size[axis];
        let count = slices.clamp(1, n);
        let figures: Vec<Quality> = (0..count)
            .map(|k| {
                let (width, height, pixels) = volume.slice(axis, k * n / count);
                measure(
                    exemplar,
                    &Rgb {
                        width,
                        height,
                        pixels: &pixels,
                    },
                )
            })
            .collect();
        let mean = |f: fn(&Quality) -> f64| figures.iter().map(f).sum::<f64>() / count as f64;
        Quality {
            coherence: mean(|q| q.coherence),
            completeness: mean(|q| q.completeness),
            seam: volume.seam(axis),
        }
    })
}

/// Mean jump across the wrap-around edges over the mean jump between
/// interior neighbours; jumps are mean absolute RGB differences.
pub fn seam(img: &Rgb) -> f64 {
    let px = |i: usize| img.pixels[i];
    seam_by(img.width, img.height, |i, j| {
        px(i)
            .iter()
            .zip(&px(j))
            .map(|(x, y)| (*x as f64 - *y as f64).abs())
            .sum::<f64>()
            / 3.0
    })
}

/// The seam score of a `width` x `height` image whose jump between the
/// pixels at row-major indices `i` and `j` is `jump(i, j)`: any channel or
/// colour space (`seam` is the RGB one).
pub fn seam_by(width: usize, height: usize, jump: impl Fn(usize, usize) -> f64) -> f64 {
    let (w, h) = (width, height);
    let (mut inner, mut inner_n) = (0.0, 0usize);
    let (mut wrap, mut wrap_n) = (0.0, 0usize);
    for y in 0..h {
        for x in 0..w {
            if x + 1 < w {
                inner += jump(y * w + x, y * w + x + 1);
                inner_n += 1;
            }
            if y + 1 < h {
                inner += jump(y * w + x, (y + 1) * w + x);
                inner_n += 1;
            }
        }
        wrap += jump(y * w + w - 1, y * w);
        wrap_n += 1;
    }
    for x in 0..w {
        wrap += jump((h - 1) * w + x, x);
        wrap_n += 1;
    }
    let inner = inner / inner_n.max(1) as f64;
    if inner == 0.0 {
        return 1.0;
    }
    (wrap / wrap_n as f64) / inner
}

//! The optimisation method of 3D block synthesis (Kopf et al. 2007, as
//! seed 002, 4.1 reviews it; Figures 4.4-4.6): per-plane search with the
//! FNPTS candidates, then a blend weighted by distance^-1.2 and damped by
//! histogram matching. See the parent module for the shared parts.

use rayon::prelude::*;

use super::{Block, BlockOptions, View, gather, plane_candidates, plane_cost, random_candidates};
use crate::synth::exemplar::Exemplar;
use crate::synth::fnpts::{MAX_PIXEL_COST, RANDOM_CANDIDATES, window};

/// Histogram bins per channel (Kopf et al. use 16).
const BINS: usize = 16;

impl Block<'_> {
    /// One round of the optimisation method: search, then blend.
    pub(super) fn optimize_round(&mut self, opts: &BlockOptions, key: [u64; 2]) {
        let r = (opts.neighbourhood / 2) as i32;
        let window = window(r);
        // Search: per plane, the best coordinate and its distance.
        let found: Vec<Vec<(u32, f32)>> = (0..3)
            .map(|a| {
                let view = self.view(a, MAX_PIXEL_COST, false);
                let e = &self.src.ex[self.src.of_axis[a]];
                (0..self.grid.len())
                    .into_par_iter()
                    .map(|v| self.best_in_plane(a, v, e, &view, &window, opts, key))
                    .collect()
            })
            .collect();
        for (a, plane) in found.iter().enumerate() {
            for (c, &(s, _)) in self.coord[a].iter_mut().zip(plane) {
                *c = s;
            }
        }
        let pixels = (window.len() * 3) as f32;
        let weight: Vec<Vec<f32>> = found
            .iter()
            .map(|plane| {
                plane
                    .iter()
                    .map(|&(_, d)| (d / pixels + 1.0).powf(-1.2))
                    .collect()
            })
            .collect();
        // Blend, class by class, histograms updated between classes.
        let target = self.exemplar_histogram();
        let mut hist = histogram(&self.colour[0]);
        let total = self.grid.len() as f32;
        for class in self.grid.classes(r as usize + 1, opts.seed, key) {
            let this = &*self;
            let excess = |c: [u8; 3]| -> f32 {
                (0..3)
                    .map(|j| {
                        let b = c[j] as usize * BINS / 256;
                        (hist[j][b] as f32 / total - target[j][b]).max(0.0) * BINS as f32
                    })
                    .sum()
            };
            let blended: Vec<[u8; 3]> = class
                .par_iter()
                .map(|&v| this.blend(v, &weight, &window, &excess))
                .collect();
            for (&v, &c) in class.iter().zip(&blended) {
                let old = self.colour[0][v];
                for j in 0..3 {
                    hist[j][old[j] as usize * BINS / 256] -= 1;
                    hist[j][c[j] as usize * BINS / 256] += 1;
                }
                self.colour[0][v] = c;
            }
        }
    }

    /// Search phase for one voxel and plane: the candidate exemplar
    /// neighbourhood nearest the block's, and its distance.
    #[allow(clippy::too_many_arguments)]
    fn best_in_plane(
        &self,
        a: usize,
        v: usize,
        e: &Exemplar,
        view: &View,
        window: &[(i32, i32)],
        opts: &BlockOptions,
        key: [u64; 2],
    ) -> (u32, f32) {
        let src = self.src;
        let mut candidates = vec![self.coord[a][v]];
        plane_candidates(
            src,
            view,
            a,
            v,
            &self.coord[a],
            opts.seed,
            key,
            &mut candidates,
        );
        random_candidates(
            src,
            &src.buckets[0].usable,
            opts.seed,
            [key[0], key[1], (v * 3 + a) as u64],
            RANDOM_CANDIDATES,
            &mut candidates,
        );
        let block = gather(view, a, self.grid.xyz(v), window);
        let mut best = (i64::MAX, candidates[0]);
        for &c in &candidates {
            let cost = plane_cost(
                src,
                e,
                &block,
                src.split(c),
                window,
                view.missing,
                0,
                best.0,
            );
            if cost < best.0 {
                best = (cost, c);
            }
        }
        (best.1, best.0 as f32)
    }

    /// Optimisation phase for one voxel (seed 002, Figure 4.5): the blend of
    /// E_a[P_a[u] + v - u] over the plane neighbours u, weighted by
    /// distance^-1.2 / (1 + histogram excess).
    fn blend(
        &self,
        v: usize,
        weight: &[Vec<f32>],
        window: &[(i32, i32)],
        excess: &dyn Fn([u8; 3]) -> f32,
    ) -> [u8; 3] {
        let src = self.src;
        let xyz = self.grid.xyz(v);
        let (mut acc, mut total) = ([0f32; 3], 0f32);
        for (a, weight) in weight.iter().enumerate() {
            let e = &src.ex[src.of_axis[a]];
            for &(du, dv) in window {
                // u = v + (du, dv); v sits at -(du, dv) in u's neighbourhood.
                let u = self.grid.neighbour(xyz, a, du, dv);
                let (sx, sy) = src.split(self.coord[a][u]);
                let Some(s) = src.usable(sx - du, sy - dv) else {
                    continue;
                };
                let c = e.pixels[s as usize];
                let w = weight[u] / (1.0 + excess(c));
                for k in 0..3 {
                    acc[k] += w * c[k] as f32;
                }
                total += w;
            }
        }
        if total == 0.0 {
            return self.colour[0][v];
        }
        acc.map(|x| (x / total).round().clamp(0.0, 255.0) as u8)
    }

    /// Per channel, the fraction of usable exemplar pixels in each bin,
    /// over the exemplars of the three planes.
    fn exemplar_histogram(&self) -> [[f32; BINS]; 3] {
        let mut h = [[0f32; BINS]; 3];
        let usable = &self.src.buckets[0].usable;
        for a in 0..3 {
            let e = &self.src.ex[self.src.of_axis[a]];
            for &i in usable {
                for (j, &c) in e.pixels[i as usize].iter().enumerate() {
                    h[j][c as usize * BINS / 256] += 1.0;
                }
            }
        }
        let n = (3 * usable.len()) as f32;
        h.map(|ch| ch.map(|x| x / n))
    }
}

/// Per channel, voxel counts in each bin.
fn histogram(colour: &[[u8; 3]]) -> [[u32; BINS]; 3] {
    let mut h = [[0u32; BINS]; 3];
    for c in colour {
        for j in 0..3 {
            h[j][c[j] as usize * BINS / 256] += 1;
        }
    }
    h
}

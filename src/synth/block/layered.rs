//! Layered (depth-varying) solid exemplars (seed 002, 4.2): a block whose
//! y axis is depth, from one 2D exemplar whose rows are depth (a cut
//! through the layers, as photographs show them). Kopf et al.'s
//! optimisation (optimize.rs) with three changes the thesis makes:
//!
//! - a depth channel beside RGB: a match at exemplar row `sy` for a voxel
//!   at depth `y` costs `DEPTH_WEIGHT * |sy - y|` per window pixel, so
//!   neighbourhoods come from their own layer;
//! - the coarsest level starts each voxel from a random pixel of the
//!   exemplar row at its depth (Figure 4.9b);
//! - search and blend run only in the two planes that contain the depth
//!   axis (across z: (x, y); across x: (z, y)), there being no exemplar of
//!   the planes across it;
//!
//! and the sweep fix (Figure 4.12): each plane keeps its two best matches;
//! where both planes' best point to the same exemplar pixel, the closer
//! match keeps it and the other plane takes its second best. Without it
//! the optimum is the exemplar swept along a diagonal of x and z (Figure
//! 4.10).
//!
//! The block tiles in x and z, not in y: the exemplar's top row is the
//! block's y = 0 (the outer layer, as the LST sampler reads it).

use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::progress::{Progress, check};
use crate::rng;
use crate::synth::exemplar::Exemplar;
use crate::synth::fnpts::{MAX_PIXEL_COST, RING, window};
use crate::synth::volume::Volume;

/// What a row of depth between match and voxel costs, per window pixel,
/// against the colour cost (up to 3 x 255): a match one row off costs
/// like a colour 60 levels off, so matches stay within a row or two.
const DEPTH_WEIGHT: i64 = 60;
/// Random same-row candidates per voxel, plane and round.
const ROW_CANDIDATES: usize = 3;
/// Smallest side of the coarsest block the default pyramid keeps.
const COARSEST: usize = 16;
/// Pixels of the largest neighbourhood (11 x 11).
const MAX_WINDOW: usize = 121;

#[derive(Clone, Debug)]
pub struct LayeredOptions {
    /// Voxels a side; the exemplar must be this many rows tall (its rows
    /// are the block's depth).
    pub size: usize,
    pub seed: u64,
    /// Search and blend rounds per level.
    pub iterations: usize,
    /// Pyramid levels; `None`: as many as keep 16 voxels a side.
    pub levels: Option<usize>,
    /// Side of each square plane neighbourhood (odd).
    pub neighbourhood: usize,
    /// Seed 002's fix for the sweeping artefact (off only to measure it).
    pub sweep_fix: bool,
}

impl Default for LayeredOptions {
    fn default() -> Self {
        LayeredOptions {
            size: 64,
            seed: 0,
            // With per-row histogram matching, 6 rounds bring each depth
            // row's mean colour within 8 of the exemplar's (3: about 11).
            iterations: 6,
            levels: None,
            neighbourhood: 5,
            sweep_fix: true,
        }
    }
}

/// The layered block of `exemplar` (rows = depth, top = outer).
pub fn synthesize_layered(
    exemplar: &Exemplar,
    opts: &LayeredOptions,
    progress: &dyn Progress,
) -> Result<Volume> {
    let n = opts.size;
    let k = opts.neighbourhood;
    if k < 3 || k.is_multiple_of(2) || k > 11 {
        return Err(Error::invalid(format!(
            "the neighbourhood must be odd, from 3 to 11, not {k}"
        )));
    }
    if opts.iterations == 0 {
        return Err(Error::invalid("iterations must be at least 1"));
    }
    if !(k..=super::MAX_BLOCK).contains(&n) {
        return Err(Error::invalid(format!(
            "the block size must be from {k} (the neighbourhood) to {} voxels, not {n}",
            super::MAX_BLOCK
        )));
    }
    if exemplar.height != n {
        return Err(Error::invalid(format!(
            "a layered exemplar's rows are the block's depth: it must be {n} rows tall for a \
             {n}-voxel block, not {} (resize it; `organtex synth3d --layered` does)",
            exemplar.height
        )));
    }
    let levels = match opts.levels {
        Some(l) if !(1..=super::MAX_LEVELS).contains(&l) => {
            return Err(Error::invalid(format!(
                "levels must be from 1 to {}, not {l}",
                super::MAX_LEVELS
            )));
        }
        Some(l) => l,
        None => {
            let mut l = 1;
            while (n >> l) >= COARSEST && (exemplar.width >> l) >= COARSEST {
                l += 1;
            }
            l
        }
    };
    let step = 1usize << (levels - 1);
    if !n.is_multiple_of(step) || n / step < k {
        return Err(Error::invalid(format!(
            "a block of {n} voxels does not fit {levels} pyramid levels: the size must be a \
             multiple of {step} and at least {}",
            k * step
        )));
    }
    let mut chain = vec![exemplar.clone()];
    while chain.len() < levels {
        let coarser = chain.last().and_then(|e| e.downsample(k)).ok_or_else(|| {
            Error::invalid(format!(
                "the layered exemplar ({}x{}) is too small for {levels} pyramid levels: it needs \
                 at least {} pixels a side, with usable pixels at every level",
                exemplar.width,
                exemplar.height,
                k << (levels - 1)
            ))
        })?;
        chain.push(coarser);
    }
    progress.stage("layered block synthesis", (levels * opts.iterations) as u64);
    let mut state: Option<Layered> = None;
    for (l, e) in chain.iter().enumerate().rev() {
        check(progress)?;
        let mut block = match state.take() {
            None => Layered::random(e, n >> l, opts.seed)?,
            Some(coarse) => coarse.refine(e, n >> l),
        };
        for round in 0..opts.iterations {
            check(progress)?;
            block.round(opts, [l as u64, round as u64]);
            progress.advance(1);
        }
        state = Some(block);
    }
    let block = state.expect("at least one level");
    // Tiles meet where neighbouring planes differ least across x and z;
    // y, depth, stays.
    Ok(Volume {
        size: [n; 3],
        spacing: 1.0,
        voxels: block.colour,
    }
    .rolled_to_smoothest_wrap_along([true, false, true]))
}

/// The synthesis state at one level: an n^3 block, x fastest, y depth.
struct Layered<'a> {
    e: &'a Exemplar,
    n: usize,
    /// Exemplar pixel per voxel, for the plane across z and across x.
    coord: [Vec<u32>; 2],
    colour: Vec<[u8; 3]>,
    /// Usable pixels of each exemplar row.
    rows: Vec<Vec<u32>>,
}

/// In-plane axes (u, v) of the two planes: across z (x, y), across x
/// (z, y); v is always depth.
const U_AXIS: [usize; 2] = [0, 2];

impl<'a> Layered<'a> {
    fn rows(e: &Exemplar) -> Vec<Vec<u32>> {
        (0..e.height)
            .map(|y| {
                (0..e.width)
                    .map(|x| (y * e.width + x) as u32)
                    .filter(|&i| e.valid[i as usize])
                    .collect()
            })
            .collect()
    }

    /// Coarsest level: each voxel a random usable pixel of its depth's row
    /// (or, where that row has none, of the whole exemplar).
    fn random(e: &'a Exemplar, n: usize, seed: u64) -> Result<Layered<'a>> {
        let rows = Self::rows(e);
        let all: Vec<u32> = rows.iter().flatten().copied().collect();
        if all.is_empty() {
            return Err(Error::invalid("the layered exemplar has no usable pixel"));
        }
        let coord = [0u64, 1].map(|a| {
            (0..n * n * n)
                .map(|v| {
                    let y = v / n % n;
                    let pool = if rows[y].is_empty() { &all } else { &rows[y] };
                    pool[rng::below(seed, &[u64::MAX, a, v as u64], pool.len())]
                })
                .collect::<Vec<u32>>()
        });
        Ok(Layered::with_coords(e, n, coord, rows))
    }

    /// A level from its coordinates, each voxel the mean of its two
    /// planes' pixels until the first blend (from the finer exemplar's
    /// pixels, not the parents' blend, which would leave 2 x 2 blocks).
    fn with_coords(
        e: &'a Exemplar,
        n: usize,
        coord: [Vec<u32>; 2],
        rows: Vec<Vec<u32>>,
    ) -> Layered<'a> {
        let colour = (0..n * n * n)
            .map(|v| {
                mean(
                    e.pixels[coord[0][v] as usize],
                    e.pixels[coord[1][v] as usize],
                )
            })
            .collect();
        Layered {
            e,
            n,
            coord,
            colour,
            rows,
        }
    }

    /// The next finer level: each coordinate's child at the voxel's offset
    /// within its parent (u and depth).
    fn refine(self, e: &'a Exemplar, n: usize) -> Layered<'a> {
        let coarse = self.n;
        let cw = self.e.width as u32;
        let parent = |v: usize| {
            let [x, y, z] = xyz(n, v).map(|c| c / 2);
            (z * coarse + y) * coarse + x
        };
        let coord = [0, 1].map(|a| {
            (0..n * n * n)
                .map(|v| {
                    let c = self.coord[a][parent(v)];
                    let children = e.children((c % cw) as usize, (c / cw) as usize);
                    let p = xyz(n, v);
                    let own = children[p[1] % 2 * 2 + p[U_AXIS[a]] % 2];
                    let child = if e.valid[own] {
                        own
                    } else {
                        children.into_iter().find(|&c| e.valid[c]).unwrap_or(own)
                    };
                    child as u32
                })
                .collect::<Vec<u32>>()
        });
        Layered::with_coords(e, n, coord, Self::rows(e))
    }

    /// The voxel at in-plane offset (du, dv) from the voxel at `p` in
    /// plane `a`: wrapped along u, `None` past the top or bottom layer.
    #[inline]
    fn neighbour_of(&self, mut p: [i32; 3], a: usize, du: i32, dv: i32) -> Option<usize> {
        let n = self.n as i32;
        p[1] += dv;
        if !(0..n).contains(&p[1]) {
            return None;
        }
        let u = U_AXIS[a];
        p[u] += du;
        // |du| <= the window's radius < n: one wrap at most.
        if p[u] < 0 {
            p[u] += n;
        } else if p[u] >= n {
            p[u] -= n;
        }
        Some(((p[2] * n + p[1]) * n + p[0]) as usize)
    }

    #[inline]
    fn usable(&self, sx: i32, sy: i32) -> Option<usize> {
        let (w, h) = (self.e.width as i32, self.e.height as i32);
        if sx < 0 || sy < 0 || sx >= w || sy >= h {
            return None;
        }
        let i = (sy * w + sx) as usize;
        self.e.valid[i].then_some(i)
    }

    /// Colour plus depth cost of exemplar pixel `c` for a voxel at
    /// `depth` whose in-plane neighbourhood is `around` (offset and colour
    /// of each window pixel inside the block, in window order); stops once
    /// past `limit`.
    fn cost(
        &self,
        depth: usize,
        around: &[(i32, i32, [u8; 3])],
        window: usize,
        c: u32,
        whole: bool,
        limit: i64,
    ) -> i64 {
        let w = self.e.width as i32;
        let (sx, sy) = (c as i32 % w, c as i32 / w);
        let mut cost = DEPTH_WEIGHT * (sy as i64 - depth as i64).abs() * window as i64;
        let sad = |p: [u8; 3], b: [u8; 3]| {
            (0..3)
                .map(|k| (p[k] as i64 - b[k] as i64).abs())
                .sum::<i64>()
        };
        if whole {
            // Every window pixel about `c` is inside and usable: no checks.
            for &(du, dv, b) in around {
                cost += sad(self.e.pixels[(c as i32 + dv * w + du) as usize], b);
                if cost >= limit {
                    break;
                }
            }
            return cost;
        }
        for &(du, dv, b) in around {
            match self.usable(sx + du, sy + dv) {
                None => cost += MAX_PIXEL_COST,
                Some(s) => cost += sad(self.e.pixels[s], b),
            }
            if cost >= limit {
                break;
            }
        }
        cost
    }

    /// Search for voxel `v` in plane `a`: the best and second best
    /// candidate (pixel, cost).
    fn search(
        &self,
        v: usize,
        a: usize,
        window: &[(i32, i32)],
        whole: &[bool],
        seed: u64,
        key: [u64; 2],
    ) -> [(u32, i64); 2] {
        let w = self.e.width as i32;
        let at = xyz(self.n, v).map(|c| c as i32);
        // At most the current pixel, one per ring neighbour and the row's
        // picks: on the stack, as this runs for every voxel and plane.
        let mut candidates = [0u32; 1 + RING.len() + ROW_CANDIDATES];
        candidates[0] = self.coord[a][v];
        let mut count = 1;
        let mut offer = |sx: i32, sy: i32| {
            if let Some(i) = self.usable(sx, sy)
                && !candidates[..count].contains(&(i as u32))
            {
                candidates[count] = i as u32;
                count += 1;
            }
        };
        // Coherence: each ring neighbour's pixel shifted back.
        for &(du, dv) in &RING {
            if let Some(q) = self.neighbour_of(at, a, du, dv) {
                let c = self.coord[a][q] as i32;
                offer(c % w - du, c / w - dv);
            }
        }
        // Random pixels of the voxel's own row (the depth channel's).
        let depth = v / self.n % self.n;
        let row = &self.rows[depth];
        for k in 0..ROW_CANDIDATES.min(row.len()) {
            let c = row[rng::below(
                seed,
                &[key[0], key[1], v as u64, 10 * a as u64 + k as u64],
                row.len(),
            )] as i32;
            offer(c % w, c / w);
        }
        // The voxel's neighbourhood is the same for every candidate: read
        // it once (window pixels past the top or bottom layer cost nothing).
        let mut around = [(0i32, 0i32, [0u8; 3]); MAX_WINDOW];
        let mut inside = 0;
        for &(du, dv) in window {
            if let Some(q) = self.neighbour_of(at, a, du, dv) {
                around[inside] = (du, dv, self.colour[q]);
                inside += 1;
            }
        }
        let around = &around[..inside];
        let mut best = [(candidates[0], i64::MAX); 2];
        for &c in &candidates[..count] {
            let cost = self.cost(depth, around, window.len(), c, whole[c as usize], best[1].1);
            if cost < best[0].1 {
                best = [(c, cost), best[0]];
            } else if cost < best[1].1 {
                best[1] = (c, cost);
            }
        }
        best
    }

    /// One round: search both planes, apply the sweep fix, blend.
    fn round(&mut self, opts: &LayeredOptions, key: [u64; 2]) {
        let window = window((opts.neighbourhood / 2) as i32);
        let whole = self.e.whole_windows(opts.neighbourhood / 2);
        let found: Vec<[[(u32, i64); 2]; 2]> = (0..self.n * self.n * self.n)
            .into_par_iter()
            .map(|v| [0, 1].map(|a| self.search(v, a, &window, &whole, opts.seed, key)))
            .collect();
        let mut cost = [vec![0f32; found.len()], vec![0f32; found.len()]];
        for (v, [p0, p1]) in found.iter().enumerate() {
            let mut pick = [p0[0], p1[0]];
            // Sweep fix (Figure 4.12): both planes on one exemplar pixel.
            if opts.sweep_fix && p0[0].0 == p1[0].0 {
                let other = if p0[0].1 <= p1[0].1 { 1 } else { 0 };
                let second = [p0[1], p1[1]][other];
                if second.1 < i64::MAX && second.0 != pick[other].0 {
                    pick[other] = second;
                }
            }
            for a in 0..2 {
                self.coord[a][v] = pick[a].0;
                cost[a][v] = pick[a].1 as f32;
            }
        }
        // Blend (Kopf et al.): each voxel the mean of what the overlapping
        // neighbourhoods put there, weighted by match distance^-1.2 and
        // damped where the colour is already more common in the voxel's
        // depth row than in the exemplar's (histogram matching, per depth
        // row: the layers differ in colour).
        let excess = self.row_excess();
        // The damping of exemplar pixel s at depth row y, (1 + excess)^p,
        // tabled once: each voxel reads it for every window pixel of both
        // planes, and the exemplar has fewer pixels than the block voxels.
        let texels = self.e.pixels.len();
        let damping: Vec<f32> = (0..self.n * texels)
            .into_par_iter()
            .map(|i| (1.0 + excess(i / texels, self.e.pixels[i % texels])).powi(HIST_POWER))
            .collect();
        let pixels = window.len() as f32;
        let weight: [Vec<f32>; 2] =
            cost.map(|c| c.iter().map(|&d| (d / pixels + 1.0).powf(-1.2)).collect());
        let colour: Vec<[u8; 3]> = (0..self.colour.len())
            .into_par_iter()
            .map(|v| {
                let (mut acc, mut total) = ([0f32; 3], 0f32);
                let w = self.e.width as i32;
                let at = xyz(self.n, v).map(|c| c as i32);
                for (a, (coord, weight)) in self.coord.iter().zip(&weight).enumerate() {
                    for &(du, dv) in &window {
                        let Some(u) = self.neighbour_of(at, a, du, dv) else {
                            continue;
                        };
                        let c = coord[u] as i32;
                        let Some(s) = self.usable(c % w - du, c / w - dv) else {
                            continue;
                        };
                        let p = self.e.pixels[s];
                        let wt = weight[u] / damping[v / self.n % self.n * texels + s];
                        for k in 0..3 {
                            acc[k] += wt * p[k] as f32;
                        }
                        total += wt;
                    }
                }
                if total == 0.0 {
                    self.colour[v]
                } else {
                    acc.map(|x| (x / total).round().clamp(0.0, 255.0) as u8)
                }
            })
            .collect();
        self.colour = colour;
    }
}

/// Histogram bins per channel (Kopf et al. use 16).
const BINS: usize = 16;
/// How hard over-represented colours are damped: weight / (1 + excess)^p.
const HIST_POWER: i32 = 2;

impl Layered<'_> {
    /// Per depth row y, how much colour `c` is over-represented in the
    /// block's row against the exemplar's rows y - 1 to y + 1 (summed over
    /// channels, in units of one bin's even share).
    fn row_excess(&self) -> impl Fn(usize, [u8; 3]) -> f32 + Sync + use<> {
        let n = self.n;
        let bin = |x: u8| x as usize * BINS / 256;
        let mut target = vec![[[0f32; BINS]; 3]; n];
        for (y, t) in target.iter_mut().enumerate() {
            let mut count = 0f32;
            for row in y.saturating_sub(1)..(y + 2).min(self.e.height) {
                for &i in &self.rows[row] {
                    for k in 0..3 {
                        t[k][bin(self.e.pixels[i as usize][k])] += 1.0;
                    }
                    count += 1.0;
                }
            }
            for ch in t.iter_mut() {
                for b in ch.iter_mut() {
                    *b /= count.max(1.0);
                }
            }
        }
        let mut hist = vec![[[0f32; BINS]; 3]; n];
        for (v, c) in self.colour.iter().enumerate() {
            let h = &mut hist[v / n % n];
            for k in 0..3 {
                h[k][bin(c[k])] += 1.0 / (n * n) as f32;
            }
        }
        move |y: usize, c: [u8; 3]| {
            (0..3)
                .map(|k| (hist[y][k][bin(c[k])] - target[y][k][bin(c[k])]).max(0.0) * BINS as f32)
                .sum()
        }
    }
}

#[inline]
fn xyz(n: usize, v: usize) -> [usize; 3] {
    [v % n, v / n % n, v / (n * n)]
}

fn mean(a: [u8; 3], b: [u8; 3]) -> [u8; 3] {
    [0, 1, 2].map(|k| (a[k] as u16 + b[k] as u16).div_ceil(2) as u8)
}

/// How much a block looks swept (seed 002, Figure 4.10): over the slices
/// across depth, the correlation of each slice with itself shifted `lag`
/// voxels along a diagonal of x and z, the larger of the two diagonals,
/// less the same along x and z (their mean). A sweep along a diagonal
/// keeps its slices alike along it, so the excess is near 1 - (x, z
/// correlation); a block with no preferred direction scores near 0.
pub fn sweep_score(block: &Volume, lag: usize) -> f64 {
    let [nx, ny, nz] = block.size;
    let lum = |x: usize, y: usize, z: usize| {
        let c = block.voxels[block.index(x % nx, y, z % nz)];
        0.299 * c[0] as f64 + 0.587 * c[1] as f64 + 0.114 * c[2] as f64
    };
    let corr = |dx: isize, dz: isize| {
        let mut total = 0.0;
        for y in 0..ny {
            let (mut sa, mut sb, mut saa, mut sbb, mut sab) = (0.0, 0.0, 0.0, 0.0, 0.0);
            for z in 0..nz {
                for x in 0..nx {
                    let a = lum(x, y, z);
                    let b = lum(
                        (x as isize + dx).rem_euclid(nx as isize) as usize,
                        y,
                        (z as isize + dz).rem_euclid(nz as isize) as usize,
                    );
                    sa += a;
                    sb += b;
                    saa += a * a;
                    sbb += b * b;
                    sab += a * b;
                }
            }
            let m = (nx * nz) as f64;
            let cov = sab / m - sa * sb / (m * m);
            let var = ((saa / m - sa * sa / (m * m)) * (sbb / m - sb * sb / (m * m))).sqrt();
            total += if var > 1e-9 { cov / var } else { 1.0 };
        }
        total / ny as f64
    };
    let l = lag as isize;
    let diagonal = corr(l, l).max(corr(l, -l));
    let axes = (corr(l, 0) + corr(0, l)) / 2.0;
    diagonal - axes
}

/// Figures of a layered block against its exemplar (issue 23).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct LayeredQuality {
    /// RMS over depth rows of the difference between the block's mean
    /// colour at that depth and the exemplar row's (per channel, 0-255).
    pub rows_rms: f64,
    /// Of slices that contain the depth axis (across x and z, depth down
    /// the image as in the exemplar), against the exemplar.
    pub coherence: f64,
    pub completeness: f64,
    /// `sweep_score` at a lag of 4 voxels.
    pub sweep: f64,
}

/// Measure `block` (depth along y) against `exemplar` (rows = depth, as
/// many as the block's y), over `slices` slices per plane.
pub fn measure_layered(block: &Volume, exemplar: &Exemplar, slices: usize) -> LayeredQuality {
    use crate::synth::quality::{Rgb, measure};
    let [nx, ny, nz] = block.size;
    // Mean colour per depth row, block and exemplar (usable pixels).
    let mut sq = 0.0;
    for y in 0..ny.min(exemplar.height) {
        let mut b = [0f64; 3];
        for z in 0..nz {
            for x in 0..nx {
                let c = block.voxels[block.index(x, y, z)];
                for (bk, &ck) in b.iter_mut().zip(&c) {
                    *bk += ck as f64;
                }
            }
        }
        let (mut e, mut count) = ([0f64; 3], 0usize);
        for x in 0..exemplar.width {
            let i = exemplar.index(x, y);
            if exemplar.valid[i] {
                for (ek, &c) in e.iter_mut().zip(&exemplar.pixels[i]) {
                    *ek += c as f64;
                }
                count += 1;
            }
        }
        for (bk, ek) in b.iter().zip(&e) {
            let d = bk / (nx * nz) as f64 - ek / count.max(1) as f64;
            sq += d * d;
        }
    }
    let rows_rms = (sq / (3 * ny.min(exemplar.height)).max(1) as f64).sqrt();
    let count = slices.clamp(1, nx.min(nz));
    let mut figures = Vec::new();
    for a in 0..2 {
        for s in 0..count {
            let at = s * nx / count;
            // Across z: (x, y); across x: (z, y); depth down the image.
            let (w, pixels): (usize, Vec<[u8; 3]>) = if a == 0 {
                (
                    nx,
                    (0..ny)
                        .flat_map(|y| (0..nx).map(move |x| (x, y)))
                        .map(|(x, y)| block.voxels[block.index(x, y, at)])
                        .collect(),
                )
            } else {
                (
                    nz,
                    (0..ny)
                        .flat_map(|y| (0..nz).map(move |z| (z, y)))
                        .map(|(z, y)| block.voxels[block.index(at, y, z)])
                        .collect(),
                )
            };
            figures.push(measure(
                exemplar,
                &Rgb {
                    width: w,
                    height: ny,
                    pixels: &pixels,
                },
            ));
        }
    }
    let mean = |f: fn(&crate::synth::quality::Quality) -> f64| {
        figures.iter().map(f).sum::<f64>() / figures.len() as f64
    };
    LayeredQuality {
        rows_rms,
        coherence: mean(|q| q.coherence),
        completeness: mean(|q| q.completeness),
        sweep: sweep_score(block, 4),
    }
}

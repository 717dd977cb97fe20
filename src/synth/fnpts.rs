//! FNPTS, fast non-parametric pixelwise texture synthesis (seed 004, section
//! 3.2; DESIGN.md "FNPTS").
//!
//! Multiscale, coarse to fine over Gaussian pyramids of exemplar and output.
//! Every output pixel holds the source coordinate its colour was copied from
//! and n, how often it has been iterated at this level (out of M). Visiting a
//! pixel picks, among candidate source pixels, the one whose K x K
//! neighbourhood best matches the output's, by the paper's cost
//!
//!   sum over neighbours i of |s_i - r_i| * n_i / M   where s_i is defined,
//!   the largest possible pixel difference              where it is not
//!
//! (undefined: outside the exemplar or masked; Manhattan distance over RGB).
//! Candidates: each neighbour's source coordinate shifted back by its offset
//! (coherence, Ashikhmin 2001), source pixels whose colour matches a
//! neighbour's (the paper's "neighbour of the same colour", colours bucketed
//! to 4 bits per channel), and a few random ones. Masked pixels are never
//! candidates, so never copied. A tileable output wraps around.
//!
//! Visiting order and parallelism (beyond the paper): pixels fall into
//! (r+1) x (r+1) interleaved classes, r the neighbourhood radius, so no two
//! pixels of a class see each other; a pass visits the classes in a seeded
//! random order, each class all at once in parallel. The output is the same
//! bytes for any number of threads. A pixel taken over from the coarser
//! level counts as iterated once. A tileable result is finally rolled so
//! the tile edges fall where the texture is most continuous (`wrap`).
//!
//! Occurrence (beyond the paper, after Kaspar et al. 2015 and Jamriška et
//! al. 2015): copying grows islands over whatever matches easily and can
//! leave parts of the exemplar unused. A candidate's cost is multiplied by
//! 1 + `occurrence` x the even shares by which its source pixel is already
//! over-used (use counted after every class, so it stays deterministic).
//! The penalty is relative, not added: on the even background of a
//! sparse-feature exemplar (a few dots or thin vessels on smooth tissue)
//! every candidate matches almost equally well, and an added penalty
//! outweighed the match there, so the least-used pixel won and the output
//! became pixels shuffled one by one, its features broken. Multiplied, a
//! coherent continuation that matches exactly stays free. On the tissue
//! database (512-pixel outputs) the added form lost to Embark's coherence
//! on 6 of 12 tissues; this form, with the deeper pyramid below, wins on
//! all 12 and on two tissues not tuned on (tools/compare_synth.py).
//! `occurrence = 0` gives the paper's cost exactly.
//!
//! The penalty's weight grows, up to four times, for small outputs (under
//! 512 pixels a side) with few pixels for their exemplar's
//! (`Level::occurrence_weight`): such an output can show each part of
//! the exemplar at most once or twice, and a few large coherent copies,
//! which the deep pyramid below favours, leave most of it unseen. At 128
//! and 256 pixels (outputs of 0.06 to 8 times the exemplar's pixels) the
//! plain weight lost to Embark's completeness on 6 of 28 cases, the grown
//! one on 1: the fundus at 128, 0.06 of its exemplar's pixels, copied one
//! region of its uneven lighting (completeness 5.72 against 4.36). So an
//! output with under an eighth of its exemplar's pixels (the whole
//! output's share, not its level's: the coarse levels of a small output
//! hold a larger share of their smaller exemplars) weighs it more again,
//! up to 8x at a sixteenth (`SCARCE_SHARE`): 28 of 28.
//!
//! Pyramid depth (beyond the paper): by default the levels go down until
//! the coarsest exemplar is about 16 pixels a side, where one 7 x 7
//! neighbourhood sees a good part of it, so the layout (shading, where the
//! sparse features lie) is decided coherently there, and the output stops
//! at 32 pixels. Outputs under 512 pixels a side (`SMALL_OUTPUT`) go
//! deeper, to an 11-pixel exemplar and an 8-pixel output, so the exemplar,
//! not the output's size, sets their depth: stopping at 32 output pixels
//! left a 128-pixel tile three levels and its coarsest exemplar 40 to 140
//! pixels wide, too wide for a neighbourhood to place its features, and
//! organtex lost to Embark (coherence or completeness) on 10 of 14
//! tissues at 128 and 3 at 256 (colonic crypts' coherence at 128: 9.0
//! against 4.4). Outputs of 512 and more keep the depth the database's
//! textures are built with (and the scenes' seams and blends were measured
//! with): deeper, they beat Embark as well (14 of 14 at 512), but the
//! MNI brain's serosa, a smoother texture, lost the seam its blending
//! hid (contrast 1.00 unblended, 1.04 blended; 1.07 and 1.02 before).

use rayon::prelude::*;

use super::exemplar::Exemplar;
use crate::error::{Error, Result};
use crate::progress::{Progress, check};
use crate::rng;

#[derive(Clone, Debug)]
pub struct SynthOptions {
    pub width: usize,
    pub height: usize,
    /// Wrap the output around so it tiles.
    pub tileable: bool,
    pub seed: u64,
    /// M: iterations per pixel and level.
    pub iterations: usize,
    /// Pyramid levels; `None` picks as many as keep the coarsest exemplar at
    /// least 16 pixels wide and the output 32 (11 and 8 for outputs under
    /// 512 pixels a side).
    pub levels: Option<usize>,
    /// K: side of the square neighbourhood (odd).
    pub neighbourhood: usize,
    /// Weight of the occurrence penalty, which multiplies a candidate's
    /// cost (0: the paper's cost alone); grown for small outputs
    /// (`Level::occurrence_weight`). 3D synthesis (`block`) weighs it the
    /// same, without the growth.
    pub occurrence: f64,
}

impl Default for SynthOptions {
    fn default() -> Self {
        SynthOptions {
            width: 256,
            height: 256,
            tileable: true,
            seed: 0,
            iterations: 3,
            levels: None,
            neighbourhood: 7,
            occurrence: 0.1,
        }
    }
}

/// A synthesised texture and, for every pixel, the exemplar pixel it copies.
#[derive(Clone, Debug, PartialEq)]
pub struct Synthesis {
    pub width: usize,
    pub height: usize,
    pub pixels: Vec<[u8; 3]>,
    pub coords: Vec<[u32; 2]>,
}

/// Largest per-pixel cost: every channel off by 255.
pub(super) const MAX_PIXEL_COST: i64 = 3 * 255;
/// Random candidates per visit.
pub(super) const RANDOM_CANDIDATES: usize = 2;

pub fn synthesize(
    ex: &Exemplar,
    opts: &SynthOptions,
    progress: &dyn Progress,
) -> Result<Synthesis> {
    check_options(opts)?;
    let pyramid = pyramid(ex, opts)?;
    let levels = pyramid.len();
    progress.stage("synthesis", (levels * opts.iterations) as u64);

    // The output's pixels per usable exemplar pixel at the finest level
    // (`Level::occurrence_weight`).
    let usable = ex.valid.iter().filter(|&&v| v).count().max(1);
    let whole_share = (opts.width * opts.height) as f64 / usable as f64;
    let mut state: Option<Level> = None;
    for l in (0..levels).rev() {
        check(progress)?;
        let src = &pyramid[l];
        let (w, h) = (opts.width.div_ceil(1 << l), opts.height.div_ceil(1 << l));
        let mut level = match state.take() {
            None => Level::random(src, w, h, opts.seed),
            Some(coarse) => coarse.refine(src, w, h),
        };
        let buckets = ColourBuckets::new(src);
        for pass in 0..opts.iterations {
            check(progress)?;
            level.pass(&buckets, opts, whole_share, l as u64, pass as u64);
            progress.advance(1);
        }
        state = Some(level);
    }
    let level = state.expect("at least one level");
    let out = Synthesis {
        width: level.w,
        height: level.h,
        pixels: level.colour,
        coords: level
            .coord
            .iter()
            .map(|&c| [c % ex.width as u32, c / ex.width as u32])
            .collect(),
    };
    Ok(if opts.tileable {
        out.rolled_to_smoothest_wrap()
    } else {
        out
    })
}

/// The output/exemplar pixel ratio under which the occurrence penalty
/// grows for a small output (`SMALL_OUTPUT`), and its largest multiple
/// (`Level::occurrence_weight`). Measured on the tissue database
/// (tools/compare_synth.py): at 128 and 256 pixels the plain weight lost
/// completeness on 6 of 28 cases; grown at 512 too, it cost the fundus
/// photograph its coherence there (0.68 against Embark's 0.55; 0.49 with
/// the plain weight), so 512-pixel outputs keep the weight they were
/// tuned with.
const SPREAD_SHARE: f64 = 4.0;
const SPREAD_BOOST: f64 = 4.0;
/// Under this share of the whole output (an exemplar more than eight
/// times the output's pixels) a small output's weight grows again, to
/// `SCARCE_BOOST` times at half the share: the penalty counts copies, not
/// shares, so a small output of a large photograph still copied one
/// region of it (the fundus photograph at 128 pixels, 0.06 of its
/// exemplar's: completeness 5.72 against Embark's 4.36; 4.18 with it,
/// coherence 0.49 against 0.52, tools/compare_synth.py, median of 3
/// seeds). At twice the weight it stayed at 5.65; grown from a half
/// instead of an eighth, the fundus at 256 (a quarter) lost its coherence
/// (0.70 against 0.59).
const SCARCE_SHARE: f64 = 0.125;
const SCARCE_BOOST: f64 = 8.0;

/// The largest occurrence weight a synthesis takes.
pub const MAX_OCCURRENCE: f64 = 10.0;

/// Most pyramid levels, 2D or 3D: each halves the exemplar, so 16 would
/// already need one 2^15 pixels a side (and shifts stay far from overflow).
pub const MAX_LEVELS: usize = 16;

/// Smallest side of the coarsest exemplar and output that the default
/// pyramid goes down to (module doc: "Pyramid depth"), and below
/// `SMALL_OUTPUT` pixels a side. 32 for both left the database's 90 to 340
/// pixel crops two or three levels, and the fine levels had to place
/// features they could not see whole; for a small output, an exemplar of
/// 16 still left the colonic mucosa (220 x 190) one level short at 128.
const COARSEST_EXEMPLAR: usize = 16;
const COARSEST_OUTPUT: usize = 32;
const SMALL_OUTPUT: usize = 512;
const SMALL_COARSEST_EXEMPLAR: usize = 11;
const SMALL_COARSEST_OUTPUT: usize = 8;

/// Exemplar pyramid, finest first: as many levels as asked, or (by
/// default) while the next exemplar keeps `COARSEST_EXEMPLAR` pixels a side
/// and the next output `COARSEST_OUTPUT`.
fn pyramid(ex: &Exemplar, opts: &SynthOptions) -> Result<Vec<Exemplar>> {
    let mut pyramid = vec![ex.clone()];
    match opts.levels {
        Some(levels) if !(1..=MAX_LEVELS).contains(&levels) => {
            return Err(Error::invalid(format!(
                "levels must be from 1 to {}, not {levels}",
                MAX_LEVELS
            )));
        }
        Some(levels) => {
            while pyramid.len() < levels {
                let coarser = pyramid
                    .last()
                    .and_then(|e| e.downsample(opts.neighbourhood))
                    .ok_or_else(|| {
                        Error::invalid(format!(
                            "{levels} pyramid levels need an exemplar of at least {} pixels a side, with usable pixels at every level",
                            opts.neighbourhood << (levels - 1)
                        ))
                    })?;
                pyramid.push(coarser);
            }
        }
        None => {
            let side = opts.width.min(opts.height);
            let (exemplar, output) = if side < SMALL_OUTPUT {
                (SMALL_COARSEST_EXEMPLAR, SMALL_COARSEST_OUTPUT)
            } else {
                (COARSEST_EXEMPLAR, COARSEST_OUTPUT)
            };
            while side >> pyramid.len() >= output {
                match pyramid.last().and_then(|e| e.downsample(exemplar)) {
                    Some(coarser) => pyramid.push(coarser),
                    None => break,
                }
            }
        }
    }
    Ok(pyramid)
}

fn check_options(opts: &SynthOptions) -> Result<()> {
    if !(1..=16384).contains(&opts.width) || !(1..=16384).contains(&opts.height) {
        return Err(Error::invalid(format!(
            "the output size {}x{} is outside 1..16384 pixels a side",
            opts.width, opts.height
        )));
    }
    check_search(opts.neighbourhood, 15, opts.iterations, opts.occurrence)?;
    if opts.levels == Some(0) {
        return Err(Error::invalid("levels must be at least 1"));
    }
    Ok(())
}

/// The search settings 2D and 3D synthesis share: an odd neighbourhood
/// side up to `largest`, iterations and the occurrence weight in range.
pub(super) fn check_search(
    neighbourhood: usize,
    largest: usize,
    iterations: usize,
    occurrence: f64,
) -> Result<()> {
    if neighbourhood.is_multiple_of(2) || !(3..=largest).contains(&neighbourhood) {
        return Err(Error::invalid(format!(
            "the neighbourhood must be odd, from 3 to {largest}, not {neighbourhood}"
        )));
    }
    if !(1..=16).contains(&iterations) {
        return Err(Error::invalid(format!(
            "iterations must be from 1 to 16, not {iterations}"
        )));
    }
    if !(0.0..=MAX_OCCURRENCE).contains(&occurrence) {
        return Err(Error::invalid(format!(
            "the occurrence weight must be from 0 to {MAX_OCCURRENCE}, not {occurrence}"
        )));
    }
    Ok(())
}

/// Usable exemplar pixels grouped by colour at 4 bits per channel.
pub(super) struct ColourBuckets {
    start: Vec<u32>,
    items: Vec<u32>,
    /// Every usable pixel, for random candidates.
    pub(super) usable: Vec<u32>,
}

#[inline]
fn bucket(c: [u8; 3]) -> usize {
    ((c[0] as usize >> 4) << 8) | ((c[1] as usize >> 4) << 4) | (c[2] as usize >> 4)
}

impl ColourBuckets {
    pub(super) fn new(src: &Exemplar) -> Self {
        let usable: Vec<u32> = (0..src.pixels.len() as u32)
            .filter(|&i| src.valid[i as usize])
            .collect();
        let mut count = vec![0u32; 4097];
        for &i in &usable {
            count[bucket(src.pixels[i as usize]) + 1] += 1;
        }
        for b in 0..4096 {
            count[b + 1] += count[b];
        }
        let mut fill = count.clone();
        let mut items = vec![0; usable.len()];
        for &i in &usable {
            let b = bucket(src.pixels[i as usize]);
            items[fill[b] as usize] = i;
            fill[b] += 1;
        }
        ColourBuckets {
            start: count,
            items,
            usable,
        }
    }

    pub(super) fn of(&self, c: [u8; 3]) -> &[u32] {
        let b = bucket(c);
        &self.items[self.start[b] as usize..self.start[b + 1] as usize]
    }
}

/// The output at one pyramid level.
struct Level<'a> {
    src: &'a Exemplar,
    w: usize,
    h: usize,
    /// Source pixel index of every output pixel.
    coord: Vec<u32>,
    /// Times each pixel was iterated at this level.
    iters: Vec<u8>,
    /// Colour of every output pixel (the source's at `coord`).
    colour: Vec<[u8; 3]>,
    /// How many output pixels copy each source pixel.
    usage: Vec<u32>,
    /// The even share: output pixels per usable source pixel.
    share: f64,
}

impl<'a> Level<'a> {
    /// Coarsest level: every pixel a random usable source pixel, not yet
    /// iterated.
    fn random(src: &'a Exemplar, w: usize, h: usize, seed: u64) -> Self {
        let usable: Vec<u32> = (0..src.pixels.len() as u32)
            .filter(|&i| src.valid[i as usize])
            .collect();
        let coord: Vec<u32> = (0..w * h)
            .map(|p| usable[rng::below(seed, &[u64::MAX, p as u64], usable.len())])
            .collect();
        Self::with_coords(src, w, h, coord, 0)
    }

    fn with_coords(src: &'a Exemplar, w: usize, h: usize, coord: Vec<u32>, iterated: u8) -> Self {
        let colour = coord.iter().map(|&c| src.pixels[c as usize]).collect();
        let mut usage = vec![0u32; src.pixels.len()];
        for &c in &coord {
            usage[c as usize] += 1;
        }
        let usable = src.valid.iter().filter(|&&v| v).count().max(1);
        Level {
            src,
            w,
            h,
            coord,
            iters: vec![iterated; w * h],
            colour,
            usage,
            share: (w * h) as f64 / usable as f64,
        }
    }

    /// The next finer level: each pixel's coordinate doubled plus its own
    /// offset within its parent, or, when that child is masked, the first
    /// usable child (a usable coarse pixel has at least three).
    fn refine(self, src: &'a Exemplar, w: usize, h: usize) -> Self {
        let coarse_w = self.src.width as u32;
        let coord = (0..w * h)
            .map(|p| {
                let (x, y) = (p % w, p / w);
                let parent = self.coord[(y / 2).min(self.h - 1) * self.w + (x / 2).min(self.w - 1)];
                let children =
                    src.children((parent % coarse_w) as usize, (parent / coarse_w) as usize);
                let own = children[(y % 2) * 2 + x % 2];
                let child = if src.valid[own] {
                    own
                } else {
                    children.into_iter().find(|&c| src.valid[c]).unwrap_or(own)
                };
                child as u32
            })
            .collect();
        Self::with_coords(src, w, h, coord, 1)
    }

    /// The occurrence penalty's weight: `occurrence` for outputs of
    /// `SMALL_OUTPUT` pixels a side or more, or with at least `SPREAD_SHARE`
    /// times the exemplar's usable pixels; below both, rising linearly
    /// with each to `SPREAD_BOOST` times it for an output half that side
    /// or less with a vanishing share (module doc: "Occurrence").
    fn occurrence_weight(&self, opts: &SynthOptions, whole_share: f64) -> f64 {
        let (side, small) = (opts.width.min(opts.height) as f64, SMALL_OUTPUT as f64);
        let small_side = ((small - side) / (small / 2.0)).clamp(0.0, 1.0);
        let small_share = (1.0 - self.share / SPREAD_SHARE).max(0.0);
        let scarce = 1.0
            + (SCARCE_BOOST - 1.0)
                * ((SCARCE_SHARE - whole_share) / (SCARCE_SHARE / 2.0)).clamp(0.0, 1.0);
        opts.occurrence
            * (1.0 + (SPREAD_BOOST - 1.0) * small_side * small_share)
            * (1.0 + (scarce - 1.0) * small_side)
    }

    /// Output pixel at (x + dx, y + dy): wrapped when tileable, else `None`
    /// outside.
    #[inline]
    fn at(&self, x: usize, y: usize, dx: i32, dy: i32, tileable: bool) -> Option<usize> {
        let (nx, ny) = (x as i32 + dx, y as i32 + dy);
        if tileable {
            let nx = nx.rem_euclid(self.w as i32) as usize;
            let ny = ny.rem_euclid(self.h as i32) as usize;
            Some(ny * self.w + nx)
        } else if nx >= 0 && ny >= 0 && (nx as usize) < self.w && (ny as usize) < self.h {
            Some(ny as usize * self.w + nx as usize)
        } else {
            None
        }
    }

    /// One pass: every pixel visited once, classes in a seeded random order.
    fn pass(
        &mut self,
        buckets: &ColourBuckets,
        opts: &SynthOptions,
        whole_share: f64,
        level: u64,
        pass: u64,
    ) {
        let weight = self.occurrence_weight(opts, whole_share);
        let r = (opts.neighbourhood / 2) as i32;
        let k = (r + 1) as usize;
        let window = window(r);
        let order = rng::permutation(opts.seed, &[level, pass], k * k);
        for class in order {
            let (cx, cy, w) = (class % k, class / k, self.w);
            let pixels: Vec<usize> = (cy..self.h)
                .step_by(k)
                .flat_map(|y| (cx..w).step_by(k).map(move |x| y * w + x))
                .collect();
            let this = &*self;
            let chosen: Vec<u32> = pixels
                .par_iter()
                .map(|&p| this.best_source(p, buckets, opts, weight, &window, [level, pass]))
                .collect();
            for (&p, &c) in pixels.iter().zip(&chosen) {
                self.usage[self.coord[p] as usize] -= 1;
                self.usage[c as usize] += 1;
                self.coord[p] = c;
                self.colour[p] = self.src.pixels[c as usize];
                self.iters[p] = self.iters[p].saturating_add(1).min(opts.iterations as u8);
            }
        }
    }

    /// The candidate source pixel whose neighbourhood costs least for
    /// output pixel `p`.
    fn best_source(
        &self,
        p: usize,
        buckets: &ColourBuckets,
        opts: &SynthOptions,
        weight: f64,
        window: &[(i32, i32)],
        key: [u64; 2],
    ) -> u32 {
        let (x, y) = (p % self.w, p / self.w);
        let sw = self.src.width as i32;
        let sh = self.src.height as i32;
        let mut candidates: Vec<u32> = Vec::with_capacity(16);
        let mut offer = |sx: i32, sy: i32| {
            if sx >= 0 && sy >= 0 && sx < sw && sy < sh {
                let i = (sy * sw + sx) as u32;
                if self.src.valid[i as usize] && !candidates.contains(&i) {
                    candidates.push(i);
                }
            }
        };
        if self.iters[p] > 0 {
            let c = self.coord[p] as i32;
            offer(c % sw, c / sw);
        }
        for &(dx, dy) in &RING {
            let Some(q) = self.at(x, y, dx, dy, opts.tileable) else {
                continue;
            };
            if self.iters[q] == 0 {
                continue;
            }
            let c = self.coord[q] as i32;
            // Coherence: the source pixel that neighbour's source sits next to.
            offer(c % sw - dx, c / sw - dy);
            // Same colour: a source pixel whose neighbour at this offset has
            // that neighbour's colour.
            if dx == 0 || dy == 0 {
                let same = buckets.of(self.colour[q]);
                if !same.is_empty() {
                    let s = same[rng::below(
                        opts.seed,
                        &[key[0], key[1], p as u64, (dx + 2 * dy + 8) as u64],
                        same.len(),
                    )] as i32;
                    offer(s % sw - dx, s / sw - dy);
                }
            }
        }
        for k in 0..RANDOM_CANDIDATES {
            let s = buckets.usable[rng::below(
                opts.seed,
                &[key[0], key[1], p as u64, 100 + k as u64],
                buckets.usable.len(),
            )] as i32;
            offer(s % sw, s / sw);
        }

        let m = opts.iterations as i64;
        let mut best = (i64::MAX, candidates[0]);
        for &c in &candidates {
            let (cx, cy) = ((c as i32) % sw, (c as i32) / sw);
            // Occurrence: copies of this source pixel beyond its even share,
            // not counting this pixel's own.
            let own = (self.coord[p] == c) as u32 as f64;
            let over =
                (self.usage[c as usize] as f64 - own - self.share).max(0.0) / self.share.max(1.0);
            let factor = 1.0 + weight * over;
            let limit = losing_match(best.0, factor);
            let mut cost = 0i64;
            for &(dx, dy) in window {
                let Some(q) = self.at(x, y, dx, dy, opts.tileable) else {
                    continue;
                };
                let (sx, sy) = (cx + dx, cy + dy);
                let s = (sy * sw + sx) as usize;
                if sx < 0 || sy < 0 || sx >= sw || sy >= sh || !self.src.valid[s] {
                    cost += MAX_PIXEL_COST * m;
                } else if self.iters[q] > 0 {
                    let (a, b) = (self.src.pixels[s], self.colour[q]);
                    let d = (a[0] as i64 - b[0] as i64).abs()
                        + (a[1] as i64 - b[1] as i64).abs()
                        + (a[2] as i64 - b[2] as i64).abs();
                    cost += d * self.iters[q] as i64;
                }
                if cost >= limit {
                    break;
                }
            }
            let cost = penalised(cost, factor);
            if cost < best.0 {
                best = (cost, c);
            }
        }
        best.1
    }
}

/// A match cost with the occurrence penalty's factor applied (module doc,
/// "Occurrence"). Rounds down, and never decreases as `cost` grows.
#[inline]
pub(super) fn penalised(cost: i64, factor: f64) -> i64 {
    (cost as f64 * factor) as i64
}

/// The smallest match cost whose `penalised` cost reaches `best`: a
/// candidate whose running sum gets there cannot win, so its sum may stop.
/// Exact, float rounding included, so stopping early never changes the
/// winner.
pub(super) fn losing_match(best: i64, factor: f64) -> i64 {
    if best == i64::MAX {
        return i64::MAX;
    }
    let mut limit = (best as f64 / factor).ceil() as i64;
    while limit > 0 && penalised(limit - 1, factor) >= best {
        limit -= 1;
    }
    while penalised(limit, factor) < best {
        limit += 1;
    }
    limit
}

/// The 8 neighbours of a pixel.
pub(super) const RING: [(i32, i32); 8] = [
    (-1, -1),
    (0, -1),
    (1, -1),
    (-1, 0),
    (1, 0),
    (-1, 1),
    (0, 1),
    (1, 1),
];

/// The (2r+1)^2 offsets of the neighbourhood, nearest first, so the cost
/// check can stop early on the pixels that matter most.
pub(super) fn window(r: i32) -> Vec<(i32, i32)> {
    let mut w: Vec<(i32, i32)> = (-r..=r)
        .flat_map(|dy| (-r..=r).map(move |dx| (dx, dy)))
        .collect();
    w.sort_by_key(|&(dx, dy)| (dx * dx + dy * dy, dy, dx));
    w
}

/// Peak memory of 2D synthesis of a `width` x `height`
/// texture, with the PNG written from it: per output pixel the level's
/// coordinate, colour and count (8 bytes, and the coarser level's quarter
/// while refining), the result's colour and coordinates and their rolled
/// copy (22), the image handed to the encoder (3 to 6).
pub fn memory_bytes(width: usize, height: usize) -> u64 {
    crate::memory::product(&[width as u64, height as u64, 36])
}

#[cfg(test)]
mod memory_tests {
    use super::*;

    #[test]
    fn the_memory_estimate_grows_with_the_texture_and_saturates() {
        assert_eq!(memory_bytes(0, 10), 0);
        assert!(memory_bytes(512, 512) > memory_bytes(256, 256));
        assert_eq!(memory_bytes(usize::MAX, usize::MAX), u64::MAX);
    }
}

#[cfg(test)]
mod depth_tests {
    use super::*;

    fn exemplar(side: usize) -> Exemplar {
        Exemplar::new(
            side,
            side,
            vec![[128, 64, 32]; side * side],
            vec![true; side * side],
        )
        .unwrap()
    }

    fn options(side: usize) -> SynthOptions {
        SynthOptions {
            width: side,
            height: side,
            ..SynthOptions::default()
        }
    }

    #[test]
    fn the_exemplar_sets_the_default_depth_down_to_an_eight_pixel_output() {
        // A 340-pixel exemplar halves to 21 pixels in five levels, whether
        // the output is 512 or 128 pixels (down to 32 and 8 output pixels);
        // a 64-pixel output stops at 8. A 90-pixel exemplar goes to 11
        // pixels for a small output, to 22 for a 512-pixel one.
        let ex = exemplar(340);
        assert_eq!(pyramid(&ex, &options(512)).unwrap().len(), 5);
        assert_eq!(pyramid(&ex, &options(128)).unwrap().len(), 5);
        assert_eq!(pyramid(&ex, &options(64)).unwrap().len(), 4);
        assert_eq!(pyramid(&exemplar(64), &options(64)).unwrap().len(), 3);
        assert_eq!(pyramid(&exemplar(90), &options(256)).unwrap().len(), 4);
        assert_eq!(pyramid(&exemplar(90), &options(512)).unwrap().len(), 3);
    }

    #[test]
    fn the_occurrence_weight_grows_only_for_small_outputs_with_few_pixels() {
        // The level's share, and the whole output's given apart.
        let weight_of = |out: usize, ex: usize, whole: Option<f64>| {
            let src = exemplar(ex);
            let level = Level::random(&src, out, out, 0);
            level.occurrence_weight(&options(out), whole.unwrap_or(level.share))
        };
        let weight = |out: usize, ex: usize| weight_of(out, ex, Some(1.0));
        let plain = SynthOptions::default().occurrence;
        // 512 pixels a side or more, or 4x the exemplar's pixels: plain.
        assert_eq!(weight(512, 560), plain);
        assert_eq!(weight_of(512, 2048, None), plain);
        assert_eq!(weight(128, 64), plain);
        // Small, and far fewer pixels than the exemplar: nearly 4x.
        let grown = weight(128, 560);
        assert!(grown > 3.8 * plain && grown <= 4.0 * plain, "{grown}");
        // Between 256 and 512 pixels the growth fades out.
        assert!(weight(384, 2048) < weight(256, 2048));
        assert!(weight(384, 2048) > plain);
        // An output with under an eighth of its exemplar's pixels weighs it
        // more again, 8x at a sixteenth (the fundus at 128: 0.06); at a
        // quarter (the fundus at 256) not at all.
        assert_eq!(weight_of(128, 560, Some(0.25)), grown);
        assert!(weight_of(128, 560, Some(0.1)) > 1.5 * grown);
        assert_eq!(weight_of(128, 560, Some(0.06)), 8.0 * grown);
    }
}

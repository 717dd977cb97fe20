//! 3D block synthesis: a solid texture that tiles space, from one exemplar
//! (isotropic tissue) or three, one per axis (seed 004, section 3.3;
//! DESIGN.md "3D block synthesis").
//!
//! A voxel has three 2D neighbourhoods, one in each axis plane: across x
//! it spans (y, z), across y (x, z), across z (x, y), which is also how
//! `Volume::slice` lays slices out. The plane across axis a is matched
//! against that axis's exemplar E_a. Two methods share the neighbourhood
//! cost, the candidate search and the pyramid:
//!
//! - `Fnpts` (seed 004, 3.3): FNPTS with the three neighbourhoods summed.
//!   Each voxel holds ONE exemplar coordinate, the one minimising the sum;
//!   the three exemplars must therefore be the same size. In plane a a
//!   voxel shows E_a at its coordinate, and the block stores the mean of
//!   those (with one exemplar: the exemplar's pixel itself). Iteration
//!   weights n_i / M, masks, occurrence and the interleaved deterministic
//!   visiting order are the 2D synthesiser's (fnpts.rs).
//! - `Optimize` (Kopf et al. 2007 as reviewed in seed 002, 4.1, Figures
//!   4.4-4.6): each voxel holds a best exemplar coordinate per plane
//!   (search phase), then every voxel becomes the blend of what the
//!   overlapping exemplar neighbourhoods put there, weighted by their
//!   match distance^-1.2 and damped where the colour is already more
//!   common in the block than in the exemplars (histogram matching). The
//!   search uses the same candidates as FNPTS (coherence, same colour,
//!   random) instead of PCA + ANN. Histograms are updated after each
//!   interleaved class of voxels rather than after each voxel, so the
//!   result does not depend on the thread count.
//!
//! Both wrap around in x, y and z, and the result is rolled so the tile
//! faces fall where the texture is most continuous.

pub mod layered;
mod optimize;

use rayon::prelude::*;

use super::exemplar::Exemplar;
use super::fnpts::{
    ColourBuckets, MAX_LEVELS, MAX_PIXEL_COST, RANDOM_CANDIDATES, RING, check_search, losing_match,
    penalised, window,
};
use super::volume::Volume;
use crate::error::{Error, Result};
use crate::progress::{Progress, check};
use crate::rng;

/// The largest block side, in voxels: 256^3 voxels take about 200 MB of
/// synthesis state (optimize: 0.9 GB).
pub const MAX_BLOCK: usize = 256;

/// Which synthesis fills the block (scene files name it in lower case).
/// FNPTS is sharp, but slices across x can show diagonal streaks (one
/// exemplar coordinate per voxel keeps at most two planes coherent);
/// optimize is isotropic but softer (seed 002, 4.1).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Method {
    #[default]
    Fnpts,
    Optimize,
}

#[derive(Clone, Debug)]
pub struct BlockOptions {
    /// Voxels a side.
    pub size: usize,
    pub seed: u64,
    /// FNPTS: M, iterations per voxel and level; optimize: search and
    /// blend rounds per level.
    pub iterations: usize,
    /// Pyramid levels; `None`: as many as keep the coarsest block and
    /// exemplar at least 16 a side.
    pub levels: Option<usize>,
    /// Side of each square plane neighbourhood (odd).
    pub neighbourhood: usize,
    /// Weight of FNPTS's occurrence penalty, which multiplies a candidate's
    /// cost as in 2D (0: the paper's cost alone), without 2D's growth for
    /// small outputs (blocks were not measured against it).
    pub occurrence: f64,
    pub method: Method,
}

impl Default for BlockOptions {
    fn default() -> Self {
        BlockOptions {
            size: 64,
            seed: 0,
            iterations: 3,
            levels: None,
            neighbourhood: 5,
            occurrence: 0.1,
            method: Method::default(),
        }
    }
}

/// The two axes a plane spans, by the axis it is across.
const PLANE_AXES: [(usize, usize); 3] = [(1, 2), (0, 2), (0, 1)];
/// Smallest side of the coarsest block and exemplar the default pyramid
/// keeps.
const COARSEST: usize = 16;

/// A solid texture from `exemplars`: one (the same in every plane) or
/// three (across x, y and z), of equal size.
pub fn synthesize_block(
    exemplars: &[Exemplar],
    opts: &BlockOptions,
    progress: &dyn Progress,
) -> Result<Volume> {
    synthesize(exemplars, opts, None, progress)
}

/// A class map the block follows (3D "texture by numbers"): a class per
/// exemplar pixel and per voxel. Copying a pixel of another class than
/// the voxel's costs as much as if every window pixel of each plane were
/// `weight` levels off in each channel. Stereology (seed 001) lays out its
/// particles this way and the photograph's own texture fills them.
#[derive(Clone, Debug)]
pub struct Guide {
    /// Per exemplar pixel, row by row.
    pub exemplar: Vec<u8>,
    /// Per voxel, x fastest, `size`^3 of them.
    pub block: Vec<u8>,
    pub weight: f64,
}

/// FNPTS block synthesis from one exemplar that follows `guide` (rolled
/// like any block, so the classes move with it).
pub fn synthesize_guided(
    exemplar: &Exemplar,
    guide: &Guide,
    opts: &BlockOptions,
    progress: &dyn Progress,
) -> Result<Volume> {
    let n = opts.size;
    if guide.exemplar.len() != exemplar.pixels.len() || guide.block.len() != n * n * n {
        return Err(Error::invalid(format!(
            "a guide needs a class per exemplar pixel ({}) and per voxel ({}), not {} and {}",
            exemplar.pixels.len(),
            n * n * n,
            guide.exemplar.len(),
            guide.block.len()
        )));
    }
    let opts = BlockOptions {
        method: Method::Fnpts,
        ..opts.clone()
    };
    synthesize(std::slice::from_ref(exemplar), &opts, Some(guide), progress)
}

fn synthesize(
    exemplars: &[Exemplar],
    opts: &BlockOptions,
    guide: Option<&Guide>,
    progress: &dyn Progress,
) -> Result<Volume> {
    let levels = check_options(exemplars, opts)?;
    let pyramid = pyramid(exemplars, opts.neighbourhood, levels, guide)?;
    // The voxels' classes at each level, finest first: each coarse voxel
    // the most common class of its 8 children.
    let mut block_classes: Vec<Vec<u8>> = guide.map(|g| vec![g.block.clone()]).unwrap_or_default();
    while guide.is_some() && block_classes.len() < levels {
        let fine = block_classes.last().expect("the finest level");
        let n = opts.size >> block_classes.len();
        let coarse = (0..n * n * n)
            .map(|v| {
                let [x, y, z] = Grid(n).xyz(v).map(|c| 2 * c as usize);
                let f = 2 * n;
                let children: [u8; 8] = std::array::from_fn(|k| {
                    fine[((z + k / 4) * f + y + k / 2 % 2) * f + x + k % 2]
                });
                most_common(&children)
            })
            .collect();
        block_classes.push(coarse);
    }
    progress.stage("block synthesis", (levels * opts.iterations) as u64);
    let mut state: Option<Block> = None;
    for (l, sources) in pyramid.iter().enumerate().rev() {
        check(progress)?;
        let grid = Grid(opts.size >> l);
        let classes = guide.map(|g| GuideLevel {
            block: std::mem::take(&mut block_classes[l]),
            penalty: (g.weight
                * 3.0
                * opts.iterations as f64
                * 3.0
                * opts.neighbourhood.pow(2) as f64) as i64,
        });
        let mut block = match state.take() {
            None => Block::random(sources, grid, opts, classes),
            Some(coarse) => coarse.refine(sources, grid, classes),
        };
        for round in 0..opts.iterations {
            check(progress)?;
            let key = [l as u64, round as u64];
            match opts.method {
                Method::Fnpts => block.fnpts_pass(opts, key),
                Method::Optimize => block.optimize_round(opts, key),
            }
            progress.advance(1);
        }
        state = Some(block);
    }
    Ok(state
        .expect("at least one level")
        .volume()
        .rolled_to_smoothest_wrap())
}

/// The most common of a few classes (ties: the larger class).
fn most_common(classes: &[u8]) -> u8 {
    let count = |c: u8| classes.iter().filter(|&&d| d == c).count();
    *classes
        .iter()
        .max_by_key(|&&c| (count(c), c))
        .expect("some classes")
}

/// A guide's voxel classes at one level and what a class mismatch costs.
struct GuideLevel {
    block: Vec<u8>,
    penalty: i64,
}

/// Check the options and exemplars; the number of pyramid levels.
fn check_options(exemplars: &[Exemplar], opts: &BlockOptions) -> Result<usize> {
    if exemplars.len() != 1 && exemplars.len() != 3 {
        return Err(Error::invalid(format!(
            "a block is synthesised from 1 exemplar or 3 (across x, y, z), not {}",
            exemplars.len()
        )));
    }
    let (w, h) = (exemplars[0].width, exemplars[0].height);
    if let Some(e) = exemplars.iter().find(|e| (e.width, e.height) != (w, h)) {
        return Err(Error::invalid(format!(
            "the exemplars must be the same size: {w}x{h} and {}x{}",
            e.width, e.height
        )));
    }
    let k = opts.neighbourhood;
    check_search(k, 11, opts.iterations, opts.occurrence)?;
    let n = opts.size;
    if !(k..=MAX_BLOCK).contains(&n) {
        return Err(Error::invalid(format!(
            "the block size must be from {k} (the neighbourhood) to {MAX_BLOCK} voxels, not {n}"
        )));
    }
    let levels = match opts.levels {
        Some(l) if !(1..=MAX_LEVELS).contains(&l) => {
            return Err(Error::invalid(format!(
                "levels must be from 1 to {MAX_LEVELS}, not {l}"
            )));
        }
        Some(l) => l,
        None => {
            let mut l = 1;
            while (n >> l) >= COARSEST && (w.min(h) >> l) >= COARSEST {
                l += 1;
            }
            l
        }
    };
    let step = 1usize << (levels - 1);
    if !n.is_multiple_of(step) || n / step < k {
        return Err(Error::invalid(format!(
            "a block of {n} voxels does not fit {levels} pyramid levels: the size must be a multiple of {step} and at least {} (e.g. {}), or the levels fewer",
            k * step,
            n.max(k * step).next_multiple_of(step)
        )));
    }
    Ok(levels)
}

/// The exemplars at one pyramid level. A coordinate may be copied only
/// where every exemplar is usable.
struct Sources {
    /// The distinct exemplars, with the shared validity.
    ex: Vec<Exemplar>,
    /// Which of `ex` each axis plane matches.
    of_axis: [usize; 3],
    buckets: Vec<ColourBuckets>,
    /// With a guide: each pixel's class, and the usable pixels of each
    /// class.
    classes: Option<(Vec<u8>, Vec<Vec<u32>>)>,
    /// Per pixel, whether its whole neighbourhood window is inside the
    /// exemplar and usable, and the window's offsets in pixel indices:
    /// such candidates are costed without a bounds check per pixel.
    interior: Vec<bool>,
    offsets: Vec<isize>,
}

impl Sources {
    fn width(&self) -> i32 {
        self.ex[0].width as i32
    }

    /// The usable coordinate (sx, sy), if it is one.
    #[inline]
    fn usable(&self, sx: i32, sy: i32) -> Option<u32> {
        let (w, h) = (self.width(), self.ex[0].height as i32);
        if sx < 0 || sy < 0 || sx >= w || sy >= h {
            return None;
        }
        let i = (sy * w + sx) as usize;
        self.ex[0].valid[i].then_some(i as u32)
    }

    #[inline]
    fn split(&self, c: u32) -> (i32, i32) {
        (c as i32 % self.width(), c as i32 / self.width())
    }

    /// What a voxel copying coordinate `c` shows: the mean of the distinct
    /// exemplars there.
    fn mean_colour(&self, c: u32) -> [u8; 3] {
        let n = self.ex.len() as u32;
        let mut sum = [0u32; 3];
        for e in &self.ex {
            for (s, &v) in sum.iter_mut().zip(&e.pixels[c as usize]) {
                *s += v as u32;
            }
        }
        sum.map(|s| ((s + n / 2) / n) as u8)
    }
}

/// Finest level first.
fn pyramid(
    exemplars: &[Exemplar],
    k: usize,
    levels: usize,
    guide: Option<&Guide>,
) -> Result<Vec<Sources>> {
    let mut chains: Vec<Vec<Exemplar>> = exemplars.iter().map(|e| vec![e.clone()]).collect();
    for chain in &mut chains {
        while chain.len() < levels {
            let coarser = chain.last().and_then(|e| e.downsample(k)).ok_or_else(|| {
                Error::invalid(format!(
                    "{levels} pyramid levels need exemplars of at least {} pixels a side, with usable pixels at every level",
                    k << (levels - 1)
                ))
            })?;
            chain.push(coarser);
        }
    }
    let of_axis = if exemplars.len() == 1 {
        [0; 3]
    } else {
        [0, 1, 2]
    };
    // The pixels' classes at each level: each coarse pixel the most common
    // class of its 4 children.
    let mut pixel_classes: Vec<Vec<u8>> =
        guide.map(|g| vec![g.exemplar.clone()]).unwrap_or_default();
    while guide.is_some() && pixel_classes.len() < levels {
        let l = pixel_classes.len();
        let (fine, coarse) = (&chains[0][l - 1], &chains[0][l]);
        let of = pixel_classes.last().expect("the finest level");
        let next = (0..coarse.height)
            .flat_map(|y| (0..coarse.width).map(move |x| (x, y)))
            .map(|(x, y)| most_common(&fine.children(x, y).map(|i| of[i])))
            .collect();
        pixel_classes.push(next);
    }
    (0..levels)
        .map(|l| {
            let valid: Vec<bool> = (0..chains[0][l].valid.len())
                .map(|i| chains.iter().all(|c| c[l].valid[i]))
                .collect();
            if !valid.iter().any(|&v| v) {
                return Err(Error::invalid(
                    "the exemplars' masks leave no pixel usable in all of them",
                ));
            }
            let ex: Vec<Exemplar> = chains
                .iter()
                .map(|c| Exemplar {
                    valid: valid.clone(),
                    ..c[l].clone()
                })
                .collect();
            let buckets = ex.iter().map(ColourBuckets::new).collect();
            let (w, r) = (ex[0].width, k / 2);
            // ex[0] carries the validity shared by all exemplars.
            let interior = ex[0].whole_windows(r);
            let offsets = window(r as i32)
                .iter()
                .map(|&(du, dv)| dv as isize * w as isize + du as isize)
                .collect();
            let classes = pixel_classes.get(l).map(|of| {
                let count = of.iter().copied().max().unwrap_or(0) as usize + 1;
                let mut members = vec![Vec::new(); count];
                for (i, &c) in of.iter().enumerate() {
                    if valid[i] {
                        members[c as usize].push(i as u32);
                    }
                }
                (of.clone(), members)
            });
            Ok(Sources {
                ex,
                of_axis,
                buckets,
                classes,
                interior,
                offsets,
            })
        })
        .collect()
}

/// A cubic block of side n that wraps around.
#[derive(Clone, Copy)]
struct Grid(usize);

impl Grid {
    fn len(self) -> usize {
        self.0 * self.0 * self.0
    }

    #[inline]
    fn xyz(self, v: usize) -> [i32; 3] {
        let n = self.0;
        [(v % n) as i32, (v / n % n) as i32, (v / (n * n)) as i32]
    }

    /// The voxel at in-plane offset (du, dv) from `xyz` in the plane
    /// across `axis`, wrapped.
    #[inline]
    fn neighbour(self, xyz: [i32; 3], axis: usize, du: i32, dv: i32) -> usize {
        let n = self.0 as i32;
        let (i, j) = PLANE_AXES[axis];
        let mut q = xyz;
        q[i] = (q[i] + du).rem_euclid(n);
        q[j] = (q[j] + dv).rem_euclid(n);
        ((q[2] * n + q[1]) * n + q[0]) as usize
    }

    /// Voxel `v`'s in-plane coordinates in the plane across `axis`.
    #[inline]
    fn plane_uv(self, v: usize, axis: usize) -> (i32, i32) {
        let p = self.xyz(v);
        let (i, j) = PLANE_AXES[axis];
        (p[i], p[j])
    }

    /// The voxels of each of the k^3 interleaved classes, k = r + 1: no two
    /// voxels of a class share a neighbourhood, so a class can be visited
    /// at once. Classes in a seeded random order.
    fn classes(self, k: usize, seed: u64, key: [u64; 2]) -> Vec<Vec<usize>> {
        let n = self.0;
        rng::permutation(seed, &[key[0], key[1], 3], k * k * k)
            .into_iter()
            .map(|class| {
                let (cx, cy, cz) = (class % k, class / k % k, class / (k * k));
                (cz..n)
                    .step_by(k)
                    .flat_map(|z| {
                        (cy..n)
                            .step_by(k)
                            .flat_map(move |y| (cx..n).step_by(k).map(move |x| (z * n + y) * n + x))
                    })
                    .collect()
            })
            .collect()
    }
}

/// What the neighbourhood cost reads of the block.
struct View<'a> {
    grid: Grid,
    /// Colour per voxel as seen in this plane.
    colour: &'a [[u8; 3]],
    /// FNPTS's iteration counts n_i (`None`: every voxel counts once).
    iters: Option<&'a [u8]>,
    /// Cost of an undefined exemplar pixel: the largest pixel cost x M.
    missing: i64,
}

/// The block's neighbourhood of voxel `xyz` in the plane across `axis`,
/// in window order: each neighbour's colour and weight n_i. Gathered once
/// per voxel, then compared against every candidate.
fn gather(view: &View, axis: usize, xyz: [i32; 3], window: &[(i32, i32)]) -> Vec<([u8; 3], i64)> {
    window
        .iter()
        .map(|&(du, dv)| {
            let q = view.grid.neighbour(xyz, axis, du, dv);
            (view.colour[q], view.iters.map_or(1, |it| it[q] as i64))
        })
        .collect()
}

/// The cost of exemplar `e`'s neighbourhood at (sx, sy) against a gathered
/// block neighbourhood, added to `cost`; stops once it reaches `limit`.
/// The paper's cost (seed 004, 3.2): sum of |s_i - r_i| * n_i over the
/// window, `missing` (the largest) where the exemplar pixel is undefined.
#[allow(clippy::too_many_arguments)]
#[inline]
fn plane_cost(
    src: &Sources,
    e: &Exemplar,
    block: &[([u8; 3], i64)],
    (sx, sy): (i32, i32),
    window: &[(i32, i32)],
    missing: i64,
    mut cost: i64,
    limit: i64,
) -> i64 {
    let centre = (sy * src.width() + sx) as usize;
    if src.interior[centre] {
        // The same sum in the same order, every pixel there.
        for (&o, &(b, n)) in src.offsets.iter().zip(block) {
            if n != 0 {
                cost += pixel_cost(e.pixels[(centre as isize + o) as usize], b) * n;
            }
            if cost >= limit {
                break;
            }
        }
        return cost;
    }
    for (&(du, dv), &(b, n)) in window.iter().zip(block) {
        match src.usable(sx + du, sy + dv) {
            None => cost += missing,
            Some(_) if n == 0 => {}
            Some(s) => cost += pixel_cost(e.pixels[s as usize], b) * n,
        }
        if cost >= limit {
            break;
        }
    }
    cost
}

/// |a - b| summed over the channels.
#[inline]
fn pixel_cost(a: [u8; 3], b: [u8; 3]) -> i64 {
    (a[0] as i64 - b[0] as i64).abs()
        + (a[1] as i64 - b[1] as i64).abs()
        + (a[2] as i64 - b[2] as i64).abs()
}

/// Offer coordinate (sx, sy) if usable and new.
#[inline]
fn offer(src: &Sources, out: &mut Vec<u32>, sx: i32, sy: i32) {
    if let Some(i) = src.usable(sx, sy)
        && !out.contains(&i)
    {
        out.push(i);
    }
}

/// Candidates from voxel `v`'s ring in the plane across `axis`:
/// coherence (each defined neighbour's coordinate shifted back by its
/// offset) and, from the four axis neighbours, a random exemplar pixel
/// whose neighbour at that offset has the neighbour's colour.
#[allow(clippy::too_many_arguments)]
fn plane_candidates(
    src: &Sources,
    view: &View,
    axis: usize,
    v: usize,
    coord: &[u32],
    seed: u64,
    key: [u64; 2],
    out: &mut Vec<u32>,
) {
    let xyz = view.grid.xyz(v);
    let buckets = &src.buckets[src.of_axis[axis]];
    for &(du, dv) in &RING {
        let q = view.grid.neighbour(xyz, axis, du, dv);
        if view.iters.is_some_and(|it| it[q] == 0) {
            continue;
        }
        let (cx, cy) = src.split(coord[q]);
        offer(src, out, cx - du, cy - dv);
        if du == 0 || dv == 0 {
            let same = buckets.of(view.colour[q]);
            if !same.is_empty() {
                let tag = (axis * 16) as u64 + (du + 2 * dv + 8) as u64;
                let s = same[rng::below(seed, &[key[0], key[1], v as u64, tag], same.len())];
                let (x, y) = src.split(s);
                offer(src, out, x - du, y - dv);
            }
        }
    }
}

/// `count` random coordinates of `pool` (usable ones).
fn random_candidates(
    src: &Sources,
    pool: &[u32],
    seed: u64,
    key: [u64; 3],
    count: usize,
    out: &mut Vec<u32>,
) {
    for k in 0..count {
        let s = pool[rng::below(seed, &[key[0], key[1], key[2], 100 + k as u64], pool.len())];
        let (x, y) = src.split(s);
        offer(src, out, x, y);
    }
}

/// The synthesis state at one level.
struct Block<'a> {
    src: &'a Sources,
    grid: Grid,
    /// Exemplar coordinate per voxel: FNPTS one list shared by the planes,
    /// optimize one per plane.
    coord: Vec<Vec<u32>>,
    /// Colour per voxel: FNPTS as seen in each distinct exemplar, optimize
    /// the one blended colour.
    colour: Vec<Vec<[u8; 3]>>,
    /// FNPTS: times each voxel was iterated at this level.
    iters: Vec<u8>,
    /// FNPTS: copies of each exemplar coordinate, and the even share.
    usage: Vec<u32>,
    share: f64,
    method: Method,
    guide: Option<GuideLevel>,
}

impl<'a> Block<'a> {
    /// Coarsest level: random usable coordinates (of the voxel's class,
    /// with a guide), not yet iterated.
    fn random(
        src: &'a Sources,
        grid: Grid,
        opts: &BlockOptions,
        guide: Option<GuideLevel>,
    ) -> Self {
        let planes = if opts.method == Method::Fnpts { 1 } else { 3 };
        let coord = (0..planes as u64)
            .map(|a| {
                (0..grid.len())
                    .map(|v| {
                        let pool = Self::pool(src, guide.as_ref(), v);
                        pool[rng::below(opts.seed, &[u64::MAX, a, v as u64], pool.len())]
                    })
                    .collect()
            })
            .collect();
        Self::with_coords(src, grid, coord, 0, opts.method, None, guide)
    }

    /// The coordinates voxel `v` draws random candidates from: the usable
    /// pixels of its class, with a guide (all usable ones if it has none).
    fn pool<'s>(src: &'s Sources, guide: Option<&GuideLevel>, v: usize) -> &'s [u32] {
        match (&src.classes, guide) {
            (Some((_, members)), Some(g)) => members
                .get(g.block[v] as usize)
                .filter(|m| !m.is_empty())
                .unwrap_or(&src.buckets[0].usable),
            _ => &src.buckets[0].usable,
        }
    }

    fn with_coords(
        src: &'a Sources,
        grid: Grid,
        coord: Vec<Vec<u32>>,
        iterated: u8,
        method: Method,
        blended: Option<Vec<[u8; 3]>>,
        guide: Option<GuideLevel>,
    ) -> Self {
        let colour = match method {
            Method::Fnpts => src
                .ex
                .iter()
                .map(|e| coord[0].iter().map(|&c| e.pixels[c as usize]).collect())
                .collect(),
            // Until the first blend: the mean of what the planes copy.
            Method::Optimize => vec![blended.unwrap_or_else(|| {
                (0..grid.len())
                    .map(|v| {
                        let mut sum = [0u32; 3];
                        for (plane, &ex) in coord.iter().zip(&src.of_axis) {
                            let e = &src.ex[ex];
                            for (s, &c) in sum.iter_mut().zip(&e.pixels[plane[v] as usize]) {
                                *s += c as u32;
                            }
                        }
                        sum.map(|s| ((s + 1) / 3) as u8)
                    })
                    .collect()
            })],
        };
        // Occurrence is FNPTS's alone.
        let mut usage = vec![0u32; src.ex[0].pixels.len()];
        if method == Method::Fnpts {
            for &c in &coord[0] {
                usage[c as usize] += 1;
            }
        }
        let usable = src.buckets[0].usable.len().max(1);
        Block {
            src,
            grid,
            coord,
            colour,
            iters: vec![iterated; grid.len()],
            usage,
            share: grid.len() as f64 / usable as f64,
            method,
            guide,
        }
    }

    /// The next finer level: each coordinate doubled plus the voxel's
    /// offset within its parent in the plane (for FNPTS's shared
    /// coordinate, the plane across z), or the first usable child.
    fn refine(self, src: &'a Sources, grid: Grid, guide: Option<GuideLevel>) -> Self {
        let coarse = self.grid;
        let coarse_w = self.src.width() as u32;
        let parent = |v: usize| {
            let [x, y, z] = grid.xyz(v).map(|c| (c / 2) as usize);
            (z * coarse.0 + y) * coarse.0 + x
        };
        let coord: Vec<Vec<u32>> = self
            .coord
            .iter()
            .enumerate()
            .map(|(a, plane)| {
                let axis = if self.method == Method::Fnpts { 2 } else { a };
                (0..grid.len())
                    .map(|v| {
                        let c = plane[parent(v)];
                        let children =
                            src.ex[0].children((c % coarse_w) as usize, (c / coarse_w) as usize);
                        let (u, w) = grid.plane_uv(v, axis);
                        let own = children[(w % 2 * 2 + u % 2) as usize];
                        let valid = &src.ex[0].valid;
                        let child = if valid[own] {
                            own
                        } else {
                            children.into_iter().find(|&c| valid[c]).unwrap_or(own)
                        };
                        child as u32
                    })
                    .collect()
            })
            .collect();
        let blended = (self.method == Method::Optimize)
            .then(|| (0..grid.len()).map(|v| self.colour[0][parent(v)]).collect());
        Self::with_coords(src, grid, coord, 1, self.method, blended, guide)
    }

    fn view(&self, axis: usize, missing: i64, iters: bool) -> View<'_> {
        let colour = match self.method {
            Method::Fnpts => &self.colour[self.src.of_axis[axis]],
            Method::Optimize => &self.colour[0],
        };
        View {
            grid: self.grid,
            colour,
            iters: iters.then_some(&self.iters[..]),
            missing,
        }
    }

    /// One FNPTS pass: every voxel visited once, class by class.
    fn fnpts_pass(&mut self, opts: &BlockOptions, key: [u64; 2]) {
        let r = (opts.neighbourhood / 2) as i32;
        let window = window(r);
        let m = opts.iterations as i64;
        for class in self.grid.classes(r as usize + 1, opts.seed, key) {
            let this = &*self;
            let views: [View; 3] = std::array::from_fn(|a| this.view(a, MAX_PIXEL_COST * m, true));
            let chosen: Vec<u32> = class
                .par_iter()
                .map(|&v| this.best_shared(v, &views, &window, opts, key))
                .collect();
            for (&v, &c) in class.iter().zip(&chosen) {
                self.usage[self.coord[0][v] as usize] -= 1;
                self.usage[c as usize] += 1;
                self.coord[0][v] = c;
                for (colour, e) in self.colour.iter_mut().zip(&self.src.ex) {
                    colour[v] = e.pixels[c as usize];
                }
                self.iters[v] = self.iters[v].saturating_add(1).min(opts.iterations as u8);
            }
        }
    }

    /// FNPTS: the coordinate whose three plane neighbourhoods cost least
    /// in sum, times the occurrence penalty.
    fn best_shared(
        &self,
        v: usize,
        views: &[View; 3],
        window: &[(i32, i32)],
        opts: &BlockOptions,
        key: [u64; 2],
    ) -> u32 {
        let src = self.src;
        let mut candidates = Vec::with_capacity(48);
        if self.iters[v] > 0 {
            candidates.push(self.coord[0][v]);
        }
        for (a, view) in views.iter().enumerate() {
            plane_candidates(
                src,
                view,
                a,
                v,
                &self.coord[0],
                opts.seed,
                key,
                &mut candidates,
            );
        }
        random_candidates(
            src,
            Self::pool(src, self.guide.as_ref(), v),
            opts.seed,
            [key[0], key[1], v as u64],
            RANDOM_CANDIDATES,
            &mut candidates,
        );
        let xyz = self.grid.xyz(v);
        let blocks: [_; 3] = std::array::from_fn(|a| gather(&views[a], a, xyz, window));
        let mismatch = |c: u32| match (&src.classes, &self.guide) {
            (Some((of, _)), Some(g)) if of[c as usize] != g.block[v] => g.penalty,
            _ => 0,
        };
        let mut best = (i64::MAX, candidates[0]);
        for &c in &candidates {
            // Copies of this coordinate beyond its even share, not counting
            // this voxel's own; the penalty multiplies the cost, as in 2D.
            let own = (self.coord[0][v] == c) as u32 as f64;
            let over =
                (self.usage[c as usize] as f64 - own - self.share).max(0.0) / self.share.max(1.0);
            let factor = 1.0 + opts.occurrence * over;
            let limit = losing_match(best.0, factor);
            let mut cost = mismatch(c);
            let s = src.split(c);
            for (a, view) in views.iter().enumerate() {
                let e = &src.ex[src.of_axis[a]];
                cost = plane_cost(src, e, &blocks[a], s, window, view.missing, cost, limit);
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

    fn volume(&self) -> Volume {
        let n = self.grid.0;
        let voxels = match self.method {
            Method::Fnpts => self.coord[0]
                .iter()
                .map(|&c| self.src.mean_colour(c))
                .collect(),
            Method::Optimize => self.colour[0].clone(),
        };
        Volume {
            size: [n; 3],
            spacing: 1.0,
            voxels,
        }
    }
}

/// Peak memory of 3D block synthesis of a `size`^3 block
/// from `exemplars` distinct exemplars. Per voxel, FNPTS holds a coordinate,
/// a colour per exemplar and a count (and the coarser level's eighth while
/// refining), the interleaved classes' voxel lists (8), and at the end the
/// block and its rolled copy (6); optimize holds three coordinates, a
/// colour, per-plane search results and weights (36) and the same lists and
/// copies.
pub fn memory_bytes(size: usize, exemplars: usize, method: Method) -> u64 {
    let per_voxel = match method {
        Method::Fnpts => 24 + 3 * exemplars as u64,
        Method::Optimize => 66,
    };
    let n = size as u64;
    crate::memory::product(&[n, n, n, per_voxel])
}

#[cfg(test)]
mod memory_tests {
    use super::*;

    #[test]
    fn the_memory_estimate_grows_with_the_block() {
        assert_eq!(memory_bytes(0, 1, Method::Fnpts), 0);
        assert!(memory_bytes(256, 1, Method::Optimize) > memory_bytes(256, 3, Method::Fnpts));
    }
}

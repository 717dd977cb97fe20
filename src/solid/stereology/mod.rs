//! Particle interiors from stereology (seed 001, Jagnow, Dorsey and
//! Rushmeier 2004): particles in a binder (fat lobules, glands in stroma,
//! nuclei), their 3D size distribution unfolded from the profiles seen in
//! photographs of sections, placed and annealed in a periodic box, and
//! coloured from the profiles, into a block that tiles in x, y and z.
//!
//! - `profiles`: the particle profiles of a section photograph;
//! - `unfold`: profile sizes to the particle size distribution;
//! - `place`: particles drawn from it, annealed apart;
//! - `residual`: the photographs' fine detail, resynthesised in 3D;
//! - here: the pipeline and the voxels.
//!
//! Sizes are in pixels of the photographs, and a voxel is a pixel.

pub mod colour;
pub mod mesh_shape;
pub mod place;
pub mod profiles;
pub mod residual;
pub mod shape;
pub mod slices;
pub mod split;
pub mod unfold;
pub mod watershed;

use std::time::Instant;

use rayon::prelude::*;

pub use profiles::{Profile, Section, sections_of};
pub use split::{Particles, Split};
pub use unfold::Distribution;

use crate::error::{Error, Result};
use crate::progress::Progress;
use crate::rng;
use crate::synth::volume::Volume;

#[derive(Clone, Debug)]
pub struct StereologyOptions {
    /// Voxels a side.
    pub size: usize,
    /// Particle-size bins reported (and unfolded into, `unfold::FINE`
    /// classes each).
    pub bins: usize,
    pub seed: u64,
    /// The particle types, each a shape and its proportion (sizes: the
    /// diameter of the disc as large as the largest section; several
    /// types share one size distribution, seed 001 eq. 10-12).
    pub shapes: Vec<(shape::Shape, f64)>,
    /// How the particles and binder get the photographs' texture.
    pub detail: Detail,
    /// Colour categories of particles (seed 001, 4.2), each unfolded on
    /// its own: 1 where colour and size are unrelated.
    pub colour_classes: usize,
}

/// How the block gets the photographs' texture inside and around the
/// particles.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Detail {
    /// The block synthesiser (FNPTS) copies the largest photograph's own
    /// pixels, guided by the placed particles: particle voxels from
    /// profile pixels, binder from binder (`synth::block::Guide`). Slices
    /// then show the nuclei and stain of the photograph, where mean
    /// colours plus a residual show flat discs; measured against the
    /// photograph it wins (README, `tools/compare_block.py`).
    #[default]
    Copied,
    /// Seed 001 (4.2-4.3): each particle a profile's mean colour, the
    /// binder its mean, plus the residual resynthesised by Heeger-Bergen
    /// pyramid matching.
    Residual,
}

/// A class mismatch in the guided synthesis costs like every window pixel
/// being as far off as the particles' mean colour is from the binder's
/// (at least this many levels per channel): a neighbourhood copied across
/// a particle's border can never pay for moving it, so particles stay
/// where they were placed and as large (at a fixed 40 the copy grew
/// high-contrast particles by a sixth of their area and bridged touching
/// ones).
const GUIDE_WEIGHT: f64 = 40.0;

/// The detail copies from a window of the largest photograph this many
/// block sides across (`detail_window`), and iterates FNPTS this many
/// times per level. Measured on the ihc photograph at 128^3 (issue 38,
/// `compare_block.py`'s slice figures, mean over x, y, z): the whole
/// photograph and 3 iterations, coherence 17.8, completeness 17.7, 80.6 s;
/// a 2x window and 1 iteration, 17.9 and 16.3 (lower is better), 12.6 s.
/// The guide already fixes where particles are; more iterations mostly
/// polish what one pass copied.
const DETAIL_WINDOW: usize = 2;
const DETAIL_ITERATIONS: usize = 1;

impl std::str::FromStr for Detail {
    type Err = String;

    fn from_str(s: &str) -> std::result::Result<Detail, String> {
        match s {
            "copied" => Ok(Detail::Copied),
            "residual" => Ok(Detail::Residual),
            _ => Err(format!("the detail is copied or residual, not {s:?}")),
        }
    }
}

impl Default for StereologyOptions {
    fn default() -> Self {
        StereologyOptions {
            size: 64,
            bins: 10,
            seed: 0,
            shapes: vec![(shape::Shape::Sphere, 1.0)],
            detail: Detail::default(),
            colour_classes: 1,
        }
    }
}

impl StereologyOptions {
    /// The size, bins and particle types in range.
    pub fn check(&self) -> Result<()> {
        if self.shapes.is_empty() || self.shapes.iter().any(|s| !(s.1.is_finite() && s.1 > 0.0)) {
            return Err(Error::invalid(
                "give at least one particle shape, each with a positive proportion",
            ));
        }
        let n = self.size;
        if !(8..=crate::synth::block::MAX_BLOCK).contains(&n) {
            return Err(Error::invalid(format!(
                "the block size must be from 8 to {} voxels, not {n}",
                crate::synth::block::MAX_BLOCK
            )));
        }
        if !(1..=8).contains(&self.colour_classes) {
            return Err(Error::invalid(format!(
                "the colour classes must be from 1 to 8, not {}",
                self.colour_classes
            )));
        }
        if !(2..=64).contains(&self.bins) {
            return Err(Error::invalid(format!(
                "the bins must be from 2 to 64, not {}",
                self.bins
            )));
        }
        Ok(())
    }
}

/// Seconds each step took.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct Seconds {
    pub unfold: f64,
    pub place: f64,
    pub colour: f64,
    pub detail: f64,
}

/// What the synthesis found and made (`organtex stereology --json`).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Report {
    /// Diameters in pixels of the photographs; particles per cubic pixel.
    pub size_distribution: Distribution,
    /// Seed 001's own solve (eq. 4, negatives clamped) on the same
    /// profiles and bins, for comparison.
    pub seed001: Distribution,
    /// The volume fraction, Delesse's estimate: of the photographs'
    /// usable area, the particles' (every particle-class region of
    /// `MIN_AREA` pixels or more, cut by the border or not, with the
    /// binder it encloses). The block's own, its particle voxels over all,
    /// is `block_volume_fraction`.
    pub volume_fraction: f64,
    pub block_volume_fraction: f64,
    /// How the photographs were split into particles and binder.
    pub split: Split,
    /// Profiles measured (wholly inside the frame), profiles cut by the
    /// border or mask and left out, and specks (particle-class regions
    /// under `MIN_AREA` pixels) given to the binder, over all
    /// photographs.
    pub profiles: usize,
    pub cut_profiles: usize,
    pub specks: usize,
    /// What looks wrong in the measurement (also printed by the CLI).
    pub warnings: Vec<String>,
    pub particles: usize,
    pub overlap_fraction: f64,
    /// The particles' colour categories (one unless asked for more).
    pub colour_classes: Vec<ColourClass>,
    /// The block's slices measured as the photographs were.
    pub slices: slices::SliceCheck,
    pub seconds: Seconds,
}

/// The sections that photographs show (PNG or JPEG, the same pixel
/// scale), `mask` (black where there is no tissue) applying to each, all
/// split into particles and binder alike (`split`), the particle class as
/// `particles` asks.
pub fn read_sections(
    photographs: &[std::path::PathBuf],
    mask: Option<&std::path::Path>,
    particles: Particles,
    seed: u64,
) -> Result<Vec<Section>> {
    use crate::synth::exemplar::read_image;
    let mask = mask
        .map(|m| read_image(m).map(|i| (m, i.to_luma8())))
        .transpose()?;
    // Per photograph: width, height, pixels, usable pixels.
    type Read = (usize, usize, Vec<[u8; 3]>, Vec<bool>);
    let read: Vec<Read> = photographs
        .par_iter()
        .map(|path| {
            let img = read_image(path)?.to_rgb8();
            let (w, h) = (img.width() as usize, img.height() as usize);
            let valid: Vec<bool> = match &mask {
                Some((at, m)) if (m.width() as usize, m.height() as usize) != (w, h) => {
                    return Err(Error::invalid(format!(
                        "the mask is {}x{} but the photograph {} is {w}x{h}",
                        m.width(),
                        m.height(),
                        path.display()
                    ))
                    .in_file(at));
                }
                Some((_, m)) => m.pixels().map(|p| p.0[0] > 127).collect(),
                None => vec![true; w * h],
            };
            let pixels: Vec<[u8; 3]> = img.pixels().map(|p| p.0).collect();
            Ok((w, h, pixels, valid))
        })
        .collect::<Result<_>>()?;
    let photos: Vec<split::Photo> = read
        .iter()
        .map(|(width, height, pixels, valid)| split::Photo {
            width: *width,
            height: *height,
            pixels,
            valid,
        })
        .collect();
    // The split is of all photographs together: name them.
    let in_files = |e: Error, photograph: Option<usize>| match (e, photograph) {
        (e, Some(k)) => e.in_file(&photographs[k]),
        (Error::Invalid { path: None, msg }, None) if photographs.len() > 1 => {
            Error::invalid(format!(
                "{} and {} other photographs: {msg}",
                photographs[0].display(),
                photographs.len() - 1
            ))
        }
        (e, None) => e.in_file(&photographs[0]),
    };
    profiles::sections_of(&photos, particles, seed, &in_files)
}

/// A colour category of particles.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct ColourClass {
    /// Mean of its profiles' mean colours.
    pub colour: [f64; 3],
    pub profiles: usize,
    /// Its share of the volume (of the profiles' area, Delesse).
    pub volume_fraction: f64,
    pub particles: usize,
    /// Its own unfolded sizes (bins up to its largest profile).
    pub size_distribution: Distribution,
}

/// The block of the particles the sections show.
pub fn synthesize(
    sections: &[Section],
    opts: &StereologyOptions,
    progress: &dyn Progress,
) -> Result<(Volume, Report)> {
    opts.check()?;
    let n = opts.size;
    let profiles: Vec<&Profile> = sections.iter().flat_map(|s| &s.profiles).collect();
    if profiles.is_empty() {
        return Err(Error::invalid("no particle profiles to unfold"));
    }
    progress.stage("stereology", 4);
    let start = Instant::now();
    let area: f64 = sections.iter().map(|s| s.area).sum();
    let fraction = sections
        .iter()
        .map(|s| s.area_fraction * s.area)
        .sum::<f64>()
        / area;
    let sizes: Vec<(f64, f64)> = profiles.iter().map(|p| (p.diameter, p.weight)).collect();
    let d_max = sizes.iter().map(|s| s.0).fold(0.0, f64::max);
    let types: Vec<(shape::ShapeStats, f64)> = opts
        .shapes
        .iter()
        .map(|(s, p)| (s.stats(opts.seed), *p))
        .collect();
    let total: f64 = types.iter().map(|t| t.1).sum();
    // Eq. 11: the types' kernels (each scaled by its caliper) weighted by
    // their proportions.
    let kernel = |s: &[f64], e: &[f64]| {
        let parts: Vec<(unfold::Kernel, f64)> = opts
            .shapes
            .iter()
            .zip(&types)
            .map(|((shape, p), (stats, _))| {
                let k = match shape {
                    shape::Shape::Sphere => unfold::sphere_kernel(s, e),
                    _ => stats.kernel(s, e),
                };
                (k, p / total)
            })
            .collect();
        unfold::Kernel::mix(&parts)
    };
    // Each colour category unfolded on its own (sec. 4.2), on the same
    // bins; its volume fraction its share of the profiles' area.
    let category = colour::categories(
        &profiles.iter().map(|p| p.colour).collect::<Vec<_>>(),
        opts.colour_classes,
    );
    let categories = category.iter().max().map_or(1, |m| m + 1);
    let members: Vec<Vec<&Profile>> = (0..categories)
        .map(|c| {
            profiles
                .iter()
                .zip(&category)
                .filter(|(_, k)| **k == c)
                .map(|(p, _)| *p)
                .collect()
        })
        .collect();
    let weighted = |m: &[&Profile]| -> f64 { m.iter().map(|p| p.area * p.weight).sum() };
    let all: f64 = members.iter().map(|m| weighted(m)).sum();
    let unfolded: Vec<(Distribution, f64)> = members
        .iter()
        .map(|m| {
            let sizes: Vec<(f64, f64)> = m.iter().map(|p| (p.diameter, p.weight)).collect();
            // Up to the category's own largest profile: small particles'
            // profiles would otherwise lend some of their volume to sizes
            // only another category has.
            let top = sizes.iter().map(|s| s.0).fold(0.0, f64::max);
            let dist = unfold::unfold(&sizes, area, opts.bins, top, &kernel);
            (dist, fraction * weighted(m) / all)
        })
        .collect();
    let edges: Vec<f64> = (0..=opts.bins)
        .map(|i| d_max * i as f64 / opts.bins as f64)
        .collect();
    let dist = if categories == 1 {
        unfolded[0].0.clone()
    } else {
        let rebinned: Vec<Distribution> = unfolded.iter().map(|(d, _)| d.rebin(&edges)).collect();
        Distribution {
            edges,
            per_volume: (0..opts.bins)
                .map(|i| rebinned.iter().map(|d| d.per_volume[i]).sum())
                .collect(),
        }
    };
    let seed001 = unfold::saltikov(&unfold::profile_density(&sizes, &dist.edges, area), d_max);
    if !dist.per_volume.iter().any(|&x| x > 0.0) {
        return Err(Error::invalid(
            "the profiles unfold to no particles: every size bin came out empty",
        ));
    }
    let unfold_s = start.elapsed().as_secs_f64();
    progress.advance(1);
    crate::progress::check(progress)?;

    let start = Instant::now();
    let side = n as f64;
    let mut particles = Vec::new();
    let mut particle_category = Vec::new();
    for (c, (dist, fraction)) in unfolded.iter().enumerate() {
        let seed = if categories == 1 {
            opts.seed
        } else {
            rng::hash(opts.seed, &[c as u64])
        };
        let drawn = place::draw(dist, side, *fraction, &types, seed);
        particle_category.extend(std::iter::repeat_n(c, drawn.len()));
        particles.extend(drawn);
    }
    if particles.is_empty() {
        return Err(Error::invalid(format!(
            "a {n}-voxel block holds none of these particles (largest {d_max:.1} pixels across, \
             volume fraction {fraction:.3}): give a larger --size"
        )));
    }
    let overlap = place::anneal(&mut particles, side, opts.seed);
    let place_s = start.elapsed().as_secs_f64();
    progress.advance(1);
    crate::progress::check(progress)?;

    let start = Instant::now();
    // Colour (sec. 4.2): each particle the mean colour of a random profile
    // of its category, the binder the mean of the binder pixels.
    let binder = sections
        .iter()
        .map(|s| s.binder_colour.map(|c| c * s.area))
        .fold([0.0; 3], |a, b| [a[0] + b[0], a[1] + b[1], a[2] + b[2]])
        .map(|c| c / area);
    let colours: Vec<[u8; 3]> = particle_category
        .iter()
        .enumerate()
        .map(|(k, &c)| {
            let m = &members[c];
            let p = m[rng::below(opts.seed, &[k as u64, 7], m.len())];
            p.colour.map(|c| c.round().clamp(0.0, 255.0) as u8)
        })
        .collect();
    let colour_classes: Vec<ColourClass> = members
        .iter()
        .zip(&unfolded)
        .enumerate()
        .map(|(c, (m, (dist, fraction)))| ColourClass {
            colour: [0, 1, 2].map(|i| m.iter().map(|p| p.colour[i]).sum::<f64>() / m.len() as f64),
            profiles: m.len(),
            volume_fraction: *fraction,
            particles: particle_category.iter().filter(|&&k| k == c).count(),
            size_distribution: dist.clone(),
        })
        .collect();
    let (mut volume, classes) = render(
        &particles,
        &particle_category,
        &colours,
        binder.map(|c| c.round() as u8),
        n,
    );
    let inside = classes.iter().filter(|&&c| c != 0).count();
    let colour_s = start.elapsed().as_secs_f64();
    progress.advance(1);
    crate::progress::check(progress)?;

    // Fine detail from the largest photograph that shows particles (one
    // of binder alone has none of their texture to give).
    let start = Instant::now();
    let (index, largest) = sections
        .iter()
        .enumerate()
        .filter(|(_, s)| !s.profiles.is_empty())
        .max_by(|a, b| a.1.area.total_cmp(&b.1.area))
        .expect("a section");
    match opts.detail {
        Detail::Copied => {
            // The photograph's pixels' classes: 0 binder, 1 + the
            // category of the profile they belong to (of the nearest
            // category's colour for a profile cut by the border).
            let first: usize = sections[..index].iter().map(|s| s.profiles.len()).sum();
            let means: Vec<[f64; 3]> = colour_classes.iter().map(|c| c.colour).collect();
            let pixel_classes: Vec<u8> = largest
                .labels
                .iter()
                .zip(&largest.pixels)
                .map(|(&l, &p)| match l {
                    0 => 0,
                    u32::MAX => 1 + colour::nearest(&means, p) as u8,
                    k => 1 + category[first + k as usize - 1] as u8,
                })
                .collect();
            volume = copied(largest, pixel_classes, classes, opts)?
        }
        Detail::Residual => {
            // Sec. 4.3: the residual, in 3D, added to the mean colours.
            let residual = largest.residual();
            let detail = residual::synthesize(&residual, n, opts.seed);
            let gain = residual.gain;
            volume
                .voxels
                .par_iter_mut()
                .zip(&detail)
                .for_each(|(c, &l)| {
                    for k in 0..3 {
                        c[k] = (c[k] as f64 + gain[k] * l as f64).round().clamp(0.0, 255.0) as u8;
                    }
                });
        }
    }
    let detail_s = start.elapsed().as_secs_f64();
    let slices = slices::check(&volume, sections, opts.bins);
    progress.advance(1);
    let cut: usize = sections.iter().map(|s| s.cut).sum();
    let specks: usize = sections.iter().map(|s| s.specks).sum();
    let split = sections[0].split.clone();
    let warnings = warnings(sections, profiles.len(), cut, specks);
    Ok((
        volume,
        Report {
            size_distribution: dist,
            seed001,
            volume_fraction: fraction,
            block_volume_fraction: inside as f64 / (n * n * n) as f64,
            split,
            profiles: profiles.len(),
            cut_profiles: cut,
            specks,
            warnings,
            particles: particles.len(),
            overlap_fraction: overlap,
            colour_classes,
            slices,
            seconds: Seconds {
                unfold: unfold_s,
                place: place_s,
                colour: colour_s,
                detail: detail_s,
            },
        },
    ))
}

/// Specks per profile past which the particle class is suspect.
const SPECKS_PER_PROFILE: usize = 4;

/// What looks wrong in a measurement of `sections` with `profiles`
/// profiles, `cut` more cut by the frame and `specks` noise regions
/// (issue 38: a flipped class gave 68,000 "profiles" and no word), and
/// which photographs had nothing to measure.
fn warnings(sections: &[Section], profiles: usize, cut: usize, specks: usize) -> Vec<String> {
    let split = &sections[0].split;
    let mut out = Vec::new();
    if 2 * cut > profiles + cut {
        out.push(format!(
            "most particle profiles ({cut} of {}) touch the border or the mask and were left out: \
             the particles are large for these photographs, and the sizes rest on the {profiles} others",
            profiles + cut
        ));
    }
    // Specks are dropped as noise; a few per profile is noise on a
    // border, many more a class that is not particles.
    if specks > SPECKS_PER_PROFILE * profiles {
        out.push(format!(
            "{specks} specks under {} pixels against {profiles} profiles in the particle class: \
             the photographs are very noisy or the particles are the other class (--particles)",
            profiles::MIN_AREA
        ));
    }
    // After 3x3 means the noise is a third.
    let noise = split.noise / if split.smoothed { 3.0 } else { 1.0 };
    let apart = (0..3)
        .map(|k| (split.particle[k] - split.binder[k]).powi(2))
        .sum::<f64>()
        .sqrt();
    if apart < 3.0 * noise {
        out.push(format!(
            "particles and binder differ little in colour against the pixels' noise ({apart:.0} levels \
             apart, noise {noise:.0}{}): profiles may be merged or broken",
            if split.smoothed { " after 3x3 means" } else { "" }
        ));
    }
    let unmeasured: Vec<String> = sections
        .iter()
        .enumerate()
        .filter_map(|(k, s)| s.unmeasured().map(|why| format!("number {}: {why}", k + 1)))
        .collect();
    if !unmeasured.is_empty() {
        out.push(format!(
            "{} of the {} photographs (in the order given) show no particle profile to measure, \
             their area counted towards the volume fraction, not the sizes: {}",
            unmeasured.len(),
            sections.len(),
            unmeasured.join("; ")
        ));
    }
    out
}

/// The block synthesiser's copy of `section`'s pixels (of classes
/// `pixel_classes`) into the particles and binder laid out by `classes`
/// (0 binder, 1 + a particle's colour category).
fn copied(
    section: &Section,
    pixel_classes: Vec<u8>,
    classes: Vec<u8>,
    opts: &StereologyOptions,
) -> Result<Volume> {
    let window = detail_window(section, pixel_classes, opts.size);
    let exemplar = crate::synth::exemplar::Exemplar::new(
        window.width,
        window.height,
        window.pixels,
        window.valid,
    )?;
    // Binder against particles: their mean colours' difference, per
    // channel.
    let mut sum = [[0f64; 3]; 2];
    let mut count = [0f64; 2];
    for ((p, &c), &v) in exemplar
        .pixels
        .iter()
        .zip(&window.classes)
        .zip(&exemplar.valid)
    {
        if v {
            let c = (c != 0) as usize;
            count[c] += 1.0;
            for k in 0..3 {
                sum[c][k] += p[k] as f64;
            }
        }
    }
    let contrast = (0..3)
        .map(|k| (sum[0][k] / count[0].max(1.0) - sum[1][k] / count[1].max(1.0)).abs())
        .sum::<f64>()
        / 3.0;
    let guide = crate::synth::block::Guide {
        exemplar: window.classes,
        block: classes,
        weight: contrast.max(GUIDE_WEIGHT),
    };
    // As many pyramid levels as the size halves into, down to 16 a side.
    let (n, side) = (opts.size, window.width.min(window.height));
    let mut levels = 1;
    while n.is_multiple_of(1 << levels) && (n >> levels) >= 16 && (side >> levels) >= 16 {
        levels += 1;
    }
    let block_opts = crate::synth::block::BlockOptions {
        size: n,
        seed: opts.seed,
        levels: Some(levels),
        iterations: DETAIL_ITERATIONS,
        ..Default::default()
    };
    crate::synth::block::synthesize_guided(&exemplar, &guide, &block_opts, &crate::progress::Silent)
}

/// The pixels the detail copies from, and their classes.
struct Window {
    width: usize,
    height: usize,
    pixels: Vec<[u8; 3]>,
    valid: Vec<bool>,
    classes: Vec<u8>,
}

/// The part of `section` (with its pixels' `classes`) the detail copies
/// from: a window `DETAIL_WINDOW` times the block's side (at least 256
/// pixels), of nine placed on a 3x3 grid the one where the particles'
/// share of the pixels is nearest the photograph's. The block
/// synthesiser's time grows with its exemplar (issue 38: 96 s for 128^3
/// from a 2048x2048 photograph, 1.8x a 512 crop's), and a window wider
/// than the block's slices holds the neighbourhoods they can show.
fn detail_window(section: &Section, classes: Vec<u8>, n: usize) -> Window {
    let side = (DETAIL_WINDOW * n).max(256);
    let (w, h) = (section.width.min(side), section.height.min(side));
    let share = |x0: usize, y0: usize, w: usize, h: usize| {
        let (mut particles, mut usable) = (0usize, 0usize);
        for y in y0..y0 + h {
            let row = y * section.width + x0..y * section.width + x0 + w;
            for (&v, &c) in section.valid[row.clone()].iter().zip(&classes[row]) {
                usable += v as usize;
                particles += (v && c != 0) as usize;
            }
        }
        (particles as f64 / usable.max(1) as f64, usable)
    };
    let all = share(0, 0, section.width, section.height).0;
    let at = |k: usize, free: usize| k * free / 2;
    let windows: Vec<((usize, usize), (f64, usize))> = (0..9)
        .map(|k| (at(k % 3, section.width - w), at(k / 3, section.height - h)))
        .map(|(x, y)| ((x, y), share(x, y, w, h)))
        .collect();
    // Of the windows at least half as usable as the most usable one.
    let most = windows.iter().map(|w| w.1.1).max().unwrap_or(0);
    let (x0, y0) = windows
        .iter()
        .filter(|w| 2 * w.1.1 >= most)
        .min_by(|a, b| (a.1.0 - all).abs().total_cmp(&(b.1.0 - all).abs()))
        .expect("the most usable window")
        .0;
    let at = |i: usize| (y0 + i / w) * section.width + x0 + i % w;
    Window {
        width: w,
        height: h,
        pixels: (0..w * h).map(|i| section.pixels[at(i)]).collect(),
        valid: (0..w * h).map(|i| section.valid[at(i)]).collect(),
        classes: (0..w * h).map(|i| classes[at(i)]).collect(),
    }
}

/// The voxels: each inside a particle its colour (the later of two
/// overlapping ones), the rest the binder's; the box wraps. Also each
/// voxel's class: 0 binder, 1 + the particle's category.
fn render(
    ps: &[place::Particle],
    category: &[usize],
    colours: &[[u8; 3]],
    binder: [u8; 3],
    n: usize,
) -> (Volume, Vec<u8>) {
    // Per z slab, in parallel: which particle covers each voxel (the
    // highest index wins, as if painted in order).
    let side = n as f64;
    let owner: Vec<Vec<u32>> = (0..n)
        .into_par_iter()
        .map(|z| {
            let mut slab = vec![u32::MAX; n * n];
            let zc = z as f64 + 0.5;
            for (k, p) in ps.iter().enumerate() {
                let dz = {
                    let d = zc - p.centre.z;
                    d - (d / side).round() * side
                };
                let reach = p.reach();
                if dz.abs() >= reach {
                    continue;
                }
                let r2 = reach * reach - dz * dz;
                let r = r2.sqrt();
                let (x0, x1) = (
                    (p.centre.x - r).floor() as i64,
                    (p.centre.x + r).ceil() as i64,
                );
                let (y0, y1) = (
                    (p.centre.y - r).floor() as i64,
                    (p.centre.y + r).ceil() as i64,
                );
                for y in y0..=y1 {
                    let dy = y as f64 + 0.5 - p.centre.y;
                    for x in x0..=x1 {
                        let dx = x as f64 + 0.5 - p.centre.x;
                        if p.contains(glam::DVec3::new(dx, dy, dz)) {
                            let (xw, yw) = (
                                x.rem_euclid(n as i64) as usize,
                                y.rem_euclid(n as i64) as usize,
                            );
                            slab[yw * n + xw] = k as u32;
                        }
                    }
                }
            }
            slab
        })
        .collect();
    let owner: Vec<u32> = owner.into_iter().flatten().collect();
    let voxels = owner
        .iter()
        .map(|&k| {
            if k == u32::MAX {
                binder
            } else {
                colours[k as usize]
            }
        })
        .collect();
    let classes = owner
        .iter()
        .map(|&k| {
            if k == u32::MAX {
                0
            } else {
                1 + category[k as usize] as u8
            }
        })
        .collect();
    (
        Volume {
            size: [n; 3],
            spacing: 1.0,
            voxels,
        },
        classes,
    )
}

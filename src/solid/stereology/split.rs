//! Particles and binder: the two colour classes of the section
//! photographs, one split for all of them (seed 001, sec. 3: the sections
//! are thresholded into the two phases before profiles are measured).
//!
//! Issue 38 found the per-photograph k-means of before flipping: at low
//! contrast under pixel noise, k-means (equal spreads, hard assignment)
//! splits the large binder class in two, and the "minority" it then calls
//! particles is noise. So:
//! - the classes are found once, on a sample pooled from every
//!   photograph, by Kittler and Illingworth's minimum-error threshold
//!   (two Gaussians of their own weight and spread) along the axis
//!   joining the classes' means, which a 92/8 mixture does not fool;
//! - where pixel noise blurs the classes (their distance under
//!   `SMOOTH_BELOW` times the noise, measured between neighbouring
//!   pixels, so particles of several colours do not count as noise),
//!   pixels are classed on their 3x3 mean, which cuts the noise
//!   threefold; pixels go to the nearer class mean, the midpoint between
//!   them, so a blurred straight border stays where it was;
//! - which class is the particles is decided by connectivity across up
//!   to `STATISTICS_PHOTOS` photographs, evenly spaced (the binder is the
//!   continuous phase: its largest region holds most of it, the
//!   particles' largest one little), else by area (the minority), else
//!   the user is asked (`Particles`).

use rayon::prelude::*;

use super::watershed::{component_sizes, components};
use crate::error::{Error, Result};
use crate::rng;

/// Classes closer than this many spreads (per pixel, along the axis
/// between them) are classed on 3x3 means: at 6 a pixel is misclassed
/// about once in 10^3 (a speck per 30x30 pixels), noise the profiles
/// would count.
const SMOOTH_BELOW: f64 = 6.0;
/// Samples per photograph for the pooled threshold.
const SAMPLES: usize = 16384;
/// The connectivity and the classes' interior colours are measured on at
/// most this many photographs, evenly spaced (each of 2048x2048 pixels
/// has thousands of regions of each class).
const STATISTICS_PHOTOS: usize = 4;
/// Histogram bins along the axis.
const BINS: usize = 256;
/// Connectivity decides when the binder's largest-region share exceeds
/// the particles' by this much.
const DECISIVE: f64 = 0.25;
/// Area decides (the minority are particles) below this share.
const MINORITY: f64 = 0.4;

/// Which colour class the particles are (`--particles`; `particles` in a
/// scene's `[node.interior]`).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(try_from = "String", into = "String")]
pub enum Particles {
    /// Decided from the photographs: connectivity, else area.
    #[default]
    Auto,
    Light,
    Dark,
    /// The class nearer this colour.
    Colour([u8; 3]),
}

impl std::str::FromStr for Particles {
    type Err = String;

    fn from_str(s: &str) -> std::result::Result<Particles, String> {
        match s {
            "auto" => Ok(Particles::Auto),
            "light" => Ok(Particles::Light),
            "dark" => Ok(Particles::Dark),
            _ => {
                let hex = s.trim_start_matches('#');
                if hex.len() == 6 && hex.chars().all(|c| c.is_ascii_hexdigit()) {
                    let c = |k: usize| u8::from_str_radix(&hex[k..k + 2], 16).expect("hex digits");
                    Ok(Particles::Colour([c(0), c(2), c(4)]))
                } else {
                    Err(format!(
                        "the particles are auto, light, dark or a colour RRGGBB, not {s:?}"
                    ))
                }
            }
        }
    }
}

impl Particles {
    pub fn is_auto(&self) -> bool {
        *self == Particles::Auto
    }
}

impl TryFrom<String> for Particles {
    type Error = String;

    fn try_from(s: String) -> std::result::Result<Particles, String> {
        s.parse()
    }
}

impl From<Particles> for String {
    fn from(p: Particles) -> String {
        match p {
            Particles::Auto => "auto".into(),
            Particles::Light => "light".into(),
            Particles::Dark => "dark".into(),
            Particles::Colour(c) => c.iter().map(|x| format!("{x:02x}")).collect(),
        }
    }
}

/// A photograph to split: its pixels row by row and which are usable.
#[derive(Clone, Copy)]
pub struct Photo<'a> {
    pub width: usize,
    pub height: usize,
    pub pixels: &'a [[u8; 3]],
    pub valid: &'a [bool],
}

/// The split every photograph (and the block's slices) is classed by.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Split {
    /// Mean colours of the particle and binder classes: of their interior
    /// pixels (all 3x3 neighbours of the class; 3x3 means where
    /// `smoothed`), the threshold's class means where a class has none.
    pub particle: [f64; 3],
    pub binder: [f64; 3],
    /// Distance between the threshold's class means over their spread,
    /// per pixel (before the interior means).
    pub separation: f64,
    /// Pixel noise along the axis between the class means (grey levels;
    /// from the differences of neighbouring pixels, median based).
    pub noise: f64,
    /// Pixels classed on their 3x3 mean (the classes overlap per pixel).
    pub smoothed: bool,
    /// How the particle class was chosen: "connectivity", "minority",
    /// or the user's "light", "dark", "colour".
    pub decided_by: &'static str,
    /// Of each class's pixels, the share in its largest 4-connected
    /// region per photograph (summed over the statistics photographs):
    /// the binder's near 1.
    pub largest_region_share: ParticleBinder,
    /// The particle class's share of the statistics photographs' usable
    /// pixels, by the threshold's means and before specks are dropped.
    pub particle_share: f64,
}

#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct ParticleBinder {
    pub particles: f64,
    pub binder: f64,
}

impl Split {
    /// Per pixel of `photo`, whether it is of the particle class
    /// (unusable pixels false).
    pub fn classify(&self, photo: Photo) -> Vec<bool> {
        self.classify_colours(&colours(photo, self.smoothed), photo.valid)
    }

    fn classify_colours(&self, colours: &[[f32; 3]], valid: &[bool]) -> Vec<bool> {
        let dist =
            |a: [f32; 3], b: [f64; 3]| (0..3).map(|k| (a[k] as f64 - b[k]).powi(2)).sum::<f64>();
        colours
            .iter()
            .zip(valid)
            .map(|(&c, &v)| v && dist(c, self.particle) < dist(c, self.binder))
            .collect()
    }
}

/// The split of `photos`, the particle class chosen as `particles` asks.
pub fn split(photos: &[Photo], particles: Particles, seed: u64) -> Result<Split> {
    // The same pixels sampled whether smoothed or not.
    let positions: Vec<Vec<usize>> = photos
        .iter()
        .enumerate()
        .map(|(p, photo)| {
            let usable: Vec<usize> = (0..photo.pixels.len())
                .filter(|&i| photo.valid[i])
                .collect();
            if usable.is_empty() {
                return usable;
            }
            (0..SAMPLES.min(usable.len()))
                .map(|k| usable[rng::below(seed, &[p as u64, k as u64], usable.len())])
                .collect()
        })
        .collect();
    let sample = |smoothed: bool| -> Vec<[f64; 3]> {
        photos
            .par_iter()
            .zip(&positions)
            .flat_map_iter(|(photo, at)| {
                at.iter()
                    .map(|&i| colour_at(*photo, smoothed, i).map(|x| x as f64))
                    .collect::<Vec<_>>()
            })
            .collect()
    };
    let raw = sample(false);
    if raw.len() < 16 {
        return Err(Error::invalid("the sections have almost no usable pixels"));
    }
    let (mut means, mut separation) = threshold(&raw).ok_or_else(one_colour)?;
    let noise = pixel_noise(photos, &positions, means);
    let smoothed = distance(means) < SMOOTH_BELOW * noise;
    if smoothed {
        (means, separation) = threshold(&sample(true)).ok_or_else(one_colour)?;
    }
    let candidate = Split {
        particle: means[0],
        binder: means[1],
        separation,
        noise,
        smoothed,
        decided_by: "",
        largest_region_share: ParticleBinder {
            particles: 0.0,
            binder: 0.0,
        },
        particle_share: 0.0,
    };
    // Per class (0 the first mean's, 1 the second's), over up to
    // STATISTICS_PHOTOS photographs: pixels, pixels in each one's largest
    // region (summed), and the colours of its
    // interior pixels (all 3x3 neighbours of the class) summed and
    // counted. The means the classes are told apart by are the interior
    // ones: a class mean taken over every pixel of the class includes its
    // blurred border, which pulls the small class's mean toward the large
    // one's and the midpoint with it (+3% of area on issue 38's noisy
    // sections).
    // Measured in parallel, summed in order: the same bytes on any number
    // of threads.
    let counts = photos
        .par_iter()
        .step_by(photos.len().div_ceil(STATISTICS_PHOTOS))
        .map(|&photo| {
            let c = colours(photo, smoothed);
            let first = candidate.classify_colours(&c, photo.valid);
            let mut out = ClassCounts::default();
            for class in 0..2 {
                let inside = |i: usize| first[i] == (class == 0);
                let (label, _) = components(photo.width, photo.height, photo.valid, &inside);
                let sizes = component_sizes(&label);
                out.pixels[class] = sizes.iter().sum();
                out.largest[class] = sizes.iter().copied().max().unwrap_or(0);
            }
            let (w, h) = (photo.width, photo.height);
            for y in 1..h.saturating_sub(1) {
                for x in 1..w - 1 {
                    let i = y * w + x;
                    let k = first[i];
                    let same = (y - 1..=y + 1).all(|yy| {
                        (x - 1..=x + 1)
                            .all(|xx| photo.valid[yy * w + xx] && first[yy * w + xx] == k)
                    });
                    if same {
                        let class = (!k) as usize;
                        out.interior[class] += 1.0;
                        for (s, &x) in out.colour[class].iter_mut().zip(&c[i]) {
                            *s += x as f64;
                        }
                    }
                }
            }
            out
        })
        .collect::<Vec<_>>()
        .into_iter()
        .fold(ClassCounts::default(), ClassCounts::add);
    for ((mean, colour), &n) in means.iter_mut().zip(&counts.colour).zip(&counts.interior) {
        if n > 0.0 {
            *mean = colour.map(|s| s / n);
        }
    }
    let share = [0, 1].map(|c| counts.largest[c] as f64 / counts.pixels[c].max(1) as f64);
    let area = counts.pixels[0] as f64 / (counts.pixels[0] + counts.pixels[1]).max(1) as f64;
    let lum = |c: [f64; 3]| c[0] + c[1] + c[2];
    let dist = |a: [f64; 3], b: [u8; 3]| (0..3).map(|k| (a[k] - b[k] as f64).powi(2)).sum::<f64>();
    // Whether the first class is the particles, and what said so.
    let (first, decided_by) = match particles {
        Particles::Light => (lum(means[0]) > lum(means[1]), "light"),
        Particles::Dark => (lum(means[0]) < lum(means[1]), "dark"),
        Particles::Colour(c) => (dist(means[0], c) < dist(means[1], c), "colour"),
        Particles::Auto if (share[0] - share[1]).abs() >= DECISIVE => {
            (share[0] < share[1], "connectivity")
        }
        Particles::Auto if area.min(1.0 - area) <= MINORITY => (area < 0.5, "minority"),
        Particles::Auto => {
            let names = if lum(means[0]) > lum(means[1]) {
                ["light", "dark"]
            } else {
                ["dark", "light"]
            };
            return Err(Error::invalid(format!(
                "cannot tell the particles from the binder: the {} class (mean colour {}) and the {} \
                 class ({}) cover {:.0}% and {:.0}% of the photographs measured, and their largest \
                 regions hold {:.0}% and {:.0}% of each (the binder is usually the one connected \
                 phase); give --particles light, dark or a colour RRGGBB (in a scene, particles = \
                 \"light\" in [node.interior])",
                names[0],
                hex(means[0]),
                names[1],
                hex(means[1]),
                100.0 * area,
                100.0 * (1.0 - area),
                100.0 * share[0],
                100.0 * share[1]
            )));
        }
    };
    let (p, b) = if first { (0, 1) } else { (1, 0) };
    Ok(Split {
        particle: means[p],
        binder: means[b],
        separation,
        noise,
        smoothed,
        decided_by,
        largest_region_share: ParticleBinder {
            particles: share[p],
            binder: share[b],
        },
        particle_share: if first { area } else { 1.0 - area },
    })
}

/// Per class: pixels, pixels of the largest region, interior pixels and
/// their colours' sum.
#[derive(Clone, Copy, Default)]
struct ClassCounts {
    pixels: [usize; 2],
    largest: [usize; 2],
    interior: [f64; 2],
    colour: [[f64; 3]; 2],
}

impl ClassCounts {
    fn add(self, o: ClassCounts) -> ClassCounts {
        ClassCounts {
            pixels: [0, 1].map(|c| self.pixels[c] + o.pixels[c]),
            largest: [0, 1].map(|c| self.largest[c] + o.largest[c]),
            interior: [0, 1].map(|c| self.interior[c] + o.interior[c]),
            colour: [0, 1].map(|c| [0, 1, 2].map(|a| self.colour[c][a] + o.colour[c][a])),
        }
    }
}

fn distance(means: [[f64; 3]; 2]) -> f64 {
    let d = sub(means[1], means[0]);
    dot(d, d).sqrt()
}

/// The pixels' noise along the axis between `means`: the median of the
/// differences between sampled pixels and their right-hand neighbours,
/// taken to a Gaussian's deviation (most neighbours are of one region, so
/// what differs between them is noise).
fn pixel_noise(photos: &[Photo], positions: &[Vec<usize>], means: [[f64; 3]; 2]) -> f64 {
    let axis = sub(means[1], means[0]).map(|x| x / distance(means).max(1e-9));
    let mut diffs: Vec<f64> = photos
        .iter()
        .zip(positions)
        .flat_map(|(photo, at)| {
            at.iter().filter_map(move |&i| {
                let j = i + 1;
                (j % photo.width != 0 && photo.valid[j]).then(|| {
                    let d =
                        [0, 1, 2].map(|k| photo.pixels[j][k] as f64 - photo.pixels[i][k] as f64);
                    dot(d, axis).abs()
                })
            })
        })
        .collect();
    if diffs.is_empty() {
        return 0.0;
    }
    let mid = diffs.len() / 2;
    let median = *diffs.select_nth_unstable_by(mid, f64::total_cmp).1;
    // |X - Y| of two N(0, s^2) has median 0.6745 sqrt(2) s.
    median / (0.6745 * 2f64.sqrt())
}

fn one_colour() -> Error {
    Error::invalid(
        "no particles found: the sections are one colour, or one colour class is under 0.2% of them",
    )
}

/// A colour as RRGGBB.
pub fn hex(c: [f64; 3]) -> String {
    c.iter()
        .map(|&x| format!("{:02x}", x.round().clamp(0.0, 255.0) as u8))
        .collect()
}

/// The photograph's colours, or with `smoothed` each pixel's mean over
/// its usable 3x3 neighbours.
fn colours(photo: Photo, smoothed: bool) -> Vec<[f32; 3]> {
    let as_f32 = |p: [u8; 3]| p.map(|c| c as f32);
    if !smoothed {
        return photo.pixels.iter().map(|&p| as_f32(p)).collect();
    }
    (0..photo.width * photo.height)
        .into_par_iter()
        .map(|i| colour_at(photo, true, i))
        .collect()
}

/// Pixel `i`'s colour, or with `smoothed` its mean over its usable 3x3
/// neighbours.
fn colour_at(photo: Photo, smoothed: bool, i: usize) -> [f32; 3] {
    if !smoothed {
        return photo.pixels[i].map(|c| c as f32);
    }
    let (w, h) = (photo.width, photo.height);
    let (x, y) = (i % w, i / w);
    let (mut sum, mut n) = ([0f32; 3], 0f32);
    for yy in y.saturating_sub(1)..(y + 2).min(h) {
        for xx in x.saturating_sub(1)..(x + 2).min(w) {
            let j = yy * w + xx;
            if photo.valid[j] {
                for (s, &x) in sum.iter_mut().zip(&photo.pixels[j]) {
                    *s += x as f32;
                }
                n += 1.0;
            }
        }
    }
    sum.map(|s| s / n.max(1.0))
}

/// The two classes' means of `sample`, and their separation (distance
/// over spread): Kittler and Illingworth's minimum-error threshold of the
/// projections on an axis, the axis then the one joining the two means,
/// three times. None when the sample is one colour.
fn threshold(sample: &[[f64; 3]]) -> Option<([[f64; 3]; 2], f64)> {
    let mut axis = principal_axis(sample)?;
    let mut result = None;
    for _ in 0..3 {
        let proj: Vec<f64> = sample.iter().map(|c| dot(*c, axis)).collect();
        let (lo, hi) = proj
            .iter()
            .fold((f64::MAX, f64::MIN), |(a, b), &p| (a.min(p), b.max(p)));
        if hi - lo < 1e-9 {
            return None;
        }
        let width = (hi - lo) / BINS as f64;
        let bin = |p: f64| (((p - lo) / width) as usize).min(BINS - 1);
        let mut hist = [0f64; BINS];
        for &p in &proj {
            hist[bin(p)] += 1.0;
        }
        let t = minimum_error(&hist)?;
        let mut sum = [[0f64; 3]; 2];
        let mut count = [0f64; 2];
        for (c, &p) in sample.iter().zip(&proj) {
            let k = (bin(p) > t) as usize;
            count[k] += 1.0;
            for a in 0..3 {
                sum[k][a] += c[a];
            }
        }
        let means = [0, 1].map(|k| sum[k].map(|s| s / count[k]));
        let between = sub(means[1], means[0]);
        let length = dot(between, between).sqrt();
        if length < 1e-9 {
            return None;
        }
        axis = between.map(|x| x / length);
        // Spread along the new axis, each class about its own mean.
        let mut var = [0f64; 2];
        for (c, &p) in sample.iter().zip(&proj) {
            let k = (bin(p) > t) as usize;
            var[k] += dot(sub(*c, means[k]), axis).powi(2);
        }
        let spread = ((var[0] / count[0] + var[1] / count[1]) / 2.0).sqrt();
        result = Some((means, length / spread.max(1e-9)));
    }
    result
}

/// The bin after which a histogram is split, minimising Kittler and
/// Illingworth's criterion P1 ln(s1/P1) + P2 ln(s2/P2) over splits
/// leaving each side at least 0.2% of the counts and some spread.
fn minimum_error(hist: &[f64]) -> Option<usize> {
    let total: f64 = hist.iter().sum();
    let (mut n, mut s, mut s2) = (0.0, 0.0, 0.0);
    let (all_s, all_s2) = hist.iter().enumerate().fold((0.0, 0.0), |(a, b), (i, &h)| {
        (a + h * i as f64, b + h * (i * i) as f64)
    });
    let mut best: Option<(f64, usize)> = None;
    for (t, &h) in hist.iter().enumerate().take(hist.len() - 1) {
        n += h;
        s += h * t as f64;
        s2 += h * (t * t) as f64;
        let m = total - n;
        if n < 0.002 * total || m < 0.002 * total {
            continue;
        }
        let v1 = s2 / n - (s / n).powi(2);
        let v2 = (all_s2 - s2) / m - ((all_s - s) / m).powi(2);
        // A spread under a quarter bin is the histogram's resolution.
        let (v1, v2) = (v1.max(1.0 / 16.0), v2.max(1.0 / 16.0));
        let (p1, p2) = (n / total, m / total);
        let j = p1 * (0.5 * v1.ln() - p1.ln()) + p2 * (0.5 * v2.ln() - p2.ln());
        if best.is_none_or(|b| j < b.0) {
            best = Some((j, t));
        }
    }
    best.map(|b| b.1)
}

/// The direction of largest spread of `sample` (power iteration on the
/// covariance from its longest row, which no axis of spread is
/// orthogonal to, unlike a fixed start such as grey; deterministic).
fn principal_axis(sample: &[[f64; 3]]) -> Option<[f64; 3]> {
    let n = sample.len() as f64;
    let mean = [0, 1, 2].map(|k| sample.iter().map(|c| c[k]).sum::<f64>() / n);
    let mut cov = [[0f64; 3]; 3];
    for c in sample {
        let d = sub(*c, mean);
        for i in 0..3 {
            for j in 0..3 {
                cov[i][j] += d[i] * d[j] / n;
            }
        }
    }
    let mut v = *cov
        .iter()
        .max_by(|a, b| dot(**a, **a).total_cmp(&dot(**b, **b)))
        .expect("three rows");
    for _ in 0..50 {
        let next = [0, 1, 2].map(|i| dot(cov[i], v));
        let length = dot(next, next).sqrt();
        if length < 1e-12 {
            return None;
        }
        v = next.map(|x| x / length);
    }
    Some(v)
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A square photograph, colour `a` where `is_a(x, y)` holds, else `b`.
    fn two_colours(
        side: usize,
        is_a: impl Fn(f64, f64) -> bool,
        a: [u8; 3],
        b: [u8; 3],
    ) -> Vec<[u8; 3]> {
        (0..side * side)
            .map(|i| {
                let (x, y) = ((i % side) as f64, (i / side) as f64);
                if is_a(x, y) { a } else { b }
            })
            .collect()
    }

    fn square<'a>(side: usize, pixels: &'a [[u8; 3]], valid: &'a [bool]) -> Photo<'a> {
        Photo {
            width: side,
            height: side,
            pixels,
            valid,
        }
    }

    /// Light discs (a quarter of the area) in a dark binder of nearly the same
    /// colour under strong noise: the per-photograph k-means of before
    /// split the binder and took its noise for particles.
    fn noisy(side: usize, noise: f64, seed: u64) -> Vec<[u8; 3]> {
        let (light, dark) = ([190.0, 150.0, 160.0], [150.0, 110.0, 120.0]);
        (0..side * side)
            .map(|i| {
                let (x, y) = ((i % side) as f64, (i / side) as f64);
                let disc = ((x % 32.0 - 16.0).powi(2) + (y % 32.0 - 16.0).powi(2)) < 81.0;
                let base = if disc { light } else { dark };
                [0, 1, 2].map(|k| {
                    let n = rng::normal(seed, &[i as u64, k as u64]);
                    (base[k] + noise * n).round().clamp(0.0, 255.0) as u8
                })
            })
            .collect()
    }

    #[test]
    fn noisy_low_contrast_sections_split_into_particles_and_binder() {
        let side = 256;
        let pixels = noisy(side, 25.0, 1);
        let valid = vec![true; side * side];
        let photo = square(side, &pixels, &valid);
        let s = split(&[photo], Particles::Auto, 0).expect("a split");
        assert!(s.smoothed, "{s:?}");
        assert_eq!(s.decided_by, "connectivity");
        assert!(s.particle[0] > s.binder[0] + 25.0, "{s:?}");
        // The discs cover 81 pi / 32^2 = 24.9% of the area.
        let found = s.classify(photo).iter().filter(|&&p| p).count() as f64 / (side * side) as f64;
        assert!((found - 0.2485).abs() < 0.02, "{found}");
        // Asked for, the other class.
        let dark = split(&[photo], Particles::Dark, 0).expect("a split");
        assert_eq!((dark.particle, dark.binder), (s.binder, s.particle));
        let near = split(&[photo], Particles::Colour([200, 150, 160]), 0).expect("a split");
        assert_eq!(near.particle, s.particle);
    }

    #[test]
    fn stripes_are_refused_as_ambiguous() {
        // Stripes: each class half the area, in as many equal regions.
        let side = 64;
        let pixels = two_colours(
            side,
            |x, _| (x as usize / 8).is_multiple_of(2),
            [40; 3],
            [200; 3],
        );
        let valid = vec![true; side * side];
        let photo = square(side, &pixels, &valid);
        let err = split(&[photo], Particles::Auto, 0).expect_err("ambiguous");
        assert!(err.to_string().contains("--particles"), "{err}");
        let light = split(&[photo], Particles::Light, 0).expect("asked");
        assert!(light.particle[0] > 150.0);
    }

    #[test]
    fn classes_of_equal_luminance_split() {
        // Red discs on green: no spread along grey at all.
        let side = 64;
        let disc = |x: f64, y: f64| (x % 16.0 - 8.0).powi(2) + (y % 16.0 - 8.0).powi(2) < 16.0;
        let pixels = two_colours(side, disc, [200, 100, 100], [100, 200, 100]);
        let valid = vec![true; side * side];
        let photo = square(side, &pixels, &valid);
        let s = split(&[photo], Particles::Auto, 0).expect("a split");
        assert_eq!(s.particle.map(|c| c.round()), [200.0, 100.0, 100.0]);
        assert_eq!(s.decided_by, "connectivity");
    }

    #[test]
    fn particles_parse() {
        assert_eq!("light".parse::<Particles>(), Ok(Particles::Light));
        assert_eq!(
            "#ff8000".parse::<Particles>(),
            Ok(Particles::Colour([255, 128, 0]))
        );
        assert!("pink".parse::<Particles>().is_err());
        // As a scene stores it and reads it back.
        for p in [
            Particles::Auto,
            Particles::Dark,
            Particles::Colour([255, 128, 0]),
        ] {
            let text = serde_json::to_string(&p).expect("serialises");
            assert_eq!(serde_json::from_str::<Particles>(&text).expect("parses"), p);
        }
    }
}

//! Particle profiles in a photograph of a section (seed 001, sec. 3-4):
//! pixels classed as particles or binder by the photographs' `split`,
//! the particle class's 4-connected components the profiles (specks under
//! `MIN_AREA` pixels are noise, given to the binder), with the binder
//! regions each one encloses (a gland's lumen inside its epithelium, or
//! noise) filled in, and those of touching particles split at their
//! necks (`watershed`). A profile touching the image's
//! border or the mask is cut by the frame, so it is left out and the
//! others weighted for it (Miles-Lantuejoul: a profile of bounding box
//! w x h is wholly seen only when its box falls inside the frame, a chance
//! of (W - w)(H - h) / WH).

use super::split::{self, Particles, Photo, Split};
use super::watershed::{component_sizes, components, four_neighbours};
use rayon::prelude::*;

use crate::error::{Error, Result};

/// Profiles smaller than this many pixels are noise, not particles.
pub const MIN_AREA: usize = 9;

#[derive(Clone, Debug, PartialEq)]
pub struct Profile {
    /// Pixels.
    pub area: f64,
    /// The diameter of the disc of that area, 2 sqrt(A / pi).
    pub diameter: f64,
    /// Mean colour, 0-255.
    pub colour: [f64; 3],
    /// Border correction (1 for a profile far from the frame).
    pub weight: f64,
}

/// What a section shows.
#[derive(Clone, Debug)]
pub struct Section {
    pub width: usize,
    pub height: usize,
    /// Profiles wholly inside the frame.
    pub profiles: Vec<Profile>,
    /// Profiles left out for touching the border or the mask.
    pub cut: usize,
    /// Particle-class regions under `MIN_AREA` pixels, given to the
    /// binder as noise.
    pub specks: usize,
    /// Usable (unmasked) pixels.
    pub area: f64,
    /// Particle pixels over usable pixels: the volume fraction (Delesse).
    pub area_fraction: f64,
    pub binder_colour: [f64; 3],
    /// Per pixel: 0 binder or masked, k + 1 profile k, u32::MAX a cut one.
    pub labels: Vec<u32>,
    /// The photograph and its usable pixels, for the block synthesiser.
    pub pixels: Vec<[u8; 3]>,
    pub valid: Vec<bool>,
    /// The particle and binder classes it was measured by (the same for
    /// every photograph of a study, and for the block's slices).
    pub split: Split,
}

impl Section {
    /// Why the section has no profile to measure; None when it has.
    pub fn unmeasured(&self) -> Option<String> {
        if !self.profiles.is_empty() {
            return None;
        }
        Some(if self.cut > 0 {
            format!(
                "every one of the {} particle profiles found touches the border or the mask: none can be measured",
                self.cut
            )
        } else if self.specks > 0 || self.area_fraction > 0.0 {
            format!("no particles found: no profile of {MIN_AREA} pixels or more")
        } else {
            "no particles found: the split of all the photographs leaves this one all binder"
                .to_string()
        })
    }

    /// The photograph less its profiles' and binder's mean colours (seed
    /// 001, 4.3), for the fine detail.
    pub fn residual(&self) -> super::residual::Residual2d {
        let means: Vec<Option<[f64; 3]>> = (0..self.pixels.len())
            .map(|i| match self.labels[i] {
                _ if !self.valid[i] => None,
                0 => Some(self.binder_colour),
                u32::MAX => None,
                k => Some(self.profiles[k as usize - 1].colour),
            })
            .collect();
        super::residual::Residual2d::new(
            self.width,
            self.height,
            &super::residual::residual(&self.pixels, &means),
        )
    }
}

/// Find the profiles of `pixels` (row by row), `valid` the usable ones,
/// split into particles and binder on their own.
pub fn find(
    width: usize,
    height: usize,
    pixels: &[[u8; 3]],
    valid: &[bool],
    seed: u64,
) -> Result<Section> {
    let photo = Photo {
        width,
        height,
        pixels,
        valid,
    };
    let mut sections = sections_of(&[photo], Particles::Auto, seed, &|e, _| e)?;
    Ok(sections.pop().expect("one photograph, one section"))
}

/// The sections `photos` show, all split into particles and binder alike
/// (`split`), the particle class as `particles` asks. A photograph with
/// no profile to measure is a section all the same (`synthesize` warns
/// of it); a study where none has one is refused. Errors go through
/// `attribute` with the photograph they concern (None: the study's).
pub fn sections_of(
    photos: &[split::Photo],
    particles: Particles,
    seed: u64,
    attribute: &(dyn Fn(Error, Option<usize>) -> Error + Sync),
) -> Result<Vec<Section>> {
    let split = split::split(photos, particles, seed).map_err(|e| attribute(e, None))?;
    let sections: Vec<Section> = photos
        .par_iter()
        .enumerate()
        .map(|(k, &photo)| find_with(photo, &split).map_err(|e| attribute(e, Some(k))))
        .collect::<Result<_>>()?;
    if let Some(why) = sections
        .iter()
        .map(Section::unmeasured)
        .collect::<Option<Vec<_>>>()
    {
        let first = &why[0];
        let msg = if photos.len() > 1 {
            format!("none of the photographs has a profile to measure; the first: {first}")
        } else {
            first.clone()
        };
        return Err(attribute(Error::invalid(msg), Some(0)));
    }
    Ok(sections)
}

/// Find the profiles of `photo`, classed by `split`. A photograph with
/// none to measure is a section all the same (`Section::unmeasured`
/// says why): in a study of several its area still counts towards the
/// volume fraction.
pub fn find_with(photo: Photo, split: &Split) -> Result<Section> {
    let Photo {
        width,
        height,
        pixels,
        valid,
    } = photo;
    let usable: Vec<usize> = (0..pixels.len()).filter(|&i| valid[i]).collect();
    if usable.len() < 16 {
        return Err(Error::invalid("the section has almost no usable pixels"));
    }
    let mut particle = split.classify(photo);
    // Particle components, specks among them (under MIN_AREA pixels:
    // noise) given to the binder; then binder components: a binder region
    // that one particle component encloses (a gland's lumen inside its
    // epithelium) is part of that particle.
    let (mut comp, _) = components(width, height, valid, &|i| particle[i]);
    let sizes = component_sizes(&comp);
    let specks = sizes.iter().filter(|&&n| n < MIN_AREA).count();
    for (p, c) in particle.iter_mut().zip(&mut comp) {
        if *c != 0 && sizes[*c as usize - 1] < MIN_AREA {
            (*p, *c) = (false, 0);
        }
    }
    let (binder, binder_touches) = components(width, height, valid, &|i| !particle[i]);
    let mut enclosing = vec![None; binder_touches.len()];
    let mut shared = vec![false; binder_touches.len()];
    for (i, &b) in binder.iter().enumerate() {
        if b == 0 {
            continue;
        }
        for j in four_neighbours(i, width, height).into_iter().flatten() {
            let c = comp[j];
            if c == 0 {
                continue;
            }
            match enclosing[b as usize - 1] {
                None => enclosing[b as usize - 1] = Some(c),
                Some(e) if e != c => shared[b as usize - 1] = true,
                _ => {}
            }
        }
    }
    for (i, &b) in binder.iter().enumerate() {
        if b != 0
            && !binder_touches[b as usize - 1]
            && !shared[b as usize - 1]
            && let Some(c) = enclosing[b as usize - 1]
        {
            comp[i] = c;
        }
    }
    let is_particle: Vec<bool> = comp.iter().map(|&c| c != 0).collect();
    // Touching particles' profiles split at their necks.
    let (comp, touches) = super::watershed::split(width, height, valid, &is_particle);
    // Per component: pixels, colour, bounding box.
    let count = touches.len();
    let mut area = vec![0usize; count];
    let mut colour = vec![[0f64; 3]; count];
    let mut bbox = vec![[usize::MAX, 0, usize::MAX, 0]; count];
    for i in 0..pixels.len() {
        let c = comp[i];
        if c == 0 {
            continue;
        }
        let k = c as usize - 1;
        area[k] += 1;
        for (s, &p) in colour[k].iter_mut().zip(&pixels[i]) {
            *s += p as f64;
        }
        let (x, y) = (i % width, i / width);
        let b = &mut bbox[k];
        *b = [b[0].min(x), b[1].max(x), b[2].min(y), b[3].max(y)];
    }
    let mut profiles = Vec::new();
    let mut cut = 0;
    let mut label_of = vec![u32::MAX; count];
    for k in 0..count {
        if touches[k] {
            cut += 1;
            continue;
        }
        if area[k] < MIN_AREA {
            continue;
        }
        let a = area[k] as f64;
        let (bw, bh) = (
            (bbox[k][1] - bbox[k][0] + 1) as f64,
            (bbox[k][3] - bbox[k][2] + 1) as f64,
        );
        let (w, h) = (width as f64, height as f64);
        let seen = ((w - bw) * (h - bh) / (w * h)).max(1e-3);
        profiles.push(Profile {
            area: a,
            diameter: 2.0 * (a / std::f64::consts::PI).sqrt(),
            colour: colour[k].map(|c| c / a),
            weight: 1.0 / seen,
        });
        label_of[k] = profiles.len() as u32;
    }
    let labels: Vec<u32> = comp
        .iter()
        .map(|&c| if c == 0 { 0 } else { label_of[c as usize - 1] })
        .collect();
    let n_particle = usable.iter().filter(|&&i| is_particle[i]).count();
    let mut binder = [0f64; 3];
    let mut n_binder = 0usize;
    for &i in &usable {
        if !is_particle[i] {
            for (b, &p) in binder.iter_mut().zip(&pixels[i]) {
                *b += p as f64;
            }
            n_binder += 1;
        }
    }
    let binder_colour = binder.map(|b| b / n_binder.max(1) as f64);
    Ok(Section {
        width,
        height,
        profiles,
        cut,
        specks,
        area: usable.len() as f64,
        area_fraction: n_particle as f64 / usable.len() as f64,
        binder_colour,
        labels,
        pixels: pixels.to_vec(),
        valid: valid.to_vec(),
        split: split.clone(),
    })
}

//! A tissue's colour under control: its statistics in CIELAB (a perceptual
//! space, where equal steps look equal) and the grading a facet may ask
//! for: hue, saturation and brightness, or a colour transfer onto another
//! entry's statistics (Reinhard et al., "Color Transfer between Images",
//! 2001: each channel's mean and spread moved onto the target's, here in
//! CIELAB). Every step is per pixel, so a tileable texture stays tileable.

use palette::{FromColor, Lab, Srgb};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Mean and standard deviation of L*, a*, b* over a texture's pixels.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct LabStats {
    pub mean: [f64; 3],
    pub spread: [f64; 3],
}

pub use crate::synth::wrap::to_lab;

fn to_rgb(lab: [f32; 3]) -> [u8; 3] {
    let rgb = Srgb::from_color(Lab::new(lab[0].clamp(0.0, 100.0), lab[1], lab[2]));
    // Out-of-gamut colours are clamped channel by channel.
    let c = |v: f32| (v.clamp(0.0, 1.0) * 255.0).round() as u8;
    [c(rgb.red), c(rgb.green), c(rgb.blue)]
}

impl LabStats {
    /// The statistics of `img`'s pixels (sums in f64, in pixel order: the
    /// same figures on any thread count).
    pub fn of(img: &image::RgbImage) -> LabStats {
        let labs: Vec<[f32; 3]> = img.pixels().map(|p| to_lab(p.0)).collect();
        let n = labs.len().max(1) as f64;
        let mut mean = [0.0; 3];
        for lab in &labs {
            for c in 0..3 {
                mean[c] += lab[c] as f64 / n;
            }
        }
        let mut var = [0.0; 3];
        for lab in &labs {
            for c in 0..3 {
                var[c] += (lab[c] as f64 - mean[c]).powi(2) / n;
            }
        }
        LabStats {
            mean,
            spread: var.map(f64::sqrt),
        }
    }
}

/// A facet's colour grading of its tissue, applied in this order: the
/// colour transfer onto `target`'s statistics, then the hue turned by
/// `hue` degrees, the chroma scaled by `saturation`, L* by `brightness`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Grade {
    pub hue: f64,
    pub saturation: f64,
    pub brightness: f64,
    /// The source's and the target's statistics, when matching.
    pub transfer: Option<(LabStats, LabStats)>,
}

impl Grade {
    /// Whether the grading changes nothing.
    pub fn is_identity(&self) -> bool {
        self.hue == 0.0
            && self.saturation == 1.0
            && self.brightness == 1.0
            && self.transfer.is_none()
    }

    /// `img` graded, pixel by pixel.
    pub fn apply(&self, img: &image::RgbImage) -> image::RgbImage {
        let (sin, cos) = (self.hue.to_radians() as f32).sin_cos();
        let (sat, bright) = (self.saturation as f32, self.brightness as f32);
        // Per channel: x -> (x - from mean) * (to spread / from spread) + to mean.
        let affine: [(f32, f32); 3] = match &self.transfer {
            Some((from, to)) => std::array::from_fn(|c| {
                let gain = to.spread[c] / from.spread[c].max(1e-6);
                (gain as f32, (to.mean[c] - from.mean[c] * gain) as f32)
            }),
            None => [(1.0, 0.0); 3],
        };
        let mut out = img.clone();
        out.par_chunks_mut(3).for_each(|px| {
            let lab = to_lab([px[0], px[1], px[2]]);
            let [l, a, b] = std::array::from_fn(|c| lab[c] * affine[c].0 + affine[c].1);
            let (a, b) = (sat * (a * cos - b * sin), sat * (a * sin + b * cos));
            px.copy_from_slice(&to_rgb([l * bright, a, b]));
        });
        out
    }
}

/// A facet's colour grading as a scene states it (`hue`, `saturation`,
/// `brightness`, `match`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Grading {
    /// Degrees the hue turns (CIELAB's a*b* plane), 0: unchanged.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub hue: f64,
    /// Chroma scale, 1: unchanged, 0: grey.
    #[serde(default = "one", skip_serializing_if = "is_one")]
    pub saturation: f64,
    /// L* scale, 1: unchanged.
    #[serde(default = "one", skip_serializing_if = "is_one")]
    pub brightness: f64,
    /// The entry whose colour statistics the texture takes on first.
    #[serde(default, rename = "match", skip_serializing_if = "Option::is_none")]
    pub matched: Option<String>,
}

fn one() -> f64 {
    1.0
}
fn is_one(x: &f64) -> bool {
    *x == 1.0
}
fn is_zero(x: &f64) -> bool {
    *x == 0.0
}

impl Default for Grading {
    fn default() -> Self {
        Grading {
            hue: 0.0,
            saturation: 1.0,
            brightness: 1.0,
            matched: None,
        }
    }
}

impl Grading {
    pub fn is_identity(&self) -> bool {
        *self == Grading::default()
    }

    /// A name for tissue `id`'s texture graded so: the id itself when
    /// nothing changes, so ungraded facets share one texture.
    pub fn key(&self, id: &str) -> String {
        if self.is_identity() {
            return id.to_string();
        }
        let mut key = format!("{id}~h{}s{}b{}", self.hue, self.saturation, self.brightness);
        if let Some(m) = &self.matched {
            key += &format!("m{m}");
        }
        key
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn photo() -> image::RgbImage {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/database/sources/endoslam_panel_c_bot.png"
        );
        image::open(path).expect("bundled").to_rgb8()
    }

    #[test]
    fn lab_round_trips_within_a_level() {
        for rgb in [[0, 0, 0], [255, 255, 255], [200, 90, 80], [12, 200, 30]] {
            let back = to_rgb(to_lab(rgb));
            for c in 0..3 {
                assert!(
                    (back[c] as i32 - rgb[c] as i32).abs() <= 1,
                    "{rgb:?} -> {back:?}"
                );
            }
        }
    }

    #[test]
    fn a_transfer_moves_the_mean_and_spread_onto_the_target() {
        let img = photo();
        let from = LabStats::of(&img);
        let to = LabStats {
            mean: [55.0, 30.0, 18.0],
            spread: [9.0, 6.0, 5.0],
        };
        let graded = Grade {
            hue: 0.0,
            saturation: 1.0,
            brightness: 1.0,
            transfer: Some((from, to)),
        }
        .apply(&img);
        let got = LabStats::of(&graded);
        for c in 0..3 {
            assert!((got.mean[c] - to.mean[c]).abs() < 2.0, "{got:?}");
            assert!((got.spread[c] / to.spread[c] - 1.0).abs() < 0.1, "{got:?}");
        }
    }

    #[test]
    fn hue_saturation_and_brightness_act_on_their_own_axes() {
        let img = photo();
        let before = LabStats::of(&img);
        let grade = |hue, saturation, brightness| {
            LabStats::of(
                &Grade {
                    hue,
                    saturation,
                    brightness,
                    transfer: None,
                }
                .apply(&img),
            )
        };
        let brighter = grade(0.0, 1.0, 1.2);
        assert!(brighter.mean[0] > before.mean[0] * 1.1);
        let grey = grade(0.0, 0.0, 1.0);
        assert!(
            grey.mean[1].abs() < 1.0 && grey.mean[2].abs() < 1.0,
            "{grey:?}"
        );
        let hue_of = |s: &LabStats| s.mean[2].atan2(s.mean[1]).to_degrees();
        let turned = grade(30.0, 1.0, 1.0);
        let dh = hue_of(&turned) - hue_of(&before);
        assert!((dh - 30.0).abs() < 5.0, "turned by {dh}");
    }
}

//! Masks computed from a photograph itself, so a database entry can say
//! what to leave out rather than ship a hand-painted mask:
//! - `dark`: the black border of a fundus or endoscope frame (with a margin,
//!   where the lens vignettes);
//! - `bright`: specular spots and the optic disc, blobs well above the
//!   photograph's brightness;
//! - `vessels`: large vessels (multiscale vesselness).

use serde::{Deserialize, Serialize};

use super::components::without_specks;
use super::exemplar::Exemplar;
use super::filter::{Plane, dilate};
use super::vessels::{threshold_range, vesselness};

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum MaskRule {
    Dark,
    Bright,
    Vessels,
}

fn luminance(p: [u8; 3]) -> f32 {
    (0.299 * p[0] as f32 + 0.587 * p[1] as f32 + 0.114 * p[2] as f32) / 255.0
}

/// Mask out what each rule finds, in order.
pub fn apply(ex: &mut Exemplar, rules: &[MaskRule]) {
    let (w, h) = (ex.width, ex.height);
    let side = w.min(h) as f32;
    for rule in rules {
        let hide: Vec<bool> = match rule {
            MaskRule::Dark => {
                let dark: Vec<bool> = ex.pixels.iter().map(|&p| luminance(p) < 0.12).collect();
                dilate(&dark, w, h, (0.006 * side).ceil() as usize)
            }
            MaskRule::Bright => {
                let lum = Plane::new(w, h, ex.pixels.iter().map(|&p| luminance(p)).collect());
                let weight: Vec<f32> = ex.valid.iter().map(|&v| v as u8 as f32).collect();
                let smooth = lum.blur((0.01 * side).max(1.0), &weight);
                let values: Vec<f32> = (0..w * h)
                    .filter(|&i| ex.valid[i])
                    .map(|i| smooth.data[i])
                    .collect();
                let n = values.len().max(1) as f32;
                let mean = values.iter().sum::<f32>() / n;
                let sd = (values.iter().map(|v| (v - mean) * (v - mean)).sum::<f32>() / n).sqrt();
                let bright: Vec<bool> = (0..w * h)
                    .map(|i| ex.valid[i] && smooth.data[i] > mean + 2.5 * sd)
                    .collect();
                dilate(&bright, w, h, (0.02 * side).ceil() as usize)
            }
            MaskRule::Vessels => {
                let scales: Vec<f32> = [0.0015, 0.0025, 0.004]
                    .iter()
                    .map(|s| (s * side).max(1.0))
                    .collect();
                let v = vesselness(ex, &scales);
                let (low, _) = threshold_range(&v);
                let vessel: Vec<bool> = v.iter().map(|&x| x >= low).collect();
                // A vessel is long: pieces of fewer pixels than 2% of the
                // side are the noise's response, and masking them would
                // riddle the exemplar with holes no neighbourhood can be
                // copied across.
                let vessel = without_specks(&vessel, w, h, (0.02 * side).ceil() as usize);
                dilate(&vessel, w, h, (0.0015 * side).ceil() as usize)
            }
        };
        for (valid, hidden) in ex.valid.iter_mut().zip(hide) {
            *valid &= !hidden;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every rule on exemplars down to one pixel, one row or one column:
    /// they only hide pixels, never fail.
    #[test]
    fn rules_handle_the_smallest_exemplars() {
        for (w, h) in [(1, 1), (2, 2), (1, 9), (9, 1), (3, 5)] {
            let pixels: Vec<[u8; 3]> = (0..w * h)
                .map(|i| [(i * 37 % 256) as u8, 0, (i * 11 % 256) as u8])
                .collect();
            let mut ex = Exemplar::new(w, h, pixels, vec![true; w * h]).unwrap();
            apply(
                &mut ex,
                &[MaskRule::Dark, MaskRule::Bright, MaskRule::Vessels],
            );
            assert_eq!(ex.valid.len(), w * h);
        }
    }
}
